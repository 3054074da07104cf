//! The remap applied to a Gaussian scene: kept Gaussians copied, new ones averaged from their
//! parents (the corners of the face they split).

use super::remap::{remap_rows, remap_strided, NEW_ROW};
use crate::splat::GaussianScene;

/// Every per-Gaussian array of `scene` through `old_of_new`. The k-th new row ([`NEW_ROW`])
/// averages the old Gaussians `parents[k]`: positions, log-scales, opacity logits and SH
/// arithmetically, rotations as the normalised sum of the parents' unit quaternions, each
/// turned to the hemisphere of the first (q and −q are one rotation).
/// Panics when `parents` has fewer entries than there are new rows (a bug of the caller).
pub fn remap_scene(
    scene: &GaussianScene,
    old_of_new: &[u32],
    parents: &[[u32; 3]],
) -> GaussianScene {
    let mut parent_of_row = vec![usize::MAX; old_of_new.len()];
    let mut k = 0;
    for (row, &from) in old_of_new.iter().enumerate() {
        if from == NEW_ROW {
            parent_of_row[row] = k;
            k += 1;
        }
    }
    assert!(k <= parents.len(), "{k} new rows but {} parent triples", parents.len());
    let corners = |row: usize| parents[parent_of_row[row]].map(|p| p as usize);
    let mean3 = |rows: &[[f32; 3]], row: usize| {
        let c = corners(row).map(|p| rows[p]);
        [0, 1, 2].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0)
    };
    let stride = scene.coefficients() * 3;
    GaussianScene {
        positions: remap_rows(&scene.positions, old_of_new, |row| mean3(&scene.positions, row)),
        log_scales: remap_rows(&scene.log_scales, old_of_new, |row| mean3(&scene.log_scales, row)),
        rotations: remap_rows(&scene.rotations, old_of_new, |row| {
            average_quaternion(corners(row).map(|p| scene.rotations[p]))
        }),
        opacity_logits: remap_rows(&scene.opacity_logits, old_of_new, |row| {
            corners(row).iter().map(|&p| scene.opacity_logits[p]).sum::<f32>() / 3.0
        }),
        sh: remap_strided(&scene.sh, stride, old_of_new, |row, dst| {
            for p in corners(row) {
                dst.iter_mut()
                    .zip(&scene.sh[p * stride..(p + 1) * stride])
                    .for_each(|(d, s)| *d += s / 3.0);
            }
        }),
        sh_degree: scene.sh_degree,
    }
}

/// Normalised sum of unit quaternions (w, x, y, z) aligned to the first one's hemisphere;
/// the first one when the sum vanishes.
pub fn average_quaternion(qs: [[f32; 4]; 3]) -> [f32; 4] {
    let unit = |q: [f32; 4]| {
        let n = q.iter().map(|c| c * c).sum::<f32>().sqrt();
        if n > 0.0 {
            q.map(|c| c / n)
        } else {
            [1.0, 0.0, 0.0, 0.0]
        }
    };
    let first = unit(qs[0]);
    let mut sum = [0.0f32; 4];
    for q in qs.map(unit) {
        let sign =
            if q.iter().zip(&first).map(|(a, b)| a * b).sum::<f32>() < 0.0 { -1.0 } else { 1.0 };
        sum.iter_mut().zip(q).for_each(|(s, c)| *s += sign * c);
    }
    let n = sum.iter().map(|c| c * c).sum::<f32>().sqrt();
    if n > 1e-6 {
        sum.map(|c| c / n)
    } else {
        first
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opposite_signs_are_one_rotation() {
        let q = [0.6, 0.8, 0.0, 0.0];
        let avg = average_quaternion([q, q.map(|c| -c), q]);
        assert!(avg.iter().zip(q).all(|(a, b)| (a - b).abs() < 1e-6), "{avg:?}");
        // Halfway between identity and a 90° turn about z is the 45° turn.
        let turn = [std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];
        let avg = average_quaternion([[1.0, 0.0, 0.0, 0.0], turn, [2.0, 0.0, 0.0, 0.0]]);
        let angle = 2.0 * avg[3].atan2(avg[0]);
        let expected = 2.0 * (turn[3]).atan2(2.0 + turn[0]);
        assert!((angle - expected).abs() < 1e-5, "{angle} vs {expected}");
    }
}
