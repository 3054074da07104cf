//! Tracking error split by how many cameras see a point: the error of points the training
//! cameras show, and of points they barely show, which no image term can pin.
//!
//! A (point, frame t) pair counts as seen when at least [`SEEN_VIEWS`] cameras see the point's
//! true position both at frame 0 and at frame t (in front of the camera, inside its image, not
//! hidden by the true surface of that frame: `SurfaceBvh::sees`). Only then can an image term
//! compare where the point was with where it is. The two parts' squared errors add up to the
//! RMSE's, as [`SurfaceSplit`](super::SurfaceSplit)'s do.

use super::EvalError;
use crate::camera::Camera;
use crate::geometry::SurfaceBvh;
use glam::DVec3;
use serde::Serialize;

/// Cameras that must see a point at frame 0 and at frame t for the pair to count as seen.
pub const SEEN_VIEWS: usize = 3;

/// Relative depth slack of the visibility test (a point's own surface does not hide it).
const SLACK: f64 = 1e-4;

/// Sums of squared errors over seen and barely seen pairs; `+` pools two sets (frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SightSplit {
    /// Pairs seen by at least [`SEEN_VIEWS`] cameras in both frames.
    pub seen_pairs: usize,
    /// Σ e² over them, squared scene units.
    pub seen_sq: f64,
    /// The other pairs.
    pub unseen_pairs: usize,
    /// Σ e² over the other pairs.
    pub unseen_sq: f64,
}

impl std::ops::Add for SightSplit {
    type Output = Self;

    #[inline]
    fn add(self, other: Self) -> Self {
        Self {
            seen_pairs: self.seen_pairs + other.seen_pairs,
            seen_sq: self.seen_sq + other.seen_sq,
            unseen_pairs: self.unseen_pairs + other.unseen_pairs,
            unseen_sq: self.unseen_sq + other.unseen_sq,
        }
    }
}

impl SightSplit {
    /// RMS error of the seen pairs, scene units (None without any).
    pub fn seen_rms(&self) -> Option<f64> {
        (self.seen_pairs > 0).then(|| (self.seen_sq / self.seen_pairs as f64).sqrt())
    }

    /// RMS error of the barely seen pairs, scene units (None without any).
    pub fn unseen_rms(&self) -> Option<f64> {
        (self.unseen_pairs > 0).then(|| (self.unseen_sq / self.unseen_pairs as f64).sqrt())
    }

    /// The seen pairs' share of all pairs (None without pairs).
    pub fn seen_share(&self) -> Option<f64> {
        let all = self.seen_pairs + self.unseen_pairs;
        (all > 0).then(|| self.seen_pairs as f64 / all as f64)
    }

    /// Adds one pair's squared error, seen by `views` cameras in both frames.
    pub fn add_pair(&mut self, error_sq: f64, views: usize) {
        if views >= SEEN_VIEWS {
            self.seen_pairs += 1;
            self.seen_sq += error_sq;
        } else {
            self.unseen_pairs += 1;
            self.unseen_sq += error_sq;
        }
    }
}

/// For each point, which of `cameras` see it on `surface` (the surface of the points' frame).
/// Errors: a non-finite point, a surface without faces or with a bad index or vertex.
pub fn cameras_seeing(
    points: &[[f64; 3]],
    surface: (&[[f32; 3]], &[[u32; 3]]),
    cameras: &[Camera],
) -> Result<Vec<Vec<bool>>, EvalError> {
    super::sample::check_mesh(surface.0, surface.1)?;
    // After that check the BVH can only refuse a mesh without faces.
    let bvh = SurfaceBvh::build(surface.0, surface.1).map_err(|_| EvalError::NoArea)?;
    points
        .iter()
        .map(|&p| {
            let p = DVec3::from(p);
            if !p.is_finite() {
                return Err(EvalError::NonFinite("ground-truth points"));
            }
            Ok(cameras.iter().map(|c| bvh.sees(c, p, SLACK).is_some()).collect())
        })
        .collect()
}

/// Cameras that see a point in both frames, from its `cameras_seeing` rows of each.
pub fn seen_in_both(frame0: &[bool], frame_t: &[bool]) -> usize {
    frame0.iter().zip(frame_t).filter(|(a, b)| **a && **b).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;

    /// A camera 5 units from the origin along `dir`, looking at it.
    fn camera(dir: DVec3) -> Camera {
        let up = if dir.z.abs() > 0.9 { DVec3::Y } else { DVec3::Z };
        Camera::look_at(64, 64, 60.0, 60.0, 32.0, 32.0, dir * 5.0, DVec3::ZERO, up).unwrap()
    }

    #[test]
    fn the_near_side_is_seen_and_the_far_side_is_not() {
        let (positions, faces) = unit_sphere(3);
        let cameras = [camera(DVec3::X), camera(DVec3::NEG_X), camera(DVec3::Z)];
        // The vertices furthest along +x, −x and +z: on the surface, facing one camera each.
        let furthest = |d: DVec3| {
            let along = |p: &&[f32; 3]| d.dot(DVec3::from(p.map(f64::from)));
            let p = positions.iter().max_by(|a, b| along(a).total_cmp(&along(b))).unwrap();
            p.map(f64::from)
        };
        let points = [furthest(DVec3::X), furthest(DVec3::NEG_X), furthest(DVec3::Z)];
        let seen = cameras_seeing(&points, (&positions, &faces), &cameras).unwrap();
        assert_eq!(seen[0], vec![true, false, false]);
        assert_eq!(seen[1], vec![false, true, false]);
        assert_eq!(seen[2], vec![false, false, true]);
        assert_eq!(seen_in_both(&seen[0], &[true, true, false]), 1);
    }

    #[test]
    fn pairs_split_at_the_threshold_and_their_squares_pool() {
        let mut split = SightSplit::default();
        split.add_pair(4.0, SEEN_VIEWS);
        split.add_pair(9.0, SEEN_VIEWS - 1);
        split.add_pair(16.0, 0);
        assert_eq!(split.seen_rms(), Some(2.0));
        assert!((split.unseen_rms().unwrap() - 12.5f64.sqrt()).abs() < 1e-12);
        assert!((split.seen_share().unwrap() - 1.0 / 3.0).abs() < 1e-12);
        let pooled = split + split;
        assert_eq!((pooled.seen_pairs, pooled.unseen_pairs), (2, 4));
        assert_eq!(pooled.seen_rms(), split.seen_rms());
        assert_eq!(SightSplit::default().seen_rms(), None);
        assert_eq!(SightSplit::default().seen_share(), None);
    }

    #[test]
    fn bad_input() {
        let (positions, faces) = unit_sphere(1);
        let cameras = [camera(DVec3::X)];
        let nan = [[f64::NAN, 0.0, 0.0]];
        assert!(matches!(
            cameras_seeing(&nan, (&positions, &faces), &cameras),
            Err(EvalError::NonFinite(_))
        ));
        assert!(matches!(
            cameras_seeing(&[[0.0; 3]], (&positions, &[]), &cameras),
            Err(EvalError::NoArea)
        ));
        // No cameras: nothing sees anything.
        assert_eq!(
            cameras_seeing(&[[0.0; 3]], (&positions, &faces), &[]).unwrap(),
            vec![Vec::<bool>::new()]
        );
    }
}
