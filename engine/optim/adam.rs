//! Fused Adam (Kingma & Ba) over the five Gaussian parameter buffers in one dispatch, six
//! learning rates (SH DC and the higher SH bands apart). Moments (m, v) live on the GPU beside
//! each parameter buffer; [`Adam::remap`] carries them through a change of the Gaussian set.

use crate::gpu::{
    push_layout, ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult, HostRing,
    PipelineDesc, Recorder,
};
use crate::shaders;
use crate::splat::{sh_coefficients, GaussianBuffers};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;
/// Four-float chunks each invocation of adam_step.comp updates (specialization constant 1).
const CHUNKS_PER_INVOCATION: u32 = 8;
const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f32 = 1e-15;
/// A remap entry for a row with no old row: its moments start at zero.
pub const NEW_ROW: u32 = u32::MAX;

/// Learning rate per parameter group for one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearningRates {
    /// Rate of the positions.
    pub positions: f32,
    /// Rate of the log-scales.
    pub log_scales: f32,
    /// Rate of the rotation quaternions.
    pub rotations: f32,
    /// Rate of the opacity logits.
    pub opacity_logits: f32,
    /// Rate of the degree-0 (DC) SH coefficient of each colour channel.
    pub sh_dc: f32,
    /// Rate of the higher SH bands.
    pub sh_rest: f32,
}

/// One step's parameters as adam_step.comp reads them from a ring slot (`AdamParams` in
/// shaders/optim/adam.glsl): five 16-byte vectors, so std430 lays them out as here.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct AdamParams {
    lr_a: [f32; 4],
    lr_b: [f32; 4],
    betas: [f32; 4],
    bias: [f32; 4],
    counts: [u32; 4],
}
const _: () = assert!(size_of::<AdamParams>() == 80);

/// Push constants of adam_step.comp: the ring slot a recorded step reads its parameters from.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct AdamSlot {
    slot: u32,
}
push_layout!(AdamSlot: [OPTIM_ADAM_STEP], [slot]);

impl AdamParams {
    /// `step` counts from 1 (the bias corrections need it).
    pub fn new(lr: &LearningRates, step: u32, gaussians: usize, sh_degree: u32) -> Self {
        let step = step.max(1) as i32;
        // 1 − β and the bias corrections in f64: in f32, 1 − 0.999 is off by 1e-5 relative.
        let f = |v: f64| v as f32;
        Self {
            lr_a: [lr.positions, lr.log_scales, lr.rotations, lr.opacity_logits],
            lr_b: [lr.sh_dc, lr.sh_rest, EPSILON, 0.0],
            betas: [f(BETA1), f(BETA2), f(1.0 - BETA1), f(1.0 - BETA2)],
            bias: [f(1.0 - BETA1.powi(step)), f(1.0 - BETA2.powi(step)), 0.0, 0.0],
            counts: [gaussians as u32, sh_coefficients(sh_degree) as u32, 0, 0],
        }
    }
}

/// Push constants of remap_rows.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RemapParams {
    new_rows: u32,
    old_rows: u32,
    row_width: u32,
    unused: u32,
}
push_layout!(RemapParams: [OPTIM_REMAP_ROWS], [new_rows, old_rows, row_width, unused]);

/// The fused Adam step and row-remap pipelines, with first and second moments for every
/// parameter float of a Gaussian set of a fixed size and SH degree.
pub struct Adam {
    ctx: Arc<GpuContext>,
    step: ComputePipeline,
    remap_rows: ComputePipeline,
    /// (m, v) per parameter float, in the order of [`GaussianBuffers`]' buffers.
    moments: [GpuBuffer<[f32; 2]>; 5],
    /// Each step's parameters, one slot per step in flight ([`Self::reserve_slots`]).
    steps: HostRing<AdamParams>,
    gaussians: usize,
    sh_degree: u32,
}

/// Floats per Gaussian in each parameter buffer.
fn row_widths(sh_degree: u32) -> [usize; 5] {
    [3, 3, 4, 1, 3 * sh_coefficients(sh_degree)]
}

fn zero_moments(
    ctx: &Arc<GpuContext>,
    gaussians: usize,
    sh_degree: u32,
) -> GpuResult<[GpuBuffer<[f32; 2]>; 5]> {
    let names = ["positions", "log-scales", "rotations", "opacity logits", "SH"];
    let make = |k: usize| {
        GpuBuffer::new(
            ctx,
            &format!("adam moments of {}", names[k]),
            gaussians * row_widths(sh_degree)[k],
        )
    };
    Ok([make(0)?, make(1)?, make(2)?, make(3)?, make(4)?])
}

