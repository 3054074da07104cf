//! Chamfer distance between point sets and between meshes (via surface samples).
//!
//! Definition, for point sets P (prediction) and G (ground truth), d(x, S) = min over s ∈ S of
//! ‖x − s‖:
//! - `squared` = ½ (mean over p ∈ P of d(p, G)² + mean over g ∈ G of d(g, P)²), squared scene
//!   units;
//! - `mean` = ½ (mean over p ∈ P of d(p, G) + mean over g ∈ G of d(g, P)), scene units;
//! - `mean_fraction` = `mean` / (diagonal of G's axis-aligned bounding box), unitless.
//!
//! Nearest neighbours come from `kiddo`'s immutable k-d tree (exact queries).

use super::sample::{sample_surface, surface_points};
use super::EvalError;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use serde::Serialize;

/// Both directed halves summed as defined in the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ChamferReport {
    /// Points drawn on each mesh (or the sizes of the point sets, when they differ).
    pub samples_pred: usize,
    /// Points drawn on (or in) the ground truth.
    pub samples_gt: usize,
    /// Symmetric mean of squared nearest-neighbour distances, squared scene units.
    pub squared: f64,
    /// Symmetric mean of nearest-neighbour distances, scene units.
    pub mean: f64,
    /// Diagonal of the ground truth's bounding box, scene units.
    pub gt_diagonal: f64,
    /// `mean / gt_diagonal`.
    pub mean_fraction: f64,
}

/// Chamfer distance between two non-empty point sets with finite coordinates.
pub fn chamfer_distance(pred: &[[f64; 3]], gt: &[[f64; 3]]) -> Result<ChamferReport, EvalError> {
    for (set, name) in [(pred, "predicted points"), (gt, "ground-truth points")] {
        if set.is_empty() {
            return Err(EvalError::Empty(name));
        }
        if set.iter().flatten().any(|v| !v.is_finite()) {
            return Err(EvalError::NonFinite(name));
        }
    }
    let (sq_pg, d_pg) = directed(pred, gt);
    let (sq_gp, d_gp) = directed(gt, pred);
    let mean = 0.5 * (d_pg + d_gp);
    let gt_diagonal = bbox_diagonal(gt);
    Ok(ChamferReport {
        samples_pred: pred.len(),
        samples_gt: gt.len(),
        squared: 0.5 * (sq_pg + sq_gp),
        mean,
        gt_diagonal,
        mean_fraction: if gt_diagonal > 0.0 { mean / gt_diagonal } else { f64::NAN },
    })
}

/// Chamfer distance between `n` area-uniform samples of each mesh (seeded, see
/// [`sample_surface`]).
pub fn chamfer_meshes(
    pred: (&[[f32; 3]], &[[u32; 3]]),
    gt: (&[[f32; 3]], &[[u32; 3]]),
    n: usize,
    seed: u64,
) -> Result<ChamferReport, EvalError> {
    if n == 0 {
        return Err(EvalError::Empty("sample count"));
    }
    let a = surface_points(pred.0, pred.1, &sample_surface(pred.0, pred.1, n, seed)?)?;
    let b = surface_points(gt.0, gt.1, &sample_surface(gt.0, gt.1, n, seed)?)?;
    chamfer_distance(&a, &b)
}

/// Means of squared and unsquared distances from each point of `from` to its nearest in `to`.
fn directed(from: &[[f64; 3]], to: &[[f64; 3]]) -> (f64, f64) {
    let tree: ImmutableKdTree<f64, u32, 3, 32> = ImmutableKdTree::new_from_slice(to);
    let (mut sq, mut d) = (0.0, 0.0);
    for p in from {
        let nn = tree.nearest_one::<SquaredEuclidean>(p);
        sq += nn.distance;
        d += nn.distance.sqrt();
    }
    (sq / from.len() as f64, d / from.len() as f64)
}

/// Diagonal length of the axis-aligned bounding box of a non-empty point set.
pub fn bbox_diagonal(points: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (0..3).map(|d| (hi[d] - lo[d]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn brute(from: &[[f64; 3]], to: &[[f64; 3]]) -> (f64, f64) {
        let mut sq = 0.0;
        let mut d = 0.0;
        for p in from {
            let m = to
                .iter()
                .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min);
            sq += m;
            d += m.sqrt();
        }
        (sq / from.len() as f64, d / from.len() as f64)
    }

    #[test]
    fn matches_brute_force_on_random_clouds() {
        let mut rng = SplitMix64::new(11);
        let mut cloud = |n: usize| {
            (0..n)
                .map(|_| [rng.next_f64(), rng.next_f64() * 2.0, rng.next_f64() - 3.0])
                .collect::<Vec<_>>()
        };
        let a = cloud(700);
        let b = cloud(500);
        let r = chamfer_distance(&a, &b).unwrap();
        let (s1, d1) = brute(&a, &b);
        let (s2, d2) = brute(&b, &a);
        assert!((r.squared - 0.5 * (s1 + s2)).abs() < 1e-12);
        assert!((r.mean - 0.5 * (d1 + d2)).abs() < 1e-12);
    }

    #[test]
    fn plane_shifted_along_its_normal_by_d() {
        // A planar grid (many equal coordinates on one axis) shifted by d: every nearest
        // neighbour is the same grid point, at distance exactly d.
        let a: Vec<[f64; 3]> =
            (0..400).map(|i| [(i % 20) as f64 * 0.1, (i / 20) as f64 * 0.1, 0.0]).collect();
        let d = 0.037;
        let b: Vec<[f64; 3]> = a.iter().map(|p| [p[0], p[1], p[2] + d]).collect();
        let r = chamfer_distance(&a, &b).unwrap();
        assert!((r.squared - d * d).abs() < 1e-15);
        assert!((r.mean - d).abs() < 1e-15);
        let diag = (2.0f64 * 1.9 * 1.9).sqrt();
        assert!((r.mean_fraction - d / diag).abs() < 1e-12);
        assert_eq!(chamfer_distance(&a, &a).unwrap().squared, 0.0);
    }

    #[test]
    fn bad_input() {
        assert!(matches!(chamfer_distance(&[], &[[0.0; 3]]), Err(EvalError::Empty(_))));
        assert!(matches!(
            chamfer_distance(&[[f64::NAN, 0.0, 0.0]], &[[0.0; 3]]),
            Err(EvalError::NonFinite(_))
        ));
    }
}
