//! Peak signal-to-noise ratio.

use super::EvalError;

/// PSNR in dB of `pred` against `gt`, both holding values in [0, 1] (any layout, same length):
/// `10 · log10(1 / MSE)` with `MSE = mean((pred − gt)²)` over every value (all pixels and
/// channels), accumulated in f64. Identical inputs give `+∞`.
pub fn psnr(pred: &[f32], gt: &[f32]) -> Result<f64, EvalError> {
    if pred.len() != gt.len() {
        return Err(EvalError::SizeMismatch(pred.len(), gt.len()));
    }
    if pred.is_empty() {
        return Err(EvalError::Empty("image"));
    }
    let mut sum = 0.0f64;
    for (&p, &g) in pred.iter().zip(gt) {
        if !p.is_finite() || !g.is_finite() {
            return Err(EvalError::NonFinite("image"));
        }
        let d = p as f64 - g as f64;
        sum += d * d;
    }
    let mse = sum / pred.len() as f64;
    Ok(-10.0 * mse.log10())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Every value off by 0.1: MSE = 0.01, PSNR = 20 dB.
        let gt = vec![0.5f32; 12];
        let pred: Vec<f32> = gt
            .iter()
            .enumerate()
            .map(|(i, v)| if i % 2 == 0 { v + 0.1 } else { v - 0.1 })
            .collect();
        assert!((psnr(&pred, &gt).unwrap() - 20.0).abs() < 1e-5);
        // One value of four off by 1: MSE = 0.25, PSNR = 10·log10(4).
        assert!(
            (psnr(&[1.0, 0.0, 0.0, 0.0], &[0.0; 4]).unwrap() - 10.0 * 4f64.log10()).abs() < 1e-12
        );
        assert_eq!(psnr(&gt, &gt).unwrap(), f64::INFINITY);
    }

    #[test]
    fn bad_input() {
        assert!(matches!(psnr(&[0.0], &[0.0, 1.0]), Err(EvalError::SizeMismatch(1, 2))));
        assert!(matches!(psnr(&[], &[]), Err(EvalError::Empty(_))));
        assert!(matches!(psnr(&[f32::NAN], &[0.0]), Err(EvalError::NonFinite(_))));
    }
}
