//! `tagsplat bench read`: how long reading a large sequence takes in each format the engine
//! writes, against reading the same sequence as OBJ + PC2 in the same run (the layout 4D
//! capture vendors deliver, and the bound the issue sets: any format within 2× of it).
//! Files of other tools (a `.usdc`, an `.abc`, an `.fbx` of the same motion) can be timed
//! beside them.

use super::{FrameFormat, MeshSequence, SequenceError};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One format's reading time.
#[derive(Clone, Debug, Serialize)]
pub struct ReadTiming {
    /// The file or folder read (its name in the scratch folder, or as given).
    pub file: String,
    /// Bytes on disk (a folder: all its files).
    pub bytes: u64,
    /// Fastest read of the repetitions, ms.
    pub read_ms: f64,
    /// `read_ms` over the OBJ + PC2 read of the same run.
    pub over_pc2: f64,
    /// The frames read equal the sequence written, position for position (a file given from
    /// outside: its frame and vertex counts equal the written sequence's).
    pub same_frames: bool,
}

/// What one `bench read` run measured (one thread).
#[derive(Clone, Debug, Serialize)]
pub struct ReadBenchReport {
    /// Vertices per frame.
    pub vertices: usize,
    /// Frames.
    pub frames: usize,
    /// Reads timed per format; the fastest is kept.
    pub repetitions: usize,
    /// One row per format, OBJ + PC2 first.
    pub formats: Vec<ReadTiming>,
    /// The slowest `over_pc2`.
    pub worst_over_pc2: f64,
}

/// A `side` × `side` grid of quads (as triangles) rippling over `frames` frames: a sequence of
/// side² vertices whose every coordinate changes every frame, as a capture's do.
pub fn ripple(side: usize, frames: usize) -> MeshSequence {
    let side = side.max(2);
    let at = |i: usize, j: usize| (i * side + j) as u32;
    let faces = (0..side - 1)
        .flat_map(|i| (0..side - 1).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
        })
        .collect();
    let frame = |t: usize| {
        let phase = t as f32 * 0.05;
        (0..side * side)
            .map(|k| {
                let (x, y) = ((k / side) as f32 / side as f32, (k % side) as f32 / side as f32);
                [x + 0.01 * phase.sin(), y, 0.1 * (6.0 * x + phase).sin() * (4.0 * y).cos()]
            })
            .collect()
    };
    MeshSequence { faces, frames: (0..frames).map(frame).collect(), colors: None }
}

/// Writes `sequence` into `scratch` as OBJ + PC2, MDD, GLB, USDA and an OBJ folder, then times
/// `repetitions` reads of each and of every file in `extra` (another tool's export of the same
/// motion), fastest kept.
pub fn bench_read(
    sequence: &MeshSequence,
    scratch: &Path,
    extra: &[PathBuf],
    repetitions: usize,
) -> Result<ReadBenchReport, SequenceError> {
    let keep = super::orient::Orientation::keep(super::orient::UpAxis::Y);
    let written = ["anim.pc2", "anim.mdd", "anim.glb", "anim.usda", "frames"];
    for name in written {
        sequence.export(&scratch.join(name), FrameFormat::Obj, 24.0, keep)?;
    }
    let files = written.iter().map(|n| scratch.join(n)).chain(extra.iter().cloned());
    let mut formats = Vec::new();
    for file in files {
        let (read_ms, back) = fastest_read(&file, repetitions)?;
        let same_frames = if extra.contains(&file) {
            back.frames.len() == sequence.frames.len() && back.faces.len() >= sequence.faces.len()
        } else {
            back.frames == sequence.frames
        };
        let name = file.strip_prefix(scratch).unwrap_or(&file).display().to_string();
        let bytes = disk_bytes(&file);
        formats.push(ReadTiming { file: name, bytes, read_ms, over_pc2: 0.0, same_frames });
    }
    let pc2 = formats[0].read_ms;
    for f in &mut formats {
        f.over_pc2 = f.read_ms / pc2;
    }
    let worst_over_pc2 = formats.iter().map(|f| f.over_pc2).fold(0.0, f64::max);
    let (vertices, frames) = (sequence.frames[0].len(), sequence.frames.len());
    Ok(ReadBenchReport { vertices, frames, repetitions, formats, worst_over_pc2 })
}

/// The fastest of `repetitions` reads of `path` in ms, and what it read.
fn fastest_read(path: &Path, repetitions: usize) -> Result<(f64, MeshSequence), SequenceError> {
    let mut best = (f64::INFINITY, MeshSequence::default());
    for _ in 0..repetitions.max(1) {
        let start = Instant::now();
        let sequence = MeshSequence::read(path)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if ms < best.0 {
            best = (ms, sequence);
        }
    }
    Ok(best)
}

/// Bytes of a file, or of every file in a folder.
fn disk_bytes(path: &Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries.flatten().filter_map(|e| e.metadata().ok()).map(|m| m.len()).sum(),
        Err(_) => std::fs::metadata(path).map_or(0, |m| m.len()),
    }
}
