//! The host side of the camera colour maps: fitting a camera's affine map from the moments its
//! renders summed (least squares, pulled toward a prior), and fixing the one freedom the maps
//! share with the scene's colours.
//!
//! The maps and the colours are determined only together: any invertible affine change of
//! every colour, undone in every map, renders the same images. [`fix_gauge`] removes it by
//! keeping the cameras' mean map the identity, so the scene's colours are those of the mean
//! camera.

use super::{ColourMap, MOMENTS};

/// The rows of `M` minimising `Σ |y − M z|² + ridge · |M − prior|²` over 4-vectors `z`, from
/// the normal matrix `Σ z zᵀ` and the rows `Σ y_k z`. With `ridge > 0` every system is
/// solvable (a camera that saw one colour keeps the prior where it learned nothing).
pub fn solve_rows(
    mut normal: [[f64; 4]; 4],
    rhs: [[f64; 4]; 3],
    ridge: f64,
    prior: [[f64; 4]; 3],
) -> [[f64; 4]; 3] {
    (0..4).for_each(|i| normal[i][i] += ridge);
    std::array::from_fn(|k| {
        solve4(normal, std::array::from_fn(|j| rhs[k][j] + ridge * prior[k][j]))
    })
}

/// `x` with `m x = b` for an invertible `m` (Gaussian elimination with partial pivoting).
pub fn solve4(mut m: [[f64; 4]; 4], mut b: [f64; 4]) -> [f64; 4] {
    for col in 0..4 {
        let pivot = (col..4).max_by(|&a, &c| m[a][col].abs().total_cmp(&m[c][col].abs()));
        let pivot = pivot.unwrap_or(col);
        m.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..4 {
            let f = m[row][col] / m[col][col];
            let pivot_row = m[col];
            for (value, p) in m[row].iter_mut().zip(pivot_row).skip(col) {
                *value -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let tail: f64 = (row + 1..4).map(|k| m[row][k] * x[k]).sum();
        x[row] = (b[row] - tail) / m[row][row];
    }
    x
}

/// The identity map: the camera sees the scene's colours.
pub const IDENTITY: ColourMap = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

/// A camera's next map from the `MOMENTS` sums of its renders (colour_map_forward.comp's
/// order: `Σ z_i z_j` for `i ≤ j`, then `Σ y_k z_j`): a gain per channel (`y_k ≈ g_k p_k`,
/// exposure times white balance), pulled toward 1 by `ridge` times the subject's summed
/// coverage `Σ α²`. The kernels take any affine map, but a subject's colours are too
/// correlated across channels to fix a full matrix, and too narrow to tell a gain from an
/// offset (docs/log/2026-11-29-camera-colour.md). `None` when the renders covered nothing (the
/// camera keeps its map) or a moment is not finite.
pub fn fit_map(moments: &[f64], ridge: f64) -> Option<ColourMap> {
    if moments.len() != MOMENTS || !moments.iter().all(|m| m.is_finite()) {
        return None;
    }
    // Σ z_k z_k sits at the start of row k of the upper triangle: 0, 4, 7, 9.
    let squares = [0, 4, 7, 9].map(|i| moments[i]);
    let coverage = squares[3];
    if coverage <= 0.0 {
        return None;
    }
    let lambda = ridge.max(1e-9) * coverage;
    let mut map = IDENTITY;
    for k in 0..3 {
        let gain = (moments[10 + 4 * k + k] + lambda) / (squares[k] + lambda);
        map[k][k] = gain as f32;
    }
    map.iter().flatten().all(|v| v.is_finite()).then_some(map)
}

/// The maps with the same renders' freedom removed: each map composed with the inverse of
/// the cameras' mean map (as 4 × 4 matrices on `(p, α)`), so the mean becomes the identity.
/// Unchanged when the mean is singular.
pub fn fix_gauge(maps: &[ColourMap]) -> Vec<ColourMap> {
    if maps.is_empty() {
        return Vec::new();
    }
    let homogeneous = |m: &ColourMap| -> [[f64; 4]; 4] {
        std::array::from_fn(|r| if r < 3 { m[r].map(f64::from) } else { [0.0, 0.0, 0.0, 1.0] })
    };
    let mut mean = [[0.0; 4]; 4];
    for m in maps {
        let h = homogeneous(m);
        (0..4).for_each(|r| (0..4).for_each(|c| mean[r][c] += h[r][c] / maps.len() as f64));
    }
    let transposed: [[f64; 4]; 4] = std::array::from_fn(|r| std::array::from_fn(|c| mean[c][r]));
    // Row r of M · mean⁻¹ is x with meanᵀ x = (row r of M).
    let fixed: Vec<ColourMap> = maps
        .iter()
        .map(|m| std::array::from_fn(|r| solve4(transposed, m[r].map(f64::from)).map(|v| v as f32)))
        .collect();
    if fixed.iter().flatten().flatten().all(|v| v.is_finite()) {
        fixed
    } else {
        maps.to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::super::reference;
    use super::*;

    /// The moments of pixels `z` (over black) seen through `map`.
    fn moments_of(z: &[[f64; 4]], map: &ColourMap) -> Vec<f64> {
        let seen: Vec<[f64; 4]> = z.iter().map(|&z| reference::seen(map, z, [0.0; 3])).collect();
        reference::moments(z, &seen, [0.0; 3])
    }

    /// Premultiplied colours with coverage, varied enough to fix a full affine map.
    fn pixels(n: usize) -> Vec<[f64; 4]> {
        (0..n)
            .map(|i| {
                let t = i as f64;
                let alpha = if i % 5 == 0 { 0.5 } else { 1.0 };
                [
                    0.5 + 0.4 * (0.37 * t).sin(),
                    0.5 + 0.3 * (0.71 * t).cos(),
                    0.4 + 0.3 * (1.3 * t).sin(),
                    1.0,
                ]
                .map(|v| v * alpha)
            })
            .collect()
    }

    #[test]
    fn a_cameras_gains_are_recovered_from_its_moments() {
        let truth: ColourMap = [[0.8, 0.0, 0.0, 0.0], [0.0, 1.1, 0.0, 0.0], [0.0, 0.0, 0.9, 0.0]];
        let fitted = fit_map(&moments_of(&pixels(400), &truth), 1e-9).unwrap();
        for (f, t) in fitted.iter().flatten().zip(truth.iter().flatten()) {
            assert!((f - t).abs() < 1e-5, "{fitted:?} against {truth:?}");
        }
    }

    #[test]
    fn the_ridge_keeps_what_the_renders_cannot_fix_at_the_identity() {
        // A subject with no red: its red gain stays 1; green and blue are fitted.
        let pixels: Vec<[f64; 4]> = pixels(200).iter().map(|p| [0.0, p[1], p[2], p[3]]).collect();
        let truth: ColourMap = [[1.3, 0.0, 0.0, 0.0], [0.0, 0.9, 0.0, 0.0], [0.0, 0.0, 1.1, 0.0]];
        let fitted = fit_map(&moments_of(&pixels, &truth), 1e-3).unwrap();
        assert_eq!(fitted[0][0], 1.0);
        assert!(
            (fitted[1][1] - 0.9).abs() < 1e-3 && (fitted[2][2] - 1.1).abs() < 1e-3,
            "{fitted:?}"
        );
        assert_eq!(fit_map(&[0.0; MOMENTS], 0.01), None, "no coverage: keep the map");
        assert_eq!(fit_map(&[f64::NAN; MOMENTS], 0.01), None);
    }

    #[test]
    fn the_gauge_makes_the_mean_map_the_identity_and_keeps_the_differences() {
        let maps: Vec<ColourMap> = vec![
            [[1.2, 0.0, 0.0, 0.1], [0.0, 1.1, 0.0, 0.0], [0.0, 0.0, 0.9, 0.0]],
            [[0.9, 0.1, 0.0, 0.0], [0.0, 1.3, 0.0, 0.05], [0.0, 0.0, 1.0, 0.0]],
        ];
        let fixed = fix_gauge(&maps);
        for r in 0..3 {
            for c in 0..4 {
                let mean = (fixed[0][r][c] + fixed[1][r][c]) / 2.0;
                assert!((mean - IDENTITY[r][c]).abs() < 1e-6, "{fixed:?}");
            }
        }
        // The ratio of two cameras' maps (M₀ M₁⁻¹) is unchanged: colours move, not the cameras'
        // differences. Checked on a colour: M₀ M₁⁻¹ y equals F₀ F₁⁻¹ y.
        let apply = |m: &ColourMap, z: [f64; 4]| -> [f64; 4] {
            std::array::from_fn(|r| {
                if r < 3 {
                    (0..4).map(|j| m[r][j] as f64 * z[j]).sum()
                } else {
                    z[3]
                }
            })
        };
        let inverse_apply =
            |m: &ColourMap, y: [f64; 4]| {
                let h: [[f64; 4]; 4] = std::array::from_fn(|r| {
                    if r < 3 {
                        m[r].map(f64::from)
                    } else {
                        [0.0, 0.0, 0.0, 1.0]
                    }
                });
                solve4(h, y)
            };
        let y = [0.3, 0.6, 0.2, 1.0];
        let before = apply(&maps[0], inverse_apply(&maps[1], y));
        let after = apply(&fixed[0], inverse_apply(&fixed[1], y));
        for (b, a) in before.iter().zip(after) {
            assert!((b - a).abs() < 1e-6, "{before:?} against {after:?}");
        }
        assert_eq!(fix_gauge(&[IDENTITY]), vec![IDENTITY]);
    }
}
