//! `Camera`: the engine's pinhole camera (OpenCV axes, pixel centres at half-integers).

use crate::arrays::{self, Kind};
use crate::errors::{bad_input, run};
use glam::DMat4;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A pinhole camera with OpenCV axes (x right, y down, z forward); pixel (i, j) is centred at
/// (i + 0.5, j + 0.5). `world_to_camera` is a rigid 4x4 matrix (row-major, last row 0 0 0 1).
#[pyclass(frozen, module = "tagsplat")]
#[derive(Clone)]
pub struct Camera {
    /// The engine's camera, checked when it was made.
    pub inner: tagsplat::Camera,
}

#[pymethods]
impl Camera {
    /// A camera from intrinsics (pixels) and a 4x4 `world_to_camera` array; the engine checks it
    /// (positive sizes and focal lengths, finite numbers, a rigid transform).
    #[new]
    #[allow(clippy::too_many_arguments)] // the intrinsics, one argument each
    fn new(
        py: Python<'_>,
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        world_to_camera: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let shape = [Some(4), Some(4)];
        let (rows, _) = arrays::rows::<f64, 4>(
            world_to_camera,
            "world_to_camera",
            Kind::Float,
            &shape,
            "(4, 4)",
        )?;
        let row_major: Vec<f64> = rows.concat();
        let matrix = DMat4::from_cols_slice(&row_major).transpose();
        let camera = tagsplat::Camera::new(width, height, fx, fy, cx, cy, matrix)
            .map_err(|e| bad_input(py, format!("camera: {e}")))?;
        Ok(Camera { inner: camera })
    }

    /// Reads a `cam.json` (width, height, fx, fy, cx, cy, world_to_camera: 16 numbers, row-major).
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        Ok(Camera { inner: run(py, || tagsplat::Camera::load_json(&path))? })
    }

    /// Writes a `cam.json`.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        run(py, || self.inner.save_json(&path))
    }

    /// Image width, pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }

    /// Image height, pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }

    /// Focal length along x, pixels.
    #[getter]
    fn fx(&self) -> f64 {
        self.inner.fx
    }

    /// Focal length along y, pixels.
    #[getter]
    fn fy(&self) -> f64 {
        self.inner.fy
    }

    /// Principal point x, pixels.
    #[getter]
    fn cx(&self) -> f64 {
        self.inner.cx
    }

    /// Principal point y, pixels.
    #[getter]
    fn cy(&self) -> f64 {
        self.inner.cy
    }

    /// The rigid world-to-camera transform, (4, 4) float64, row-major (a new array).
    #[getter]
    fn world_to_camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let rows = self.inner.world_to_camera.transpose().to_cols_array().to_vec();
        arrays::owned(py, rows, &[4, 4])
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Camera({}x{}, fx={}, fy={}, cx={}, cy={})",
            c.width, c.height, c.fx, c.fy, c.cx, c.cy
        )
    }
}

/// A camera argument: a `Camera` or the path of a `cam.json`.
pub fn camera_arg(py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<tagsplat::Camera> {
    if let Ok(camera) = value.cast::<Camera>() {
        return Ok(camera.get().inner);
    }
    let path: PathBuf = value.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(
            "camera: expected a Camera or the path of a cam.json",
        )
    })?;
    run(py, || tagsplat::Camera::load_json(&path))
}
