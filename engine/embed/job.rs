//! A training or a fit on a thread of its own, which a host polls, waits for or cancels: what
//! the Python and C fronts hand their callers as a job object.

use super::failure::{panicked, Failure};
use crate::gpu::GpuContext;
use crate::io::lock::OutputLock;
use crate::train::pipeline::{run_train_with, Stage, TrainJob, TrainProgress, TrainReport};
use crate::train::TrainError;
use crate::train::{run_fit_job, write_fit_outputs, FitJob, FitOutcome, Progress as FitProgress};
use std::ops::ControlFlow;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What a job is doing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobStage {
    /// Not started yet.
    #[default]
    Starting,
    /// A training run builds its cameras' background plates (`iteration` of `iterations`).
    Plates,
    /// A training run decodes a frame's views (`iteration` of `iterations`).
    Views,
    /// A training run optimises a frame.
    Frame,
    /// A fit optimises its frame.
    Fit,
}

/// Where a job is: its latest report.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct JobProgress {
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
    /// The mean loss of the last statistics interval, once there is one.
    pub loss: Option<f64>,
    /// Seconds since the job started.
    pub elapsed_s: f64,
    /// How many reports the job has made: it grows with each, so a poller sees what is new.
    pub update: u64,
}

impl JobProgress {
    fn of_train(p: &TrainProgress) -> Self {
        let stage = match p.stage {
            Stage::Plates => JobStage::Plates,
            Stage::Views => JobStage::Views,
            Stage::Frame => JobStage::Frame,
        };
        let (frame, frames_end, iteration, iterations) =
            (p.frame, p.frames_end, p.iteration, p.iterations);
        Self { stage, frame, frames_end, iteration, iterations, loss: p.loss, ..Self::default() }
    }

    fn of_fit(frame: usize, p: &FitProgress) -> Self {
        let (iteration, iterations, loss) = (p.iteration, p.iterations, p.loss.map(f64::from));
        let frames_end = frame + 1;
        Self {
            stage: JobStage::Fit,
            frame,
            frames_end,
            iteration,
            iterations,
            loss,
            ..Self::default()
        }
    }
}

/// Called on the job's thread after every report, outside any lock; answering `Break` cancels
/// the job as [`Job::cancel`] does.
pub type Observer = Box<dyn FnMut(&JobProgress) -> ControlFlow<()> + Send>;

/// A job's report function, which the work calls at every step: `Break` means stop.
type Report<'a> = &'a mut dyn FnMut(JobProgress) -> ControlFlow<()>;

/// Work running on its own thread. Every method may be called from any thread. Dropping an
/// unfinished job cancels it and waits for its thread to end.
pub struct Job<T> {
    shared: Arc<Shared<T>>,
    thread: Option<JoinHandle<()>>,
}

struct Shared<T> {
    state: Mutex<State<T>>,
    finished: Condvar,
    cancel: AtomicBool,
}

struct State<T> {
    progress: JobProgress,
    /// Some once the work ended, until taken.
    result: Option<Result<T, Failure>>,
    done: bool,
}

impl Job<TrainReport> {
    /// Runs (or resumes) `job` as [`run_train_with`] does; a cancelled run fails with
    /// [`ErrorKind::Cancelled`](super::ErrorKind::Cancelled) and keeps its finished frames.
    pub fn train(ctx: Arc<GpuContext>, job: TrainJob, observer: Option<Observer>) -> Self {
        Self::spawn(observer, move |report| {
            let mut relay = |p: &TrainProgress| report(JobProgress::of_train(p));
            run_train_with(&ctx, &job, &mut relay).map_err(|e| Failure::of(&e))
        })
    }
}

