//! PC2 point caches (the format Blender, Maya and 3ds Max read): per-sample vertex positions.
//!
//! Layout, little-endian: the 12 bytes `POINTCACHE2\0`, i32 version (1), i32 point count,
//! f32 start frame, f32 sample rate (frames per sample), i32 sample count, then f32 x y z per
//! point per sample. A file whose size differs from what its header promises is refused.

use std::io::Write;
use std::path::{Path, PathBuf};

const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";
const HEADER_BYTES: usize = 32;

/// An error that names the PC2 file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct Pc2Error {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: String,
}

fn error(path: &Path, problem: impl Into<String>) -> Pc2Error {
    Pc2Error { path: path.to_path_buf(), problem: problem.into() }
}

/// The contents of a PC2 file.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCache {
    /// Frame of the first sample.
    pub start_frame: f32,
    /// Frames per sample (1 = one sample per frame).
    pub sample_rate: f32,
    /// Vertex positions per sample, all of one length.
    pub samples: Vec<Vec<[f32; 3]>>,
}

/// Reads a PC2 file.
pub fn read_pc2(path: &Path) -> Result<PointCache, Pc2Error> {
    let bytes = std::fs::read(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    parse_pc2(path, &bytes)
}

/// Parses PC2 bytes; `path` only names the source in errors. Errors: a short header, a wrong
/// signature or version, negative counts, samples of no points, a body shorter or longer than
/// the header promises (checked before anything is allocated), a non-finite coordinate.
pub fn parse_pc2(path: &Path, bytes: &[u8]) -> Result<PointCache, Pc2Error> {
    if bytes.len() < HEADER_BYTES {
        return Err(error(
            path,
            format!("truncated: {} bytes, a PC2 header alone has {HEADER_BYTES}", bytes.len()),
        ));
    }
    if &bytes[..12] != SIGNATURE {
        return Err(error(path, "not a PC2 file (no POINTCACHE2 signature)"));
    }
    let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
    let version = i32::from_le_bytes(word(12));
    if version != 1 {
        return Err(error(path, format!("version {version}, only version 1 exists")));
    }
    let points = i32::from_le_bytes(word(16));
    let start_frame = f32::from_le_bytes(word(20));
    let sample_rate = f32::from_le_bytes(word(24));
    let samples = i32::from_le_bytes(word(28));
    let (Ok(points), Ok(samples)) = (usize::try_from(points), usize::try_from(samples)) else {
        return Err(error(path, format!("negative count ({points} points, {samples} samples)")));
    };
    // Samples of no points take no bytes, so the file size cannot bound how many there are.
    if points == 0 && samples > 0 {
        return Err(error(path, format!("{samples} samples of 0 points: no positions to read")));
    }
    // Checked, so that the size every allocation below is bounded by cannot wrap.
    let expected = points
        .checked_mul(samples)
        .and_then(|n| n.checked_mul(12))
        .and_then(|n| n.checked_add(HEADER_BYTES))
        .filter(|&n| n <= bytes.len())
        .ok_or_else(|| {
            error(path, format!(
                "truncated: {} bytes, the header promises {points} points x {samples} samples x 12 + {HEADER_BYTES}",
                bytes.len()
            ))
        })?;
    if bytes.len() > expected {
        return Err(error(
            path,
            format!(
                "{} bytes after the {points} points x {samples} samples the header promises",
                bytes.len() - expected
            ),
        ));
    }
    let mut out = Vec::with_capacity(samples);
    for s in 0..samples {
        let base = HEADER_BYTES + s * points * 12;
        let sample: Vec<[f32; 3]> = (0..points)
            .map(|p| {
                let at = base + p * 12;
                [
                    f32::from_le_bytes(word(at)),
                    f32::from_le_bytes(word(at + 4)),
                    f32::from_le_bytes(word(at + 8)),
                ]
            })
            .collect();
        if let Some(p) = sample.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(error(
                path,
                format!("sample {s}, point {p} is not finite: {:?}", sample[p]),
            ));
        }
        out.push(sample);
    }
    Ok(PointCache { start_frame, sample_rate, samples: out })
}

