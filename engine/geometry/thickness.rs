//! Local thickness of a closed surface: the shape diameter function (Shapira, Shamir and
//! Cohen-Or 2008) at every vertex, the median length of a cone of rays cast from the vertex
//! into the inside. A limb scores its diameter; a torso, its depth.

use super::SurfaceBvh;
use glam::DVec3;

/// Rays per vertex: the inward normal and a ring around it.
const RING_RAYS: usize = 6;
/// Half-angle of the ring (Shapira et al. use a 120° cone; a narrower one keeps a flank's rays
/// from leaving through the neighbouring skin).
const RING_ANGLE: f64 = std::f64::consts::PI / 6.0;

/// The median hit distance of `1 + RING_RAYS` rays cast from each vertex against `-normal` and
/// around it, or `None` where a vertex has no normal or most rays miss (an open or inside-out
/// surface). Rays start `offset` inside the vertex so they skip the vertex's own faces.
pub fn vertex_thickness(
    bvh: &SurfaceBvh,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    offset: f64,
) -> Vec<Option<f64>> {
    positions
        .iter()
        .zip(normals)
        .map(|(&p, &n)| {
            let inward = -DVec3::from(n.map(f64::from));
            let normal_ok = (inward.length() - 1.0).abs() < 1e-3;
            normal_ok.then(|| median_hit(bvh, DVec3::from(p.map(f64::from)), inward, offset))?
        })
        .collect()
}

fn median_hit(bvh: &SurfaceBvh, p: DVec3, inward: DVec3, offset: f64) -> Option<f64> {
    let origin = p + offset * inward;
    let (u, v) = inward.any_orthonormal_pair();
    let ring = (0..RING_RAYS).map(|k| {
        let phi = std::f64::consts::TAU * k as f64 / RING_RAYS as f64;
        RING_ANGLE.cos() * inward + RING_ANGLE.sin() * (phi.cos() * u + phi.sin() * v)
    });
    let mut hits: Vec<f64> = std::iter::once(inward)
        .chain(ring)
        .filter_map(|dir| bvh.ray_cast(origin, dir))
        .map(|hit| hit.distance + offset)
        .collect();
    // A majority of hits, so that the median is one of them.
    if 2 * hits.len() <= RING_RAYS + 1 {
        return None;
    }
    hits.sort_unstable_by(f64::total_cmp);
    Some(hits[hits.len() / 2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;

    #[test]
    fn a_sphere_is_its_diameter_thick_and_an_open_face_has_none() {
        let (positions, faces) = unit_sphere(3);
        let scaled: Vec<[f32; 3]> = positions.iter().map(|p| p.map(|c| 2.5 * c)).collect();
        let normals: Vec<[f32; 3]> = positions.clone();
        let bvh = SurfaceBvh::build(&scaled, &faces).unwrap();
        for t in vertex_thickness(&bvh, &scaled, &normals, 1e-6) {
            // A chord at angle θ from the diameter has length 2r cos θ; the median of the ray
            // ring lies on it (θ = 30°), the normal ray itself on the diameter.
            let t = t.expect("every ray of a closed sphere hits");
            assert!((t - 5.0 * RING_ANGLE.cos()).abs() < 0.1, "thickness {t}");
        }
        let one_face = SurfaceBvh::build(&scaled, &faces[..1]).unwrap();
        assert!(vertex_thickness(&one_face, &scaled[3..4], &normals[3..4], 1e-6)[0].is_none());
    }
}
