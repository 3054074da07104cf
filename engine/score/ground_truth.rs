//! The hard-motion benchmarks' ground truth (`DIR/gt/`, Panoptic-layout datasets):
//! - `meshes/FFFFFF.ply`: the true surface of every frame (six-digit frame index);
//! - `points.csv` (`id,x,y,z`): surface points on frame 0;
//! - `tracks.csv` (`id,frame,x,y,z`): where each of those points is in every frame;
//! - `info.json`: at least `size`, the largest side of frame 0's bounding box (scene units),
//!   the unit every benchmark score is divided by.

use super::SequenceEvalError;
use crate::dataset::own::frame_name;
use crate::io::trajectories::{read_trajectories_csv, TrackPoint};
use crate::track::queries::read_points;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A ground-truth folder, read and checked.
#[derive(Clone, Debug)]
pub struct GroundTruth {
    /// The folder holding `info.json`.
    pub root: PathBuf,
    /// `info.json`'s `size`, scene units, finite and positive.
    pub size: f64,
    /// Frames 0..frames have a mesh (counted from `000000.ply` up to the first gap).
    pub frames: usize,
    /// `points.csv`: frame-0 positions by id.
    pub points: Vec<(String, [f64; 3])>,
    /// `tracks.csv`: every row names a point of `points`.
    pub tracks: Vec<TrackPoint>,
}

/// The ground-truth folder of `dir`: `dir/gt` when it holds `info.json`, else `dir` itself
/// when it does; None when neither does (not a benchmark dataset).
pub fn find_ground_truth(dir: &Path) -> Option<PathBuf> {
    [dir.join("gt"), dir.to_owned()].into_iter().find(|d| d.join("info.json").is_file())
}

impl GroundTruth {
    /// Reads the folder `root` (as found by [`find_ground_truth`]). Every problem is an error
    /// naming its file: no `size`, a bad CSV row (NaN included), a track of an unknown
    /// point, no frame-0 mesh.
    pub fn read(root: &Path) -> Result<Self, SequenceEvalError> {
        let size = read_size(&root.join("info.json"))?;
        let points = read_points(&root.join("points.csv")).map_err(SequenceEvalError::Query)?;
        let tracks_path = root.join("tracks.csv");
        let tracks = read_trajectories_csv(&tracks_path).map_err(SequenceEvalError::Read)?;
        let ids: HashSet<&str> = points.iter().map(|(id, _)| id.as_str()).collect();
        if let Some(t) = tracks.iter().find(|t| !ids.contains(t.id.as_str())) {
            let problem = format!("point `{}` (frame {}) is not in points.csv", t.id, t.frame);
            return Err(SequenceEvalError::Invalid { path: tracks_path, problem });
        }
        let gt = GroundTruth { root: root.to_owned(), size, frames: 0, points, tracks };
        let frames = (0..).take_while(|&t| gt.mesh_path(t).is_file()).count();
        if frames == 0 {
            return Err(SequenceEvalError::Invalid {
                path: gt.mesh_path(0),
                problem: "missing: the ground truth needs a frame-0 mesh".into(),
            });
        }
        Ok(GroundTruth { frames, ..gt })
    }

    /// `meshes/FFFFFF.ply` of frame `t`.
    pub fn mesh_path(&self, t: usize) -> PathBuf {
        self.root.join("meshes").join(format!("{}.ply", frame_name(t)))
    }
}

/// `size` of an `info.json`: a finite positive number.
fn read_size(path: &Path) -> Result<f64, SequenceEvalError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| SequenceEvalError::Io { path: path.to_owned(), source })?;
    let invalid = |problem: String| SequenceEvalError::Invalid { path: path.to_owned(), problem };
    let info: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| invalid(format!("not JSON: {e}")))?;
    match info.get("size") {
        Some(v) => v.as_f64().filter(|s| s.is_finite() && *s > 0.0).ok_or_else(|| {
            invalid(format!("`size` is {v}, expected a positive number (scene units)"))
        }),
        None => Err(invalid(
            "no `size` (the largest side of frame 0's bounding box, the unit of every score)"
                .into(),
        )),
    }
}