/// Writes a PC2 file, atomically. Errors: samples of different lengths or of no points, counts
/// beyond i32.
pub fn write_pc2(path: &Path, cache: &PointCache) -> Result<(), Pc2Error> {
    let points = cache.samples.first().map_or(0, Vec::len);
    if let Some(s) = cache.samples.iter().position(|s| s.len() != points) {
        return Err(error(
            path,
            format!(
                "cannot write: sample {s} has {} points, sample 0 has {points}",
                cache.samples[s].len()
            ),
        ));
    }
    if points == 0 && !cache.samples.is_empty() {
        return Err(error(path, "cannot write: samples of 0 points (the reader refuses them)"));
    }
    let (Ok(n), Ok(count)) = (i32::try_from(points), i32::try_from(cache.samples.len())) else {
        return Err(error(path, "cannot write: more points or samples than PC2's i32 counts hold"));
    };
    crate::io::write_atomically(path, |w| {
        w.write_all(SIGNATURE)?;
        w.write_all(&1i32.to_le_bytes())?;
        w.write_all(&n.to_le_bytes())?;
        w.write_all(&cache.start_frame.to_le_bytes())?;
        w.write_all(&cache.sample_rate.to_le_bytes())?;
        w.write_all(&count.to_le_bytes())?;
        for c in cache.samples.iter().flatten().flatten() {
            w.write_all(&c.to_le_bytes())?;
        }
        Ok(())
    })
    .map_err(|e| error(path, format!("cannot write: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cache() -> PointCache {
        PointCache {
            start_frame: 1.0,
            sample_rate: 1.0,
            samples: vec![
                vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
                vec![[-1.5, 1e-30, 7.0], [8.0, 9.0, 1e30]],
            ],
        }
    }

    #[test]
    fn round_trip_and_byte_layout() {
        let path = std::env::temp_dir().join(format!("tagsplat-pc2-{}.pc2", std::process::id()));
        write_pc2(&path, &cache()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 32 + 2 * 2 * 12);
        assert_eq!(&bytes[..12], b"POINTCACHE2\0");
        assert_eq!(bytes[16..20], 2i32.to_le_bytes());
        assert_eq!(bytes[28..32], 2i32.to_le_bytes());
        assert_eq!(
            bytes[32 + 12..32 + 16],
            3.0f32.to_le_bytes(),
            "point 1 of sample 0 follows point 0"
        );
        assert_eq!(read_pc2(&path).unwrap(), cache());
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn damaged_files_are_refused_with_the_reason() {
        let path =
            std::env::temp_dir().join(format!("tagsplat-pc2-bad-{}.pc2", std::process::id()));
        write_pc2(&path, &cache()).unwrap();
        let good = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let p = Path::new("anim.pc2");
        let with = |at: usize, value: [u8; 4]| {
            let mut b = good.clone();
            b[at..at + 4].copy_from_slice(&value);
            b
        };
        let header = |points: i32, samples: i32| {
            let counts = [&points.to_le_bytes()[..], &good[20..28], &samples.to_le_bytes()];
            [&good[..16], &counts.concat()].concat()
        };
        for (bytes, needle) in [
            (
                good[..good.len() - 1].to_vec(),
                "truncated: 79 bytes, the header promises 2 points x 2 samples x 12 + 32",
            ),
            // Refused from the header alone, before anything is allocated.
            (header(2, i32::MAX), "32 bytes, the header promises 2 points x 2147483647 samples"),
            (header(i32::MAX, i32::MAX), "32 bytes, the header promises 2147483647 points x"),
            (header(0, i32::MAX), "2147483647 samples of 0 points: no positions to read"),
            (good[..20].to_vec(), "truncated: 20 bytes"),
            ([good.as_slice(), &[0]].concat(), "1 bytes after"),
            (with(0, *b"PONT"), "no POINTCACHE2 signature"),
            (with(12, 2i32.to_le_bytes()), "version 2"),
            (with(16, (-1i32).to_le_bytes()), "negative count"),
            (with(32, f32::NAN.to_le_bytes()), "sample 0, point 0 is not finite"),
        ] {
            let e = parse_pc2(p, &bytes).unwrap_err().to_string();
            assert!(e.starts_with("anim.pc2: ") && e.contains(needle), "{e}");
        }
        let ragged = PointCache { samples: vec![vec![[0.0; 3]; 2], vec![[0.0; 3]; 1]], ..cache() };
        assert!(write_pc2(&path, &ragged)
            .unwrap_err()
            .to_string()
            .contains("sample 1 has 1 points"));
        let no_points = PointCache { samples: vec![Vec::new(); 3], ..cache() };
        assert!(write_pc2(&path, &no_points)
            .unwrap_err()
            .to_string()
            .contains("samples of 0 points"));
    }
}
