//! The splatting kernels, one pipeline per shader, recorded with the buffers the caller owns.
//! Forward and backward of each stage side by side: project ↔ project_backward,
//! rasterize ↔ rasterize_backward; binning (emit, tile ranges) has no backward.

use super::buffers::GaussianBuffers;
use super::frame::{FrameParams, Splat};
use crate::gpu::{
    push_layout, ComputePipeline, FixedSums, GpuBuffer, GpuContext, GpuResult, PipelineDesc,
    Recorder, Shader,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// Invocations per workgroup of the per-Gaussian and per-intersection kernels.
const LINEAR_WORKGROUP: u32 = 128;
/// One workgroup per 16×16 tile.
const TILE_WORKGROUP: u32 = super::TILE_SIZE * super::TILE_SIZE;

/// Push constants of tile_ranges.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RangeParams {
    intersections: u32,
    tile_count: u32,
}
push_layout!(RangeParams: [SPLAT_TILE_RANGES], [intersections, tile_count]);

/// The scene's buffers as project.comp and project_backward.comp name them, and their gradients.
const SCENE: [&str; 5] = ["positions", "log_scales", "rotations", "opacity_logits", "sh"];
const GRADS: [&str; 5] =
    ["grad_positions", "grad_log_scales", "grad_rotations", "grad_opacity_logits", "grad_sh"];

pub(crate) struct Kernels {
    project: ComputePipeline,
    project_backward: ComputePipeline,
    emit_intersections: ComputePipeline,
    tile_ranges: ComputePipeline,
    rasterize: ComputePipeline,
    rasterize_backward: ComputePipeline,
}

fn groups(items: usize) -> u64 {
    items.div_ceil(LINEAR_WORKGROUP as usize) as u64
}

