//! `Tracks`: a tracking run's result as arrays, and the files `tagsplat track` writes of it,
//! each by the engine writer the program calls.

use crate::arrays;
use crate::errors::run;
use crate::sequence::signed_axis;
use numpy::{Element, PyArrayDyn};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use tagsplat::sequence::orient::UpAxis;
use tagsplat::track::bindings::write_bindings_csv;
use tagsplat::track::output::{write_pinned_tracks_csv, write_report_json};
use tagsplat::track::pins::write_pins_glb;
use tagsplat::track::{TrackReport, Tracked, TrackedPoint};

/// The result of `track`: the bound points' trajectories, orientation frames and bindings, the
/// frames' clock, and the queries that could not be bound. Its arrays belong to it (made once,
/// read-only, no copy per read).
#[pyclass(frozen, module = "tagsplat")]
pub struct Tracks {
    /// The engine's result, which the writers write.
    tracked: Tracked,
    ids: Py<PyList>,
    positions: Py<PyArrayDyn<f64>>,
    normals: Py<PyArrayDyn<f64>>,
    tangents: Py<PyArrayDyn<f64>>,
    orientation_held: Py<PyArrayDyn<bool>>,
    faces: Py<PyArrayDyn<u32>>,
    barycentric: Py<PyArrayDyn<f64>>,
    distances: Py<PyArrayDyn<f64>>,
    polygons: Py<PyArrayDyn<u32>>,
    times: Py<PyArrayDyn<f64>>,
    unbound: Py<PyList>,
    engine_s: f64,
}

impl Tracks {
    /// The engine's result as a `Tracks`, its arrays handed over to numpy; `engine_s` is the
    /// engine call's time.
    pub fn new(py: Python<'_>, tracked: Tracked, engine_s: f64) -> PyResult<Self> {
        let report = &tracked.report;
        let points = report.points.as_slice();
        let (n, t) = (points.len(), report.frames);
        let per_frame = |of: fn(&TrackedPoint) -> &[[f64; 3]]| {
            array(
                py,
                points.iter().flat_map(|p| of(p).as_flattened()).copied().collect(),
                &[n, t, 3],
            )
        };
        Ok(Tracks {
            ids: PyList::new(py, points.iter().map(|p| p.id.as_str()))?.unbind(),
            positions: per_frame(|p| &p.trajectory)?,
            normals: per_frame(|p| &p.normal)?,
            tangents: per_frame(|p| &p.tangent)?,
            orientation_held: array(
                py,
                points.iter().flat_map(|p| held_mask(p, t)).collect(),
                &[n, t],
            )?,
            faces: array(py, column(points, |p| p.binding.face), &[n])?,
            barycentric: array(py, column(points, |p| p.binding.barycentric).concat(), &[n, 3])?,
            distances: array(py, column(points, |p| p.binding.distance), &[n])?,
            polygons: array(py, column(points, |p| p.polygon), &[n])?,
            times: array(py, tracked.clock.times.clone(), &[t])?,
            unbound: unbound_list(py, report)?.unbind(),
            engine_s,
            tracked,
        })
    }
}

/// Per frame of `frames`, whether `point`'s orientation is held there.
fn held_mask(point: &TrackedPoint, frames: usize) -> impl Iterator<Item = bool> + '_ {
    (0..frames as u32).map(|k| point.orientation_held.contains(&k))
}

/// One value per point.
fn column<T>(points: &[TrackedPoint], of: impl Fn(&TrackedPoint) -> T) -> Vec<T> {
    points.iter().map(of).collect()
}

/// `data` handed over to numpy with `shape` ([`arrays::owned`]), held past the GIL.
fn array<T: Element>(py: Python<'_>, data: Vec<T>, shape: &[usize]) -> PyResult<Py<PyArrayDyn<T>>> {
    arrays::owned(py, data, shape).map(Bound::unbind)
}

