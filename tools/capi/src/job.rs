//! `tagsplat_job`: a training run or a fit on the engine's worker thread, with a progress
//! callback that can cancel, and calls to poll, wait for, cancel and read it.

use crate::buffers::{optional_path, optional_text, output_text, store, to_path};
use crate::context::Context;
use crate::handles::{create, get, release, Handle};
use crate::status::{call, engine, Error, Status};
use std::ffi::{c_char, c_int, c_void};
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;
use tagsplat::dataset::LoadOptions;
use tagsplat::embed::{self, ErrorKind, Failure, JobProgress, JobStage as EngineStage, Observer};
use tagsplat::train::{ConfigError, ConfigText, FitConfig, FitJob, FitOutcome};
use tagsplat::{TrainConfig, TrainJob, TrainReport};

/// What a job is doing.
#[repr(i32)]
#[derive(Clone, Copy)]
pub enum JobStage {
    /// Not started yet.
    Starting = 0,
    /// A training run builds its cameras' background plates (`iteration` of `iterations`).
    Plates = 1,
    /// A training run decodes a frame's views (`iteration` of `iterations`).
    Views = 2,
    /// A training run optimises a frame.
    Frame = 3,
    /// A fit optimises its frame.
    Fit = 4,
}

/// Where a job is: its latest report.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Progress {
    /// What `iteration` and `iterations` count.
    pub stage: JobStage,
    /// The frame being worked on.
    pub frame: usize,
    /// One past the job's last frame.
    pub frames_end: usize,
    /// The last finished iteration, 1-based (or views decoded, plates built).
    pub iteration: u32,
    /// The frame's iteration cap (or views, cameras).
    pub iterations: u32,
    /// The mean loss of the last statistics interval; NaN before there is one.
    pub loss: f64,
    /// Seconds since the job started.
    pub elapsed_s: f64,
    /// How many reports the job has made (0 before the first): a poller sees what is new.
    pub update: u64,
}

/// The progress callback: called on the job's worker thread after every report (each
/// iteration), with the report (valid during the call only) and the `user` pointer given at
/// the start. Returning nonzero cancels the job. It must not unwind (a C++ exception) or
/// longjmp out, and must not free its own job.
pub type ProgressFn = Option<unsafe extern "C" fn(*const Progress, *mut c_void) -> c_int>;

/// A training run (`tagsplat train`). Strings are copied at the start; NULL means "not given".
#[repr(C)]
pub struct TrainDesc {
    /// The dataset folder.
    pub data: *const c_char,
    /// The output folder; a run into one with complete frames resumes after them.
    pub out: *const c_char,
    /// The frame-0 mesh (PLY or OBJ); NULL builds it from the masks.
    pub mesh: *const c_char,
    /// A TOML config file; keys left out take their defaults.
    pub config_path: *const c_char,
    /// A TOML config as text (instead of config_path).
    pub config_toml: *const c_char,
    /// Frames frame_start..frame_end (end excluded); both 0: every frame.
    pub frame_start: usize,
    /// One past the last frame to produce.
    pub frame_end: usize,
}

/// A fit of one frame (`tagsplat fit`). Strings are copied at the start; NULL means "not given".
#[repr(C)]
pub struct FitDesc {
    /// The dataset folder.
    pub data: *const c_char,
    /// The output folder the fit writes as `tagsplat fit` does; NULL writes nothing.
    pub out: *const c_char,
    /// A point cloud or mesh (PLY or OBJ) whose vertices seed the Gaussians.
    pub init: *const c_char,
    /// A TOML config file; keys left out take their defaults.
    pub config_path: *const c_char,
    /// A TOML config as text (instead of config_path).
    pub config_toml: *const c_char,
    /// The frame to fit.
    pub frame: usize,
}

/// A running or finished job.
pub struct Job {
    work: Box<dyn Running>,
    /// The result once taken from the engine's job: the report as JSON, or the failure.
    result: Mutex<Option<Result<String, Failure>>>,
}

impl Handle for Job {
    const NAME: &'static str = "tagsplat_job";
}

/// The engine's job of either kind, seen through what C asks of it.
trait Running: Send + Sync {
    fn progress(&self) -> JobProgress;
    fn cancel(&self);
    fn is_finished(&self) -> bool;
    fn wait(&self, timeout: Option<Duration>) -> bool;
    /// The result, once, after the job ended: its report as JSON.
    fn take(&self) -> Option<Result<String, Failure>>;
}

/// What a job produces, as the JSON of its report.
trait Outcome: Send + 'static {
    fn report_json(&self) -> serde_json::Result<String>;
}

impl Outcome for TrainReport {
    fn report_json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(self)
    }
}

impl Outcome for FitOutcome {
    fn report_json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(&self.report)
    }
}

impl<T: Outcome> Running for embed::Job<T> {
    fn progress(&self) -> JobProgress {
        embed::Job::progress(self)
    }