impl Kernels {
    pub(crate) fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        // Constant 0 is the workgroup size, 1 the subgroup size (read by the rasterizers).
        let subgroup = ctx.limits().subgroup_size;
        let pipeline = |name, shader: &'static Shader, workgroup: u32| {
            ComputePipeline::new(
                ctx,
                &PipelineDesc { name, shader, specialization: &[workgroup, subgroup] },
            )
        };
        let linear = LINEAR_WORKGROUP;
        Ok(Self {
            project: pipeline("splat project", &shaders::SPLAT_PROJECT, linear)?,
            project_backward: pipeline(
                "splat project backward",
                &shaders::SPLAT_PROJECT_BACKWARD,
                linear,
            )?,
            emit_intersections: pipeline(
                "splat emit intersections",
                &shaders::SPLAT_EMIT_INTERSECTIONS,
                linear,
            )?,
            tile_ranges: pipeline("splat tile ranges", &shaders::SPLAT_TILE_RANGES, linear)?,
            rasterize: pipeline("splat rasterize", &shaders::SPLAT_RASTERIZE, TILE_WORKGROUP)?,
            rasterize_backward: pipeline(
                "splat rasterize backward",
                &shaders::SPLAT_RASTERIZE_BACKWARD,
                TILE_WORKGROUP,
            )?,
        })
    }

    /// Splats, per-Gaussian tile counts, and the visible splats' depth range narrowed into
    /// `depth_range` (filled with all ones first; see intersection_key.glsl).
    pub(crate) fn project<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        scene: &'a GaussianBuffers,
        splats: &'a GpuBuffer<Splat>,
        (tile_counts, depth_range): (&'a GpuBuffer<u32>, &'a GpuBuffer<u32>),
    ) -> GpuResult<()> {
        let bindings: Vec<_> = scene
            .bindings(SCENE)
            .into_iter()
            .chain([
                ("splats", splats.binding()),
                ("tile_counts", tile_counts.binding()),
                ("depth_range", depth_range.binding()),
            ])
            .collect();
        rec.dispatch_1d(&self.project, &bindings, frame, groups(frame.gaussians()))
    }

    /// Adds parameter gradients and densification statistics from the 2D gradients.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn project_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        scene: &'a GaussianBuffers,
        grad2d: &'a GpuBuffer<f32>,
        grads: &'a GaussianBuffers,
        densify_stats: &'a GpuBuffer<[f32; 2]>,
    ) -> GpuResult<()> {
        let bindings: Vec<_> = scene
            .bindings(SCENE)
            .into_iter()
            .chain([("grad2d", grad2d.binding())])
            .chain(grads.bindings(GRADS))
            .chain([("densify_stats", densify_stats.binding())])
            .collect();
        rec.dispatch_1d(&self.project_backward, &bindings, frame, groups(frame.gaussians()))
    }

    /// (key, Gaussian) pairs from the scanned tile counts and the depth range of
    /// [`Self::project`].
    pub(crate) fn emit_intersections<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        (splats, offsets, depth_range): (
            &'a GpuBuffer<Splat>,
            &'a GpuBuffer<u32>,
            &'a GpuBuffer<u32>,
        ),
        keys: &'a GpuBuffer<u32>,
        ids: &'a GpuBuffer<u32>,
    ) -> GpuResult<()> {
        let bindings = [
            ("splats", splats.binding()),
            ("tile_offsets", offsets.binding()),
            ("keys", keys.binding()),
            ("gaussian_ids", ids.binding()),
            ("depth_range", depth_range.binding()),
        ];
        rec.dispatch_1d(&self.emit_intersections, &bindings, frame, groups(frame.gaussians()))
    }

    /// Each tile's run in the sorted keys (all `keys.len()` slots, unfilled ones included);
    /// `ranges` must be zeroed first.
    pub(crate) fn tile_ranges<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        keys: &'a GpuBuffer<u32>,
        ranges: &'a GpuBuffer<[u32; 2]>,
    ) -> GpuResult<()> {
        let (tiles_x, tiles_y) = frame.tiles();
        let params =
            RangeParams { intersections: keys.len() as u32, tile_count: tiles_x * tiles_y };
        rec.dispatch_1d(
            &self.tile_ranges,
            &[("keys", keys.binding()), ("tile_ranges", ranges.binding())],
            &params,
            groups(keys.len()),
        )
    }

    pub(crate) fn rasterize<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        inputs: &RasterInputs<'a>,
        outputs: &RasterOutputs<'a>,
    ) {
        let bindings = [
            ("splats", inputs.splats.binding()),
            ("tile_ranges", inputs.ranges.binding()),
            ("gaussian_ids", inputs.ids.binding()),
            ("out_rgba", outputs.rgba.binding()),
            ("out_depth", outputs.depth.binding()),
            ("pixel_state", outputs.pixel_state.binding()),
        ];
        let (tiles_x, tiles_y) = frame.tiles();
        rec.dispatch(&self.rasterize, &bindings, frame, [tiles_x, tiles_y, 1]);
    }

    /// Adds 2D gradients per Gaussian to `grad2d_sums` (zeroed first) from the per-pixel loss
    /// gradients `(dL/d(colour, alpha), dL/ddepth)`.
    pub(crate) fn rasterize_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        (inputs, outputs): (&RasterInputs<'a>, &RasterOutputs<'a>),
        (grad_rgba, grad_depth): (&'a GpuBuffer<[f32; 4]>, &'a GpuBuffer<f32>),
        grad2d_sums: &'a FixedSums,
    ) {
        let bindings = [
            ("splats", inputs.splats.binding()),
            ("tile_ranges", inputs.ranges.binding()),
            ("gaussian_ids", inputs.ids.binding()),
            ("depth_out", outputs.depth.binding()),
            ("pixel_state", outputs.pixel_state.binding()),
            ("grad_rgba", grad_rgba.binding()),
            ("grad_depth", grad_depth.binding()),
            ("grad2d_sums", grad2d_sums.binding()),
        ];
        let (tiles_x, tiles_y) = frame.tiles();
        rec.dispatch(&self.rasterize_backward, &bindings, frame, [tiles_x, tiles_y, 1]);
    }
}

/// What the rasterizer reads: splats, per-tile runs and the depth-sorted Gaussian ids.
pub(crate) struct RasterInputs<'a> {
    pub splats: &'a GpuBuffer<Splat>,
    pub ranges: &'a GpuBuffer<[u32; 2]>,
    pub ids: &'a GpuBuffer<u32>,
}

/// What the forward rasterizer writes, and the backward reads again.
pub(crate) struct RasterOutputs<'a> {
    pub rgba: &'a GpuBuffer<[f32; 4]>,
    pub depth: &'a GpuBuffer<f32>,
    pub pixel_state: &'a GpuBuffer<[u32; 2]>,
}
