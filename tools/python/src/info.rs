//! `dataset_info` and `eval`: what `tagsplat dataset info --json` and `tagsplat eval --json`
//! say, as dicts, from the engine's `tagsplat::embed` functions.

use crate::context::Context;
use crate::errors::{bad_input, run, run_failing};
use pyo3::prelude::*;
use std::path::PathBuf;
use tagsplat::dataset::LoadOptions;
use tagsplat::embed::{evaluate, DatasetInfo, EvalOptions};

/// What `tagsplat dataset info --json` says of the dataset folder `data`: cameras, frames,
/// the memory a run at `scale` needs on `ctx`'s device, the backdrop, missing files, and with
/// `check` every image and mask decoded (slow on large captures).
#[pyfunction]
#[pyo3(signature = (ctx, data, scale = 1.0, check = false))]
pub fn dataset_info(
    py: Python<'_>,
    ctx: &Context,
    data: PathBuf,
    scale: f64,
    check: bool,
) -> PyResult<Py<PyAny>> {
    let options = LoadOptions { scale: Some(scale), ..LoadOptions::default() };
    let info = run(py, || DatasetInfo::gather(&ctx.inner, &data, &options, check))?;
    dict_of(py, &info)
}

/// The figures `tagsplat eval --json` prints for the prediction folder `pred` against the
/// ground truth `gt` (a benchmark's folder or gt/: the sequence scores; otherwise a folder in
/// the prediction's layout, compared file by file). `frames`: a range or (a, b), benchmark
/// only. Nothing is written.
#[pyfunction]
#[pyo3(signature = (pred, gt, frames = None, *, chamfer_samples = None, emd_samples = None, seed = 0))]
pub fn eval(
    py: Python<'_>,
    pred: PathBuf,
    gt: PathBuf,
    frames: Option<(usize, usize)>,
    chamfer_samples: Option<usize>,
    emd_samples: Option<usize>,
    seed: u64,
) -> PyResult<Py<PyAny>> {
    let frames = match frames {
        Some((a, b)) if a >= b => {
            return Err(bad_input(py, format!("frames: '{a}..{b}' is empty (A must be below B)")))
        }
        other => other.map(|(a, b)| a..b),
    };
    let options = EvalOptions { chamfer_samples, emd_samples, seed, frames };
    let evaluation = run_failing(py, || evaluate(&pred, &gt, &options))?;
    dict_of(py, &evaluation)
}

/// An engine value as the dict `json.loads` makes of its JSON.
pub fn dict_of<T: serde::Serialize>(py: Python<'_>, value: &T) -> PyResult<Py<PyAny>> {
    let text =
        serde_json::to_string(value).map_err(|e| crate::errors::Error::new_err(e.to_string()))?;
    Ok(py.import("json")?.call_method1("loads", (text,))?.unbind())
}
