//! Binding query points to the frame-0 surface as (face, barycentric).

use crate::geometry::bvh::SurfaceBvh;
use glam::DVec3;

/// A point fixed to the surface: its position in a frame with vertices v is `Σ bₖ·v[face[k]]`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Binding {
    /// Index of the frame-0 face the point lies on.
    pub face: u32,
    /// b ≥ 0, Σb = 1.
    pub barycentric: [f64; 3],
    /// Distance from the query point to the surface (0 for a ray hit).
    pub distance: f64,
}

/// Why a query point was not bound. Nothing is snapped silently.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Unbound {
    /// The closest surface point is farther than the allowed distance.
    TooFar {
        /// Distance from the query point to the closest surface point.
        distance: f64,
    },
    /// The ray hits no face.
    Missed,
    /// The query has a non-finite coordinate.
    NonFinite,
}

impl std::fmt::Display for Unbound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unbound::TooFar { distance } => write!(f, "{distance} from the surface"),
            Unbound::Missed => write!(f, "its ray misses the mesh"),
            Unbound::NonFinite => write!(f, "non-finite coordinates"),
        }
    }
}

/// Binds `p` to its closest surface point, unless that is farther than `max_distance`.
pub fn bind_point(bvh: &SurfaceBvh, p: DVec3, max_distance: f64) -> Result<Binding, Unbound> {
    let hit = bvh.closest_point(p).ok_or(Unbound::NonFinite)?;
    if hit.distance > max_distance {
        return Err(Unbound::TooFar { distance: hit.distance });
    }
    Ok(Binding { face: hit.face, barycentric: hit.barycentric, distance: hit.distance })
}

/// Binds the first surface point hit by the ray `origin + t·dir`, t ≥ 0 (e.g. a pixel's ray
/// from `Camera::pixel_ray`).
pub fn bind_ray(bvh: &SurfaceBvh, origin: DVec3, dir: DVec3) -> Result<Binding, Unbound> {
    if !origin.is_finite() || !dir.is_finite() {
        return Err(Unbound::NonFinite);
    }
    let hit = bvh.ray_cast(origin, dir).ok_or(Unbound::Missed)?;
    Ok(Binding { face: hit.face, barycentric: hit.barycentric, distance: 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> SurfaceBvh {
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        SurfaceBvh::build(&positions, &[[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    #[test]
    fn far_points_are_refused_with_their_distance_and_near_ones_bound() {
        let bvh = square();
        let near = bind_point(&bvh, DVec3::new(0.75, 0.25, 0.01), 0.02).unwrap();
        assert_eq!(near.face, 0);
        assert!((near.distance - 0.01).abs() < 1e-15);
        let far = bind_point(&bvh, DVec3::new(0.75, 0.25, 0.5), 0.02);
        assert!(matches!(far, Err(Unbound::TooFar { distance }) if (distance - 0.5).abs() < 1e-15));
        assert_eq!(bind_point(&bvh, DVec3::new(f64::NAN, 0.0, 0.0), 1.0), Err(Unbound::NonFinite));
    }

    #[test]
    fn rays_that_miss_are_refused() {
        let bvh = square();
        let hit = bind_ray(&bvh, DVec3::new(0.25, 0.75, -1.0), DVec3::Z).unwrap();
        assert_eq!(hit.face, 1);
        assert_eq!(bind_ray(&bvh, DVec3::new(2.0, 0.5, -1.0), DVec3::Z), Err(Unbound::Missed));
        assert_eq!(
            bind_ray(&bvh, DVec3::new(0.5, 0.5, -1.0), DVec3::new(0.0, 0.0, f64::NAN)),
            Err(Unbound::NonFinite)
        );
    }
}
