//! The long-range silhouette term (shaders/loss/silhouette.comp): every vertex of a correct
//! surface projects inside every view's mask, so a vertex outside one is pulled towards it by
//! the mask's distance field, from any distance: the anti-aliased edge gradient of the
//! rasterizer acts within a pixel of the outline, this acts everywhere. All views are scored
//! in every step (one field lookup per vertex and view); a view whose mask is empty is left out
//! and named by [`SilhouetteTerm::views_without_mask`]. The fields of consecutive views share
//! a buffer up to the device's largest storage buffer, one dispatch per buffer, so no buffer
//! grows with views × pixels (42 views at 1080² are 196 MB of fields). [`CoverageTerm`] is the
//! other direction: mask pixels the render leaves uncovered pull the nearest vertex.

mod coverage;
mod distance;
pub mod reference;

pub use coverage::CoverageTerm;
pub use distance::mask_distance;

use crate::camera::Camera;
use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult,
    PipelineDesc, Recorder,
};
use crate::loss::pinhole_view::PinholeView;
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::ops::Range;
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of silhouette.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    vertices: u32,
    first_view: u32,
    views: u32,
    scale: f32,
    near: f32,
}
push_layout!(Push: [LOSS_SILHOUETTE], [vertices, first_view, views, scale, near]);

/// A view's camera and its mask's distance field (`None`: the mask is empty).
pub struct SilhouetteView {
    /// The view's camera; its size is the field's size.
    pub camera: Camera,
    /// The mask's distance field ([`mask_distance`]): row-major, in pixels; `None` for an
    /// empty mask.
    pub field: Option<Vec<f32>>,
}

impl SilhouetteView {
    /// From a camera and its mask (row-major, one value per pixel, > 0.5 is foreground).
    pub fn from_mask(camera: Camera, mask: &[f32]) -> Self {
        Self { camera, field: mask_distance(mask, camera.width as usize, camera.height as usize) }
    }
}

/// Consecutive views whose fields share one buffer, scored in one dispatch.
struct FieldChunk {
    views: Range<usize>,
    fields: GpuBuffer<f32>,
}

/// The silhouette kernel with every view's camera and distance field uploaded, and the
/// buffer its weighted value is summed in.
pub struct SilhouetteTerm {
    pipeline: ComputePipeline,
    views: GpuBuffer<PinholeView>,
    chunks: Vec<FieldChunk>,
    loss_sum: FixedSums,
    with_mask: usize,
    without_mask: Vec<usize>,
}

impl SilhouetteTerm {
    /// Uploads the views' fields. Views must be at least 2 × 2 pixels.
    pub fn new(
        ctx: &Arc<GpuContext>,
        views: &[SilhouetteView],
    ) -> Result<Self, crate::gpu::GpuError> {
        Self::with_buffer_limit(ctx, views, ctx.limits().max_buffer_bytes())
    }

    /// [`Self::new`] with the fields split into buffers of at most `max_bytes` each (a
    /// single view's field over it is refused, naming its buffer).
    pub fn with_buffer_limit(
        ctx: &Arc<GpuContext>,
        views: &[SilhouetteView],
        max_bytes: u64,
    ) -> Result<Self, crate::gpu::GpuError> {
        let usable: Vec<Option<&[f32]>> = views
            .iter()
            .map(|view| {
                let c = &view.camera;
                view.field.as_deref().filter(|f| {
                    c.width >= 2 && c.height >= 2 && f.len() == (c.width * c.height) as usize
                })
            })
            .collect();
        let lens: Vec<usize> = usable.iter().map(|f| f.map_or(0, <[f32]>::len)).collect();
        let max_len = (max_bytes / size_of::<f32>() as u64) as usize;
        let (mut gpu_views, mut chunks) = (Vec::new(), Vec::new());
        for range in consecutive_chunks(&lens, max_len) {
            let mut fields = Vec::with_capacity(lens[range.clone()].iter().sum());
            for v in range.clone() {
                // The kernel's words: where the view's field starts in its chunk, and whether it
                // has one.
                let words = [fields.len() as u32, usable[v].is_some() as u32];
                gpu_views.push(PinholeView::new(&views[v].camera, words));
                fields.extend_from_slice(usable[v].unwrap_or_default());
            }
            let name = format!("silhouette distance fields of views {range:?}");
            chunks.push(FieldChunk {
                fields: GpuBuffer::from_slice(ctx, &name, &fields)?,
                views: range,
            });
        }
        let without_mask: Vec<usize> = (0..views.len()).filter(|&v| usable[v].is_none()).collect();
        Ok(Self {
            pipeline: ComputePipeline::new(
                ctx,
                &PipelineDesc {
                    name: "silhouette",
                    shader: &shaders::LOSS_SILHOUETTE,
                    specialization: &[WORKGROUP],
                },
            )?,
            views: GpuBuffer::from_slice(ctx, "silhouette views", &gpu_views)?,
            chunks,
            loss_sum: FixedSums::new(ctx, "silhouette loss", 1, FixedPrecision::Total)?,
            with_mask: views.len() - without_mask.len(),
            without_mask,
        })
    }

