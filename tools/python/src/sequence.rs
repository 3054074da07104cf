//! `Sequence`: a mesh sequence (one face list, vertex positions per frame) held as flat
//! buffers, so its arrays are views of them with no copy.

use crate::arrays::{self, Kind};
use crate::errors::{bad_input, run};
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use std::path::PathBuf;
use tagsplat::sequence::orient::{Orientation, SignedAxis, UpAxis};
use tagsplat::sequence::{ReadOptions, SequenceInfo};
use tagsplat::{FrameFormat, MeshSequence};

/// A topology-consistent mesh sequence: faces `(F, 3) uint32`, positions `(T, V, 3) float32`,
/// colours `(T, V, 3) uint8` or None.
///
/// Its arrays are read-only views of the sequence's own buffers (no copy; two reads share
/// memory). It never changes after it is made.
#[pyclass(frozen, module = "tagsplat")]
pub struct Sequence {
    faces: Vec<[u32; 3]>,
    /// Every frame's positions, frame after frame.
    positions: Vec<[f32; 3]>,
    /// Every frame's colours, frame after frame, when the sequence has them.
    colors: Option<Vec<[u8; 3]>>,
    frames: usize,
    vertices: usize,
    /// What the file said beside its frames (default for a sequence made from arrays).
    info: SequenceInfo,
}

impl Sequence {
    /// Flattens the engine's sequence once (checked by the engine as it was read or made).
    pub fn of(sequence: MeshSequence) -> Self {
        Self::read_as(sequence, SequenceInfo::default())
    }

    /// Flattens a sequence read from a file, keeping what the file said.
    fn read_as(sequence: MeshSequence, info: SequenceInfo) -> Self {
        let frames = sequence.frames.len();
        let vertices = sequence.frames.first().map_or(0, Vec::len);
        Sequence {
            faces: sequence.faces,
            positions: sequence.frames.concat(),
            colors: sequence.colors.map(|c| c.concat()),
            frames,
            vertices,
            info,
        }
    }

    /// Positions per frame, as the engine's functions take them (a copy per call: the engine's
    /// sequences hold one buffer per frame; `benches/python/track_overhead.py` measures it).
    pub fn frames(&self) -> Vec<Vec<[f32; 3]>> {
        self.positions.chunks(self.vertices.max(1)).map(<[_]>::to_vec).collect()
    }

    /// The engine's form of the sequence (a copy).
    pub fn engine(&self) -> MeshSequence {
        let colors = self
            .colors
            .as_ref()
            .map(|c| c.chunks(self.vertices.max(1)).map(<[_]>::to_vec).collect());
        MeshSequence { faces: self.faces.clone(), frames: self.frames(), colors }
    }

    /// The number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames
    }

    /// The face list.
    pub fn face_list(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// What the file said beside its frames (the default for a sequence made from arrays).
    pub fn info(&self) -> &SequenceInfo {
        &self.info
    }

    /// Frame `t`'s positions; None past the end.
    pub fn frame(&self, t: usize) -> Option<&[[f32; 3]]> {
        (t < self.frames).then(|| &self.positions[t * self.vertices..(t + 1) * self.vertices])
    }

    /// Frame `t`'s colours, when the sequence has them.
    pub fn frame_colors(&self, t: usize) -> Option<&[[u8; 3]]> {
        let colors = self.colors.as_ref()?;
        (t < self.frames).then(|| &colors[t * self.vertices..(t + 1) * self.vertices])
    }
}

#[pymethods]
impl Sequence {
    /// A sequence from arrays: `faces` (F, 3) of integers, `positions` (T, V, 3) of floats,
    /// `colors` (T, V, 3) uint8 or None. They are copied; the engine checks them (face indices in
    /// range, finite positions) and refuses them with BadInputError.
    #[new]
    #[pyo3(signature = (faces, positions, colors = None))]
    fn new(
        py: Python<'_>,
        faces: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        colors: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let faces = arrays::indices::<3>(faces, "faces", &[None, Some(3)], "(F, 3)")?;
        let shape = [None, None, Some(3)];
        let (positions, dims) =
            arrays::rows::<f64, 3>(positions, "positions", Kind::Float, &shape, "(T, V, 3)")?;
        let (frames, vertices) = (dims[0], dims[1]);
        let colors = match colors {
            None => None,
            Some(c) => {
                let want = [Some(frames), Some(vertices), Some(3)];
                let words = format!("({frames}, {vertices}, 3), as positions");
                Some(arrays::rows::<u8, 3>(c, "colors", Kind::Byte, &want, &words)?.0)
            }
        };
        let per_frame = |flat: Vec<[f32; 3]>| -> Vec<Vec<[f32; 3]>> {
            flat.chunks(vertices.max(1)).map(<[_]>::to_vec).collect()
        };
        let sequence = MeshSequence {
            faces,
            frames: per_frame(positions.iter().map(|p| p.map(|v| v as f32)).collect()),
            colors: colors.map(|c| c.chunks(vertices.max(1)).map(<[_]>::to_vec).collect()),
        };
        if let Some(problem) = sequence.problem() {
            return Err(bad_input(py, format!("Sequence(faces, positions): {problem}")));
        }
        Ok(Sequence::of(sequence))
    }

