//! The SSIM window and formula that the metric (`eval::ssim`) and the image loss (`loss`) share,
//! so the loss is exactly one minus the metric: an 11×11 Gaussian window with σ = 1.5 (weights
//! normalised to sum 1), C1 = 0.01², C2 = 0.03² for data range 1, as scikit-image defines it.

/// Window radius: scikit-image uses `int(3.5 · σ + 0.5)` = 5 for σ = 1.5.
pub const RADIUS: usize = 5;
/// Window side in pixels (11).
pub const WINDOW: usize = 2 * RADIUS + 1;
const SIGMA: f64 = 1.5;
/// Stabilizer of the luminance term, (0.01 · L)² for data range L = 1.
pub const C1: f64 = 0.01 * 0.01;
/// Stabilizer of the contrast-structure term, (0.03 · L)² for data range L = 1.
pub const C2: f64 = 0.03 * 0.03;

/// The separable window's weights, summing to 1.
pub fn gaussian_weights() -> [f64; WINDOW] {
    let mut w = [0.0; WINDOW];
    for (k, wk) in w.iter_mut().enumerate() {
        let x = k as f64 - RADIUS as f64;
        *wk = (-0.5 * x * x / (SIGMA * SIGMA)).exp();
    }
    let sum: f64 = w.iter().sum();
    w.map(|v| v / sum)
}

/// S from the moments (μx, μy, `E[x²]`, `E[y²]`, `E[xy]`), with population (co)variances.
#[inline]
pub fn ssim_formula([ux, uy, uxx, uyy, uxy]: [f64; 5]) -> f64 {
    let vx = uxx - ux * ux;
    let vy = uyy - uy * uy;
    let vxy = uxy - ux * uy;
    ((2.0 * ux * uy + C1) * (2.0 * vxy + C2)) / ((ux * ux + uy * uy + C1) * (vx + vy + C2))
}
