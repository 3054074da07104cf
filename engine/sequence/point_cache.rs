//! A point cache beside its base mesh: `anim.pc2` or `anim.mdd` with `anim.obj`, the form 4D
//! capture vendors, Houdini and Blender deliver. The cache holds positions per frame, the OBJ
//! the faces (and frame-0 colours); the two must agree on the vertex count.

use super::{from_source, invalid, MeshSequence, SequenceError, SequenceInfo, SourceSequence};
use crate::io::mdd::{read_mdd as read_mdd_file, write_mdd as write_mdd_file, Mdd};
use crate::io::pc2::{self, PointCache};
use crate::mesh::TriMesh;
use std::path::Path;

impl MeshSequence {
    /// Reads `anim.pc2` and its base mesh `anim.obj`: faces (and colours) from the OBJ,
    /// positions of every frame from the PC2 samples.
    pub fn read_pc2(path: &Path) -> Result<Self, SequenceError> {
        let cache = pc2::read_pc2(path)?;
        let points = cache.samples.first().ok_or_else(|| invalid(path, "no samples"))?.len();
        let base = base_mesh(path, points, "sample")?;
        let frames = cache.samples.len();
        Ok(MeshSequence {
            faces: base.faces,
            colors: base.colors.map(|c| vec![c; frames]),
            frames: cache.samples,
        })
    }

    /// Writes `anim.pc2` (one sample per frame, starting at frame 0) and the base mesh
    /// `anim.obj` (frame 0, with frame-0 colours).
    pub fn write_pc2(&self, path: &Path) -> Result<(), SequenceError> {
        write_base_mesh(self, path)?;
        let cache = PointCache { start_frame: 0.0, sample_rate: 1.0, samples: self.frames.clone() };
        Ok(pc2::write_pc2(path, &cache)?)
    }
}

/// The sequence of `anim.mdd` and its base mesh `anim.obj`: faces (and frame-0 colours) from
/// the OBJ, positions and times from the MDD, checked as every reader's result is.
pub fn read_mdd(path: &Path) -> Result<(MeshSequence, SequenceInfo), SequenceError> {
    let format = |problem: String| SequenceError::Format { path: path.to_path_buf(), problem };
    let mdd = read_mdd_file(path).map_err(|e| format(e.problem))?;
    let points = mdd.frames.first().ok_or_else(|| format("the file holds no frames".into()))?;
    let base = base_mesh(path, points.len(), "frame")?;
    let source = SourceSequence {
        counts: vec![3; base.faces.len()],
        indices: base.faces.concat(),
        frames: mdd.frames,
        times: mdd.times.iter().map(|&t| f64::from(t)).collect(),
        colors: base.colors,
        ..SourceSequence::default()
    };
    from_source(path, Ok(source))
}

/// Writes `anim.mdd` (frame `t` at `t / fps` seconds) and the base mesh `anim.obj` (frame 0,
/// with frame-0 colours).
pub fn write_mdd(path: &Path, sequence: &MeshSequence, fps: f64) -> Result<(), SequenceError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(invalid(path, format!("cannot write: {fps} frames per second")));
    }
    write_base_mesh(sequence, path)?;
    let times = (0..sequence.frames.len()).map(|t| (t as f64 / fps) as f32).collect();
    let mdd = Mdd { times, frames: sequence.frames.clone() };
    write_mdd_file(path, &mdd).map_err(|e| invalid(path, e.problem))
}

/// The base mesh beside the cache `path`, which holds `points` per `unit` (sample, frame).
/// Errors name the cache: a missing or bad OBJ, or a vertex count that is not `points`.
fn base_mesh(path: &Path, points: usize, unit: &str) -> Result<TriMesh, SequenceError> {
    let base_path = path.with_extension("obj");
    if !base_path.is_file() {
        return Err(invalid(path, format!("the base mesh {} is missing", base_path.display())));
    }
    let base = TriMesh::read_obj(&base_path)?;
    if base.positions.len() != points {
        let (name, vertices) = (base_path.display(), base.positions.len());
        return Err(invalid(
            path,
            format!("{points} points per {unit}, the base mesh {name} has {vertices} vertices"),
        ));
    }
    Ok(base)
}

/// Checks `sequence` and writes its frame 0 as the base mesh beside the cache `path`.
fn write_base_mesh(sequence: &MeshSequence, path: &Path) -> Result<(), SequenceError> {
    sequence.check(path)?;
    let base = sequence.frame_mesh(0).ok_or_else(|| invalid(path, "no frames"))?;
    Ok(base.write_obj(&path.with_extension("obj"))?)
}
