//! `track`: surface points bound on frame 0 and followed through a sequence, by the engine's
//! `tagsplat::track::track_sequence` (the function `tagsplat track` calls).

use crate::arrays;
use crate::camera::camera_arg;
use crate::errors::{bad_input, run};
use crate::sequence::Sequence;
use crate::tracks::Tracks;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use std::time::Instant;
use tagsplat::sequence::{ReadOptions, SequenceInfo};
use tagsplat::track::bindings::{read_bindings, Anchor};
use tagsplat::track::{track_sequence, RunError, Targets};
use tagsplat::{MeshSequence, Queries};

/// Tracks `points`, `pixels` (through `camera`) or `bindings` over `sequence` (a Sequence or the
/// path of one, read with the CLI's `animation`, `fps` and `mesh` options, as `Sequence.read`
/// reads it). `points`: a dict id -> (x, y, z), or an (N, 3) array with `ids` (default "0",
/// "1", ...). `pixels`: an (N, 2) array of (u, v), pixel (i, j) centred at (i + 0.5, j + 0.5),
/// with `ids` likewise. `bindings`: points bound already, as `tagsplat track --bindings` takes
/// them: the path of a bindings CSV (its rows name their points), a tuple (faces (N,),
/// barycentric (N, 3)) as `Tracks.bindings` gives it, or an array of vertex ids (N,); arrays
/// are named by `ids`. `max_distance`: the farthest a point may lie from the frame-0 surface,
/// as a fraction of its bounding-box diagonal; farther points are listed in `unbound`.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // the queries' and the read's keywords
#[pyo3(signature = (sequence, *, points = None, pixels = None, bindings = None, ids = None, camera = None, max_distance = 0.01, animation = None, fps = None, mesh = None))]
pub fn track(
    py: Python<'_>,
    sequence: &Bound<'_, PyAny>,
    points: Option<&Bound<'_, PyAny>>,
    pixels: Option<&Bound<'_, PyAny>>,
    bindings: Option<&Bound<'_, PyAny>>,
    ids: Option<Vec<String>>,
    camera: Option<&Bound<'_, PyAny>>,
    max_distance: f64,
    animation: Option<String>,
    fps: Option<f64>,
    mesh: Option<String>,
) -> PyResult<Tracks> {
    let targets = targets(py, points, pixels, bindings, ids, camera)?;
    let source = source(py, sequence, ReadOptions { animation, fps, mesh })?;
    let (tracked, engine_s) = run(py, || {
        source.with_frames(|faces, frames, info| {
            let started = Instant::now();
            let tracked = track_sequence(faces, frames, info, &targets, max_distance)?;
            Ok::<_, RunError>((tracked, started.elapsed().as_secs_f64()))
        })
    })?;
    Tracks::new(py, tracked, engine_s)
}

/// The sequence to track through: one in Python's hands, or one just read from a file.
enum Source<'a> {
    Held(&'a Sequence),
    Read(MeshSequence, SequenceInfo),
}

/// `sequence` held, or read from its path with `options` (which only a path takes).
fn source<'a>(
    py: Python<'_>,
    sequence: &'a Bound<'_, PyAny>,
    options: ReadOptions,
) -> PyResult<Source<'a>> {
    if let Ok(held) = sequence.cast::<Sequence>() {
        if options != ReadOptions::default() {
            let message = "animation, fps, mesh: only with the path of a sequence (a Sequence \
                           was read already; Sequence.read takes them)";
            return Err(bad_input(py, message));
        }
        return Ok(Source::Held(held.get()));
    }
    let path: PathBuf = sequence.extract().map_err(|_| {
        PyTypeError::new_err("sequence: expected a Sequence or the path of a sequence")
    })?;
    let (read, info) = run(py, || MeshSequence::read_with(&path, &options))?;
    Ok(Source::Read(read, info))
}

impl Source<'_> {
    /// Calls `work` with the sequence's faces, positions per frame and what its file said.
    fn with_frames<R>(
        &self,
        work: impl FnOnce(&[[u32; 3]], &[Vec<[f32; 3]>], &SequenceInfo) -> R,
    ) -> R {
        match self {
            Source::Held(held) => work(held.face_list(), &held.frames(), held.info()),
            Source::Read(read, info) => work(&read.faces, &read.frames, info),
        }
    }
}

