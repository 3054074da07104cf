//! Per-vertex stiffness of the temporal edge-length and rigidity terms, from the surface's
//! thickness: thin parts (limbs) keep the full weight, thick parts (a torso) less.
//!
//! Why: as a running animal's spine flexes, its rig stretches the skin of the flank and belly
//! with the legs; the temporal terms resist that stretch, and weakening them everywhere lets
//! the legs lose their shape where they cross (measured: docs/log/2026-11-26-leg-slide-tries.md,
//! docs/log/2026-11-27-limb-stiffness.md). Thickness tells the two apart without a skeleton.
//! It is measured against the subject's own thickest parts, so the same setting finds the
//! limbs of a fox and of a stocky body.

use crate::geometry::thickness::vertex_thickness;
use crate::geometry::{SurfaceBvh, SurfaceError};
use crate::topology::{mean_edge_length, vertex_normals, ManifoldMesh};

/// The percentile of vertex thickness that stands for the subject's thickest part (not the
/// maximum, which one stray ray decides).
const THICKEST_PERCENTILE: f64 = 0.95;

/// sᵢ = min(1, l / tᵢ) per vertex row, tᵢ the vertex's thickness ([`vertex_thickness`]) and
/// l = `limb_fraction` × the 95th percentile of the thicknesses; 1 where the thickness is
/// unknown, and everywhere when `limb_fraction` is not positive (phrased so that NaN switches
/// it off too) or no thickness is known.
pub fn limb_stiffness(mesh: &ManifoldMesh, limb_fraction: f64) -> Result<Vec<f32>, SurfaceError> {
    let off = vec![1.0; mesh.vertex_rows()];
    if limb_fraction.is_nan() || limb_fraction <= 0.0 {
        return Ok(off);
    }
    let bvh = SurfaceBvh::build(&mesh.positions, &mesh.live_faces())?;
    let offset = 1e-3 * mean_edge_length(mesh) as f64;
    let thickness = vertex_thickness(&bvh, &mesh.positions, &vertex_normals(mesh), offset);
    let mut known: Vec<f64> = thickness.iter().flatten().copied().collect();
    if known.is_empty() {
        return Ok(off);
    }
    known.sort_unstable_by(f64::total_cmp);
    let thickest = known[((known.len() - 1) as f64 * THICKEST_PERCENTILE) as usize];
    let limb = limb_fraction * thickest;
    Ok(thickness.into_iter().map(|t| t.map_or(1.0, |t| (limb / t).min(1.0) as f32)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;

    /// Two spheres in one mesh: radius 0.2 (a limb, 18 vertices) and 2 (a torso, 258).
    fn limb_and_torso() -> ManifoldMesh {
        let (small, small_faces) = unit_sphere(1);
        let (big, big_faces) = unit_sphere(3);
        let place = |unit: Vec<[f32; 3]>, r: f32, x: f32| {
            unit.into_iter().map(move |p| [r * p[0] + x, r * p[1], r * p[2]])
        };
        let n = small.len() as u32;
        let positions: Vec<[f32; 3]> =
            place(small, 0.2, -5.0).chain(place(big, 2.0, 0.0)).collect();
        let shifted = big_faces.iter().map(|f| f.map(|i| i + n));
        let faces: Vec<[u32; 3]> = small_faces.iter().copied().chain(shifted).collect();
        ManifoldMesh::new(positions, faces).unwrap()
    }

    #[test]
    fn thin_parts_keep_full_weight_and_thick_ones_scale_with_their_thickness() {
        let mesh = limb_and_torso();
        let limb_rows = unit_sphere(1).0.len();
        // The torso, 93.5 % of the vertices, sets the 95th percentile: its thickness is its 30° chord
        // (2 · 2 cos 30° = 3.46 on the sphere; the facets shorten it a little), so l ≈ 1.73.
        let s = limb_stiffness(&mesh, 0.5).unwrap();
        assert!(s[..limb_rows].iter().all(|&s| s == 1.0), "the limb is thinner than l");
        for &s in &s[limb_rows..] {
            assert!((s - 0.5).abs() < 0.01, "torso stiffness {s}");
        }
    }

    #[test]
    fn off_when_the_limb_fraction_is_not_positive() {
        let mesh = limb_and_torso();
        for limb in [0.0, -1.0, f64::NAN] {
            assert!(limb_stiffness(&mesh, limb).unwrap().iter().all(|&s| s == 1.0));
        }
    }
}
