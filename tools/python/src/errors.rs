//! The exception hierarchy and the one conversion of an engine failure into it.
//!
//! `Error` is the base of everything the engine raises; `BadInputError` is also a `ValueError`,
//! so code that catches `ValueError` for bad arguments keeps working. The message is the
//! engine's (the command-line program's) message, which names the file or argument.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use tagsplat::embed::{guard, ErrorKind, Failure};

pyo3::create_exception!(tagsplat, Error, PyException, "Base class of every tagsplat error.");
pyo3::create_exception!(
    tagsplat,
    FileFormatError,
    Error,
    "A file exists but cannot be read as what it should be (a sequence, a mesh, a camera)."
);
pyo3::create_exception!(
    tagsplat,
    DeviceError,
    Error,
    "The Vulkan device failed: none suitable, out of memory, lost, or a validation failure."
);
pyo3::create_exception!(
    tagsplat,
    CancelledError,
    Error,
    "The job was cancelled (by its progress callback, `cancel()` or Ctrl-C)."
);

/// `BadInputError(Error, ValueError)`: two bases, which `create_exception!` cannot declare, so it
/// is made once by calling `type`.
static BAD_INPUT: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// The `BadInputError` class.
pub fn bad_input_type(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    let made = BAD_INPUT.get_or_try_init(py, || -> PyResult<Py<PyType>> {
        let bases = PyTuple::new(py, [py.get_type::<Error>(), py.get_type::<PyValueError>()])?;
        let namespace = PyDict::new(py);
        namespace.set_item(
            "__doc__",
            "An argument, path, config value or array the caller can fix (also a ValueError).",
        )?;
        namespace.set_item("__module__", "tagsplat")?;
        let made = py.get_type::<PyType>().call1(("BadInputError", bases, namespace))?;
        Ok(made.cast_into::<PyType>()?.unbind())
    })?;
    Ok(made.bind(py))
}

/// The Python exception for `failure`: its class by kind, its message as is.
pub fn to_py(py: Python<'_>, failure: Failure) -> PyErr {
    let message = failure.message;
    match failure.kind {
        ErrorKind::BadInput => match bad_input_type(py) {
            Ok(class) => PyErr::from_type(class.clone(), message),
            Err(e) => e,
        },
        ErrorKind::FileFormat => FileFormatError::new_err(message),
        ErrorKind::Device => DeviceError::new_err(message),
        ErrorKind::Cancelled => CancelledError::new_err(message),
        _ => Error::new_err(message),
    }
}

/// A front's own argument check failed: `BadInputError(message)`.
pub fn bad_input(py: Python<'_>, message: impl Into<String>) -> PyErr {
    to_py(py, Failure::bad_input(message))
}

/// Runs engine work with the GIL released, a panic turned into `tagsplat.Error` and an engine
/// error into its exception class.
pub fn run<T, E>(py: Python<'_>, work: impl FnOnce() -> Result<T, E> + Send) -> PyResult<T>
where
    T: Send,
    E: std::error::Error + 'static,
{
    run_failing(py, || work().map_err(|e| Failure::of(&e)))
}

/// [`run`] for work whose errors are failures already (several engine calls in a row).
pub fn run_failing<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Failure> + Send,
) -> PyResult<T> {
    py.detach(|| guard(work)).map_err(|f| to_py(py, f))
}

/// `error` as a failure: for `map_err` in work given to [`run_failing`].
pub fn failure<E: std::error::Error + 'static>(error: E) -> Failure {
    Failure::of(&error)
}
