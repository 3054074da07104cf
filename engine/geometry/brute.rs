//! Closest point and ray cast by testing every triangle: O(faces) per query. The reference the
//! BVH is tested and benchmarked against; it shares the triangle routines with the BVH, so the
//! two agree exactly except for the choice among equally distant faces.

use super::bvh::SurfacePoint;
use super::triangle::{closest_on_triangle, interpolate, ray_triangle};
use glam::DVec3;

/// Corners of every triangle in f64, indexed by face (from [`super::bvh::triangles`]).
pub fn corners_f64(triangles: &[[[f32; 3]; 3]]) -> Vec<[DVec3; 3]> {
    triangles.iter().map(|t| t.map(|v| DVec3::from(v.map(f64::from)))).collect()
}

/// The surface point closest to `p`, lowest face index among ties; None for no triangles.
pub fn closest_point(corners: &[[DVec3; 3]], p: DVec3) -> Option<SurfacePoint> {
    let mut best: Option<SurfacePoint> = None;
    for (face, &[a, b, c]) in corners.iter().enumerate() {
        let barycentric = closest_on_triangle(p, a, b, c);
        let position = interpolate(barycentric, a, b, c);
        let distance = p.distance(position);
        if best.is_none_or(|best| distance < best.distance) {
            best = Some(SurfacePoint { face: face as u32, barycentric, position, distance });
        }
    }
    best
}

/// The first hit of the ray `origin + t·dir`, t ≥ 0; `distance` is t.
pub fn ray_cast(corners: &[[DVec3; 3]], origin: DVec3, dir: DVec3) -> Option<SurfacePoint> {
    let mut best: Option<SurfacePoint> = None;
    for (face, &[a, b, c]) in corners.iter().enumerate() {
        let t_max = best.map_or(f64::INFINITY, |b| b.distance);
        if let Some((t, barycentric)) = ray_triangle(origin, dir, t_max, a, b, c) {
            let position = interpolate(barycentric, a, b, c);
            best = Some(SurfacePoint { face: face as u32, barycentric, position, distance: t });
        }
    }
    best
}
