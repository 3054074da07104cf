//! MDD point caches (LightWave's MotionDesigner format, written by Houdini, LightWave and
//! Blender's `io_shape_mdd`): per-frame vertex positions and the time of each frame, no faces.
//!
//! Layout, big-endian: i32 frame count, i32 point count, f32 time of each frame in seconds, then
//! f32 x y z per point per frame. A file whose size differs from what its header promises is
//! refused.
//!
//! An MDD holds no faces, so a sequence is an MDD with its base mesh beside it: `anim.mdd` and
//! `anim.obj` (as for PC2; see `sequence::point_cache`). Blender's exporter writes world-space positions in Blender's axes
//! (+Z up; its Y/Z flip is commented out), times `k / fps` from 0 whatever the start frame, and
//! with "Rest Frame" on, one extra first frame: the start frame's evaluated mesh again (so frame
//! 0 and 1 are equal and the count is end − start + 2). Both are read as the file says.

use super::write_atomically;
use std::io::Write;
use std::path::{Path, PathBuf};

const HEADER_BYTES: usize = 8;

/// An error that names the MDD file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct MddError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: String,
}

fn error(path: &Path, problem: impl Into<String>) -> MddError {
    MddError { path: path.to_path_buf(), problem: problem.into() }
}

/// The contents of an MDD file.
#[derive(Clone, Debug, PartialEq)]
pub struct Mdd {
    /// Time of each frame in seconds, as stored (not checked for order: see
    /// [`crate::sequence::SourceSequence::into_sequence`]).
    pub times: Vec<f32>,
    /// Vertex positions of each frame, all of one length.
    pub frames: Vec<Vec<[f32; 3]>>,
}