    /// How many buffers the fields were split into.
    pub fn field_buffers(&self) -> usize {
        self.chunks.len()
    }

    /// Indices (into the views given to [`Self::new`]) of views left out: empty mask.
    pub fn views_without_mask(&self) -> &[usize] {
        &self.without_mask
    }

    /// Records the term for `vertices` positions (3 floats each), ADDING `weight` × its
    /// gradient (the mean over vertices and views with a mask) into `grad_positions`; the
    /// weighted value is summed for [`Self::take_loss`]. `near`: closer points are skipped.
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        positions: &'a GpuBuffer<f32>,
        grad_positions: &'a GpuBuffer<f32>,
        weight: f32,
        near: f32,
    ) -> GpuResult<()> {
        let vertices = positions.len() / 3;
        if vertices == 0 || self.with_mask == 0 || weight == 0.0 {
            return Ok(());
        }
        let scale = weight / (vertices * self.with_mask) as f32;
        for chunk in &self.chunks {
            let push = Push {
                vertices: vertices as u32,
                first_view: chunk.views.start as u32,
                views: chunk.views.len() as u32,
                scale,
                near,
            };
            let buffers = [
                ("positions", positions.binding()),
                ("views", self.views.binding()),
                ("fields", chunk.fields.binding()),
                ("grad_positions", grad_positions.binding()),
                ("loss_sum", self.loss_sum.binding()),
            ];
            let groups = (vertices as u64).div_ceil(WORKGROUP as u64);
            rec.dispatch_1d(&self.pipeline, &buffers, &push, groups)?;
        }
        Ok(())
    }

    /// The weighted loss summed since the last call (which restarts the sum).
    pub fn take_loss(&self) -> GpuResult<f32> {
        Ok(self.loss_sum.take()?[0] as f32)
    }
}

/// Splits items of `lens` into runs of consecutive items whose lengths add up to at most
/// `max_len` each (an item over it alone makes a run of its own); every item is in exactly one
/// run, in order; no items, no runs.
fn consecutive_chunks(lens: &[usize], max_len: usize) -> Vec<Range<usize>> {
    let mut runs: Vec<Range<usize>> = Vec::new();
    let mut used = 0;
    for (i, &len) in lens.iter().enumerate() {
        match runs.last_mut() {
            Some(run) if len == 0 || used + len <= max_len => run.end = i + 1,
            _ => {
                runs.push(i..i + 1);
                used = 0;
            }
        }
        used += len;
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::consecutive_chunks;

    #[test]
    fn chunks_cover_every_item_in_order_under_the_limit() {
        assert_eq!(consecutive_chunks(&[], 10), vec![]);
        assert_eq!(consecutive_chunks(&[4, 4, 4, 0, 4], 8), vec![0..2, 2..5]);
        // An item over the limit stands alone; empty fields join any run.
        assert_eq!(consecutive_chunks(&[3, 12, 0, 5, 5], 10), vec![0..1, 1..3, 3..5]);
        assert_eq!(consecutive_chunks(&[1; 5], usize::MAX), vec![0..5]);
    }
}
