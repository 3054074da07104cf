//! USD text (`.usda`) mesh sequences, the point-cache exchange that Blender, Maya, Houdini,
//! Unreal and Omniverse all import: one `Mesh` prim with the face list written once,
//! time-sampled `points` and `extent`, a per-frame `displayColor` primvar (linear, per vertex)
//! when the sequence has colours, and optionally tracked points as a time-sampled `Points` prim.
//! Stage metadata: `upAxis`, `metersPerUnit` 1 (scene units are written as metres),
//! `timeCodesPerSecond` and `framesPerSecond` = the frame rate, time codes 0..frames-1. USD's
//! default orientation (right-handed, counter-clockwise from outside) is the engine's winding.
//! Floats are written as shortest round-trip decimals, so a reader gets every f32 back exactly.

use super::glb::srgb_to_linear;
use super::orient::Orientation;
pub use super::orient::UpAxis;
use super::MeshSequence;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Tracked points to add: an id and a position per frame (scene units), each trajectory as
/// long as the sequence.
pub struct UsdTracks<'a> {
    /// One id per tracked point.
    pub ids: &'a [String],
    /// Per tracked point (in the order of `ids`), its position in every frame.
    pub trajectories: &'a [Vec<[f64; 3]>],
}

/// An error that names the `.usda` file and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct UsdError {
    /// The `.usda` file.
    pub path: PathBuf,
    /// What is wrong: the sequence, the frame rate, the tracks, or the write.
    pub problem: String,
}

/// Writes `sequence` (and `tracks`) to `path` atomically, turned by `orientation`, whose up
/// axis the stage declares. Errors: an unusable sequence, `fps`
/// not positive and finite, tracks whose lengths do not match the frames, a write failure.
pub fn write_usda(
    path: &Path,
    sequence: &MeshSequence,
    fps: f64,
    orientation: Orientation,
    tracks: Option<&UsdTracks>,
) -> Result<(), UsdError> {
    let fail = |problem: String| UsdError { path: path.to_owned(), problem };
    if let Some(problem) = sequence.problem() {
        return Err(fail(format!("cannot write: {problem}")));
    }
    if sequence.frames.is_empty() {
        return Err(fail("cannot write: the sequence has no frames".into()));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(fail(format!("cannot write: frame rate {fps} is not positive")));
    }
    if let Some(problem) = tracks.and_then(|t| track_problem(t, sequence.frames.len())) {
        return Err(fail(format!("cannot write the tracks: {problem}")));
    }
    let sequence = orientation.sequence(sequence);
    let trajectories: Option<Vec<Vec<[f64; 3]>>> = tracks.map(|t| {
        t.trajectories.iter().map(|p| p.iter().map(|&x| orientation.apply(x)).collect()).collect()
    });
    let tracks = tracks
        .zip(trajectories.as_deref())
        .map(|(t, trajectories)| UsdTracks { ids: t.ids, trajectories });
    let up = orientation.up;
    crate::io::write_atomically(path, |w| write_stage(w, &sequence, fps, up, tracks.as_ref()))
        .map_err(|e| fail(format!("cannot write: {e}")))
}

fn track_problem(tracks: &UsdTracks, frames: usize) -> Option<String> {
    if tracks.ids.len() != tracks.trajectories.len() {
        return Some(format!(
            "{} ids, {} trajectories",
            tracks.ids.len(),
            tracks.trajectories.len()
        ));
    }
    let bad = tracks.trajectories.iter().position(|t| t.len() != frames)?;
    Some(format!(
        "point {} has {} positions, the sequence {frames} frames",
        tracks.ids[bad],
        tracks.trajectories[bad].len()
    ))
}

fn write_stage(
    w: &mut impl Write,
    sequence: &MeshSequence,
    fps: f64,
    up: UpAxis,
    tracks: Option<&UsdTracks>,
) -> std::io::Result<()> {
    let last = sequence.frames.len() - 1;
    let up = up.name();
    writeln!(w, "#usda 1.0\n(\n    defaultPrim = \"Sequence\"\n    metersPerUnit = 1")?;
    writeln!(w, "    startTimeCode = 0\n    endTimeCode = {last}")?;
    writeln!(
        w,
        "    timeCodesPerSecond = {fps}\n    framesPerSecond = {fps}\n    upAxis = \"{up}\"\n)\n"
    )?;
    writeln!(w, "def Xform \"Sequence\" (\n    kind = \"component\"\n)\n{{")?;
    write_mesh(w, sequence)?;
    if let Some(tracks) = tracks {
        write_tracks(w, tracks)?;
    }
    writeln!(w, "}}")
}

