//! Axis-aligned bounds of a point set: the scale that every relative tolerance multiplies.

use glam::DVec3;

/// (lowest corner, highest corner), or None for no points.
pub fn bounding_box(positions: &[[f32; 3]]) -> Option<(DVec3, DVec3)> {
    let mut points = positions.iter().map(|p| DVec3::from(p.map(f64::from)));
    let first = points.next()?;
    Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
}

/// Length of the bounding box's diagonal; 0 for no points.
pub fn bounding_diagonal(positions: &[[f32; 3]]) -> f64 {
    bounding_box(positions).map_or(0.0, |(lo, hi)| lo.distance(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_of_the_box() {
        assert_eq!(bounding_diagonal(&[]), 0.0);
        assert!(
            (bounding_diagonal(&[[0.0, 0.0, 0.0], [1.0, 2.0, 2.0], [0.5, 0.5, 0.5]]) - 3.0).abs()
                < 1e-15
        );
        assert_eq!(
            bounding_box(&[[1.0, -2.0, 3.0]]),
            Some((DVec3::new(1.0, -2.0, 3.0), DVec3::new(1.0, -2.0, 3.0)))
        );
    }
}
