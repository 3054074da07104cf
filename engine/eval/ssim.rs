//! Structural similarity (Wang et al. 2004) with a Gaussian window.
//!
//! Definition: per channel, with Gaussian-weighted local means μ, variances σ² and covariance
//! σ_xy (11×11 window, σ = 1.5, weights normalised to sum 1, population statistics),
//! `S = (2 μx μy + C1)(2 σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2))`, C1 = 0.01²,
//! C2 = 0.03² (data range 1). SSIM is the mean of S over the pixels whose window lies inside the
//! image (5 pixels are cropped from every border), then the mean over channels. This is exactly
//! what scikit-image's `structural_similarity(gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False, data_range=1, channel_axis=-1)` computes for float64 input.

use super::EvalError;
use crate::ssim_window::{gaussian_weights, ssim_formula, RADIUS, WINDOW};

/// Mean SSIM (unitless, ≤ 1) of `pred` against `gt`: interleaved `height × width × channels`
/// arrays with values in [0, 1]. Both images must be at least 11×11.
pub fn ssim(
    pred: &[f32],
    gt: &[f32],
    width: usize,
    height: usize,
    channels: usize,
) -> Result<f64, EvalError> {
    if pred.len() != gt.len() {
        return Err(EvalError::SizeMismatch(pred.len(), gt.len()));
    }
    if width.checked_mul(height).and_then(|n| n.checked_mul(channels)) != Some(pred.len())
        || channels == 0
    {
        return Err(EvalError::ImageShape { len: pred.len(), width, height, channels });
    }
    if width < WINDOW || height < WINDOW {
        return Err(EvalError::ImageTooSmall { width, height, window: WINDOW });
    }
    if pred.iter().chain(gt).any(|v| !v.is_finite()) {
        return Err(EvalError::NonFinite("image"));
    }
    let weights = gaussian_weights();
    let total: f64 =
        (0..channels).map(|c| ssim_channel(pred, gt, width, height, channels, c, &weights)).sum();
    Ok(total / channels as f64)
}

/// The five filtered moments (x, y, xx, yy, xy) of one channel, horizontal pass first over the
/// valid columns, then vertical over the valid rows; returns the mean of S.
fn ssim_channel(
    pred: &[f32],
    gt: &[f32],
    width: usize,
    height: usize,
    channels: usize,
    c: usize,
    w: &[f64; WINDOW],
) -> f64 {
    let out_w = width - 2 * RADIUS;
    let out_h = height - 2 * RADIUS;
    let at = |img: &[f32], x: usize, y: usize| img[(y * width + x) * channels + c] as f64;
    // Horizontal pass: rows × valid columns, five moments each.
    let mut rows = vec![[0.0f64; 5]; height * out_w];
    for y in 0..height {
        for x in 0..out_w {
            let mut m = [0.0f64; 5];
            for (k, wk) in w.iter().enumerate() {
                let a = at(pred, x + k, y);
                let b = at(gt, x + k, y);
                m[0] += wk * a;
                m[1] += wk * b;
                m[2] += wk * a * a;
                m[3] += wk * b * b;
                m[4] += wk * a * b;
            }
            rows[y * out_w + x] = m;
        }
    }
    let mut sum = 0.0f64;
    for y in 0..out_h {
        for x in 0..out_w {
            let mut m = [0.0f64; 5];
            for (k, wk) in w.iter().enumerate() {
                let r = &rows[(y + k) * out_w + x];
                for (mi, ri) in m.iter_mut().zip(r) {
                    *mi += wk * ri;
                }
            }
            sum += ssim_formula(m);
        }
    }
    sum / (out_w * out_h) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ssim_window::C1;

    #[test]
    fn identical_images_give_one_and_constant_offset_the_luminance_term() {
        let img: Vec<f32> = (0..20 * 16 * 3).map(|i| ((i * 37) % 101) as f32 / 100.0).collect();
        assert!((ssim(&img, &img, 20, 16, 3).unwrap() - 1.0).abs() < 1e-12);
        // Two constant images a, b: variances are 0, S = (2ab + C1) / (a² + b² + C1).
        let a = vec![0.25f32; 12 * 12];
        let b = vec![0.75f32; 12 * 12];
        let expect = (2.0 * 0.25 * 0.75 + C1) / (0.25f64 * 0.25 + 0.75 * 0.75 + C1);
        assert!((ssim(&a, &b, 12, 12, 1).unwrap() - expect).abs() < 1e-12);
    }

    #[test]
    fn weights_match_the_gaussian() {
        let w = gaussian_weights();
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((w[RADIUS + 1] / w[RADIUS] - (-0.5f64 / 2.25).exp()).abs() < 1e-15);
    }

    #[test]
    fn bad_input() {
        assert!(matches!(
            ssim(&[0.0; 100], &[0.0; 100], 10, 10, 1),
            Err(EvalError::ImageTooSmall { .. })
        ));
        assert!(matches!(
            ssim(&[0.0; 100], &[0.0; 100], 11, 11, 1),
            Err(EvalError::ImageShape { .. })
        ));
        assert!(matches!(ssim(&[0.0; 2], &[0.0; 3], 1, 1, 1), Err(EvalError::SizeMismatch(2, 3))));
        let mut a = vec![0.5f32; 121];
        a[7] = f32::INFINITY;
        assert!(matches!(ssim(&a, &[0.5; 121], 11, 11, 1), Err(EvalError::NonFinite(_))));
    }
}
