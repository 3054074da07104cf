//! Fused image loss on the GPU: value and dL/dimage of
//!
//! `L = Σ_c λ_c · (0.8 · mean_p w_p |x − y| + 0.2 · mean_{p ∈ V} w_p (1 − S_c(p)))`
//!
//! over the four channels of a vec4 image (colour and alpha), with an optional per-pixel weight
//! `w` (1 without). `S` is the SSIM map of the metric ([`crate::ssim_window`]: 11×11 Gaussian
//! window, σ = 1.5, C1 = 0.01², C2 = 0.03², population statistics) and `V` the pixels whose
//! window lies inside the image, so with `w = 1` the SSIM term is exactly one minus the metric.
//! Colour and mask losses are one run: λ = (λ_colour/3, λ_colour/3, λ_colour/3, λ_mask) scores
//! a render's colour and alpha against an image and its mask.
//!
//! Four passes, the fewest a separable window allows: the horizontal filter of the five moments;
//! the vertical filter fused with S, the loss terms and dL/d(moments); the horizontal filter of
//! those derivatives (the window is symmetric, so the adjoint is the same filter); the vertical
//! one fused with the L1 gradient.

mod params;
pub mod reference;
pub mod silhouette;

pub use params::{LossParams, LOSS_SHARE_L1, LOSS_SHARE_SSIM};

use crate::gpu::{
    ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuError, GpuResult,
    PipelineDesc, Recorder,
};
use crate::shaders;
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// The loss terms of one run, per channel and unweighted by λ: the mean absolute error and the
/// mean of `w (1 − S)` (0 when the image is smaller than the window).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossTerms {
    /// Per channel, the mean over all pixels of `w |x − y|`.
    pub l1: [f32; 4],
    /// Per channel, the mean of `w (1 − S)` over the pixels whose window lies inside the image.
    pub dssim: [f32; 4],
}

impl LossTerms {
    /// Unpacks the 8 sums of a terms buffer.
    pub fn from_sums(sums: &[f64]) -> Self {
        let mut out = Self::default();
        for c in 0..4 {
            out.l1[c] = sums[c] as f32;
            out.dssim[c] = sums[4 + c] as f32;
        }
        out
    }

    /// A terms buffer for [`ImageLoss::record`]: 8 order-independent sums, zero.
    pub fn sums(ctx: &Arc<GpuContext>, name: &str) -> GpuResult<FixedSums> {
        FixedSums::new(ctx, name, 8, FixedPrecision::Total)
    }

    /// Reads the terms summed in `sums` and zeroes them, so the next sum starts afresh.
    pub fn take(sums: &FixedSums) -> GpuResult<Self> {
        Ok(Self::from_sums(&sums.take()?))
    }

    /// `Σ_c λ_c (0.8 l1_c + 0.2 dssim_c)`.
    pub fn total(&self, channel_weights: [f32; 4]) -> f32 {
        (0..4)
            .map(|c| {
                channel_weights[c] * (LOSS_SHARE_L1 * self.l1[c] + LOSS_SHARE_SSIM * self.dssim[c])
            })
            .sum()
    }
}

/// The fused loss kernels and their per-pixel scratch (filtered moments and derivatives),
/// grown to the largest image seen.
pub struct ImageLoss {
    ctx: Arc<GpuContext>,
    blur_moments: ComputePipeline,
    ssim_forward: ComputePipeline,
    blur_gradients: ComputePipeline,
    ssim_backward: ComputePipeline,
    /// Horizontal filter of x, y, x², y², xy.
    moments: [GpuBuffer<[f32; 4]>; 5],
    /// dL/dμx, dL/dE[x²], dL/dE[xy] and their horizontal filters.
    derivatives: [GpuBuffer<[f32; 4]>; 3],
    filtered: [GpuBuffer<[f32; 4]>; 3],
    /// Stands in for the weight image when there is none.
    unit_weight: GpuBuffer<f32>,
}

fn scratch<const N: usize>(
    ctx: &Arc<GpuContext>,
    name: &str,
    len: usize,
) -> GpuResult<[GpuBuffer<[f32; 4]>; N]> {
    let buffers: Vec<_> = (0..N)
        .map(|i| GpuBuffer::new(ctx, &format!("{name} {i}"), len))
        .collect::<GpuResult<_>>()?;
    Ok(buffers.try_into().unwrap_or_else(|_| unreachable!("exactly N buffers")))
}