    fn cancel(&self) {
        embed::Job::cancel(self)
    }

    fn is_finished(&self) -> bool {
        embed::Job::is_finished(self)
    }

    fn wait(&self, timeout: Option<Duration>) -> bool {
        embed::Job::wait(self, timeout)
    }

    fn take(&self) -> Option<Result<String, Failure>> {
        let json = |outcome: T| {
            let text = outcome.report_json();
            text.map_err(|e| Failure {
                kind: ErrorKind::Internal,
                message: format!("cannot write the report as JSON: {e}"),
            })
        };
        self.take_result().map(|result| result.and_then(json))
    }
}

impl From<&JobProgress> for Progress {
    fn from(p: &JobProgress) -> Self {
        let stage = match p.stage {
            EngineStage::Starting => JobStage::Starting,
            EngineStage::Plates => JobStage::Plates,
            EngineStage::Views => JobStage::Views,
            EngineStage::Frame => JobStage::Frame,
            EngineStage::Fit => JobStage::Fit,
        };
        Progress {
            stage,
            frame: p.frame,
            frames_end: p.frames_end,
            iteration: p.iteration,
            iterations: p.iterations,
            loss: p.loss.unwrap_or(f64::NAN),
            elapsed_s: p.elapsed_s,
            update: p.update,
        }
    }
}

/// The caller's callback and its `user` pointer, moved to the worker thread: the header makes
/// the caller answer for using `user` there.
struct Callback {
    function: unsafe extern "C" fn(*const Progress, *mut c_void) -> c_int,
    user: *mut c_void,
}

// SAFETY: the header's contract: the callback and `user` may be used from the worker thread.
unsafe impl Send for Callback {}

impl Callback {
    fn observer(callback: ProgressFn, user: *mut c_void) -> Option<Observer> {
        let callback = Callback { function: callback?, user };
        Some(Box::new(move |p: &JobProgress| callback.report(p)))
    }

    fn report(&self, p: &JobProgress) -> ControlFlow<()> {
        let report = Progress::from(p);
        // SAFETY: the caller's function, with a report valid for the call and its own pointer.
        match unsafe { (self.function)(&report, self.user) } {
            0 => ControlFlow::Continue(()),
            _ => ControlFlow::Break(()),
        }
    }
}

/// The config `path_arg` names or `text_arg` holds (not both), else the defaults.
unsafe fn config<T: Default>(
    (path_arg, config_path): (&str, *const c_char),
    (text_arg, config_toml): (&str, *const c_char),
    load: fn(&Path) -> Result<T, ConfigError>,
    parse: fn(&str, &Path, ConfigText) -> Result<T, ConfigError>,
) -> Result<T, Error> {
    let file = unsafe { optional_path(path_arg, config_path) }?;
    let text = unsafe { optional_text(text_arg, config_toml) }?;
    let config = match (file, text) {
        (Some(_), Some(_)) => {
            return Err(Error::bad_input(format!("give {path_arg} or {text_arg}, not both")))
        }
        (Some(file), None) => load(&file),
        (None, Some(text)) => parse(text, Path::new(text_arg), ConfigText::Toml),
        (None, None) => Ok(T::default()),
    };
    config.map_err(|e| engine(&e))
}

/// Starts training `desc` on `context`'s device, on a worker thread; `callback` (may be NULL)
/// sees every report and may cancel. Stores the new handle in `*out` at once; the run's own
/// errors (a missing dataset, an output folder another run is writing into) come from
/// tagsplat_job_result. A bad config is refused here.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_train_start(
    context: *const Context,
    desc: *const TrainDesc,
    callback: ProgressFn,
    user: *mut c_void,
    out: *mut *mut Job,
) -> Status {
    call("tagsplat_train_start", || unsafe {
        create("out", out, || {
            let context = get("context", context)?;
            let d = desc.as_ref().ok_or_else(|| Error::bad_input("desc is NULL"))?;
            let files = (to_path("desc.data", d.data)?, to_path("desc.out", d.out)?);
            let config = config(
                ("desc.config_path", d.config_path),
                ("desc.config_toml", d.config_toml),
                TrainConfig::load,
                TrainConfig::parse,
            )?;
            let frames = (d.frame_start, d.frame_end) != (0, 0);
            let job = TrainJob {
                mesh: optional_path("desc.mesh", d.mesh)?,
                frames: frames.then_some(d.frame_start..d.frame_end),
                ..TrainJob::new(files.0, files.1, config)
            };
            let observer = Callback::observer(callback, user);
            Ok(Job::of(embed::Job::train(context.gpu.clone(), job, observer)))
        })
    })
}

