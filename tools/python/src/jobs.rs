//! `train` and `fit`: the engine's jobs (`tagsplat::embed::Job`, on their own thread), driven
//! from Python. The blocking calls poll with the GIL released, call the progress callback on the
//! calling thread and honour Ctrl-C; the `start_*` calls hand back a job object instead.

use crate::context::Context;
use crate::errors::{bad_input, run, to_py};
use crate::info::dict_of;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyRange, PyRangeMethods};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;
use tagsplat::dataset::{LoadOptions, PixelCenters};
use tagsplat::embed::{Job, JobProgress, JobStage};
use tagsplat::train::{ConfigText, FitConfig, FitJob, FitOutcome};
use tagsplat::{TrainConfig, TrainJob, TrainReport};

/// How often a blocking call looks at its job (and at Ctrl-C).
const POLL: Duration = Duration::from_millis(50);

/// A job's latest report.
#[pyclass(frozen, module = "tagsplat", get_all)]
pub struct Progress {
    /// "starting", "plates", "views", "frame" or "fit": what `iteration` counts.
    stage: String,
    /// The frame being worked on.
    frame: usize,
    /// One past the job's last frame.
    frames_end: usize,
    /// The last finished iteration, 1-based (or views decoded, plates built).
    iteration: u32,
    /// The frame's iteration cap (or views, cameras).
    iterations: u32,
    /// The last statistics interval's mean loss, once there is one.
    loss: Option<f64>,
    /// Seconds since the job started.
    elapsed_s: f64,
    /// How many reports the job has made.
    update: u64,
}

#[pymethods]
impl Progress {
    fn __repr__(&self) -> String {
        format!(
            "Progress({} frame {} of {}, {}/{}, loss {:?}, {:.1} s)",
            self.stage,
            self.frame,
            self.frames_end,
            self.iteration,
            self.iterations,
            self.loss,
            self.elapsed_s
        )
    }
}

impl From<JobProgress> for Progress {
    fn from(p: JobProgress) -> Self {
        let stage = match p.stage {
            JobStage::Starting => "starting",
            JobStage::Plates => "plates",
            JobStage::Views => "views",
            JobStage::Frame => "frame",
            JobStage::Fit => "fit",
        };
        let (frame, frames_end, iteration, iterations) =
            (p.frame, p.frames_end, p.iteration, p.iterations);
        let (loss, elapsed_s, update) = (p.loss, p.elapsed_s, p.update);
        let stage = stage.to_string();
        Progress { stage, frame, frames_end, iteration, iterations, loss, elapsed_s, update }
    }
}

/// What a job's result becomes in Python: its report as a dict (what report.json holds).
trait Outcome: Send + 'static {
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>>;
}

impl Outcome for TrainReport {
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        dict_of(py, self)
    }
}

impl Outcome for FitOutcome {
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        dict_of(py, &self.report)
    }
}

/// An engine job and its result once converted, so `wait` answers the same every time.
struct Handle<T> {
    job: Job<T>,
    result: Mutex<Option<PyResult<Py<PyAny>>>>,
}

impl<T: Outcome> Handle<T> {
    fn new(job: Job<T>) -> Self {
        Handle { job, result: Mutex::new(None) }
    }

    fn poll(&self) -> Option<Progress> {
        (!self.job.is_finished()).then(|| self.job.progress().into())
    }

    /// Waits (GIL released) up to `timeout` seconds (None: until it ends); then its report, or
    /// its failure raised. A job still running after `timeout` raises TimeoutError.
    fn wait(&self, py: Python<'_>, timeout: Option<f64>) -> PyResult<Py<PyAny>> {
        let limit = timeout.map(|s| Duration::try_from_secs_f64(s.max(0.0))).transpose();
        let limit = limit.map_err(|e| bad_input(py, format!("timeout: {e}")))?;
        if !py.detach(|| self.job.wait(limit)) {
            return Err(pyo3::exceptions::PyTimeoutError::new_err("the job is still running"));
        }
        let mut result = self.result.lock().unwrap_or_else(|e| e.into_inner());
        if result.is_none() {
            *result = self.job.take_result().map(|r| convert(py, r));
        }
        match result.as_ref() {
            Some(Ok(report)) => Ok(report.clone_ref(py)),
            Some(Err(e)) => Err(e.clone_ref(py)),
            None => Err(crate::errors::Error::new_err("the job's result is gone")),
        }
    }

