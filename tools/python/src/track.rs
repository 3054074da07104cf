//! `track`: surface points bound on frame 0 and followed through a sequence, by the engine's
//! `tagsplat::track` (the function `tagsplat track` calls).

use crate::arrays;
use crate::camera::camera_arg;
use crate::errors::{bad_input, run};
use crate::sequence::Sequence;
use numpy::PyArrayDyn;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::time::Instant;
use tagsplat::{MeshSequence, Queries, TrackReport};

/// The result of `track`: the bound points' trajectories and bindings, and the queries that
/// could not be bound. Its arrays belong to it (handed over from the engine, no copy).
#[pyclass(frozen, module = "tagsplat")]
pub struct Tracks {
    ids: Py<PyList>,
    positions: Py<PyArrayDyn<f64>>,
    faces: Py<PyArrayDyn<u32>>,
    barycentric: Py<PyArrayDyn<f64>>,
    distances: Py<PyArrayDyn<f64>>,
    unbound: Py<PyList>,
    max_distance: f64,
    engine_s: f64,
}

#[pymethods]
impl Tracks {
    /// The bound points' ids, in query order.
    #[getter]
    fn ids(&self, py: Python<'_>) -> Py<PyList> {
        self.ids.clone_ref(py)
    }

    /// Positions, (N, T, 3) float64: point i in frame t.
    #[getter]
    fn positions(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.positions.clone_ref(py)
    }

    /// (faces, barycentric): the frame-0 face each point is bound to, (N,) uint32, and its
    /// barycentric coordinates there, (N, 3) float64.
    #[getter]
    fn bindings(&self, py: Python<'_>) -> (Py<PyArrayDyn<u32>>, Py<PyArrayDyn<f64>>) {
        (self.faces.clone_ref(py), self.barycentric.clone_ref(py))
    }

    /// Distance of each query point to the frame-0 surface (0 for a pixel's ray hit), (N,).
    #[getter]
    fn distances(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.distances.clone_ref(py)
    }

    /// The queries not bound, in query order: dicts of id, reason and distance (None unless the
    /// reason is the distance).
    #[getter]
    fn unbound(&self, py: Python<'_>) -> Py<PyList> {
        self.unbound.clone_ref(py)
    }

    /// The largest accepted distance to the frame-0 surface, scene units.
    #[getter]
    fn max_distance(&self) -> f64 {
        self.max_distance
    }

    /// Seconds the engine's tracking call took, without the conversions around it.
    #[getter]
    fn engine_s(&self) -> f64 {
        self.engine_s
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.ids.bind(py).len()
    }
}

/// Tracks `points` or `pixels` (through `camera`) over `sequence` (a Sequence or the path of
/// one). `points`: a dict id -> (x, y, z), or an (N, 3) array with `ids` (default "0", "1",
/// ...). `pixels`: an (N, 2) array of (u, v), pixel (i, j) centred at (i + 0.5, j + 0.5), with
/// `ids` likewise. `max_distance`: the farthest a point may lie from the frame-0 surface, as a
/// fraction of its bounding-box diagonal; farther points are listed in `unbound`.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // the queries' keywords
#[pyo3(signature = (sequence, *, points = None, pixels = None, ids = None, camera = None, max_distance = 0.01))]
pub fn track(
    py: Python<'_>,
    sequence: &Bound<'_, PyAny>,
    points: Option<&Bound<'_, PyAny>>,
    pixels: Option<&Bound<'_, PyAny>>,
    ids: Option<Vec<String>>,
    camera: Option<&Bound<'_, PyAny>>,
    max_distance: f64,
) -> PyResult<Tracks> {
    let queries = queries(py, points, pixels, ids, camera)?;
    let source = match sequence.cast::<Sequence>() {
        Ok(held) => Source::Held(held.get()),
        Err(_) => {
            let path: PathBuf = sequence.extract().map_err(|_| {
                PyTypeError::new_err("sequence: expected a Sequence or the path of a sequence")
            })?;
            Source::Read(run(py, || MeshSequence::read(&path))?)
        }
    };
    let (report, engine_s) = run(py, || {
        source.with_frames(|faces, frames| {
            let started = Instant::now();
            let report = tagsplat::track(faces, frames, &queries, max_distance)?;
            Ok::<_, tagsplat::TrackError>((report, started.elapsed().as_secs_f64()))
        })
    })?;
    tracks(py, report, engine_s)
}

