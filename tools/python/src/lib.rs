//! The tagsplat Python package's extension module, `tagsplat._tagsplat` (re-exported by the
//! package `tagsplat`). A thin front: it converts arguments and results and calls the engine,
//! which holds every behaviour (and `tagsplat::embed` the jobs and the error kinds).
//!
//! - [`context`]: devices and the Vulkan context;
//! - [`sequence`]: mesh sequences as zero-copy arrays, read and written in every format;
//! - [`track`](mod@track): points, pixels and bindings tracked through a sequence;
//!   [`tracks`]: the result's arrays and files;
//! - [`camera`], [`render`]: cameras, and splat scenes and meshes rendered into arrays;
//! - [`jobs`]: training and fitting, blocking or as job objects;
//! - [`info`]: dataset info and evaluation, as dicts;
//! - [`arrays`], [`errors`]: numpy conversions and the exception hierarchy.

mod arrays;
mod camera;
mod context;
mod errors;
mod info;
mod jobs;
mod render;
mod sequence;
mod track;
mod tracks;

use pyo3::prelude::*;

#[pymodule]
fn _tagsplat(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("BadInputError", errors::bad_input_type(py)?)?;
    m.add("FileFormatError", py.get_type::<errors::FileFormatError>())?;
    m.add("DeviceError", py.get_type::<errors::DeviceError>())?;
    m.add("CancelledError", py.get_type::<errors::CancelledError>())?;
    m.add_class::<context::Device>()?;
    m.add_class::<context::Context>()?;
    m.add_class::<sequence::Sequence>()?;
    m.add_class::<tracks::Tracks>()?;
    m.add_class::<camera::Camera>()?;
    m.add_class::<jobs::Progress>()?;
    m.add_class::<jobs::TrainJobHandle>()?;
    m.add_class::<jobs::FitJobHandle>()?;
    m.add_function(wrap_pyfunction!(context::devices, m)?)?;
    m.add_function(wrap_pyfunction!(info::dataset_info, m)?)?;
    m.add_function(wrap_pyfunction!(info::eval, m)?)?;
    m.add_function(wrap_pyfunction!(track::track, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_splats, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::train, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::start_train, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::fit, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::start_fit, m)?)?;
    Ok(())
}
