//! f64 reference of the fused image loss ([`super`]): each SSIM window is gathered directly in
//! 2D (no separable passes) and dL/dS is scattered back over it, an independent route to the
//! same maths for the tests to compare against.

use super::{LOSS_SHARE_L1, LOSS_SHARE_SSIM};
use crate::ssim_window::{gaussian_weights, ssim_formula, C1, C2, RADIUS, WINDOW};

/// Loss value, its per-channel terms and dL/drender.
pub struct ReferenceLoss {
    /// `Σ_c λ_c (0.8 l1_c + 0.2 dssim_c)`.
    pub total: f64,
    /// Per channel, the mean over all pixels of `w |x − y|` (0 where λ is 0: such a channel is
    /// not summed).
    pub l1: [f64; 4],
    /// Per channel, the mean of `w (1 − S)` over the pixels whose window lies inside the image
    /// (0 where λ is 0).
    pub dssim: [f64; 4],
    /// dL/drender, one vec4 per pixel (row-major).
    pub gradient: Vec<[f64; 4]>,
}

/// The loss of `render` against `target` (vec4 per pixel, row-major) with per-pixel `weight`.
pub fn image_loss(
    render: &[[f32; 4]],
    target: &[[f32; 4]],
    weight: Option<&[f32]>,
    width: usize,
    height: usize,
    channel_weights: [f64; 4],
) -> ReferenceLoss {
    let pixels = width * height;
    let w = |p: usize| weight.map_or(1.0, |w| w[p] as f64);
    let counted = |c: usize| (channel_weights[c] != 0.0) as u8 as f64;
    let mut out = ReferenceLoss {
        total: 0.0,
        l1: [0.0; 4],
        dssim: [0.0; 4],
        gradient: vec![[0.0; 4]; pixels],
    };
    for p in 0..pixels {
        for c in 0..4 {
            let d = render[p][c] as f64 - target[p][c] as f64;
            out.l1[c] += counted(c) * w(p) * d.abs() / pixels as f64;
            out.gradient[p][c] += channel_weights[c]
                * LOSS_SHARE_L1 as f64
                * w(p)
                * d.signum()
                * (d != 0.0) as u8 as f64
                / pixels as f64;
        }
    }
    if width >= WINDOW && height >= WINDOW {
        let valid = ((width - 2 * RADIUS) * (height - 2 * RADIUS)) as f64;
        for (c, channel_weight) in channel_weights.iter().enumerate() {
            let scale = -channel_weight * LOSS_SHARE_SSIM as f64 / valid;
            for y in RADIUS..height - RADIUS {
                for x in RADIUS..width - RADIUS {
                    let p = y * width + x;
                    let window = Window { render, target, width, c, x, y };
                    let moments = window.moments();
                    out.dssim[c] += counted(c) * w(p) * (1.0 - ssim_formula(moments)) / valid;
                    window.scatter(
                        ssim_partials(moments).map(|d| d * scale * w(p)),
                        &mut out.gradient,
                    );
                }
            }
        }
    }
    out.total = (0..4)
        .map(|c| {
            channel_weights[c]
                * (LOSS_SHARE_L1 as f64 * out.l1[c] + LOSS_SHARE_SSIM as f64 * out.dssim[c])
        })
        .sum();
    out
}

/// The 11×11 window of one channel centred on (x, y).
struct Window<'a> {
    render: &'a [[f32; 4]],
    target: &'a [[f32; 4]],
    width: usize,
    c: usize,
    x: usize,
    y: usize,
}

impl Window<'_> {
    /// (pixel index, 2D weight) over the window.
    fn taps(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        let g = gaussian_weights();
        (0..WINDOW).flat_map(move |j| {
            (0..WINDOW).map(move |i| {
                ((self.y + j - RADIUS) * self.width + self.x + i - RADIUS, g[i] * g[j])
            })
        })
    }

    /// μx, μy, E[x²], E[y²], E[xy].
    fn moments(&self) -> [f64; 5] {
        let mut m = [0.0; 5];
        for (q, g) in self.taps() {
            let (a, b) = (self.render[q][self.c] as f64, self.target[q][self.c] as f64);
            for (mi, v) in m.iter_mut().zip([a, b, a * a, b * b, a * b]) {
                *mi += g * v;
            }
        }
        m
    }

    /// Adds `[dL/dμx, dL/dE[x²], dL/dE[xy]]` through the window to dL/drender.
    fn scatter(&self, d: [f64; 3], gradient: &mut [[f64; 4]]) {
        for (q, g) in self.taps() {
            let (a, b) = (self.render[q][self.c] as f64, self.target[q][self.c] as f64);
            gradient[q][self.c] += g * (d[0] + 2.0 * a * d[1] + b * d[2]);
        }
    }
}

/// dS/dμx, dS/dE[x²], dS/dE[xy] with μy, E[y²] fixed.
fn ssim_partials([ux, uy, uxx, uyy, uxy]: [f64; 5]) -> [f64; 3] {
    let n1 = 2.0 * ux * uy + C1;
    let n2 = 2.0 * (uxy - ux * uy) + C2;
    let d1 = ux * ux + uy * uy + C1;
    let d2 = (uxx - ux * ux) + (uyy - uy * uy) + C2;
    let s = n1 * n2 / (d1 * d2);
    let d_ux = (2.0 * uy * n2 - 2.0 * uy * n1) / (d1 * d2) - s * (2.0 * ux / d1 - 2.0 * ux / d2);
    [d_ux, -s / d2, 2.0 * n1 / (d1 * d2)]
}
