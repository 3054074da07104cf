//! Per-vertex stiffness of the temporal edge-length and rigidity terms, from the surface's
//! thickness: thin parts (limbs) keep the full weight, thick parts (a torso) less.
//!
//! Why: as a running animal's spine flexes, its rig stretches the skin of the flank and belly
//! with the legs; the temporal terms resist that stretch, and weakening them everywhere lets
//! the legs lose their shape where they cross (measured, docs/pipeline.md). Thickness tells the
//! two apart without a skeleton.

use crate::geometry::thickness::vertex_thickness;
use crate::geometry::{SurfaceBvh, SurfaceError};
use crate::topology::{mean_edge_length, vertex_normals, ManifoldMesh};

/// sᵢ = min(1, `limb_thickness` / tᵢ) per vertex row, tᵢ the vertex's thickness
/// ([`vertex_thickness`]); 1 where the thickness is unknown, and everywhere when
/// `limb_thickness` is not positive (phrased so that NaN switches it off too).
pub fn limb_stiffness(mesh: &ManifoldMesh, limb_thickness: f64) -> Result<Vec<f32>, SurfaceError> {
    if !(limb_thickness > 0.0) {
        return Ok(vec![1.0; mesh.vertex_rows()]);
    }
    let bvh = SurfaceBvh::build(&mesh.positions, &mesh.live_faces())?;
    let offset = 1e-3 * mean_edge_length(mesh) as f64;
    let thickness = vertex_thickness(&bvh, &mesh.positions, &vertex_normals(mesh), offset);
    Ok(thickness
        .into_iter()
        .map(|t| t.map_or(1.0, |t| (limb_thickness / t).min(1.0) as f32))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;

    /// Two spheres in one mesh: radius 0.2 (a limb) and 2 (a torso).
    fn limb_and_torso() -> ManifoldMesh {
        let (unit, faces) = unit_sphere(3);
        let place = |r: f32, x: f32| unit.iter().map(move |p| [r * p[0] + x, r * p[1], r * p[2]]);
        let positions: Vec<[f32; 3]> = place(0.2, -5.0).chain(place(2.0, 0.0)).collect();
        let n = unit.len() as u32;
        let shifted = faces.iter().map(|f| f.map(|i| i + n));
        let faces: Vec<[u32; 3]> = faces.iter().copied().chain(shifted).collect();
        ManifoldMesh::new(positions, faces).unwrap()
    }

    #[test]
    fn thin_parts_keep_full_weight_and_thick_ones_scale_with_their_thickness() {
        let mesh = limb_and_torso();
        let s = limb_stiffness(&mesh, 0.5).unwrap();
        let half = mesh.vertex_rows() / 2;
        assert!(s[..half].iter().all(|&s| s == 1.0), "the limb is thinner than 0.5");
        // The torso's thickness is its 30° chord, 2 · 2 cos 30° = 3.46.
        for &s in &s[half..] {
            assert!((s - 0.5 / 3.46).abs() < 0.01, "torso stiffness {s}");
        }
    }

    #[test]
    fn off_when_the_limb_thickness_is_not_positive() {
        let mesh = limb_and_torso();
        for limb in [0.0, -1.0, f64::NAN] {
            assert!(limb_stiffness(&mesh, limb).unwrap().iter().all(|&s| s == 1.0));
        }
    }
}