/// The sequence to track through: one in Python's hands, or one just read from a file.
enum Source<'a> {
    Held(&'a Sequence),
    Read(MeshSequence),
}

impl Source<'_> {
    /// Calls `work` with the sequence's faces and positions per frame.
    fn with_frames<R>(&self, work: impl FnOnce(&[[u32; 3]], &[Vec<[f32; 3]>]) -> R) -> R {
        match self {
            Source::Held(held) => work(held.face_list(), &held.frames()),
            Source::Read(read) => work(&read.faces, &read.frames),
        }
    }
}

/// The engine's queries from the Python arguments; exactly one of `points` and `pixels`.
fn queries(
    py: Python<'_>,
    points: Option<&Bound<'_, PyAny>>,
    pixels: Option<&Bound<'_, PyAny>>,
    ids: Option<Vec<String>>,
    camera: Option<&Bound<'_, PyAny>>,
) -> PyResult<Queries> {
    match (points, pixels, camera) {
        (Some(points), None, _) => Ok(Queries::Points(point_queries(py, points, ids)?)),
        (None, Some(pixels), Some(camera)) => {
            let camera = camera_arg(py, camera)?;
            let uv = arrays::finite_rows::<2>(pixels, "pixels")?;
            Ok(Queries::Pixels { camera, pixels: named(py, uv, ids)? })
        }
        (None, Some(_), None) => Err(bad_input(py, "pixels: need camera, the camera they are in")),
        _ => Err(bad_input(py, "give points, or pixels with camera (not both)")),
    }
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
fn named<const N: usize>(
    py: Python<'_>,
    rows: Vec<[f64; N]>,
    ids: Option<Vec<String>>,
) -> PyResult<Vec<(String, [f64; N])>> {
    let ids = ids.unwrap_or_else(|| (0..rows.len()).map(|i| i.to_string()).collect());
    if ids.len() != rows.len() {
        let message = format!("ids: {} ids for {} queries", ids.len(), rows.len());
        return Err(bad_input(py, message));
    }
    Ok(ids.into_iter().zip(rows).collect())
}

/// The report as a `Tracks`, its arrays handed over to numpy.
fn tracks(py: Python<'_>, report: TrackReport, engine_s: f64) -> PyResult<Tracks> {
    let (n, t) = (report.points.len(), report.frames);
    let mut positions = Vec::with_capacity(n * t * 3);
    let mut barycentric = Vec::with_capacity(n * 3);
    for p in &report.points {
        positions.extend(p.trajectory.iter().flatten());
        barycentric.extend(p.binding.barycentric);
    }
    let faces = report.points.iter().map(|p| p.binding.face).collect();
    let distances = report.points.iter().map(|p| p.binding.distance).collect();
    let unbound = PyList::empty(py);
    for u in &report.unbound {
        let entry = PyDict::new(py);
        entry.set_item("id", &u.id)?;
        entry.set_item("reason", &u.reason)?;
        entry.set_item("distance", u.distance)?;
        unbound.append(entry)?;
    }
    let ids = report.points.iter().map(|p| p.id.as_str());
    Ok(Tracks {
        ids: PyList::new(py, ids)?.unbind(),
        positions: arrays::owned(py, positions, &[n, t, 3])?.unbind(),
        faces: arrays::owned(py, faces, &[n])?.unbind(),
        barycentric: arrays::owned(py, barycentric, &[n, 3])?.unbind(),
        distances: arrays::owned(py, distances, &[n])?.unbind(),
        unbound: unbound.unbind(),
        max_distance: report.max_distance,
        engine_s,
    })
}