    /// Runs the job to its end from a blocking call: every `POLL` (GIL released) it checks
    /// Ctrl-C and hands `progress` the latest report when there is a new one. `progress`
    /// returning False cancels the job; Ctrl-C or an exception in `progress` cancels it, waits
    /// for it to stop, and raises.
    fn drive(&self, py: Python<'_>, progress: Option<&Bound<'_, PyAny>>) -> PyResult<Py<PyAny>> {
        let mut seen = 0;
        loop {
            let finished = py.detach(|| self.job.wait(Some(POLL)));
            let latest = self.job.progress();
            let called = match progress {
                Some(callback) if latest.update != seen => {
                    seen = latest.update;
                    Some(callback.call1((Progress::from(latest),)))
                }
                _ => None,
            };
            let interrupted = py.check_signals().err();
            let failed = match called {
                Some(Err(raised)) => Some(raised),
                Some(Ok(answer)) => {
                    if matches!(answer.extract::<bool>(), Ok(false)) {
                        self.job.cancel();
                    }
                    interrupted
                }
                None => interrupted,
            };
            if let Some(error) = failed {
                self.job.cancel();
                py.detach(|| self.job.wait(None));
                return Err(error);
            }
            if finished {
                return self.wait(py, None);
            }
        }
    }
}

/// The job's result as Python sees it: the report as a dict, or the failure's exception.
fn convert<T: Outcome>(
    py: Python<'_>,
    result: Result<T, tagsplat::embed::Failure>,
) -> PyResult<Py<PyAny>> {
    result.map_err(|f| to_py(py, f))?.to_dict(py)
}