/// Reads an MDD file.
pub fn read_mdd(path: &Path) -> Result<Mdd, MddError> {
    let bytes = std::fs::read(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    parse_mdd(path, &bytes)
}

/// Parses MDD bytes; `path` only names the source in errors. Errors: a short header, negative
/// counts, frames of no points, a body shorter or longer than the header promises (checked
/// before anything is allocated). Times and positions are returned as stored.
pub fn parse_mdd(path: &Path, bytes: &[u8]) -> Result<Mdd, MddError> {
    if bytes.len() < HEADER_BYTES {
        return Err(error(
            path,
            format!("truncated: {} bytes, an MDD header alone has {HEADER_BYTES}", bytes.len()),
        ));
    }
    let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
    let (frames, points) = (i32::from_be_bytes(word(0)), i32::from_be_bytes(word(4)));
    let (Ok(frames), Ok(points)) = (usize::try_from(frames), usize::try_from(points)) else {
        return Err(error(path, format!("negative count ({frames} frames, {points} points)")));
    };
    if points == 0 && frames > 0 {
        return Err(error(path, format!("{frames} frames of 0 points: no positions to read")));
    }
    // Checked, so that the size every allocation below is bounded by cannot wrap.
    let expected = points
        .checked_mul(12)
        .and_then(|n| n.checked_add(4))
        .and_then(|n| n.checked_mul(frames))
        .and_then(|n| n.checked_add(HEADER_BYTES))
        .filter(|&n| n <= bytes.len())
        .ok_or_else(|| {
            error(path, format!(
                "truncated: {} bytes, the header promises {frames} frames x ({points} points x 12 + 4) + {HEADER_BYTES}",
                bytes.len()
            ))
        })?;
    if bytes.len() > expected {
        return Err(error(
            path,
            format!(
                "{} bytes after the {frames} frames of {points} points the header promises",
                bytes.len() - expected
            ),
        ));
    }
    let float = |at: usize| f32::from_be_bytes(word(at));
    let times = (0..frames).map(|t| float(HEADER_BYTES + 4 * t)).collect();
    let body = HEADER_BYTES + 4 * frames;
    let frames = (0..frames)
        .map(|t| {
            let base = body + t * points * 12;
            (0..points).map(|p| [0, 4, 8].map(|axis| float(base + p * 12 + axis))).collect()
        })
        .collect();
    Ok(Mdd { times, frames })
}

/// Writes an MDD file, atomically. Errors: a time count that is not the frame count, frames of
/// different lengths or of no points, counts beyond i32.
pub fn write_mdd(path: &Path, mdd: &Mdd) -> Result<(), MddError> {
    let points = mdd.frames.first().map_or(0, Vec::len);
    if mdd.times.len() != mdd.frames.len() {
        return Err(error(
            path,
            format!("cannot write: {} times for {} frames", mdd.times.len(), mdd.frames.len()),
        ));
    }
    if let Some(t) = mdd.frames.iter().position(|f| f.len() != points) {
        return Err(error(
            path,
            format!(
                "cannot write: frame {t} has {} points, frame 0 has {points}",
                mdd.frames[t].len()
            ),
        ));
    }
    if points == 0 && !mdd.frames.is_empty() {
        return Err(error(path, "cannot write: frames of 0 points (the reader refuses them)"));
    }
    let (Ok(n), Ok(count)) = (i32::try_from(points), i32::try_from(mdd.frames.len())) else {
        return Err(error(path, "cannot write: more points or frames than MDD's i32 counts hold"));
    };
    write_atomically(path, |w| {
        w.write_all(&count.to_be_bytes())?;
        w.write_all(&n.to_be_bytes())?;
        for t in &mdd.times {
            w.write_all(&t.to_be_bytes())?;
        }
        for c in mdd.frames.iter().flatten().flatten() {
            w.write_all(&c.to_be_bytes())?;
        }
        Ok(())
    })
    .map_err(|e| error(path, format!("cannot write: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mdd() -> Mdd {
        Mdd {
            times: vec![0.0, 0.04],
            frames: vec![
                vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
                vec![[-1.5, 1e-30, 7.0], [8.0, 9.0, 1e30]],
            ],
        }
    }

    #[test]
    fn round_trip_and_byte_layout() {
        let path = std::env::temp_dir().join(format!("tagsplat-mdd-{}.mdd", std::process::id()));
        write_mdd(&path, &mdd()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 8 + 2 * 4 + 2 * 2 * 12);
        assert_eq!(bytes[..4], 2i32.to_be_bytes());
        assert_eq!(bytes[4..8], 2i32.to_be_bytes());
        assert_eq!(bytes[12..16], 0.04f32.to_be_bytes(), "the second time");
        assert_eq!(bytes[16 + 12..16 + 16], 3.0f32.to_be_bytes(), "point 1 follows point 0");
        assert_eq!(read_mdd(&path).unwrap(), mdd());
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn damaged_files_are_refused_with_the_reason() {
        let path =
            std::env::temp_dir().join(format!("tagsplat-mdd-bad-{}.mdd", std::process::id()));
        write_mdd(&path, &mdd()).unwrap();
        let good = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let header = |frames: i32, points: i32| {
            [&frames.to_be_bytes()[..], &points.to_be_bytes(), &good[8..]].concat()
        };
        for (bytes, needle) in [
            (
                good[..good.len() - 1].to_vec(),
                "truncated: 63 bytes, the header promises 2 frames x (2 points x 12 + 4) + 8",
            ),
            // Refused from the header alone, before anything is allocated.
            (header(i32::MAX, 2), "the header promises 2147483647 frames x (2 points"),
            (header(i32::MAX, i32::MAX), "2147483647 frames x (2147483647 points"),
            (header(i32::MAX, 0), "2147483647 frames of 0 points: no positions to read"),
            (good[..5].to_vec(), "truncated: 5 bytes, an MDD header alone has 8"),
            ([good.as_slice(), &[0]].concat(), "1 bytes after the 2 frames of 2 points"),
            (header(-1, 2), "negative count (-1 frames, 2 points)"),
        ] {
            let e = parse_mdd(Path::new("anim.mdd"), &bytes).unwrap_err().to_string();
            assert!(e.starts_with("anim.mdd: ") && e.contains(needle), "{e}");
        }
        let ragged = Mdd { frames: vec![vec![[0.0; 3]; 2], vec![[0.0; 3]; 1]], ..mdd() };
        let refused = |m: &Mdd| write_mdd(&path, m).unwrap_err().to_string();
        assert!(refused(&ragged).contains("frame 1 has 1 points"));
        assert!(refused(&Mdd { times: vec![0.0], ..mdd() }).contains("1 times for 2 frames"));
        let no_points = Mdd { times: vec![0.0; 3], frames: vec![Vec::new(); 3] };
        assert!(refused(&no_points).contains("frames of 0 points"));
        assert!(!path.exists());
    }
}
