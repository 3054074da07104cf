//! A sequence as an animation file stores it, before it becomes a [`MeshSequence`]: polygons
//! of any size, positions per sample, the sample times, and what the file says about its axes.
//! Every animation reader (glTF, USD, Alembic, FBX, MDD) returns one, and
//! [`SourceSequence::into_sequence`] checks it and fans its polygons into triangles the same way
//! for every format.

use super::orient::SignedAxis;
use super::MeshSequence;
use crate::mesh::polygon::fan_triangulate;

/// Samples per second of an animation (glTF, FBX) whose keys set no rate of their own.
pub const SAMPLING_FPS: f64 = 30.0;

/// The frame rate of a sequence whose file has no clock (a folder of frames, OBJ + PC2).
pub const CLOCKLESS_FPS: f64 = 24.0;

/// What to read from a file that holds more than one thing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// glTF and FBX: the animation (take) to play, by name or index. None: the file's only
    /// one; a file with several and no choice is an error that lists them.
    pub animation: Option<String>,
    /// glTF and FBX: samples per second. None: the animation's own key rate, else 30.
    pub fps: Option<f64>,
    /// The mesh to read when a file holds several: a USD prim path, an Alembic object path, a
    /// glTF or FBX node name. None: the only one; several and no choice is an error that lists
    /// them.
    pub mesh: Option<String>,
}

/// A sequence as read, polygons not yet triangulated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SourceSequence {
    /// Vertex count of each polygon, in file order.
    pub counts: Vec<u32>,
    /// The polygons' vertex indices, concatenated, counter-clockwise seen from outside (the
    /// reader of a clockwise format, Alembic's, reverses each polygon).
    pub indices: Vec<u32>,
    /// Vertex positions of each frame, in the file's units and axes.
    pub frames: Vec<Vec<[f32; 3]>>,
    /// Time of each frame in seconds, strictly increasing.
    pub times: Vec<f64>,
    /// Frame-0 vertex colours, when the file has them.
    pub colors: Option<Vec<[u8; 3]>>,
    /// The file's up axis, when it says (USD `upAxis`, FBX's axis system, glTF's +Y).
    pub up: Option<SignedAxis>,
    /// Metres per file unit, when the file says (USD `metersPerUnit`, FBX's unit scale).
    pub meters_per_unit: Option<f64>,
    /// What the reader chose or noticed, for the user, e.g. "animation `Run` (2 of 3), 25 keys
    /// per second" or "no animation: one frame".
    pub notes: Vec<String>,
}

/// What a read said about the sequence beside its frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SequenceInfo {
    /// Time of each frame in seconds; None where the format has no clock (a folder of frames).
    pub times: Option<Vec<f64>>,
    /// Frames per second: the file's own rate or the rate it was sampled at.
    pub fps: Option<f64>,
    /// Per triangle of the sequence, the file polygon it was fanned from; None when the file's
    /// faces are the triangles.
    pub polygon_of: Option<Vec<u32>>,
    /// The file's up axis, when it says.
    pub up: Option<SignedAxis>,
    /// Metres per file unit, when the file says.
    pub meters_per_unit: Option<f64>,
    /// What the reader chose or noticed (see [`SourceSequence::notes`]).
    pub notes: Vec<String>,
}

impl SourceSequence {
    /// The triangulated sequence and what the file said, after checking that there is a frame,
    /// that every frame has the same vertex count, that every polygon has 3 or more vertices in
    /// range, that the times are finite and strictly increasing, one per frame, and that every
    /// position is finite. Errors are the problem, for the caller to put after the file name.
    pub fn into_sequence(self) -> Result<(MeshSequence, SequenceInfo), String> {
        let n = self.frames.first().map(Vec::len).ok_or("the file holds no frames")?;
        if let Some(t) = self.frames.iter().position(|f| f.len() != n) {
            return Err(format!(
                "frame {t} has {} vertices, frame 0 has {n}",
                self.frames[t].len()
            ));
        }
        check_times(&self.times, self.frames.len())?;
        let (faces, polygon_of) = fan_triangulate(&self.counts, &self.indices, n)?;
        let all_triangles = self.counts.iter().all(|&c| c == 3);
        let frames = self.frames.len();
        let sequence = MeshSequence {
            faces,
            colors: self.colors.map(|c| vec![c; frames]),
            frames: self.frames,
        };
        if let Some(problem) = sequence.problem() {
            return Err(problem);
        }
        let info = SequenceInfo {
            fps: fps_of(&self.times),
            times: Some(self.times),
            polygon_of: (!all_triangles).then_some(polygon_of),
            up: self.up,
            meters_per_unit: self.meters_per_unit,
            notes: self.notes,
        };
        Ok((sequence, info))
    }
}

/// One finite time per frame, strictly increasing.
fn check_times(times: &[f64], frames: usize) -> Result<(), String> {
    if times.len() != frames {
        return Err(format!("{} frame times for {frames} frames", times.len()));
    }
    if let Some(t) = times.iter().position(|t| !t.is_finite()) {
        return Err(format!("frame {t} has time {}", times[t]));
    }
    match times.windows(2).position(|w| w[1] <= w[0]) {
        Some(t) => Err(format!(
            "time samples out of order: frame {} at {} s follows frame {t} at {} s",
            t + 1,
            times[t + 1],
            times[t]
        )),
        None => Ok(()),
    }
}

/// The rate of evenly spaced times (within 0.1 % of their mean step); None for one frame or
/// uneven steps.
fn fps_of(times: &[f64]) -> Option<f64> {
    let (first, last) = (times.first()?, times.last()?);
    let step = (last - first) / (times.len() - 1).max(1) as f64;
    let even = times.windows(2).all(|w| ((w[1] - w[0]) - step).abs() <= 1e-3 * step);
    (times.len() > 1 && even).then(|| 1.0 / step)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(frames: Vec<Vec<[f32; 3]>>, times: Vec<f64>) -> SourceSequence {
        SourceSequence {
            counts: vec![4],
            indices: vec![0, 1, 2, 3],
            frames,
            times,
            ..SourceSequence::default()
        }
    }

    #[test]
    fn a_quad_becomes_two_triangles_of_one_polygon_at_the_sampled_rate() {
        let f = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let (sequence, info) = quad(vec![f.clone(), f], vec![0.0, 0.04]).into_sequence().unwrap();
        assert_eq!(sequence.faces, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(info.polygon_of, Some(vec![0, 0]));
        assert!((info.fps.unwrap() - 25.0).abs() < 1e-9);
    }

    #[test]
    fn refuses_changing_counts_bad_times_and_nan() {
        let f = vec![[0.0; 3]; 4];
        let short = vec![[0.0; 3]; 3];
        let fail = |s: SourceSequence| s.into_sequence().unwrap_err();
        assert!(fail(quad(vec![f.clone(), short], vec![0.0, 1.0])).contains("frame 1 has 3"));
        assert!(fail(quad(vec![f.clone(), f.clone()], vec![1.0, 1.0])).contains("out of order"));
        assert!(fail(quad(vec![f.clone()], vec![f64::NAN])).contains("time NaN"));
        assert!(fail(quad(vec![f.clone()], vec![])).contains("0 frame times"));
        let mut nan = f.clone();
        nan[2][1] = f32::NAN;
        assert!(fail(quad(vec![nan], vec![0.0])).contains("frame 0"));
        assert!(fail(quad(vec![], vec![])).contains("no frames"));
    }
}