/// The engine's targets from the Python arguments: exactly one of `points`, `pixels` (with
/// `camera`) and `bindings`.
fn targets(
    py: Python<'_>,
    points: Option<&Bound<'_, PyAny>>,
    pixels: Option<&Bound<'_, PyAny>>,
    bindings: Option<&Bound<'_, PyAny>>,
    ids: Option<Vec<String>>,
    camera: Option<&Bound<'_, PyAny>>,
) -> PyResult<Targets> {
    match (points, pixels, bindings, camera) {
        (Some(points), None, None, _) => {
            Ok(Targets::Queries(Queries::Points(point_queries(py, points, ids)?)))
        }
        (None, Some(pixels), None, Some(camera)) => {
            let camera = camera_arg(py, camera)?;
            let uv = arrays::finite_rows::<2>(pixels, "pixels")?;
            Ok(Targets::Queries(Queries::Pixels { camera, pixels: named(py, uv, ids)? }))
        }
        (None, Some(_), None, None) => {
            Err(bad_input(py, "pixels: need camera, the camera they are in"))
        }
        (None, None, Some(bindings), _) => given_bindings(py, bindings, ids),
        _ => Err(bad_input(py, "give one of points, pixels with camera, or bindings")),
    }
}

/// A bindings file's rows, a (faces, barycentric) pair, or vertex ids named by `ids`.
fn given_bindings(
    py: Python<'_>,
    bindings: &Bound<'_, PyAny>,
    ids: Option<Vec<String>>,
) -> PyResult<Targets> {
    if let Ok(path) = bindings.extract::<PathBuf>() {
        if ids.is_some() {
            return Err(bad_input(
                py,
                "ids: not with a bindings file (its rows name their points)",
            ));
        }
        return Ok(Targets::File(run(py, || read_bindings(&path))?));
    }
    let anchors = match bindings.cast::<PyTuple>() {
        Ok(pair) if pair.len() == 2 => surface_anchors(py, &pair.get_item(0)?, &pair.get_item(1)?)?,
        _ => {
            let vertices =
                arrays::indices::<1>(bindings, "bindings", &[None], "(N,) of vertex ids")?;
            vertices.into_iter().map(|[v]| Anchor::Vertex(v)).collect()
        }
    };
    Ok(Targets::Anchors(named(py, anchors, ids)?))
}

/// Barycentric coordinates on faces: `faces` (N,) and `barycentric` (N, 3), one row each.
fn surface_anchors(
    py: Python<'_>,
    faces: &Bound<'_, PyAny>,
    barycentric: &Bound<'_, PyAny>,
) -> PyResult<Vec<Anchor>> {
    let faces = arrays::indices::<1>(faces, "bindings faces", &[None], "(N,)")?;
    let weights = arrays::finite_rows::<3>(barycentric, "bindings barycentric")?;
    if faces.len() != weights.len() {
        let counts = format!("{} faces and {} barycentric rows", faces.len(), weights.len());
        return Err(bad_input(py, format!("bindings: {counts}: one row per face")));
    }
    let anchor =
        |([face], barycentric): ([u32; 1], [f64; 3])| Anchor::Surface { face, barycentric };
    Ok(faces.into_iter().zip(weights).map(anchor).collect())
}

/// A dict id -> xyz, or an (N, 3) array named by `ids`.
fn point_queries(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    ids: Option<Vec<String>>,
) -> PyResult<Vec<(String, [f64; 3])>> {
    let Ok(table) = points.cast::<PyDict>() else {
        return named(py, arrays::finite_rows::<3>(points, "points")?, ids);
    };
    if ids.is_some() {
        return Err(bad_input(py, "ids: not with a dict of points (its keys are the ids)"));
    }
    let keys: Vec<String> =
        table.keys().iter().map(|k| k.str().map(|s| s.to_string())).collect::<PyResult<_>>()?;
    let xyz = arrays::finite_rows::<3>(table.values().as_any(), "points")?;
    Ok(keys.into_iter().zip(xyz).collect())
}

/// Rows paired with `ids` (default "0", "1", ...), which must be as many.
fn named<T>(py: Python<'_>, rows: Vec<T>, ids: Option<Vec<String>>) -> PyResult<Vec<(String, T)>> {
    let ids = ids.unwrap_or_else(|| (0..rows.len()).map(|i| i.to_string()).collect());
    if ids.len() != rows.len() {
        let message = format!("ids: {} ids for {} queries", ids.len(), rows.len());
        return Err(bad_input(py, message));
    }
    Ok(ids.into_iter().zip(rows).collect())
}
