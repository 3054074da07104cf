//! Fused image loss on the GPU: value and dL/dimage of
//!
//! `L = Σ_c λ_c · (0.8 · mean_p w_p |x − y| + 0.2 · mean_{p ∈ V} w_p (1 − S_c(p)))`
//!
//! over the four channels of a vec4 image (colour and alpha), with an optional per-pixel weight
//! `w` (1 without). `S` is the SSIM map of the metric (`ssim_window`: 11×11 Gaussian
//! window, σ = 1.5, C1 = 0.01², C2 = 0.03², population statistics) and `V` the pixels whose
//! window lies inside the image, so with `w = 1` the SSIM term is exactly one minus the metric.
//! Colour and mask losses are one run: λ = (λ_colour/3, λ_colour/3, λ_colour/3, λ_mask) scores
//! a render's colour and alpha against an image and its mask.
//!
//! Four passes, the fewest a separable window allows: the horizontal filter of the moments;
//! the vertical filter fused with S, the loss terms and dL/d(moments); the horizontal filter of
//! those derivatives (the window is symmetric, so the adjoint is the same filter); the vertical
//! one fused with the L1 gradient. Each invocation filters a run of 8 pixels, so a pixel costs
//! about 2.25 loads per filtered map instead of 11. One run scores one or two renders against
//! the same target (a view's Gaussian and mesh renders): they share the target's loads and
//! its moments.

pub mod colour_map;
pub mod flow;
mod params;
mod pinhole_view;
pub mod reference;
pub mod silhouette;

pub use params::{LOSS_SHARE_L1, LOSS_SHARE_SSIM};

use params::LossParams;

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

/// One render a run of [`ImageLoss::record`] scores: its image, its per-channel weights λ, the
/// 8 sums its terms are ADDED to ([`LossTerms::sums`]; zero them first to read one run) and the
/// buffer dL/drender is WRITTEN to. Images are vec4 per pixel, row-major.
#[derive(Clone, Copy)]
pub struct ScoredRender<'a> {
    /// The render.
    pub image: &'a GpuBuffer<[f32; 4]>,
    /// λ per channel (r, g, b, alpha).
    pub channel_weights: [f32; 4],
    /// Where its loss terms are summed.
    pub terms: &'a FixedSums,
    /// Where dL/drender goes.
    pub gradient: &'a GpuBuffer<[f32; 4]>,
}

/// What the renders of one run are scored against: a `width × height` target and optionally
/// one weight per pixel.
#[derive(Clone, Copy)]
pub struct LossTarget<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The target image.
    pub image: &'a GpuBuffer<[f32; 4]>,
    /// The per-pixel weight `w`, 1 everywhere when `None`.
    pub weight: Option<&'a GpuBuffer<f32>>,
}

/// The four passes of the loss, specialized for a number of renders per run.
struct LossPasses {
    blur_moments: ComputePipeline,
    ssim_forward: ComputePipeline,
    blur_gradients: ComputePipeline,
    ssim_backward: ComputePipeline,
}

impl LossPasses {
    fn new(ctx: &Arc<GpuContext>, renders: usize) -> GpuResult<Self> {
        let specialization = [WORKGROUP, renders as u32];
        let pipeline = |name, shader| {
            ComputePipeline::new(
                ctx,
                &PipelineDesc { name, shader, specialization: &specialization },
            )
        };
        Ok(Self {
            blur_moments: pipeline("loss blur moments", &shaders::LOSS_BLUR_MOMENTS)?,
            ssim_forward: pipeline("loss ssim forward", &shaders::LOSS_SSIM_FORWARD)?,
            blur_gradients: pipeline("loss blur gradients", &shaders::LOSS_BLUR_GRADIENTS)?,
            ssim_backward: pipeline("loss ssim backward", &shaders::LOSS_SSIM_BACKWARD)?,
        })
    }
}

/// The fused loss kernels for runs of one render or, built for two, of one or two (a view's
/// Gaussian and mesh renders, which then share the target's loads and moments), and their
/// per-pixel scratch (filtered moments and derivatives, one plane per render of the largest
/// run), grown to the largest image seen. Runs of either size share the scratch.
pub struct ImageLoss {
    ctx: Arc<GpuContext>,
    /// `passes[n - 1]`: the passes of a run of `n` renders.
    passes: Vec<LossPasses>,
    /// Horizontal filter of the target's y and y².
    target_moments: [GpuBuffer<[f32; 4]>; 2],
    /// Horizontal filter of each render's x, x², xy; once the second pass has read them, the
    /// horizontal filter of the derivatives (a run touches a quarter less memory, which
    /// matters where the images do not stay in cache between runs).
    moments: [GpuBuffer<[f32; 4]>; 3],
    /// dL/dμx, dL/dE[x²], dL/dE[xy] of each render.
    derivatives: [GpuBuffer<[f32; 4]>; 3],
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
    /// Builds the pipelines for runs of up to `renders` renders (1 or 2, else
    /// [`GpuError::LengthMismatch`]) with empty scratch (see [`Self::reserve`]); fails when a
    /// pipeline or buffer cannot be created.
    pub fn new(ctx: &Arc<GpuContext>, renders: usize) -> GpuResult<Self> {
        if !(1..=2).contains(&renders) {
            return Err(GpuError::LengthMismatch {
                what: "image loss renders per run (1 or 2)",
                name: "ImageLoss::new".into(),
                len: renders,
                capacity: 2,
            });
        }
        Ok(Self {
            ctx: ctx.clone(),
            passes: (1..=renders).map(|n| LossPasses::new(ctx, n)).collect::<GpuResult<_>>()?,
            target_moments: scratch(ctx, "loss target moments", 0)?,
            moments: scratch(ctx, "loss moments", 0)?,
            derivatives: scratch(ctx, "loss moment derivatives", 0)?,
            unit_weight: GpuBuffer::from_slice(ctx, "loss unit weight", &[1.0])?,
        })
    }