/// A job class for Python: `$name` wraps a `Handle<$outcome>`; `$what` names what it runs in
/// the docstrings. Python classes cannot be generic, so one macro writes both.
macro_rules! job_class {
    ($(#[$doc:meta])* $name:ident, $python:literal, $outcome:ty, $what:literal) => {
        $(#[$doc])*
        #[pyclass(frozen, module = "tagsplat", name = $python)]
        pub struct $name {
            handle: Handle<$outcome>,
        }

        #[pymethods]
        impl $name {
            #[doc = concat!("The latest progress report; None once the ", $what, " has finished. Never blocks.")]
            fn poll(&self) -> Option<Progress> {
                self.handle.poll()
            }

            #[doc = concat!("Asks the ", $what, " to stop at its next iteration; `wait` then raises CancelledError.")]
            #[doc = "What a run finished stays in OUT, and the next `train` on OUT resumes after it."]
            fn cancel(&self) {
                self.handle.job.cancel()
            }

            #[doc = concat!("Whether the ", $what, " has finished (done, failed or cancelled).")]
            #[getter]
            fn done(&self) -> bool {
                self.handle.job.is_finished()
            }

            #[doc = concat!("The latest progress report, also after the ", $what, " finished.")]
            #[getter]
            fn progress(&self) -> Progress {
                self.handle.job.progress().into()
            }

            #[doc = concat!("Waits for the ", $what, " (at most `timeout` seconds; TimeoutError past it) and")]
            #[doc = "returns its report as a dict, or raises its error."]
            #[pyo3(signature = (timeout = None))]
            fn wait(&self, py: Python<'_>, timeout: Option<f64>) -> PyResult<Py<PyAny>> {
                self.handle.wait(py, timeout)
            }
        }
    };
}

job_class!(
    /// A training run in progress (from `start_train`): poll it, cancel it, wait for its report.
    /// Dropping it cancels the run.
    TrainJobHandle, "TrainJob", TrainReport, "run"
);
job_class!(
    /// A fit in progress (from `start_fit`): poll it, cancel it, wait for its report.
    /// Dropping it cancels the fit.
    FitJobHandle, "FitJob", FitOutcome, "fit"
);

/// Starts training `data` into `out` and returns at once with the job. `config`: a dict or the
/// path of a TOML file (keys left out take their defaults); `frames`: a range or (a, b), frames
/// before a complete in `out`; `mesh`: the frame-0 mesh (PLY/OBJ); `up`: "y" or "z" for the
/// exports; `fps`: the exports' frame rate; `scale`: the images' scale in (0, 1];
/// `pixel_centers`: "integer" or "half-integer". A run into an `out` with complete frames
/// resumes, as `tagsplat train` does; one into an `out` another run is writing is refused.
#[pyfunction]
#[pyo3(signature = (ctx, data, out, *, config = None, frames = None, mesh = None, fps = None, up = None, scale = None, pixel_centers = None))]
#[allow(clippy::too_many_arguments)] // `tagsplat train`'s options, one keyword each
pub fn start_train(
    py: Python<'_>,
    ctx: &Context,
    data: PathBuf,
    out: PathBuf,
    config: Option<&Bound<'_, PyAny>>,
    frames: Option<&Bound<'_, PyAny>>,
    mesh: Option<PathBuf>,
    fps: Option<f64>,
    up: Option<&str>,
    scale: Option<f64>,
    pixel_centers: Option<&str>,
) -> PyResult<TrainJobHandle> {
    let config = match config {
        None => TrainConfig::default(),
        Some(c) => train_config(py, c)?,
    };
    if let Some(fps) = fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(bad_input(py, format!("fps: '{fps}' is not a positive frame rate")));
    }
    let job = TrainJob {
        mesh,
        frames: frames.map(|f| frame_range(py, f)).transpose()?,
        up: up.map(|u| crate::sequence::up_axis(py, "up", u)).transpose()?,
        load: load_options(py, pixel_centers, scale)?,
        fps,
        ..TrainJob::new(data, out, config)
    };
    let job = Job::train(ctx.inner.clone(), job, None);
    Ok(TrainJobHandle { handle: Handle::new(job) })
}

/// Trains as `start_train` does and blocks until the run ends, with the GIL released; returns
/// its report. `progress(p)` is called on this thread with each new report (at most every
/// 50 ms); returning False cancels the run (CancelledError), raising cancels it and the
/// exception propagates; Ctrl-C cancels it and raises KeyboardInterrupt once it has stopped.
#[pyfunction]
#[pyo3(signature = (ctx, data, out, *, config = None, frames = None, mesh = None, fps = None, up = None, scale = None, pixel_centers = None, progress = None))]
#[allow(clippy::too_many_arguments)] // as start_train, plus the callback
pub fn train(
    py: Python<'_>,
    ctx: &Context,
    data: PathBuf,
    out: PathBuf,
    config: Option<&Bound<'_, PyAny>>,
    frames: Option<&Bound<'_, PyAny>>,
    mesh: Option<PathBuf>,
    fps: Option<f64>,
    up: Option<&str>,
    scale: Option<f64>,
    pixel_centers: Option<&str>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let job = start_train(py, ctx, data, out, config, frames, mesh, fps, up, scale, pixel_centers)?;
    job.handle.drive(py, progress)
}

/// Starts fitting Gaussians to frame `frame` of `data` and returns at once with the job.
/// `out`: where to write gaussians.ply, renders/ and report.json as `tagsplat fit` does (None:
/// nothing written); `config`: a dict or a TOML path; `iterations` overrides the config's;
/// `init`: a PLY/OBJ whose vertices seed the Gaussians.
#[pyfunction]
#[pyo3(signature = (ctx, data, frame = 0, *, out = None, config = None, iterations = None, init = None, pixel_centers = None))]
#[allow(clippy::too_many_arguments)] // `tagsplat fit`'s options, one keyword each
pub fn start_fit(
    py: Python<'_>,
    ctx: &Context,
    data: PathBuf,
    frame: usize,
    out: Option<PathBuf>,
    config: Option<&Bound<'_, PyAny>>,
    iterations: Option<u32>,
    init: Option<PathBuf>,
    pixel_centers: Option<&str>,
) -> PyResult<FitJobHandle> {
    let mut config = match config {
        None => FitConfig::default(),
        Some(c) => fit_config(py, c)?,
    };
    if let Some(iterations) = iterations {
        config.iterations = iterations;
    }
    let load = load_options(py, pixel_centers, None)?;
    let job = FitJob { data, frame, init, config, load };
    let job = Job::fit(ctx.inner.clone(), job, out, None);
    Ok(FitJobHandle { handle: Handle::new(job) })
}

/// Fits as `start_fit` does and blocks until it ends; `progress` as in `train`.
#[pyfunction]
#[pyo3(signature = (ctx, data, frame = 0, *, out = None, config = None, iterations = None, init = None, pixel_centers = None, progress = None))]
#[allow(clippy::too_many_arguments)] // as start_fit, plus the callback
pub fn fit(
    py: Python<'_>,
    ctx: &Context,
    data: PathBuf,
    frame: usize,
    out: Option<PathBuf>,
    config: Option<&Bound<'_, PyAny>>,
    iterations: Option<u32>,
    init: Option<PathBuf>,
    pixel_centers: Option<&str>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let job = start_fit(py, ctx, data, frame, out, config, iterations, init, pixel_centers)?;
    job.handle.drive(py, progress)
}

/// A training config from a dict or a TOML path, parsed and checked by the engine.
fn train_config(py: Python<'_>, config: &Bound<'_, PyAny>) -> PyResult<TrainConfig> {
    match json_text(config)? {
        Some(text) => run(py, || TrainConfig::parse(&text, Path::new(DICT), ConfigText::Json)),
        None => {
            let path = config_path(config)?;
            run(py, || TrainConfig::load(&path))
        }
    }
}

/// A fit config from a dict or a TOML path, parsed and checked by the engine.
fn fit_config(py: Python<'_>, config: &Bound<'_, PyAny>) -> PyResult<FitConfig> {
    match json_text(config)? {
        Some(text) => run(py, || FitConfig::parse(&text, Path::new(DICT), ConfigText::Json)),
        None => {
            let path = config_path(config)?;
            run(py, || FitConfig::load(&path))
        }
    }
}

/// How a config given as a dict is named in errors.
const DICT: &str = "(the config dict)";

/// A dict config as JSON text; None for anything else (a path).
fn json_text(config: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if !config.is_instance_of::<PyDict>() {
        return Ok(None);
    }
    let text = config.py().import("json")?.call_method1("dumps", (config,))?;
    Ok(Some(text.extract()?))
}

/// A config argument that is not a dict: the path of a TOML file.
fn config_path(config: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    config.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err("config: expected a dict or the path of a TOML file")
    })
}

