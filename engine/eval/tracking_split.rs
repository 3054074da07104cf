//! Tracking error split into a part off the true surface and a part along it.
//!
//! Definition, for a predicted point p, its true position g and the true surface S of the same
//! frame, with e = ‖p − g‖ and d(p, S) the distance from p to the closest point of S (point to
//! triangle, through `SurfaceBvh`):
//! - off the surface: o = min(d(p, S), e);
//! - along the surface: a = √(e² − o²).
//!
//! g lies on S, so d(p, S) ≤ e and o is p's distance to the surface: a surface in the wrong
//! place. a is the rest: the right surface with the point in the wrong place on it (skin that
//! slid). The min only absorbs rounding (or a g off S), so o² + a² = e² for every pair, and the
//! root-mean-square parts of a set of pairs add up the same way to its tracking RMSE.

use super::EvalError;
use crate::geometry::SurfaceBvh;
use glam::DVec3;
use serde::Serialize;

/// Sums of squares over a set of (prediction, truth) pairs; `+` pools two sets (frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SurfaceSplit {
    /// Pairs measured.
    pub pairs: usize,
    /// Σ o², squared scene units.
    pub off_surface_sq: f64,
    /// Σ a², squared scene units.
    pub along_surface_sq: f64,
}

impl std::ops::Add for SurfaceSplit {
    type Output = Self;

    #[inline]
    fn add(self, other: Self) -> Self {
        Self {
            pairs: self.pairs + other.pairs,
            off_surface_sq: self.off_surface_sq + other.off_surface_sq,
            along_surface_sq: self.along_surface_sq + other.along_surface_sq,
        }
    }
}

impl SurfaceSplit {
    /// Root mean square of the parts off and along the surface, scene units (None without
    /// pairs).
    pub fn rms(&self) -> Option<(f64, f64)> {
        let n = self.pairs as f64;
        (self.pairs > 0)
            .then(|| ((self.off_surface_sq / n).sqrt(), (self.along_surface_sq / n).sqrt()))
    }
}

/// Splits every pair's error against the true surface `surface` (see the module docs). Errors:
/// a non-finite point, a face index out of range or a non-finite vertex, a surface without
/// faces.
pub fn split_on_surface(
    pairs: &[([f64; 3], [f64; 3])],
    surface: (&[[f32; 3]], &[[u32; 3]]),
) -> Result<SurfaceSplit, EvalError> {
    super::sample::check_mesh(surface.0, surface.1)?;
    // After that check the BVH can only refuse a mesh without faces.
    let bvh = SurfaceBvh::build(surface.0, surface.1).map_err(|_| EvalError::NoArea)?;
    let mut split = SurfaceSplit::default();
    for &(predicted, truth) in pairs {
        let (p, g) = (DVec3::from(predicted), DVec3::from(truth));
        // Phrased as "not finite" so a NaN anywhere is refused.
        if !(p.is_finite() && g.is_finite()) {
            return Err(EvalError::NonFinite("tracked points"));
        }
        let e2 = p.distance_squared(g);
        let d = bvh.closest_point(p).map_or(f64::INFINITY, |hit| hit.distance);
        let o2 = (d * d).min(e2);
        split.pairs += 1;
        split.off_surface_sq += o2;
        split.along_surface_sq += e2 - o2;
    }
    Ok(split)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles over the unit square in the plane z = 0.
    fn square() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        (
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn a_lift_is_off_the_surface_and_a_slide_along_it() {
        let (v, f) = square();
        let g = [0.5, 0.5, 0.0];
        // Slid by (0.3, 0.4) in the plane (0.5), lifted by 1.2 off it: e = 1.3.
        let s = split_on_surface(&[([0.8, 0.9, 1.2], g)], (&v, &f)).unwrap();
        let (o, a) = s.rms().unwrap();
        assert!((o - 1.2).abs() < 1e-9 && (a - 0.5).abs() < 1e-9, "{o} {a}");
        // The truth itself: nothing either way.
        assert_eq!(split_on_surface(&[(g, g)], (&v, &f)).unwrap().rms(), Some((0.0, 0.0)));
    }

    #[test]
    fn the_parts_add_up_to_the_error_everywhere() {
        let (v, f) = square();
        // Beyond the square's edge, below it, at a corner, on it, and a truth off the surface.
        let pairs = [
            ([2.0, 0.5, 0.0], [0.5, 0.5, 0.0]),
            ([0.2, 0.7, -0.3], [0.9, 0.1, 0.0]),
            ([-1.0, -1.0, 1.0], [0.0, 0.0, 0.0]),
            ([0.25, 0.25, 0.0], [0.75, 0.5, 0.0]),
            ([0.5, 0.5, 0.1], [0.5, 0.5, 3.0]),
        ];
        let mut total = SurfaceSplit::default();
        let mut e2 = 0.0;
        for &(p, g) in &pairs {
            let s = split_on_surface(&[(p, g)], (&v, &f)).unwrap();
            let sq = DVec3::from(p).distance_squared(DVec3::from(g));
            assert!((s.off_surface_sq + s.along_surface_sq - sq).abs() < 1e-12, "{p:?} {g:?}");
            assert!(s.along_surface_sq >= 0.0);
            total = total + s;
            e2 += sq;
        }
        // Beyond the edge: 1 from the edge x = 1, the rest of 1.5 along.
        let edge = split_on_surface(&[pairs[0]], (&v, &f)).unwrap();
        assert!((edge.off_surface_sq - 1.0).abs() < 1e-12);
        assert_eq!(total, split_on_surface(&pairs, (&v, &f)).unwrap());
        let (o, a) = total.rms().unwrap();
        assert!((o * o + a * a - e2 / pairs.len() as f64).abs() < 1e-12);
    }

    #[test]
    fn bad_input() {
        let (v, f) = square();
        let g = [0.5; 3];
        assert_eq!(split_on_surface(&[], (&v, &f)).unwrap().rms(), None);
        assert!(matches!(
            split_on_surface(&[([f64::NAN, 0.0, 0.0], g)], (&v, &f)),
            Err(EvalError::NonFinite(_))
        ));
        assert!(matches!(split_on_surface(&[(g, g)], (&v, &[])), Err(EvalError::NoArea)));
        assert!(matches!(
            split_on_surface(&[(g, g)], (&v, &[[0, 1, 9]])),
            Err(EvalError::FaceIndex { .. })
        ));
    }
}
