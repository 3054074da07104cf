//! The coverage term, the silhouette term's other direction (shaders/loss/coverage_*.comp):
//! a pixel the mask covers but the render does not pulls the nearest projected vertex towards
//! itself, so a limb that moved many pixels is drawn to where the mask now shows it. Scored on
//! the step's view: E = weight / pixels · Σ over such pixels p of ‖uv_s − p‖², s the nearest
//! vertex among the lowest-id vertex of each pixel within `radius` pixels (Chebyshev).

use crate::camera::Camera;
use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedResolve, FixedSums, GpuBuffer, GpuContext,
    GpuResult, PipelineDesc, Recorder,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of both kernels (coverage_common.glsl `Push`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    world_to_camera: [f32; 16],
    intrinsics: [f32; 4],
    width: u32,
    height: u32,
    vertices: u32,
    radius: u32,
    scale: f32,
    near: f32,
}
push_layout!(
    Push: [LOSS_COVERAGE_SEED, LOSS_COVERAGE_PULL],
    [world_to_camera, intrinsics, width, height, vertices, radius, scale, near]
);

/// The coverage kernels and their scratch (projected vertices, per-pixel seeds) sized for a
/// vertex count and the largest view, and the buffer its weighted value is summed in.
pub struct CoverageTerm {
    seed: ComputePipeline,
    pull: ComputePipeline,
    projected: GpuBuffer<[f32; 2]>,
    seeds: GpuBuffer<u32>,
    /// The gradient (3 per vertex) and the loss as order-independent sums.
    grad_position_sums: FixedSums,
    resolve: FixedResolve,
    loss_sum: FixedSums,
    radius: u32,
}

impl CoverageTerm {
    /// For `vertices` vertices and views of at most `pixels` pixels, searching `radius` pixels.
    pub fn new(
        ctx: &Arc<GpuContext>,
        vertices: usize,
        pixels: usize,
        radius: u32,
    ) -> GpuResult<Self> {
        let pipeline = |name, shader| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[WORKGROUP] })
        };
        Ok(Self {
            seed: pipeline("coverage seed", &shaders::LOSS_COVERAGE_SEED)?,
            pull: pipeline("coverage pull", &shaders::LOSS_COVERAGE_PULL)?,
            projected: GpuBuffer::new(ctx, "coverage projected vertices", vertices)?,
            seeds: GpuBuffer::new(ctx, "coverage seeds", pixels)?,
            grad_position_sums: FixedSums::new(
                ctx,
                "coverage gradient sums",
                3 * vertices,
                FixedPrecision::Gradient,
            )?,
            resolve: FixedResolve::new(ctx)?,
            loss_sum: FixedSums::new(ctx, "coverage loss", 1, FixedPrecision::Total)?,
            radius,
        })
    }

    /// Records the term for `camera`'s view: `target` and `render` are its rgba images (alpha:
    /// the mask and the render's coverage), `positions` 3 floats per vertex; ADDS the weighted
    /// gradient into `grad_positions` and sums the weighted value for [`Self::take_loss`].
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        camera: &Camera,
        (target, render): (&'a GpuBuffer<[f32; 4]>, &'a GpuBuffer<[f32; 4]>),
        positions: &'a GpuBuffer<f32>,
        grad_positions: &'a GpuBuffer<f32>,
        weight: f32,
        near: f32,
    ) -> GpuResult<()> {
        let (vertices, pixels) =
            (positions.len() / 3, camera.width as usize * camera.height as usize);
        if weight == 0.0 || vertices == 0 || pixels == 0 {
            return Ok(());
        }
        // The buffers were sized at construction; a larger mesh or view would overrun them.
        for (name, len, capacity) in [
            (self.projected.name(), vertices, self.projected.len()),
            (self.grad_position_sums.name(), 3 * vertices, self.grad_position_sums.len()),
            (grad_positions.name(), 3 * vertices, grad_positions.len()),
            (self.seeds.name(), pixels, self.seeds.len().min(target.len()).min(render.len())),
        ] {
            if len > capacity {
                return Err(crate::gpu::GpuError::LengthMismatch {
                    what: "coverage term",
                    name: name.to_string(),
                    len,
                    capacity,
                });
            }
        }
        let push = Push {
            world_to_camera: camera.world_to_camera.to_cols_array().map(|v| v as f32),
            intrinsics: [camera.fx, camera.fy, camera.cx, camera.cy].map(|v| v as f32),
            width: camera.width,
            height: camera.height,
            vertices: vertices as u32,
            radius: self.radius,
            scale: weight / pixels as f32,
            near,
        };
        rec.fill_buffer(&self.seeds, u32::MAX);
        rec.dispatch_1d(
            &self.seed,
            &[
                ("positions", positions.binding()),
                ("projected", self.projected.binding()),
                ("seeds", self.seeds.binding()),
            ],
            &push,
            (vertices as u64).div_ceil(WORKGROUP as u64),
        )?;
        let pull = [
            ("positions", positions.binding()),
            ("projected", self.projected.binding()),
            ("seeds", self.seeds.binding()),
            ("target", target.binding()),
            ("render", render.binding()),
            ("grad_position_sums", self.grad_position_sums.binding()),
            ("loss_sum", self.loss_sum.binding()),
        ];
        rec.dispatch_1d(&self.pull, &pull, &push, (pixels as u64).div_ceil(WORKGROUP as u64))?;
        self.resolve.record(rec, &self.grad_position_sums, grad_positions, 3 * vertices)
    }

    /// The weighted loss summed since the last call (which restarts the sum).
    pub fn take_loss(&self) -> GpuResult<f32> {
        Ok(self.loss_sum.take()?[0] as f32)
    }
}
