//! What the Python and C fronts (and any host embedding the engine) call: every behaviour they
//! offer lives here or below, once, and the fronts only convert arguments and results.
//!
//! - [`Failure`] and [`ErrorKind`]: any engine error, classified once, with the command-line
//!   program's message; [`guard`] keeps a panic from unwinding into a foreign caller.
//! - [`Job`]: a training run or a fit on its own thread, with progress, cancellation and a
//!   result to poll or wait for.
//! - [`DatasetInfo`]: what `tagsplat dataset info` says of a dataset folder.
//! - [`evaluate`]: what `tagsplat eval` measures of a prediction against its ground truth.

mod dataset_info;
mod evaluate;
mod failure;
mod job;

pub use dataset_info::{CameraInfo, DatasetInfo};
pub use evaluate::{evaluate, EvalOptions, Evaluation};
pub use failure::{guard, ErrorKind, Failure};
pub use job::{Job, JobProgress, JobStage, Observer};