impl Adam {
    /// An optimizer for parameters shaped like `params`, moments at zero.
    pub fn new(ctx: &Arc<GpuContext>, params: &GaussianBuffers) -> GpuResult<Self> {
        let pipeline = |name, shader, specialization| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization })
        };
        let step = [WORKGROUP, CHUNKS_PER_INVOCATION];
        let adam = Self {
            ctx: ctx.clone(),
            step: pipeline("adam step", &shaders::OPTIM_ADAM_STEP, &step)?,
            remap_rows: pipeline("adam remap rows", &shaders::OPTIM_REMAP_ROWS, &[WORKGROUP])?,
            moments: zero_moments(ctx, params.len(), params.sh_degree())?,
            steps: HostRing::new(ctx, "adam step parameters", 1)?,
            gaussians: params.len(),
            sh_degree: params.sh_degree(),
        };
        let mut rec = Recorder::new(ctx)?;
        adam.moments.iter().for_each(|m| rec.fill_buffer(m, 0));
        rec.submit_and_wait()?;
        Ok(adam)
    }

    /// The number of Gaussians the moments are shaped for.
    pub fn len(&self) -> usize {
        self.gaussians
    }

    /// Whether the optimizer is shaped for no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.gaussians == 0
    }

    /// Records one Adam step of `params` along `grads` (both shaped like the optimizer) with
    /// `adam`, written to slot 0 of the step ring now: for a recording submitted before the
    /// next call (a replayed step uses [`Self::record_step_from`]).
    pub fn record_step<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        grads: &'a GaussianBuffers,
        adam: &AdamParams,
    ) -> GpuResult<()> {
        self.set_step(0, adam);
        self.record_step_from(rec, params, grads, 0)
    }

    /// Makes room for `slots` steps in flight; the slots start zeroed.
    pub fn reserve_slots(&mut self, slots: usize) -> GpuResult<()> {
        if self.steps.slots() < slots {
            self.steps = HostRing::new(&self.ctx, "adam step parameters", slots)?;
        }
        Ok(())
    }

    /// Writes the parameters a step recorded with `slot` will use; no submission that reads
    /// the slot may be on the queue.
    pub fn set_step(&self, slot: usize, adam: &AdamParams) {
        self.steps.write(slot, adam);
    }

    /// Records one Adam step of `params` along `grads` (both shaped like the optimizer) with
    /// the parameters in ring slot `slot` when it runs ([`Self::set_step`]).
    pub fn record_step_from<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        grads: &'a GaussianBuffers,
        slot: usize,
    ) -> GpuResult<()> {
        for (what, buffers) in [("adam parameters", params), ("adam gradients", grads)] {
            if buffers.len() != self.gaussians || buffers.sh_degree() != self.sh_degree {
                return Err(GpuError::LengthMismatch {
                    what,
                    name: buffers.positions.name().to_string(),
                    len: buffers.len(),
                    capacity: self.gaussians,
                });
            }
        }
        if slot >= self.steps.slots() {
            return Err(GpuError::LengthMismatch {
                what: "adam step slot",
                name: "adam step parameters".into(),
                len: slot + 1,
                capacity: self.steps.slots(),
            });
        }
        // Names of adam_step.comp: parameters, their gradients (g_) and moments (m_).
        let moments = ["m_positions", "m_log_scales", "m_rotations", "m_opacity_logits", "m_sh"];
        let bindings: Vec<_> = params
            .bindings(["positions", "log_scales", "rotations", "opacity_logits", "sh"])
            .into_iter()
            .chain(grads.bindings([
                "g_positions",
                "g_log_scales",
                "g_rotations",
                "g_opacity_logits",
                "g_sh",
            ]))
            .chain(moments.into_iter().zip(&self.moments).map(|(name, m)| (name, m.binding())))
            .chain([("steps", self.steps.binding())])
            .collect();
        // One invocation per CHUNKS_PER_INVOCATION chunks of four floats (see adam_step.comp).
        let chunks: usize =
            row_widths(self.sh_degree).iter().map(|w| (w * self.gaussians).div_ceil(4)).sum();
        let groups = chunks.div_ceil((WORKGROUP * CHUNKS_PER_INVOCATION) as usize) as u64;
        rec.dispatch_1d(&self.step, &bindings, &AdamSlot { slot: slot as u32 }, groups)
    }

    /// Carries the moments to a new Gaussian set: new row `i` takes the moments of old row
    /// `old_of_new[i]`, or zero for [`NEW_ROW`] (any index past the old rows counts as new).
    pub fn remap(&mut self, old_of_new: &[u32]) -> GpuResult<()> {
        let remap = GpuBuffer::from_slice(
            &self.ctx,
            "adam remap",
            if old_of_new.is_empty() { &[NEW_ROW] } else { old_of_new },
        )?;
        let moments = zero_moments(&self.ctx, old_of_new.len(), self.sh_degree)?;
        let mut rec = Recorder::new(&self.ctx)?;
        for ((old, new), width) in self.moments.iter().zip(&moments).zip(row_widths(self.sh_degree))
        {
            let params = RemapParams {
                new_rows: old_of_new.len() as u32,
                old_rows: self.gaussians as u32,
                row_width: width as u32,
                unused: 0,
            };
            let groups = (old_of_new.len() * width).div_ceil(WORKGROUP as usize) as u64;
            rec.dispatch_1d(
                &self.remap_rows,
                &[
                    ("old_rows", old.binding()),
                    ("old_of_new", remap.binding()),
                    ("new_rows", new.binding()),
                ],
                &params,
                groups,
            )?;
        }
        rec.submit_and_wait()?;
        self.moments = moments;
        self.gaussians = old_of_new.len();
        Ok(())
    }

    /// The moments as host arrays, in [`GaussianBuffers`]' buffer order.
    pub fn read_moments(&self) -> GpuResult<[Vec<[f32; 2]>; 5]> {
        let [a, b, c, d, e] = &self.moments;
        Ok([a.read()?, b.read()?, c.read()?, d.read()?, e.read()?])
    }
}
