//! Tracking error against ground-truth trajectories.
//!
//! Definition: over every ground-truth (point id, frame) pair and its prediction,
//! `mse` = mean of ‖p − g‖² (squared scene units), `rmse` = √mse (scene units), `max` = the
//! largest ‖p − g‖ (scene units); the same per frame. Predictions for pairs the ground truth lacks are ignored
//! (counted in `ignored`); a ground-truth pair without a prediction is an error.

use super::EvalError;
use crate::io::trajectories::TrackPoint;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};

/// Tracking error as defined in the module docs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackingReport {
    /// Distinct point ids and frames in the ground truth, and the pairs compared.
    pub points: usize,
    /// Distinct frames in the ground truth.
    pub frames: usize,
    /// (point id, frame) pairs compared: every ground-truth row.
    pub pairs: usize,
    /// Mean squared error, squared scene units.
    pub mse: f64,
    /// Root mean squared error, scene units.
    pub rmse: f64,
    /// Largest single error, scene units.
    pub max: f64,
    /// RMSE of each frame, scene units, in frame order.
    pub rmse_per_frame: Vec<(u32, f64)>,
    /// Largest error of each frame, scene units, in frame order.
    pub max_per_frame: Vec<(u32, f64)>,
    /// Predicted pairs without ground truth.
    pub ignored: usize,
}

/// Compares `pred` to `gt`, matching rows by (id, frame).
pub fn tracking_error(pred: &[TrackPoint], gt: &[TrackPoint]) -> Result<TrackingReport, EvalError> {
    if gt.is_empty() {
        return Err(EvalError::Empty("ground-truth trajectories"));
    }
    let lookup: HashMap<(&str, u32), [f64; 3]> =
        pred.iter().map(|p| ((p.id.as_str(), p.frame), p.position)).collect();
    // Per frame: sum of squares, pairs, largest error.
    let mut per_frame: BTreeMap<u32, (f64, usize, f64)> = BTreeMap::new();
    let mut ids = BTreeSet::new();
    let (mut sum, mut max) = (0.0f64, 0.0f64);
    for g in gt {
        let p = lookup
            .get(&(g.id.as_str(), g.frame))
            .ok_or_else(|| EvalError::MissingPrediction { id: g.id.clone(), frame: g.frame })?;
        let e2: f64 = (0..3).map(|k| (p[k] - g.position[k]).powi(2)).sum();
        if !e2.is_finite() {
            return Err(EvalError::NonFinite("trajectories"));
        }
        sum += e2;
        max = max.max(e2.sqrt());
        let f = per_frame.entry(g.frame).or_default();
        f.0 += e2;
        f.1 += 1;
        f.2 = f.2.max(e2.sqrt());
        ids.insert(g.id.as_str());
    }
    let mse = sum / gt.len() as f64;
    let gt_keys: HashSet<(&str, u32)> = gt.iter().map(|g| (g.id.as_str(), g.frame)).collect();
    Ok(TrackingReport {
        points: ids.len(),
        frames: per_frame.len(),
        pairs: gt.len(),
        mse,
        rmse: mse.sqrt(),
        max,
        rmse_per_frame: per_frame
            .iter()
            .map(|(&f, &(s, n, _))| (f, (s / n as f64).sqrt()))
            .collect(),
        max_per_frame: per_frame.iter().map(|(&f, &(_, _, m))| (f, m)).collect(),
        ignored: pred.iter().filter(|p| !gt_keys.contains(&(p.id.as_str(), p.frame))).count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(id: u64, frame: u32, position: [f64; 3]) -> TrackPoint {
        TrackPoint { id: id.to_string(), frame, position }
    }

    #[test]
    fn hand_computed() {
        let gt =
            [pt(0, 0, [0.0; 3]), pt(1, 0, [1.0, 0.0, 0.0]), pt(0, 1, [0.0; 3]), pt(1, 1, [0.0; 3])];
        // Errors: 0, 3 (along x), 0, 5 (3 along x, 4 along y).
        let pred = [
            pt(1, 1, [3.0, 4.0, 0.0]),
            pt(0, 0, [0.0; 3]),
            pt(1, 0, [4.0, 0.0, 0.0]),
            pt(0, 1, [0.0; 3]),
            pt(9, 0, [0.0; 3]),
        ];
        let r = tracking_error(&pred, &gt).unwrap();
        assert_eq!((r.points, r.frames, r.pairs, r.ignored), (2, 2, 4, 1));
        assert!((r.mse - (9.0 + 25.0) / 4.0).abs() < 1e-12);
        assert!((r.rmse - 8.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(r.max, 5.0);
        assert_eq!(r.rmse_per_frame, vec![(0, 4.5f64.sqrt()), (1, 12.5f64.sqrt())]);
        assert_eq!(r.max_per_frame, vec![(0, 3.0), (1, 5.0)]);
        assert_eq!(tracking_error(&gt, &gt).unwrap().mse, 0.0);
    }

    #[test]
    fn missing_prediction_names_the_point() {
        let gt = [pt(4, 2, [0.0; 3])];
        assert!(
            matches!(tracking_error(&[], &gt), Err(EvalError::MissingPrediction { ref id, frame: 2 }) if id == "4")
        );
        assert!(matches!(tracking_error(&gt, &[]), Err(EvalError::Empty(_))));
    }
}
