//! How hard a sequence is to track: how far its vertices move between consecutive frames.

use serde::Serialize;

/// Per-frame vertex motion as fractions of the subject's size (the largest side of frame 0's
/// bounding box), over every vertex of every pair of consecutive frames: the measure the
/// benchmarks' README tabulates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MotionStats {
    /// Mean vertex displacement.
    pub mean: f64,
    /// 90th-percentile vertex displacement.
    pub p90: f64,
    /// Largest vertex displacement.
    pub max: f64,
}

/// The statistics of `frames` (same vertex count each); all zero for fewer than two frames or
/// a subject of zero size.
pub fn motion_stats(frames: &[Vec<[f32; 3]>]) -> MotionStats {
    let size = frames
        .first()
        .and_then(|f| crate::mesh::bounding_box(f))
        .map_or(0.0, |(lo, hi)| (hi - lo).max_element());
    let mut steps: Vec<f64> = frames
        .windows(2)
        .flat_map(|pair| {
            pair[0].iter().zip(&pair[1]).map(|(a, b)| {
                (0..3).map(|k| (b[k] as f64 - a[k] as f64).powi(2)).sum::<f64>().sqrt()
            })
        })
        .collect();
    if steps.is_empty() || size.is_nan() || size <= 0.0 {
        return MotionStats::default();
    }
    steps.sort_unstable_by(f64::total_cmp);
    let mean = steps.iter().sum::<f64>() / steps.len() as f64;
    let p90 = steps[((steps.len() - 1) as f64 * 0.9).round() as usize];
    MotionStats { mean: mean / size, p90: p90 / size, max: steps[steps.len() - 1] / size }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn translation_by_a_tenth_of_the_size() {
        let a = vec![[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]];
        let b: Vec<[f32; 3]> = a.iter().map(|p| [p[0] + 0.2, p[1], p[2]]).collect();
        let s = motion_stats(&[a.clone(), b]);
        assert!(
            (s.mean - 0.1).abs() < 1e-6 && (s.max - 0.1).abs() < 1e-6 && (s.p90 - 0.1).abs() < 1e-6
        );
        assert_eq!(motion_stats(&[a]), MotionStats::default());
    }
}