/// A range (step 1) or a pair (a, b) as a frame range a..b, a below b.
fn frame_range(py: Python<'_>, frames: &Bound<'_, PyAny>) -> PyResult<Range<usize>> {
    let (a, b): (isize, isize) = match frames.cast::<PyRange>() {
        Ok(range) if range.step()? == 1 => (range.start()?, range.stop()?),
        Ok(_) => return Err(bad_input(py, "frames: a range of step 1")),
        Err(_) => frames.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err("frames: expected a range or a pair (a, b)")
        })?,
    };
    match (usize::try_from(a), usize::try_from(b)) {
        (Ok(a), Ok(b)) if a < b => Ok(a..b),
        _ => Err(bad_input(py, format!("frames: '{a}..{b}' is empty (A must be below B)"))),
    }
}

/// The dataset's load options, with the command-line program's words.
fn load_options(
    py: Python<'_>,
    centers: Option<&str>,
    scale: Option<f64>,
) -> PyResult<LoadOptions> {
    let pixel_centers = match centers {
        None => None,
        Some("integer") => Some(PixelCenters::Integer),
        Some("half-integer") => Some(PixelCenters::HalfInteger),
        Some(other) => {
            let message = format!("pixel_centers: '{other}' is not integer or half-integer");
            return Err(bad_input(py, message));
        }
    };
    Ok(LoadOptions { pixel_centers, scale })
}
