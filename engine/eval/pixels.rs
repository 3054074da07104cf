//! Tracking error in pixels: how far a tracked point lands from its true position in the
//! images of the training cameras that see it.
//!
//! Definition, for a predicted point p and its true position g at frame t: over the training
//! cameras that see g at frame t (`cameras_seeing`), the distance in pixels between the
//! projections of p and g; the pair's error is the median over those cameras (the mean of the
//! middle two for an even count). A pair no camera sees, or whose prediction projects behind
//! one of them, has no pixel error and is counted apart. Over a set of pairs the figure is the
//! root mean square of the pairs' errors, so frames pool as the scene-unit RMSE does.
//!
//! Pixels compare across framings (a camera twice as far halves them) and with published
//! figures at other resolutions, where fractions of the subject's size do not.

use crate::camera::Camera;
use glam::DVec3;
use serde::Serialize;

/// Sums of squared pixel errors over a set of pairs; `+` pools two sets (frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PixelSplit {
    /// Pairs with a pixel error.
    pub pairs: usize,
    /// Σ of their squared errors, square pixels.
    pub sum_sq: f64,
    /// Pairs without one: no training camera sees the true point.
    pub unmeasured: usize,
}

impl std::ops::Add for PixelSplit {
    type Output = Self;

    #[inline]
    fn add(self, other: Self) -> Self {
        Self {
            pairs: self.pairs + other.pairs,
            sum_sq: self.sum_sq + other.sum_sq,
            unmeasured: self.unmeasured + other.unmeasured,
        }
    }
}

impl PixelSplit {
    /// RMS of the pairs' pixel errors (None without a measured pair).
    pub fn rms(&self) -> Option<f64> {
        (self.pairs > 0).then(|| (self.sum_sq / self.pairs as f64).sqrt())
    }

    /// Adds the pair (`predicted`, `truth`), seen by the cameras of `cameras` flagged in `sees`.
    pub fn add_pair(&mut self, predicted: DVec3, truth: DVec3, cameras: &[Camera], sees: &[bool]) {
        match pixel_error(predicted, truth, cameras, sees) {
            Some(px) => {
                self.pairs += 1;
                self.sum_sq += px * px;
            }
            None => self.unmeasured += 1,
        }
    }
}

/// The median over the cameras flagged in `sees` of the pixel distance between the
/// projections of `predicted` and `truth`; None when no flagged camera projects both.
pub fn pixel_error(
    predicted: DVec3,
    truth: DVec3,
    cameras: &[Camera],
    sees: &[bool],
) -> Option<f64> {
    let distance = |c: &Camera| Some(c.project(predicted)?.distance(c.project(truth)?));
    let mut errors: Vec<f64> = cameras
        .iter()
        .zip(sees)
        .filter(|(_, &seen)| seen)
        .map(|(c, _)| distance(c))
        .collect::<Option<_>>()?;
    errors.sort_unstable_by(f64::total_cmp);
    let n = errors.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(errors[n / 2]),
        _ => Some(0.5 * (errors[n / 2 - 1] + errors[n / 2])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64² camera with focal length `f` pixels at `eye`, looking at the origin.
    fn camera(eye: DVec3, f: f64) -> Camera {
        let up = if eye.z.abs() > 0.9 * eye.length() { DVec3::Y } else { DVec3::Z };
        Camera::look_at(64, 64, f, f, 32.0, 32.0, eye, DVec3::ZERO, up).unwrap()
    }

    #[test]
    fn a_sideways_offset_is_its_size_in_pixels_and_the_median_ignores_one_outlier() {
        // At depth 5 with f = 50 px, 0.1 units across the view are 1 px.
        let along_x =
            [camera(DVec3::new(0.0, -5.0, 0.0), 50.0), camera(DVec3::new(0.0, 0.0, 5.0), 50.0)];
        let (g, p) = (DVec3::ZERO, DVec3::new(0.1, 0.0, 0.0));
        for c in &along_x {
            assert!(
                (pixel_error(p, g, std::slice::from_ref(c), &[true]).unwrap() - 1.0).abs() < 1e-12
            );
        }
        // A camera looking along the offset sees no motion: the median of (0, 1, 1) is 1, of
        // (0, 1) is 0.5; a camera not flagged does not count.
        let mut all = along_x.to_vec();
        all.push(camera(DVec3::new(5.0, 0.0, 0.0), 50.0));
        assert!((pixel_error(p, g, &all, &[true, true, true]).unwrap() - 1.0).abs() < 1e-12);
        assert!((pixel_error(p, g, &all, &[true, false, true]).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(pixel_error(p, g, &all, &[false, false, false]), None);
    }

    #[test]
    fn pairs_pool_as_root_mean_squares_and_unseen_pairs_are_counted_apart() {
        let cameras = [camera(DVec3::new(0.0, -5.0, 0.0), 50.0)];
        let mut split = PixelSplit::default();
        split.add_pair(DVec3::new(0.3, 0.0, 0.0), DVec3::ZERO, &cameras, &[true]);
        split.add_pair(DVec3::new(0.4, 0.0, 0.0), DVec3::ZERO, &cameras, &[true]);
        split.add_pair(DVec3::new(9.0, 0.0, 0.0), DVec3::ZERO, &cameras, &[false]);
        assert_eq!((split.pairs, split.unmeasured), (2, 1));
        assert!((split.rms().unwrap() - 12.5f64.sqrt()).abs() < 1e-9);
        let pooled = split + split;
        assert_eq!((pooled.pairs, pooled.unmeasured), (4, 2));
        assert!((pooled.rms().unwrap() - split.rms().unwrap()).abs() < 1e-12);
        assert_eq!(PixelSplit::default().rms(), None);
        // A prediction behind the camera cannot be measured there.
        let behind = DVec3::new(0.0, -6.0, 0.0);
        assert_eq!(pixel_error(behind, DVec3::ZERO, &cameras, &[true]), None);
    }
}
