//! The two regularizer passes (shaders/regularize/): `vertex` (per Gaussian: L_2d, Laplacian
//! offsets, normal term) and `gather` (per Gaussian: every position/rotation gradient that
//! lands on its rows, temporal terms), recorded into the caller's [`Recorder`].

use super::{Losses, Neighbourhoods, RegularizeError, Weights, LOSS_SLOTS};
use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult,
    PipelineDesc, Recorder,
};
use crate::shaders;
use crate::splat::GaussianBuffers;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of both passes (shaders/regularize/common.glsl `Push`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    count: u32,
    temporal: u32,
    inv_count: f32,
    omega_scale: f32,
    w_scale_2d: f32,
    w_laplacian: f32,
    w_normal: f32,
    w_edge_length: f32,
    w_rigidity: f32,
    w_rotation: f32,
    huber: f32,
}
push_layout!(
    Push: [REGULARIZE_VERTEX, REGULARIZE_GATHER],
    [
        count,
        temporal,
        inv_count,
        omega_scale,
        w_scale_2d,
        w_laplacian,
        w_normal,
        w_edge_length,
        w_rigidity,
        w_rotation,
        huber,
    ]
);

/// The previous frame's positions (3 floats per Gaussian) and rotations, for the temporal
/// terms.
#[derive(Clone, Copy)]
pub struct Temporal<'a> {
    /// Previous positions, x, y, z per Gaussian.
    pub positions: &'a GpuBuffer<f32>,
    /// Previous rotations, one (w, x, y, z) quaternion per Gaussian.
    pub rotations: &'a GpuBuffer<[f32; 4]>,
}

impl<'a> Temporal<'a> {
    /// The positions and rotations of `previous`.
    pub fn of(previous: &'a GaussianBuffers) -> Self {
        Self { positions: &previous.positions, rotations: &previous.rotations }
    }
}

/// Pipelines, the uploaded neighbourhoods, per-Gaussian scratch and the loss buffer.
pub struct Regularizers {
    ctx: Arc<GpuContext>,
    vertex: ComputePipeline,
    gather: ComputePipeline,
    ranges: GpuBuffer<[u32; 2]>,
    ring: GpuBuffer<u32>,
    stiffness: GpuBuffer<f32>,
    deltas: GpuBuffer<[f32; 4]>,
    normal_grads: GpuBuffer<[f32; 4]>,
    loss_sums: FixedSums,
    count: usize,
    mean_edge_length: f32,
}

