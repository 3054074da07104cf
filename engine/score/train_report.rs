//! What a training run says about its frames: `OUT/report.json` of `tagsplat train`, read
//! generically (as JSON values) so fields the trainer adds later do not break the reader and
//! fields it lacks are reported as absent, never invented.

use super::SequenceEvalError;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// One entry of the report's `frames[]`; None where the entry lacks the field (or holds
/// null: serde_json writes a non-finite number as null).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameTrainStats {
    /// Held-out (or training, see the report's `eval_views`) PSNR of the Gaussian and the mesh
    /// renders, dB.
    pub psnr_gs_db: Option<f64>,
    /// PSNR of the mesh renders, dB (the report's `psnr_mesh`).
    pub psnr_mesh_db: Option<f64>,
    /// The frame's per-vertex iterations (the report's `iterations`; the graph stage's not
    /// included).
    pub iterations: Option<u64>,
    /// Optimisation wall time of the frame, seconds.
    pub wall_s: Option<f64>,
    /// Why the frame's optimisation stopped, as the trainer words it.
    pub stop_reason: Option<String>,
    /// The trainer's `lost_views` entry, as it is.
    pub lost_views: Option<serde_json::Value>,
}

/// The per-frame entries of the report at `path`, by frame; None when there is no such file.
/// Errors (naming the file): unreadable, not JSON, `frames` not a list, an entry without a
/// non-negative integer `frame`.
pub fn read_train_report(
    path: &Path,
) -> Result<Option<BTreeMap<usize, FrameTrainStats>>, SequenceEvalError> {
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path)
        .map_err(|source| SequenceEvalError::Io { path: path.to_owned(), source })?;
    let invalid = |problem: String| SequenceEvalError::Invalid { path: path.to_owned(), problem };
    let report: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| invalid(format!("not JSON: {e}")))?;
    let Some(frames) = report.get("frames").and_then(|f| f.as_array()) else {
        return Err(invalid("no `frames` list".into()));
    };
    let mut stats = BTreeMap::new();
    for (i, entry) in frames.iter().enumerate() {
        let frame = entry
            .get("frame")
            .and_then(|f| f.as_u64())
            .ok_or_else(|| invalid(format!("frames[{i}] has no `frame` index")))?;
        stats.insert(frame as usize, frame_stats(entry));
    }
    Ok(Some(stats))
}

fn frame_stats(entry: &serde_json::Value) -> FrameTrainStats {
    let number = |key: &str| entry.get(key).and_then(|v| v.as_f64());
    FrameTrainStats {
        psnr_gs_db: number("psnr_gs"),
        psnr_mesh_db: number("psnr_mesh"),
        iterations: entry.get("iterations").and_then(|v| v.as_u64()),
        wall_s: number("wall_s"),
        // A reason given as something other than text is kept in its JSON form.
        stop_reason: entry
            .get("stop_reason")
            .filter(|v| !v.is_null())
            .map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_owned)),
        lost_views: entry.get("lost_views").filter(|v| !v.is_null()).cloned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_read_when_present_and_absent_otherwise() {
        let entry = serde_json::json!({"frame": 3, "psnr_gs": 31.5, "psnr_mesh": null, "iterations": 200, "stop_reason": "converged", "new_field": [1]});
        let s = frame_stats(&entry);
        assert_eq!(
            (s.psnr_gs_db, s.psnr_mesh_db, s.iterations, s.wall_s),
            (Some(31.5), None, Some(200), None)
        );
        assert_eq!((s.stop_reason.as_deref(), s.lost_views), (Some("converged"), None));
        assert_eq!(
            frame_stats(&serde_json::json!({"stop_reason": {"plateau": 40}}))
                .stop_reason
                .as_deref(),
            Some("{\"plateau\":40}")
        );
    }
}
