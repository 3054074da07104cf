//! `tagsplat bench read`: how long reading a large sequence takes in each format the engine
//! writes, against reading the same sequence as OBJ + PC2 in the same run (the layout 4D
//! capture vendors deliver, and the bound the issue sets: any format within 2× of it).
//! Files of other tools (a `.usdc`, an `.abc`, an `.fbx` of the same motion) can be timed
//! beside them. Each row also has a bare parse of the same bytes: the time to read them and,
//! for a text format, to parse each decimal in them with the standard float parser and build
//! nothing, which says how much of a text reader's time its numbers alone cost.

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
    /// A bare parse of these bytes (see the module docs): the fastest of the repetitions, ms.
    pub parse_ms: f64,
    /// `parse_ms` over the OBJ + PC2 read of the same run.
    pub parse_over_pc2: f64,
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
    let text =
        |file: &Path| file.ends_with("frames") || file.extension().is_some_and(|e| e == "usda");
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
        let (bytes, parse_ms) = (disk_bytes(&file), parse_ms(&file, text(&file), repetitions)?);
        let (over_pc2, parse_over_pc2) = (0.0, 0.0);
        formats.push(ReadTiming {
            file: name,
            bytes,
            read_ms,
            over_pc2,
            parse_ms,
            parse_over_pc2,
            same_frames,
        });
    }
    let pc2 = formats[0].read_ms;
    for f in &mut formats {
        (f.over_pc2, f.parse_over_pc2) = (f.read_ms / pc2, f.parse_ms / pc2);
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

/// A bare parse of `path` (a file, or a folder's files), fastest of `repetitions`, ms: its bytes
/// read and, when it is `text`, each decimal in them parsed by the standard (exact) float
/// parser, on every thread (a folder's files spread over them, a file's text cut at line ends),
/// and nothing built. A text reader using the same parser spends about this on numbers alone.
fn parse_ms(path: &Path, text: bool, repetitions: usize) -> Result<f64, SequenceError> {
    let files: Vec<PathBuf> = match std::fs::read_dir(path) {
        Ok(entries) => entries.flatten().map(|e| e.path()).collect(),
        Err(_) => vec![path.to_owned()],
    };
    let mut best = f64::INFINITY;
    for _ in 0..repetitions.max(1) {
        let start = Instant::now();
        std::hint::black_box(read_all(&files, text)?);
        best = best.min(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(best)
}

/// Reads `files` on every thread and, when `text`, parses the decimals in them; how many.
fn read_all(files: &[PathBuf], text: bool) -> Result<usize, SequenceError> {
    // A single file is cut at line ends so that its text too is spread over the threads.
    let threads = match files.len() {
        1 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        _ => 1,
    };
    let counts = crate::io::host::parallel_map(files, |file| -> Result<usize, SequenceError> {
        let bytes = std::fs::read(file).map_err(|e| SequenceError::Invalid {
            path: file.clone(),
            problem: format!("cannot read: {e}"),
        })?;
        if !text {
            return Ok(0);
        }
        let chunks = line_chunks(&bytes, threads);
        let counts =
            crate::io::host::parallel_map(&chunks, |c| Ok::<_, SequenceError>(count_numbers(c)))?;
        Ok(counts.iter().sum::<usize>())
    })?;
    Ok(counts.iter().sum())
}

/// `bytes` cut into about `parts` pieces, each ending at a line end (or the end).
fn line_chunks(bytes: &[u8], parts: usize) -> Vec<&[u8]> {
    let (mut chunks, mut rest) = (Vec::new(), bytes);
    let step = bytes.len().div_ceil(parts.max(1)).max(1);
    while !rest.is_empty() {
        let cut =
            rest.iter().skip(step).position(|&b| b == b'\n').map_or(rest.len(), |i| step + i + 1);
        let (head, tail) = rest.split_at(cut.min(rest.len()));
        chunks.push(head);
        rest = tail;
    }
    chunks
}

/// How many of the words of `bytes` (split at white space and commas, brackets and parentheses
/// trimmed) written as decimals (with a point or an exponent: the coordinates) parse as an `f32`, each
/// one parsed as a reader of the text must. Integers (face indices, counts) are left alone: a
/// reader may compare a frame's face text with frame 0's instead of parsing it again.
fn count_numbers(bytes: &[u8]) -> usize {
    let separator = |b: &u8| b.is_ascii_whitespace() || *b == b',';
    fn trim(w: &[u8]) -> &[u8] {
        let bracket = |b: &u8| b"()[]{}".contains(b);
        let start = w.iter().position(|b| !bracket(b)).unwrap_or(w.len());
        let end = w.iter().rposition(|b| !bracket(b)).map_or(start, |i| i + 1);
        &w[start..end.max(start)]
    }
    let decimal = |w: &&[u8]| w.iter().any(|b| matches!(b, b'.' | b'e' | b'E'));
    let number = |w: &[u8]| std::str::from_utf8(w).is_ok_and(|w| w.parse::<f32>().is_ok());
    bytes.split(separator).map(trim).filter(decimal).filter(|w| number(w)).count()
}

/// Bytes of a file, or of every file in a folder.
fn disk_bytes(path: &Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries.flatten().filter_map(|e| e.metadata().ok()).map(|m| m.len()).sum(),
        Err(_) => std::fs::metadata(path).map_or(0, |m| m.len()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_end_at_line_ends_and_join_back() {
        let text = b"v 0.5 -1.25 3e2\nf 1/2/3 4 5\nv 1.0 2.0 3.0\nlast 0.5";
        for parts in [1, 2, 3, 7, 100] {
            let chunks = line_chunks(text, parts);
            assert_eq!(chunks.concat(), text, "{parts} parts");
            let (last, whole) = chunks.split_last().unwrap();
            assert!(whole.iter().all(|c| c.ends_with(b"\n")) && !last.is_empty(), "{parts}");
        }
        assert!(line_chunks(b"", 4).is_empty());
    }

    #[test]
    fn decimals_are_counted_and_integers_and_words_are_not() {
        let text =
            b"v 0.5 -1.25 3e2\nf 1/2/3 4 5\npoint3f[] points = [(0.25, 1.5, -.5)]\nname.obj e";
        assert_eq!(count_numbers(text), 6);
    }
}
