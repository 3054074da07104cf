//! The raster kernels, one pipeline per shader. Forward: transform → outline flags → setup
//! (with the small-triangle raster) → large-triangle raster → resolve → anti-aliasing
//! crossings → anti-aliasing blend. Backward: anti-aliasing backward → interior backward.

use crate::gpu::{ComputePipeline, FixedResolve, GpuContext, GpuResult, PipelineDesc, Shader};
use crate::shaders;
use std::sync::Arc;

/// Invocations per workgroup of the per-vertex and per-triangle kernels.
pub(crate) const LINEAR_WORKGROUP: u32 = 128;

pub(crate) struct Kernels {
    pub transform: ComputePipeline,
    pub outline: ComputePipeline,
    pub setup: ComputePipeline,
    pub raster_large: ComputePipeline,
    pub resolve: ComputePipeline,
    pub aa_pairs: ComputePipeline,
    pub aa_forward: ComputePipeline,
    pub aa_backward: ComputePipeline,
    pub interior_backward: ComputePipeline,
    /// Fixed-point gradient sums into the caller's float gradients.
    pub resolve_sums: FixedResolve,
}

impl Kernels {
    pub(crate) fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        let linear = [LINEAR_WORKGROUP];
        // The per-pixel kernels fix their 16x16 workgroup in the shader.
        let pipeline = |name, shader: &'static Shader, specialization: &[u32]| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization })
        };
        Ok(Self {
            transform: pipeline("raster transform", &shaders::RASTER_TRANSFORM, &linear)?,
            outline: pipeline("raster outline flags", &shaders::RASTER_OUTLINE, &linear)?,
            setup: pipeline("raster setup", &shaders::RASTER_SETUP, &linear)?,
            raster_large: pipeline("raster large triangles", &shaders::RASTER_RASTER_LARGE, &[])?,
            resolve: pipeline("raster resolve", &shaders::RASTER_RESOLVE, &[])?,
            aa_pairs: pipeline("raster antialias crossings", &shaders::RASTER_AA_PAIRS, &[])?,
            aa_forward: pipeline("raster antialias", &shaders::RASTER_AA_FORWARD, &[])?,
            aa_backward: pipeline("raster antialias backward", &shaders::RASTER_AA_BACKWARD, &[])?,
            interior_backward: pipeline(
                "raster interior backward",
                &shaders::RASTER_INTERIOR_BACKWARD,
                &[],
            )?,
            resolve_sums: FixedResolve::new(ctx)?,
        })
    }
}

/// Workgroups of the linear kernels for `items` items.
pub(crate) fn linear_groups(items: usize) -> u64 {
    items.div_ceil(LINEAR_WORKGROUP as usize) as u64
}