/// The queries not bound, as dicts of id, reason and distance.
fn unbound_list<'py>(py: Python<'py>, report: &TrackReport) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for u in &report.unbound {
        let entry = PyDict::new(py);
        entry.set_item("id", &u.id)?;
        entry.set_item("reason", &u.reason)?;
        entry.set_item("distance", u.distance)?;
        list.append(entry)?;
    }
    Ok(list)
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

    /// The bound triangle's unit normal, (N, T, 3) float64: point i in frame t.
    #[getter]
    fn normals(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.normals.clone_ref(py)
    }

    /// The unit tangent along the bound triangle's first edge, orthogonal to the normal,
    /// (N, T, 3) float64. With the normal it is the frame a locator pinned there follows.
    #[getter]
    fn tangents(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.tangents.clone_ref(py)
    }

    /// (N, T) bool: True where the bound triangle had no area in that frame, so its normal and
    /// tangent are held from a neighbouring frame (usually all False).
    #[getter]
    fn orientation_held(&self, py: Python<'_>) -> Py<PyArrayDyn<bool>> {
        self.orientation_held.clone_ref(py)
    }

    /// (faces, barycentric): the frame-0 face each point is bound to, (N,) uint32, and its
    /// barycentric coordinates there, (N, 3) float64; `track(..., bindings=)` takes them back.
    #[getter]
    fn bindings(&self, py: Python<'_>) -> (Py<PyArrayDyn<u32>>, Py<PyArrayDyn<f64>>) {
        (self.faces.clone_ref(py), self.barycentric.clone_ref(py))
    }

    /// The file polygon each point's triangle was fanned from, (N,) uint32 (the face itself
    /// when the file's faces are triangles).
    #[getter]
    fn polygons(&self, py: Python<'_>) -> Py<PyArrayDyn<u32>> {
        self.polygons.clone_ref(py)
    }

    /// Distance of each query point to the frame-0 surface (0 for a pixel's ray hit or a
    /// given binding), (N,).
    #[getter]
    fn distances(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.distances.clone_ref(py)
    }

    /// Each frame's time in seconds, (T,) float64: the file's times, else frame k at k / fps.
    #[getter]
    fn times(&self, py: Python<'_>) -> Py<PyArrayDyn<f64>> {
        self.times.clone_ref(py)
    }

    /// Frames per second: the file's rate, else its times' mean rate, else 24.
    #[getter]
    fn fps(&self) -> f64 {
        self.tracked.clock.fps
    }

    /// The scene frame of frame 0 (times[0] * fps): frame k plays at start_frame + k.
    #[getter]
    fn start_frame(&self) -> f64 {
        self.tracked.clock.start_frame
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
        self.tracked.report.max_distance
    }

    /// Seconds the engine's tracking call took, without the conversions around it.
    #[getter]
    fn engine_s(&self) -> f64 {
        self.engine_s
    }

    /// Writes the tracks as `tagsplat track --out` does: CSV
    /// `id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame`, one row per point per frame.
    fn write_csv(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let t = &self.tracked;
        run(py, || write_pinned_tracks_csv(&path, &t.report.points, &t.clock))
    }

    /// Writes the JSON report `tagsplat track --json` writes: the clock, bindings (face,
    /// barycentric, distance, polygon), trajectories, normals, tangents and the unbound queries.
    fn write_json(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let t = &self.tracked;
        run(py, || write_report_json(&path, &t.report, &t.clock))
    }

    /// Writes the GLB of animated empties `tagsplat track --glb` writes: one node per point,
    /// named by its id, moved and turned by its position and orientation frame at every frame's
    /// time. glTF is +Y up: positions are turned onto it from `from_up` (+x, -x, +y, -y, +z or
    /// -z), by default the up the sequence's file declares, else taken as +Y already.
    #[pyo3(signature = (path, from_up = None))]
    fn write_pins(&self, py: Python<'_>, path: PathBuf, from_up: Option<&str>) -> PyResult<()> {
        let from_up = from_up.map(|text| signed_axis(py, "from_up", text)).transpose()?;
        let t = &self.tracked;
        let orientation = t.pins_orientation(from_up, UpAxis::Y);
        run(py, || write_pins_glb(&path, &t.report.points, &t.clock, orientation))
    }

    /// Writes the bindings as `tagsplat track --bindings-out` does: CSV `id,face,u,v,w,polygon`,
    /// which `track(..., bindings=path)` and `tagsplat track --bindings` read back bit for bit.
    fn write_bindings(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        run(py, || write_bindings_csv(&path, &self.tracked.report.points))
    }

    fn __len__(&self) -> usize {
        self.tracked.report.points.len()
    }
}
