//! numpy arrays in and out.
//!
//! In: anything `numpy.ascontiguousarray` takes (an array of any layout, a list), so a
//! non-contiguous array is copied, never refused. A wrong kind of value is a `TypeError`, a
//! wrong shape a `ValueError`, each naming the argument and what it expected.
//!
//! Out: views of buffers a Python object owns (no copy), marked read-only, since the engine's
//! objects do not change after they are made.

use numpy::ndarray::{ArrayView, IxDyn};
use numpy::{Element, PyArray, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods};
use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What values an argument takes, in the words of its error.
#[derive(Clone, Copy)]
pub enum Kind {
    /// float32 or float64 (read as f64).
    Float,
    /// Any integer dtype (read as i64).
    Integer,
    /// uint8.
    Byte,
}

impl Kind {
    fn accepts(self, dtype_kind: char, itemsize: usize) -> bool {
        match self {
            Kind::Float => dtype_kind == 'f' && (itemsize == 4 || itemsize == 8),
            Kind::Integer => dtype_kind == 'i' || dtype_kind == 'u',
            Kind::Byte => dtype_kind == 'u' && itemsize == 1,
        }
    }

    fn words(self) -> &'static str {
        match self {
            Kind::Float => "float32 or float64 values",
            Kind::Integer => "integer values",
            Kind::Byte => "uint8 values",
        }
    }

    /// The dtype the values are read in.
    fn read_as(self) -> &'static str {
        match self {
            Kind::Float => "float64",
            Kind::Integer => "int64",
            Kind::Byte => "uint8",
        }
    }
}

/// `value` as a C-contiguous array of `kind` whose shape matches `shape` (None: any length),
/// its elements converted to the kind's read type. `name` and `shape_words` ("(N, 3)") make the
/// messages.
fn checked<'py>(
    value: &Bound<'py, PyAny>,
    name: &str,
    kind: Kind,
    shape: &[Option<usize>],
    shape_words: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = value.py();
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (value,)).map_err(|_| {
        PyTypeError::new_err(format!("{name}: expected an array of {}", kind.words()))
    })?;
    let array = array.cast_into::<PyUntypedArray>()?;
    let dtype = array.dtype();
    let (dtype_kind, itemsize) = (dtype.kind() as char, dtype.itemsize());
    if !kind.accepts(dtype_kind, itemsize) {
        let got = dtype.str()?;
        return Err(PyTypeError::new_err(format!(
            "{name}: expected {}, got an array of dtype {got}",
            kind.words()
        )));
    }
    let dims = array.shape();
    let fits = dims.len() == shape.len()
        && dims.iter().zip(shape).all(|(&d, want)| want.is_none_or(|w| w == d));
    if !fits {
        return Err(PyValueError::new_err(format!(
            "{name}: expected an array of shape {shape_words}, got shape {dims:?}"
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", kind.read_as())?;
    Ok(numpy.call_method("ascontiguousarray", (array,), Some(&kwargs))?.cast_into()?)
}

/// The elements of a checked array, in C order.
fn elements<T: Element + Copy>(array: &Bound<'_, PyUntypedArray>) -> PyResult<Vec<T>> {
    let typed = array.cast::<PyArrayDyn<T>>()?;
    Ok(typed.readonly().as_slice()?.to_vec())
}

/// Rows of `N` values of `kind`, from an array of shape `(rows, N)` (or `lead` leading axes
/// before the last when `lead` > 1): the elements in C order, grouped by N.
pub fn rows<T: Element + Copy, const N: usize>(
    value: &Bound<'_, PyAny>,
    name: &str,
    kind: Kind,
    shape: &[Option<usize>],
    shape_words: &str,
) -> PyResult<(Vec<[T; N]>, Vec<usize>)> {
    let array = checked(value, name, kind, shape, shape_words)?;
    let flat: Vec<T> = elements(&array)?;
    let grouped = flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect();
    Ok((grouped, array.shape().to_vec()))
}

/// Rows of `N` indices (vertex or face numbers) from an integer array of `shape` (see
/// [`rows`]): a negative index, or one past u32, is bad input naming `name` and the row.
pub fn indices<const N: usize>(
    value: &Bound<'_, PyAny>,
    name: &str,
    shape: &[Option<usize>],
    shape_words: &str,
) -> PyResult<Vec<[u32; N]>> {
    let (rows, _) = rows::<i64, N>(value, name, Kind::Integer, shape, shape_words)?;
    let checked = |(i, row): (usize, &[i64; N])| {
        let mut indices = [0u32; N];
        for (index, &v) in indices.iter_mut().zip(row) {
            *index = u32::try_from(v).map_err(|_| {
                let message = format!("{name}: row {i} {row:?} is not a list of indices");
                crate::errors::bad_input(value.py(), message)
            })?;
        }
        Ok(indices)
    };
    rows.iter().enumerate().map(checked).collect()
}

/// Float rows (`(N, K)`) that must be finite: a NaN or infinity is bad input naming `name`.
pub fn finite_rows<const N: usize>(
    value: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<Vec<[f64; N]>> {
    let words = format!("(N, {N})");
    let (rows, _) = rows::<f64, N>(value, name, Kind::Float, &[None, Some(N)], &words)?;
    if let Some(i) = rows.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
        let message = format!("{name}: row {i} has a non-finite value {:?}", rows[i]);
        return Err(crate::errors::bad_input(value.py(), message));
    }
    Ok(rows)
}

/// A read-only numpy view of `data` with `shape`, kept alive by `owner`, which owns `data` and
/// never changes or moves it.
///
/// # Safety
/// `data` must live as long as `owner` and not change while it lives.
pub unsafe fn view<'py, T: Element>(
    owner: Bound<'py, PyAny>,
    data: &[T],
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let view = ArrayView::from_shape(IxDyn(shape), data)
        .map_err(|e| PyValueError::new_err(format!("internal: view of {shape:?}: {e}")))?;
    let array = PyArray::borrow_from_array(&view, owner);
    read_only(array)
}

/// `data` handed over to numpy (no copy) with `shape`, read-only.
pub fn owned<'py, T: Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    let flat = PyArray::from_vec(py, data);
    let shaped = flat.reshape(IxDyn(shape))?;
    read_only(shaped)
}

fn read_only<T: Element>(array: Bound<'_, PyArrayDyn<T>>) -> PyResult<Bound<'_, PyArrayDyn<T>>> {
    let kwargs = PyDict::new(array.py());
    kwargs.set_item("write", false)?;
    array.call_method("setflags", (), Some(&kwargs))?;
    Ok(array)
}