    /// Reads any sequence `tagsplat convert` reads. `animation` (glTF, FBX: a name or index),
    /// `fps` (the rate an animation is sampled at, or the clock of a folder or PC2) and `mesh`
    /// (which mesh of a file that holds several: a USD prim path, an Alembic object path, a
    /// glTF or FBX node name) are the CLI's `--animation`, `--fps` and `--mesh`.
    #[staticmethod]
    #[pyo3(signature = (path, *, animation = None, fps = None, mesh = None))]
    fn read(
        py: Python<'_>,
        path: PathBuf,
        animation: Option<String>,
        fps: Option<f64>,
        mesh: Option<String>,
    ) -> PyResult<Self> {
        let options = ReadOptions { animation, fps, mesh };
        let (sequence, info) = run(py, || MeshSequence::read_with(&path, &options))?;
        Ok(Sequence::read_as(sequence, info))
    }

    /// Frames per second: the file's own rate or the rate it was sampled at; None when the
    /// file has no clock and none was given.
    #[getter]
    fn fps(&self) -> Option<f64> {
        self.info.fps
    }

    /// Each frame's time in seconds, when the file has a clock.
    #[getter]
    fn times(&self) -> Option<Vec<f64>> {
        self.info.times.clone()
    }

    /// The up axis the file declares ("+Y", "+Z", ...), or None.
    #[getter]
    fn up(&self) -> Option<String> {
        self.info.up.map(|axis| axis.to_string())
    }

    /// Metres per file unit, when the file says.
    #[getter]
    fn meters_per_unit(&self) -> Option<f64> {
        self.info.meters_per_unit
    }

    /// What the reader chose or noticed (which animation, "no animation: one frame", ...).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.info.notes.clone()
    }

    /// Writes FILE.pc2 (plus FILE.obj), FILE.glb or FILE.usda (at `fps`), or otherwise a new
    /// folder of `frame_format` ("ply" or "obj") frames, as `tagsplat convert` does. `up` ("y"
    /// or "z") is the file's up axis; `from_up` (+x, -x, +y, -y, +z or -z, default `up`) the
    /// sequence's, turned onto `up` by quarter turns.
    #[pyo3(signature = (path, fps = 24.0, up = "y", from_up = None, frame_format = "ply"))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        fps: f64,
        up: &str,
        from_up: Option<&str>,
        frame_format: &str,
    ) -> PyResult<()> {
        let orientation = orientation(py, up, from_up)?;
        let format = match frame_format {
            "ply" => FrameFormat::Ply,
            "obj" => FrameFormat::Obj,
            other => {
                return Err(bad_input(py, format!("frame_format: '{other}' is not ply or obj")))
            }
        };
        if !(fps.is_finite() && fps > 0.0) {
            return Err(bad_input(py, format!("fps: {fps} is not a positive frame rate")));
        }
        let sequence = self.engine();
        run(py, || sequence.export(&path, format, fps, orientation))
    }

    /// Triangles as vertex indices, (F, 3) uint32 (a read-only view, no copy).
    #[getter]
    fn faces<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArrayDyn<u32>>> {
        let this = slf.get();
        let shape = [this.faces.len(), 3];
        // SAFETY: the buffer belongs to the frozen pyclass, which the view keeps alive.
        unsafe { arrays::view(slf.clone().into_any(), this.faces.as_flattened(), &shape) }
    }

    /// Vertex positions per frame, (T, V, 3) float32 (a read-only view, no copy).
    #[getter]
    fn positions<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let this = slf.get();
        let shape = [this.frames, this.vertices, 3];
        // SAFETY: as in `faces`.
        unsafe { arrays::view(slf.clone().into_any(), this.positions.as_flattened(), &shape) }
    }

    /// Vertex colours per frame, (T, V, 3) uint8 (a read-only view, no copy), or None.
    #[getter]
    fn colors<'py>(slf: &Bound<'py, Self>) -> PyResult<Option<Bound<'py, PyArrayDyn<u8>>>> {
        let this = slf.get();
        let shape = [this.frames, this.vertices, 3];
        let Some(colors) = &this.colors else { return Ok(None) };
        // SAFETY: as in `faces`.
        unsafe { arrays::view(slf.clone().into_any(), colors.as_flattened(), &shape).map(Some) }
    }

    /// Vertices per frame.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// The number of frames.
    fn __len__(&self) -> usize {
        self.frames
    }

    fn __repr__(&self) -> String {
        format!(
            "Sequence({} frames, {} vertices, {} faces{})",
            self.frames,
            self.vertices,
            self.faces.len(),
            if self.colors.is_some() { ", colours" } else { "" }
        )
    }
}

/// The file's up axis ("y" or "z") and the sequence's (`from_up`, default `up`), with the
/// command-line program's messages.
pub fn orientation(py: Python<'_>, up: &str, from_up: Option<&str>) -> PyResult<Orientation> {
    let up = up_axis(py, "up", up)?;
    match from_up {
        Some(text) => Ok(Orientation::new(signed_axis(py, "from_up", text)?, up)),
        None => Ok(Orientation::keep(up)),
    }
}

/// One of +x, -x, +y, -y, +z, -z as an axis; `name` is the argument's.
pub fn signed_axis(py: Python<'_>, name: &str, text: &str) -> PyResult<SignedAxis> {
    SignedAxis::parse(text).ok_or_else(|| {
        bad_input(py, format!("{name}: '{text}' is not one of +x, -x, +y, -y, +z, -z"))
    })
}

/// "y" or "z" as an up axis; `name` is the argument's.
pub fn up_axis(py: Python<'_>, name: &str, text: &str) -> PyResult<UpAxis> {
    match text.to_ascii_lowercase().as_str() {
        "y" => Ok(UpAxis::Y),
        "z" => Ok(UpAxis::Z),
        _ => Err(bad_input(py, format!("{name}: '{text}' is not y or z"))),
    }
}