impl ImageLoss {
    /// Builds the four pipelines with empty scratch (see [`Self::reserve`]); fails when a pipeline
    /// or buffer cannot be created.
    pub fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        let pipeline = |name, shader| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[WORKGROUP] })
        };
        Ok(Self {
            ctx: ctx.clone(),
            blur_moments: pipeline("loss blur moments", &shaders::LOSS_BLUR_MOMENTS)?,
            ssim_forward: pipeline("loss ssim forward", &shaders::LOSS_SSIM_FORWARD)?,
            blur_gradients: pipeline("loss blur gradients", &shaders::LOSS_BLUR_GRADIENTS)?,
            ssim_backward: pipeline("loss ssim backward", &shaders::LOSS_SSIM_BACKWARD)?,
            moments: scratch(ctx, "loss moments", 0)?,
            derivatives: scratch(ctx, "loss moment derivatives", 0)?,
            filtered: scratch(ctx, "loss filtered derivatives", 0)?,
            unit_weight: GpuBuffer::from_slice(ctx, "loss unit weight", &[1.0])?,
        })
    }

    /// Makes room for `pixels`; call before recording (recording borrows the scratch, and
    /// fails naming it when it is too small).
    pub fn reserve(&mut self, pixels: usize) -> GpuResult<()> {
        if self.moments[0].len() < pixels {
            self.moments = scratch(&self.ctx, "loss moments", pixels)?;
            self.derivatives = scratch(&self.ctx, "loss moment derivatives", pixels)?;
            self.filtered = scratch(&self.ctx, "loss filtered derivatives", pixels)?;
        }
        Ok(())
    }

    /// Records the loss of `render` against `target` (vec4 per pixel, row-major, `width ×
    /// height` of them): ADDS the terms to `terms` (8 sums from [`LossTerms::sums`]; zero them
    /// first to read one run) and WRITES dL/drender to `gradient`. `weight` is one float per pixel.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &LossParams,
        render: &'a GpuBuffer<[f32; 4]>,
        target: &'a GpuBuffer<[f32; 4]>,
        weight: Option<&'a GpuBuffer<f32>>,
        terms: &'a FixedSums,
        gradient: &'a GpuBuffer<[f32; 4]>,
    ) -> GpuResult<()> {
        let pixels = params.pixels();
        let images = [render, target, gradient, &self.moments[0]].map(|b| (b.len(), b.name()));
        let short = images
            .into_iter()
            .chain(weight.map(|w| (w.len(), w.name())))
            .find(|&(len, _)| len < pixels);
        if let Some((capacity, name)) = short {
            return Err(GpuError::LengthMismatch {
                what: "image loss pixels",
                name: name.to_string(),
                len: pixels,
                capacity,
            });
        }
        if terms.len() < 8 {
            return Err(GpuError::LengthMismatch {
                what: "image loss terms",
                name: terms.name().to_string(),
                len: 8,
                capacity: terms.len(),
            });
        }
        let weight = ("weight", weight.unwrap_or(&self.unit_weight).binding());
        let groups = pixels.div_ceil(WORKGROUP as usize) as u64;
        let [mx, my, mxx, myy, mxy] = self.moments.each_ref().map(|b| b.binding());
        let [dx, dxx, dxy] = self.derivatives.each_ref().map(|b| b.binding());
        let [fx, fxx, fxy] = self.filtered.each_ref().map(|b| b.binding());
        let images = [("render", render.binding()), ("target", target.binding())];
        let moments =
            [("mean_x", mx), ("mean_y", my), ("mean_xx", mxx), ("mean_yy", myy), ("mean_xy", mxy)];
        let derivatives = [("d_mean_x", dx), ("d_mean_xx", dxx), ("d_mean_xy", dxy)];
        let filtered = [("blur_x", fx), ("blur_xx", fxx), ("blur_xy", fxy)];
        rec.dispatch_1d(&self.blur_moments, &[&images[..], &moments].concat(), params, groups)?;
        let terms = ("term_sums", terms.binding());
        let fused = [&images[..], &[weight], &moments, &derivatives, &[terms]].concat();
        rec.dispatch_1d(&self.ssim_forward, &fused, params, groups)?;
        rec.dispatch_1d(&self.blur_gradients, &[derivatives, filtered].concat(), params, groups)?;
        let gradient = ("gradient", gradient.binding());
        let backward = [&images[..], &[weight], &filtered, &[gradient]].concat();
        rec.dispatch_1d(&self.ssim_backward, &backward, params, groups)
    }
}
