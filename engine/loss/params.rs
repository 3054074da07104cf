//! The push constants of the loss kernels (`LossParams` in shaders/loss/loss.glsl).

use crate::gpu::push_layout;
use crate::ssim_window::{gaussian_weights, RADIUS, WINDOW};
use bytemuck::{Pod, Zeroable};

/// Pixels one invocation filters (`RUN` in shaders/loss/loss.glsl).
const RUN: u32 = 8;

/// Shares of the two terms of the image loss (3DGS's λ_D-SSIM = 0.2).
pub const LOSS_SHARE_L1: f32 = 0.8;
/// The D-SSIM term's share; [`LOSS_SHARE_L1`] is the rest.
pub const LOSS_SHARE_SSIM: f32 = 0.2;

/// One image size, each render's per-channel weights λ and the SSIM window.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LossParams {
    channel_weights: [[f32; 4]; 2],
    size: [u32; 4],
    scales: [f32; 4],
    window: [f32; WINDOW],
}
push_layout!(
    LossParams: [LOSS_BLUR_MOMENTS, LOSS_SSIM_FORWARD, LOSS_BLUR_GRADIENTS, LOSS_SSIM_BACKWARD],
    [channel_weights, size, scales, window]
);

impl LossParams {
    /// `channel_weights`: λ of the first and (when the run scores two renders) the second
    /// render; `has_weight`: whether a per-pixel weight image is bound.
    pub fn new(width: u32, height: u32, channel_weights: [[f32; 4]; 2], has_weight: bool) -> Self {
        let pixels = width as f64 * height as f64;
        let valid = |n: u32| n.saturating_sub(2 * RADIUS as u32) as f64;
        let ssim_pixels = valid(width) * valid(height);
        let inverse = |n: f64| if n > 0.0 { (1.0 / n) as f32 } else { 0.0 };
        Self {
            channel_weights,
            size: [width, height, has_weight as u32, 0],
            scales: [LOSS_SHARE_L1, LOSS_SHARE_SSIM, inverse(pixels), inverse(ssim_pixels)],
            window: gaussian_weights().map(|w| w as f32),
        }
    }

    /// Width × height of the image.
    pub fn pixels(&self) -> usize {
        self.size[0] as usize * self.size[1] as usize
    }

    /// Invocations of a horizontal pass (one per run of `RUN` pixels along a row, loss.glsl).
    pub(crate) fn row_runs(&self) -> usize {
        self.size[0].div_ceil(RUN) as usize * self.size[1] as usize
    }

    /// Invocations of a vertical pass (one per run of `RUN` pixels down a column).
    pub(crate) fn column_runs(&self) -> usize {
        self.size[0] as usize * self.size[1].div_ceil(RUN) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_the_push_constant_minimum() {
        // Vulkan guarantees 128 bytes of push constants, in whole words.
        assert!(size_of::<LossParams>() <= 128);
        assert_eq!(size_of::<LossParams>() % 4, 0);
    }

    #[test]
    fn runs_cover_every_pixel() {
        let p = LossParams::new(17, 9, [[1.0; 4]; 2], false);
        assert_eq!(p.row_runs(), 3 * 9);
        assert_eq!(p.column_runs(), 17 * 2);
    }

    #[test]
    fn small_images_have_no_ssim_term() {
        let p = LossParams::new(10, 40, [[1.0; 4]; 2], false);
        assert_eq!(p.scales[3], 0.0);
        assert_eq!(LossParams::new(11, 11, [[1.0; 4]; 2], false).scales[3], 1.0);
    }
}
