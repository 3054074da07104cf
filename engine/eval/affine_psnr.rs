//! PSNR after each view's own affine colour map: a render is compared with its image after the
//! 3 × 4 map `A` that minimises `Σ |A·[r, g, b, 1] − image|²` over the view's pixels (least
//! squares, fitted per view on that view's image). A camera's own exposure and white balance,
//! which no shared model can know for a held-out camera, then cost nothing, so this figure
//! tells a colour mismatch from a wrong surface (as appearance-embedding methods evaluate).

use super::{psnr, EvalError};
use crate::loss::colour_map::affine::solve_rows;

/// PSNR in dB of `pred` mapped by its best affine colour map onto `gt`; both interleaved RGB
/// in [0, 1], same length. At least the plain PSNR (the identity is one such map). A render
/// without colour variation still gets the best constant (the map's solve is regularised).
pub fn affine_corrected_psnr(pred: &[f32], gt: &[f32]) -> Result<f64, EvalError> {
    if pred.len() != gt.len() {
        return Err(EvalError::SizeMismatch(pred.len(), gt.len()));
    }
    if !pred.len().is_multiple_of(3) {
        return Err(EvalError::Empty("whole RGB pixels"));
    }
    let map = fit_affine(pred, gt);
    let mapped: Vec<f32> = pred
        .chunks_exact(3)
        .flat_map(|p| {
            let x = [p[0] as f64, p[1] as f64, p[2] as f64, 1.0];
            map.map(|row| (0..4).map(|k| row[k] * x[k]).sum::<f64>() as f32)
        })
        .collect();
    // The least-squares map is no worse than the identity up to rounding; keep the bound exact.
    Ok(psnr(&mapped, gt)?.max(psnr(pred, gt)?))
}

/// The rows of the least-squares affine map from `pred`'s pixels to `gt`'s (normal equations
/// in f64, a ridge of 1e-9 of the trace keeping a degenerate render solvable).
fn fit_affine(pred: &[f32], gt: &[f32]) -> [[f64; 4]; 3] {
    let (mut normal, mut rhs) = ([[0.0f64; 4]; 4], [[0.0f64; 4]; 3]);
    for (p, g) in pred.chunks_exact(3).zip(gt.chunks_exact(3)) {
        let x = [p[0] as f64, p[1] as f64, p[2] as f64, 1.0];
        for i in 0..4 {
            for j in 0..4 {
                normal[i][j] += x[i] * x[j];
            }
            for c in 0..3 {
                rhs[c][i] += x[i] * g[c] as f64;
            }
        }
    }
    let ridge = 1e-9 * (0..4).map(|i| normal[i][i]).sum::<f64>().max(1e-30);
    solve_rows(normal, rhs, ridge, [[0.0; 4]; 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels of a smooth, varied image.
    fn image(n: usize) -> Vec<f32> {
        (0..3 * n).map(|i| (0.5 + 0.4 * ((i as f32) * 0.37).sin()).clamp(0.0, 1.0)).collect()
    }

    #[test]
    fn an_exact_affine_change_costs_nothing_and_noise_still_counts() {
        let pred = image(500);
        // A camera's white balance and exposure: per channel gain, a cross-talk and an offset.
        let gt: Vec<f32> = pred
            .chunks(3)
            .flat_map(|p| {
                [0.8 * p[0] + 0.05, 0.1 * p[0] + 0.9 * p[1] + 0.02, 0.6 * p[2] + 0.1 * p[1]]
            })
            .collect();
        assert!(psnr(&pred, &gt).unwrap() < 25.0);
        assert!(affine_corrected_psnr(&pred, &gt).unwrap() > 90.0);
        // Noise no affine map removes: the corrected PSNR is the noise's, about 40 dB here.
        let noisy: Vec<f32> =
            gt.iter().enumerate().map(|(i, g)| g + if i % 2 == 0 { 0.01 } else { -0.01 }).collect();
        let corrected = affine_corrected_psnr(&pred, &noisy).unwrap();
        assert!((39.0..41.0).contains(&corrected), "{corrected}");
    }

    #[test]
    fn never_below_the_plain_figure_and_flat_renders_are_solved() {
        let (pred, gt) = (image(300), image(300).iter().rev().copied().collect::<Vec<_>>());
        let (plain, corrected) =
            (psnr(&pred, &gt).unwrap(), affine_corrected_psnr(&pred, &gt).unwrap());
        assert!(corrected >= plain && corrected.is_finite());
        let flat = vec![0.3f32; 900];
        assert!(affine_corrected_psnr(&flat, &gt).unwrap().is_finite());
        assert!(affine_corrected_psnr(&pred, &gt[..6]).is_err());
    }
}