/// Starts fitting `desc` on `context`'s device, on a worker thread, as tagsplat_train_start
/// does.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_fit_start(
    context: *const Context,
    desc: *const FitDesc,
    callback: ProgressFn,
    user: *mut c_void,
    out: *mut *mut Job,
) -> Status {
    call("tagsplat_fit_start", || unsafe {
        create("out", out, || {
            let context = get("context", context)?;
            let d = desc.as_ref().ok_or_else(|| Error::bad_input("desc is NULL"))?;
            let job = FitJob {
                data: to_path("desc.data", d.data)?,
                frame: d.frame,
                init: optional_path("desc.init", d.init)?,
                config: config(
                    ("desc.config_path", d.config_path),
                    ("desc.config_toml", d.config_toml),
                    FitConfig::load,
                    FitConfig::parse,
                )?,
                load: LoadOptions::default(),
            };
            let folder = optional_path("desc.out", d.out)?;
            let observer = Callback::observer(callback, user);
            Ok(Job::of(embed::Job::fit(context.gpu.clone(), job, folder, observer)))
        })
    })
}

impl Job {
    fn of(work: impl Running + 'static) -> Self {
        Job { work: Box::new(work), result: Mutex::new(None) }
    }

    /// Runs `read` on the job's result once it has ended; [`Status::NotFinished`] before.
    fn with_result<R>(&self, read: impl FnOnce(&Result<String, Failure>) -> R) -> Result<R, Error> {
        let mut result = self.result.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if result.is_none() {
            *result = self.work.take();
        }
        let message = "the job has not finished (tagsplat_job_wait waits for it)";
        result.as_ref().map(read).ok_or_else(|| Error::new(Status::NotFinished, message))
    }
}

/// The job's latest report into `*progress` and whether it has finished into `*finished`
/// (1 or 0); either may be NULL. Does not block.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_job_poll(
    job: *const Job,
    progress: *mut Progress,
    finished: *mut c_int,
) -> Status {
    call("tagsplat_job_poll", || unsafe {
        let job = get("job", job)?;
        if !progress.is_null() {
            store("progress", progress, Progress::from(&job.work.progress()))?;
        }
        if !finished.is_null() {
            store("finished", finished, c_int::from(job.work.is_finished()))?;
        }
        Ok(())
    })
}

/// Asks the job to stop at its next report (one iteration at most); it then ends with
/// TAGSPLAT_STATUS_CANCELLED, keeping the frames it finished, and the next run on the same
/// output resumes after them. Returns at once; cancelling a finished job does nothing.
#[no_mangle]
pub extern "C" fn tagsplat_job_cancel(job: *const Job) -> Status {
    call("tagsplat_job_cancel", || {
        get("job", job)?.work.cancel();
        Ok(())
    })
}

/// Blocks until the job ends or `timeout_s` seconds pass (negative: no limit); stores whether it
/// has ended in `*finished` (1 or 0; may be NULL).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_job_wait(
    job: *const Job,
    timeout_s: f64,
    finished: *mut c_int,
) -> Status {
    call("tagsplat_job_wait", || unsafe {
        let job = get("job", job)?;
        let timeout = match timeout_s < 0.0 {
            true => None,
            false => Some(
                Duration::try_from_secs_f64(timeout_s)
                    .map_err(|e| Error::bad_input(format!("timeout_s {timeout_s}: {e}")))?,
            ),
        };
        let ended = job.work.wait(timeout);
        match finished.is_null() {
            true => Ok(()),
            false => store("finished", finished, c_int::from(ended)),
        }
    })
}

/// How the job ended: TAGSPLAT_STATUS_OK, or its failure (TAGSPLAT_STATUS_CANCELLED, bad
/// input, ...) with the engine's message as this thread's last error. While it runs:
/// TAGSPLAT_STATUS_NOT_FINISHED. May be asked any number of times.
#[no_mangle]
pub extern "C" fn tagsplat_job_result(job: *const Job) -> Status {
    call("tagsplat_job_result", || {
        let job = get("job", job)?;
        let ended = job.with_result(|result| result.as_ref().map(|_| ()).map_err(|f| f.clone()))?;
        ended.map_err(Error::from)
    })
}

/// The finished job's report as JSON (the run's report.json): a string of `*needed` bytes with
/// its NUL (`buf` NULL and `len` 0 only ask for the size). Fails as tagsplat_job_result does
/// when the job has not finished or did not succeed.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_job_report_json(
    job: *const Job,
    buf: *mut c_char,
    len: usize,
    needed: *mut usize,
) -> Status {
    call("tagsplat_job_report_json", || unsafe {
        let job = get("job", job)?;
        let report = job.with_result(|result| result.clone())?.map_err(Error::from)?;
        output_text("buf", &report, (buf, len), needed)
    })
}

/// Frees `job` (NULL: nothing). An unfinished job is cancelled and waited for first: once this
/// returns (and no other thread's call on the job still runs), its callback is not
/// called again.
#[no_mangle]
pub extern "C" fn tagsplat_job_free(job: *mut Job) -> Status {
    call("tagsplat_job_free", || release("job", job))
}