    /// The most renders a run may score.
    pub fn max_renders(&self) -> usize {
        self.passes.len()
    }

    /// Makes room for images of `pixels`; call before recording (recording borrows the scratch,
    /// and fails naming it when it is too small).
    pub fn reserve(&mut self, pixels: usize) -> GpuResult<()> {
        if self.target_moments[0].len() < pixels {
            let planes = self.passes.len() * pixels;
            self.target_moments = scratch(&self.ctx, "loss target moments", pixels)?;
            self.moments = scratch(&self.ctx, "loss moments", planes)?;
            self.derivatives = scratch(&self.ctx, "loss moment derivatives", planes)?;
        }
        Ok(())
    }

    /// Records the loss of each of `renders` (one, or two when [`Self::new`] was built for
    /// two) against `target`: per render, ADDS its terms to its sums and WRITES dL/drender to
    /// its gradient.
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        target: &LossTarget<'a>,
        renders: &[ScoredRender<'a>],
    ) -> GpuResult<()> {
        let (passes, [first, second]) =
            match (self.passes.get(renders.len().wrapping_sub(1)), renders) {
                (Some(passes), &[a]) => (passes, [a, a]),
                (Some(passes), &[a, b]) => (passes, [a, b]),
                _ => {
                    return Err(GpuError::LengthMismatch {
                        what: "image loss renders per run",
                        name: "ImageLoss::record".into(),
                        len: renders.len(),
                        capacity: self.passes.len(),
                    })
                }
            };
        let params = LossParams::new(
            target.width,
            target.height,
            [first.channel_weights, second.channel_weights],
            target.weight.is_some(),
        );
        self.check_sizes(&params, target, renders)?;
        let weight = ("weight", target.weight.unwrap_or(&self.unit_weight).binding());
        let rows = params.row_runs().div_ceil(WORKGROUP as usize) as u64;
        let columns = params.column_runs().div_ceil(WORKGROUP as usize) as u64;
        let [my, myy] = self.target_moments.each_ref().map(|b| b.binding());
        let [mx, mxx, mxy] = self.moments.each_ref().map(|b| b.binding());
        let [dx, dxx, dxy] = self.derivatives.each_ref().map(|b| b.binding());
        let images = [
            ("render_a", first.image.binding()),
            ("render_b", second.image.binding()),
            ("target", target.image.binding()),
        ];
        let target_moments = [("mean_y", my), ("mean_yy", myy)];
        let moments = [("mean_x", mx), ("mean_xx", mxx), ("mean_xy", mxy)];
        let derivatives = [("d_mean_x", dx), ("d_mean_xx", dxx), ("d_mean_xy", dxy)];
        let filtered = [("blur_x", mx), ("blur_xx", mxx), ("blur_xy", mxy)];
        let terms =
            [("term_sums_a", first.terms.binding()), ("term_sums_b", second.terms.binding())];
        let pass_1 = [&images[..], &target_moments, &moments, &[weight], &terms].concat();
        rec.dispatch_1d(&passes.blur_moments, &pass_1, &params, rows)?;
        let pass_2 = [&[weight][..], &target_moments, &moments, &derivatives, &terms].concat();
        rec.dispatch_1d(&passes.ssim_forward, &pass_2, &params, columns)?;
        let pass_3 = [derivatives, filtered].concat();
        rec.dispatch_1d(&passes.blur_gradients, &pass_3, &params, rows)?;
        let gradients =
            [("gradient_a", first.gradient.binding()), ("gradient_b", second.gradient.binding())];
        let pass_4 = [&images[..], &[weight], &filtered, &gradients].concat();
        rec.dispatch_1d(&passes.ssim_backward, &pass_4, &params, columns)
    }

    /// Refuses a run whose images, weight, scratch or sums are smaller than it needs, naming
    /// the buffer.
    fn check_sizes(
        &self,
        params: &LossParams,
        target: &LossTarget,
        renders: &[ScoredRender],
    ) -> GpuResult<()> {
        let pixels = params.pixels();
        let images = renders
            .iter()
            .flat_map(|r| [(r.image.len(), r.image.name()), (r.gradient.len(), r.gradient.name())])
            .chain([(target.image.len(), target.image.name())])
            .chain([(self.target_moments[0].len(), self.target_moments[0].name())])
            .chain(target.weight.map(|w| (w.len(), w.name())));
        if let Some((capacity, name)) = images.into_iter().find(|&(len, _)| len < pixels) {
            return Err(GpuError::LengthMismatch {
                what: "image loss pixels",
                name: name.to_string(),
                len: pixels,
                capacity,
            });
        }
        if let Some(short) = renders.iter().find(|r| r.terms.len() < 8) {
            return Err(GpuError::LengthMismatch {
                what: "image loss terms",
                name: short.terms.name().to_string(),
                len: 8,
                capacity: short.terms.len(),
            });
        }
        Ok(())
    }
}
