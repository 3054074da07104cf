//! The long-range silhouette term (shaders/loss/silhouette.comp): every vertex of a correct
//! surface projects inside every view's mask, so a vertex outside one is pulled towards it by
//! the mask's distance field, from any distance: the anti-aliased edge gradient of the
//! rasterizer acts within a pixel of the outline, this acts everywhere. All views are scored
//! in every step (one field lookup per vertex and view); a view whose mask is empty is left out
//! and named by [`SilhouetteTerm::views_without_mask`]. [`CoverageTerm`] is the other
//! direction: mask pixels the render leaves uncovered pull the nearest vertex.

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
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of silhouette.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    vertices: u32,
    views: u32,
    scale: f32,
    near: f32,
}
push_layout!(Push: [LOSS_SILHOUETTE], [vertices, views, scale, near]);

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

/// The silhouette kernel with every view's camera and distance field uploaded, and the
/// buffer its weighted value is summed in.
pub struct SilhouetteTerm {
    pipeline: ComputePipeline,
    views: GpuBuffer<PinholeView>,
    fields: GpuBuffer<f32>,
    loss_sum: FixedSums,
    view_count: usize,
    with_mask: usize,
    without_mask: Vec<usize>,
}

impl SilhouetteTerm {
    /// Uploads the views' fields. Views must be at least 2 × 2 pixels.
    pub fn new(
        ctx: &Arc<GpuContext>,
        views: &[SilhouetteView],
    ) -> Result<Self, crate::gpu::GpuError> {
        let (mut gpu_views, mut fields, mut without_mask) = (Vec::new(), Vec::new(), Vec::new());
        for (index, view) in views.iter().enumerate() {
            let c = &view.camera;
            let usable = view.field.as_ref().filter(|f| {
                c.width >= 2 && c.height >= 2 && f.len() == (c.width * c.height) as usize
            });
            if usable.is_none() {
                without_mask.push(index);
            }
            // The kernel's words: where the view's field starts, and whether it has one.
            gpu_views.push(PinholeView::new(c, [fields.len() as u32, usable.is_some() as u32]));
            fields.extend_from_slice(usable.map_or(&[][..], |f| f));
        }
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
            fields: GpuBuffer::from_slice(ctx, "silhouette distance fields", &fields)?,
            loss_sum: FixedSums::new(ctx, "silhouette loss", 1, FixedPrecision::Total)?,
            view_count: views.len(),
            with_mask: views.len() - without_mask.len(),
            without_mask,
        })
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
        let push = Push {
            vertices: vertices as u32,
            views: self.view_count as u32,
            scale: weight / (vertices * self.with_mask) as f32,
            near,
        };
        let buffers = [
            ("positions", positions.binding()),
            ("views", self.views.binding()),
            ("fields", self.fields.binding()),
            ("grad_positions", grad_positions.binding()),
            ("loss_sum", self.loss_sum.binding()),
        ];
        rec.dispatch_1d(
            &self.pipeline,
            &buffers,
            &push,
            (vertices as u64).div_ceil(WORKGROUP as u64),
        )
    }

    /// The weighted loss summed since the last call (which restarts the sum).
    pub fn take_loss(&self) -> GpuResult<f32> {
        Ok(self.loss_sum.take()?[0] as f32)
    }
}