impl Job<FitOutcome> {
    /// Fits `job` as `tagsplat fit` does, and with `out` writes its files there as it does
    /// (holding `out`'s lock while it runs).
    pub fn fit(
        ctx: Arc<GpuContext>,
        job: FitJob,
        out: Option<PathBuf>,
        observer: Option<Observer>,
    ) -> Self {
        Self::spawn(observer, move |report| {
            let failure = |e: TrainError| Failure::of(&e);
            let lock = out.as_deref().map(OutputLock::take).transpose();
            let _lock = lock.map_err(|e| failure(e.into()))?;
            let mut relay = |p: FitProgress| report(JobProgress::of_fit(job.frame, &p));
            let outcome = run_fit_job(&ctx, &job, &mut relay).map_err(failure)?;
            if let Some(out) = &out {
                write_fit_outputs(out, &outcome).map_err(failure)?;
            }
            Ok(outcome)
        })
    }
}

impl<T: Send + 'static> Job<T> {
    /// Starts `work` on a new thread. Its reports update [`Job::progress`] (time and count
    /// filled in here) and reach `observer`; a panic in it becomes an internal failure.
    fn spawn(
        mut observer: Option<Observer>,
        work: impl FnOnce(Report) -> Result<T, Failure> + Send + 'static,
    ) -> Self {
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                progress: JobProgress::default(),
                result: None,
                done: false,
            }),
            finished: Condvar::new(),
            cancel: AtomicBool::new(false),
        });
        let inside = Arc::clone(&shared);
        let thread = std::thread::spawn(move || {
            let started = Instant::now();
            let mut report = |mut p: JobProgress| {
                p.elapsed_s = started.elapsed().as_secs_f64();
                {
                    let mut state = inside.lock();
                    p.update = state.progress.update + 1;
                    state.progress = p;
                }
                if observer.as_mut().is_some_and(|o| o(&p).is_break()) {
                    inside.cancel.store(true, Ordering::SeqCst);
                }
                match inside.cancel.load(Ordering::SeqCst) {
                    true => ControlFlow::Break(()),
                    false => ControlFlow::Continue(()),
                }
            };
            let ran = catch_unwind(AssertUnwindSafe(|| work(&mut report)));
            let result = ran.unwrap_or_else(|payload| Err(panicked(&*payload)));
            let mut state = inside.lock();
            (state.result, state.done) = (Some(result), true);
            inside.finished.notify_all();
        });
        Self { shared, thread: Some(thread) }
    }
}

impl<T> Job<T> {
    /// The latest report (all zero, stage `Starting`, before the first).
    pub fn progress(&self) -> JobProgress {
        self.shared.lock().progress
    }

    /// Asks the job to stop at its next report (the next iteration, at most); it then ends with
    /// a [`Failure`] of kind `Cancelled`. Returns at once; a finished job is left as it is.
    pub fn cancel(&self) {
        self.shared.cancel.store(true, Ordering::SeqCst);
    }

    /// Whether the work has ended (its result is ready, or was taken).
    pub fn is_finished(&self) -> bool {
        self.shared.lock().done
    }

    /// Blocks until the job ends or `timeout` passes (None: no limit); true when it has ended.
    pub fn wait(&self, timeout: Option<Duration>) -> bool {
        let state = self.shared.lock();
        let not_done = |s: &mut State<T>| !s.done;
        let finished = &self.shared.finished;
        let state = match timeout {
            None => finished.wait_while(state, not_done).unwrap_or_else(|p| p.into_inner()),
            Some(t) => {
                finished.wait_timeout_while(state, t, not_done).unwrap_or_else(|p| p.into_inner()).0
            }
        };
        state.done
    }

    /// The job's result, once it has ended; None before, and after it was taken.
    pub fn take_result(&self) -> Option<Result<T, Failure>> {
        self.shared.lock().result.take()
    }
}

impl<T> Shared<T> {
    /// The state; a thread that panicked while holding it left nothing half-changed (every
    /// change is one assignment), so a poisoned lock is used as it is.
    fn lock(&self) -> MutexGuard<'_, State<T>> {
        self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl<T> Drop for Job<T> {
    fn drop(&mut self) {
        self.cancel();
        if let Some(thread) = self.thread.take() {
            // The work's panics are caught inside the thread; nothing is left to report here.
            let _ = thread.join();
        }
    }
}
