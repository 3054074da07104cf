//! Chamfer distance from surface samples to the other mesh's surface.
//!
//! Definition, for meshes P (prediction) and G (ground truth), with d(x, S) the distance from x
//! to the closest point of surface S (point to triangle, through `SurfaceBvh`):
//! `mean` = ½ (mean over n samples p of P of d(p, G) + mean over n samples g of G of d(g, P)),
//! scene units. The samples are area-uniform ([`sample_surface`]). Unlike sample-to-sample
//! Chamfer ([`super::chamfer_meshes`]) it has no sampling noise floor: a mesh against itself
//! scores 0 up to rounding (about 1e-16 of the mesh's size), whatever n.

use super::sample::{sample_surface, surface_points};
use super::EvalError;
use crate::geometry::SurfaceBvh;
use glam::DVec3;
use serde::Serialize;

/// Both directed halves and their mean, scene units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SurfaceChamferReport {
    /// Samples drawn on each mesh.
    pub samples: usize,
    /// Mean distance from the prediction's samples to the ground-truth surface.
    pub pred_to_gt: f64,
    /// Mean distance from the ground truth's samples to the predicted surface.
    pub gt_to_pred: f64,
    /// ½ (pred_to_gt + gt_to_pred).
    pub mean: f64,
}

/// Point-to-surface Chamfer between two meshes with `n` samples on each (seeded, the same
/// seed on both). Errors: n = 0, a face index out of range, a non-finite position, a mesh
/// without area.
pub fn chamfer_to_surface(
    pred: (&[[f32; 3]], &[[u32; 3]]),
    gt: (&[[f32; 3]], &[[u32; 3]]),
    n: usize,
    seed: u64,
) -> Result<SurfaceChamferReport, EvalError> {
    if n == 0 {
        return Err(EvalError::Empty("sample count"));
    }
    let pred_to_gt = directed(pred, gt, n, seed)?;
    let gt_to_pred = directed(gt, pred, n, seed)?;
    Ok(SurfaceChamferReport {
        samples: n,
        pred_to_gt,
        gt_to_pred,
        mean: 0.5 * (pred_to_gt + gt_to_pred),
    })
}

/// Mean distance from `n` samples of `from` to the surface of `to`.
fn directed(
    from: (&[[f32; 3]], &[[u32; 3]]),
    to: (&[[f32; 3]], &[[u32; 3]]),
    n: usize,
    seed: u64,
) -> Result<f64, EvalError> {
    let points = surface_points(from.0, from.1, &sample_surface(from.0, from.1, n, seed)?)?;
    // Sampling checked `to` only when it was `from`: check it before building its BVH.
    super::sample::check_mesh(to.0, to.1)?;
    // After that check the BVH can only refuse a mesh without faces.
    let bvh = SurfaceBvh::build(to.0, to.1).map_err(|_| EvalError::NoArea)?;
    let mut sum = 0.0;
    for p in points {
        // Finite: the samples lie on a finite mesh.
        sum += bvh.closest_point(DVec3::from(p)).map_or(f64::NAN, |hit| hit.distance);
    }
    Ok(sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles over the unit square at height z.
    fn square(z: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        (
            vec![[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn a_point_off_a_triangle_edge_measures_to_the_edge_not_to_samples() {
        // A small square beside the unit square: its samples are 0.5..0.6 from the unit
        // square's edge x = 1 in x, and on its plane.
        let (a, f) = square(0.0);
        let b: Vec<[f32; 3]> = a.iter().map(|p| [1.5 + 0.1 * p[0], 0.1 * p[1], 0.0]).collect();
        let r = chamfer_to_surface((&b, &f), (&a, &f), 2000, 1).unwrap();
        assert!((r.pred_to_gt - 0.55).abs() < 0.01, "{}", r.pred_to_gt);
        assert!(r.gt_to_pred > r.pred_to_gt);
    }

    #[test]
    fn bad_input() {
        let (a, f) = square(0.0);
        assert!(matches!(chamfer_to_surface((&a, &f), (&a, &f), 0, 0), Err(EvalError::Empty(_))));
        assert!(matches!(chamfer_to_surface((&a, &f), (&a, &[]), 10, 0), Err(EvalError::NoArea)));
        assert!(matches!(
            chamfer_to_surface((&a, &f), (&a, &[[0, 1, 9]]), 10, 0),
            Err(EvalError::FaceIndex { .. })
        ));
        let nan = vec![[f32::NAN; 3]; 4];
        assert!(matches!(
            chamfer_to_surface((&a, &f), (&nan, &f), 10, 0),
            Err(EvalError::NonFinite(_))
        ));
    }
}