impl Regularizers {
    /// Pipelines and empty neighbourhoods; [`Self::upload`] before recording.
    pub fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        let pipeline = |name, shader| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[WORKGROUP] })
        };
        Ok(Self {
            ctx: ctx.clone(),
            vertex: pipeline("regularize vertex", &shaders::REGULARIZE_VERTEX)?,
            gather: pipeline("regularize gather", &shaders::REGULARIZE_GATHER)?,
            ranges: GpuBuffer::new(ctx, "regularize ranges", 0)?,
            ring: GpuBuffer::new(ctx, "regularize ring", 0)?,
            stiffness: GpuBuffer::new(ctx, "regularize stiffness", 0)?,
            deltas: GpuBuffer::new(ctx, "regularize deltas", 0)?,
            normal_grads: GpuBuffer::new(ctx, "regularize normal gradients", 0)?,
            loss_sums: FixedSums::new(ctx, "regularize losses", LOSS_SLOTS, FixedPrecision::Total)?,
            count: 0,
            mean_edge_length: 1.0,
        })
    }

    /// Uploads the 1-rings (after every topology change) and sizes the scratch buffers.
    pub fn upload(&mut self, nb: &Neighbourhoods) -> GpuResult<()> {
        self.ranges = GpuBuffer::from_slice(&self.ctx, "regularize ranges", &nb.ranges)?;
        self.ring = GpuBuffer::from_slice(&self.ctx, "regularize ring", &nb.ring)?;
        self.stiffness = GpuBuffer::from_slice(&self.ctx, "regularize stiffness", &nb.stiffness)?;
        self.deltas = GpuBuffer::new(&self.ctx, "regularize deltas", nb.len())?;
        self.normal_grads = GpuBuffer::new(&self.ctx, "regularize normal gradients", nb.len())?;
        self.count = nb.len();
        self.mean_edge_length = nb.mean_edge_length;
        Ok(())
    }

    /// Records both passes: zeroes the loss buffer, then ADDS the weighted gradients of every
    /// term into `grads` (positions, log-scales, rotations) and writes the unweighted losses to
    /// [`Self::read_losses`]. Temporal terms run only with `previous`. Nothing is read back.
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        grads: &'a GaussianBuffers,
        weights: &Weights,
        previous: Option<Temporal<'a>>,
    ) -> Result<(), RegularizeError> {
        self.check_shapes(params, grads, previous)?;
        let push = Push {
            count: self.count as u32,
            temporal: previous.is_some() as u32,
            inv_count: 1.0 / self.count.max(1) as f32,
            omega_scale: weights.lambda_w / self.mean_edge_length,
            w_scale_2d: weights.scale_2d,
            w_laplacian: weights.laplacian,
            w_normal: weights.normal,
            w_edge_length: weights.edge_length,
            w_rigidity: weights.rigidity,
            w_rotation: weights.rotation,
            huber: weights.huber * self.mean_edge_length,
        };
        let groups = self.count.div_ceil(WORKGROUP as usize) as u64;
        self.loss_sums.clear(rec);
        let vertex = [
            ("positions", params.positions.binding()),
            ("log_scales", params.log_scales.binding()),
            ("rotations", params.rotations.binding()),
            ("ranges", self.ranges.binding()),
            ("ring", self.ring.binding()),
            ("grad_log_scales", grads.log_scales.binding()),
            ("grad_rotations", grads.rotations.binding()),
            ("deltas", self.deltas.binding()),
            ("normal_grads", self.normal_grads.binding()),
            ("loss_sums", self.loss_sums.binding()),
        ];
        rec.dispatch_1d(&self.vertex, &vertex, &push, groups)?;
        // Without a previous frame the kernel never reads these; bind the current ones.
        let prev = previous
            .unwrap_or(Temporal { positions: &params.positions, rotations: &params.rotations });
        let gather = [
            ("positions", params.positions.binding()),
            ("rotations", params.rotations.binding()),
            ("prev_positions", prev.positions.binding()),
            ("prev_rotations", prev.rotations.binding()),
            ("ranges", self.ranges.binding()),
            ("ring", self.ring.binding()),
            ("deltas", self.deltas.binding()),
            ("normal_grads", self.normal_grads.binding()),
            ("grad_positions", grads.positions.binding()),
            ("grad_rotations", grads.rotations.binding()),
            ("loss_sums", self.loss_sums.binding()),
            ("stiffness", self.stiffness.binding()),
        ];
        rec.dispatch_1d(&self.gather, &gather, &push, groups)?;
        Ok(())
    }

    fn check_shapes(
        &self,
        params: &GaussianBuffers,
        grads: &GaussianBuffers,
        previous: Option<Temporal<'_>>,
    ) -> Result<(), RegularizeError> {
        let n = self.count;
        let mut shapes = vec![("parameters", params.len()), ("gradients", grads.len())];
        if let Some(p) = previous {
            shapes.push(("previous positions", p.positions.len() / 3));
            shapes.push(("previous rotations", p.rotations.len()));
        }
        match shapes.iter().find(|(_, len)| *len != n) {
            Some((what, len)) => {
                Err(RegularizeError::Shape(format!("{len} {what} for {n} uploaded neighbourhoods")))
            }
            None => Ok(()),
        }
    }

    /// Reads the losses back (after the recorder was submitted).
    pub fn read_losses(&self) -> GpuResult<Losses<f32>> {
        let v: Vec<f32> = self.loss_sums.read()?.into_iter().map(|sum| sum as f32).collect();
        Ok(Losses::from_slots([v[0], v[1], v[2], v[3], v[4], v[5]]))
    }

    /// Gaussians covered by the uploaded neighbourhoods.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether the uploaded neighbourhoods cover no Gaussian.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}