fn write_mesh(w: &mut impl Write, sequence: &MeshSequence) -> std::io::Result<()> {
    writeln!(w, "    def Mesh \"Mesh\"\n    {{")?;
    writeln!(w, "        uniform token subdivisionScheme = \"none\"")?;
    write!(w, "        int[] faceVertexCounts = [")?;
    write_list(w, sequence.faces.iter().map(|_| 3))?;
    write!(w, "]\n        int[] faceVertexIndices = [")?;
    write_list(w, sequence.faces.iter().flatten())?;
    writeln!(w, "]")?;
    let extents = sequence.frames.iter().map(|f| extent(f.iter().map(|p| p.map(f64::from))));
    write_samples(w, "float3[] extent", None, extents.map(|[lo, hi]| vec![lo, hi]))?;
    let points = sequence.frames.iter().map(|f| f.iter().map(|p| p.map(f64::from)).collect());
    write_samples(w, "point3f[] points", None, points)?;
    if let Some(colors) = &sequence.colors {
        let linear = |c: &[u8; 3]| c.map(|v| f64::from(srgb_to_linear(v)));
        let samples = colors.iter().map(|frame| frame.iter().map(linear).collect());
        write_samples(w, "color3f[] primvars:displayColor", Some(VERTEX), samples)?;
    }
    writeln!(w, "    }}")
}

fn write_tracks(w: &mut impl Write, tracks: &UsdTracks) -> std::io::Result<()> {
    writeln!(w, "\n    def Points \"Tracks\"\n    {{")?;
    let frames = tracks.trajectories.first().map_or(0, Vec::len);
    let at = |t: usize| tracks.trajectories.iter().map(move |p| p[t]);
    write_samples(w, "float3[] extent", None, (0..frames).map(|t| extent(at(t)).to_vec()))?;
    write_samples(w, "point3f[] points", None, (0..frames).map(|t| at(t).collect()))?;
    // The ids, in the order of the points, so a tool can name each one.
    write!(w, "        string[] primvars:trackIds = [")?;
    write_list(w, tracks.ids.iter().map(|id| quoted(id)))?;
    writeln!(w, "] ({VERTEX})\n    }}")
}

/// Metadata of a primvar with one value per vertex (or per point).
const VERTEX: &str = "interpolation = \"vertex\"";

/// `DECLARATION.timeSamples = { t: [(x, y, z), …], … }`, one sample per frame, after the bare
/// declaration with its `metadata` when there is some.
fn write_samples(
    w: &mut impl Write,
    declaration: &str,
    metadata: Option<&str>,
    samples: impl Iterator<Item = Vec<[f64; 3]>>,
) -> std::io::Result<()> {
    if let Some(metadata) = metadata {
        writeln!(w, "        {declaration} ({metadata})")?;
    }
    writeln!(w, "        {declaration}.timeSamples = {{")?;
    for (t, values) in samples.enumerate() {
        write!(w, "            {t}: [")?;
        write_list(
            w,
            values.iter().map(|v| format!("({}, {}, {})", v[0] as f32, v[1] as f32, v[2] as f32)),
        )?;
        writeln!(w, "],")?;
    }
    writeln!(w, "        }}")
}

fn write_list<T: std::fmt::Display>(
    w: &mut impl Write,
    items: impl Iterator<Item = T>,
) -> std::io::Result<()> {
    for (i, item) in items.enumerate() {
        if i > 0 {
            write!(w, ", ")?;
        }
        write!(w, "{item}")?;
    }
    Ok(())
}

/// A USD string literal: quotes and backslashes escaped (ids hold neither commas nor newlines).
fn quoted(text: &str) -> String {
    format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""))
}

/// [lowest, highest] corner of the points' box; zeros for no points.
fn extent(points: impl Iterator<Item = [f64; 3]>) -> [[f64; 3]; 2] {
    let mut bounds: Option<[[f64; 3]; 2]> = None;
    for p in points {
        let [lo, hi] = bounds.get_or_insert([p, p]);
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    bounds.unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unusable_input_is_refused_naming_the_file() {
        let path = Path::new("out/s.usda");
        let sequence = MeshSequence {
            faces: vec![[0, 1, 2]],
            frames: vec![vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; 2],
            colors: None,
        };
        let error = |fps, tracks: Option<&UsdTracks>| {
            write_usda(path, &sequence, fps, Orientation::keep(UpAxis::Y), tracks)
                .unwrap_err()
                .to_string()
        };
        assert!(error(0.0, None).starts_with("out/s.usda: cannot write: frame rate 0"));
        assert!(error(f64::NAN, None).contains("frame rate NaN"));
        let ids = ["a".to_string()];
        let short = [vec![[0.0; 3]]];
        let tracks = UsdTracks { ids: &ids, trajectories: &short };
        assert!(
            error(24.0, Some(&tracks)).contains("point a has 1 positions, the sequence 2 frames")
        );
        let empty = MeshSequence::default();
        let message = write_usda(path, &empty, 24.0, Orientation::keep(UpAxis::Y), None)
            .unwrap_err()
            .to_string();
        assert!(message.contains("no frames"), "{message}");
    }
}
