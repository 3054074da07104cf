//! `tagsplat bench sequence`: a training run on a hard-motion benchmark dataset
//! ([`run_train`], resuming when the output folder holds frames already), then its scores
//! against the dataset's ground truth ([`evaluate_sequence`]), with the machine it ran on and
//! the time per frame. The evaluation files (`eval.csv`, `eval.json`, `eval.svg`) go into the
//! output folder.

use crate::gpu::GpuContext;
use crate::score::{
    evaluate_sequence, find_ground_truth, write_sequence_eval, FrameScores, GroundTruth,
    SequenceEvalError, SequenceEvalOptions, SequenceSummary,
};
use crate::train::pipeline::{run_train, TrainJob, TrainProgress};
use crate::train::TrainError;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// Why [`bench_sequence`] failed.
#[derive(Debug, thiserror::Error)]
pub enum SequenceBenchError {
    /// The dataset folder (named) has neither `gt/info.json` nor `info.json`.
    #[error("{}: no ground truth to score against (neither gt/info.json nor info.json)", .0.display())]
    NoGroundTruth(PathBuf),
    /// The training run failed.
    #[error(transparent)]
    Train(#[from] TrainError),
    /// Reading the ground truth, scoring, or writing the evaluation files failed.
    #[error(transparent)]
    Eval(#[from] SequenceEvalError),
}

/// What [`bench_sequence`] measured and scored.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceBenchReport {
    /// The Vulkan device's name.
    pub device: String,
    /// The host CPU model, `None` when /proc/cpuinfo cannot be read.
    pub cpu: Option<String>,
    /// The dataset folder trained on.
    pub data: PathBuf,
    /// The ground-truth folder scored against.
    pub ground_truth: PathBuf,
    /// The output folder of the training run and the evaluation files.
    pub out: PathBuf,
    /// Wall seconds of the whole training run (resumed frames cost nothing).
    pub train_total_s: f64,
    /// Optimisation seconds of frame 0, and the mean over the later scored frames (None where
    /// the training report lacks them, e.g. frames resumed from an earlier run).
    pub frame0_s: Option<f64>,
    /// Mean optimisation seconds over the scored frames after frame 0 that report it.
    pub later_frame_mean_s: Option<f64>,
    /// Iterations of each scored frame, in frame order.
    pub iterations: Vec<Option<u64>>,
    /// The sequence's scores against the ground truth.
    pub scores: SequenceSummary,
    /// The scores of each scored frame, in frame order.
    pub rows: Vec<FrameScores>,
    /// The evaluation files written.
    pub files: Vec<PathBuf>,
}

/// Trains `job` (its frames are the ones scored) and scores the output. The ground truth is
/// read before training, so a dataset without one fails at once.
pub fn bench_sequence(
    ctx: &Arc<GpuContext>,
    job: &TrainJob,
    eval: &SequenceEvalOptions,
    progress: &mut dyn FnMut(TrainProgress),
) -> Result<SequenceBenchReport, SequenceBenchError> {
    let root = find_ground_truth(&job.data)
        .ok_or_else(|| SequenceBenchError::NoGroundTruth(job.data.clone()))?;
    let gt = GroundTruth::read(&root)?;
    let train = run_train(ctx, job, progress)?;
    let options = SequenceEvalOptions { frames: job.frames.clone(), ..eval.clone() };
    let scored = evaluate_sequence(&job.out, &gt, &options)?;
    let files = write_sequence_eval(&job.out, &scored)?;
    let seconds = |f: &FrameScores| f.train.wall_s;
    let later: Vec<f64> =
        scored.frames.iter().filter(|f| f.frame > 0).filter_map(seconds).collect();
    Ok(SequenceBenchReport {
        device: ctx.info().name.clone(),
        cpu: super::host_cpu_model(),
        data: job.data.clone(),
        ground_truth: scored.ground_truth,
        out: job.out.clone(),
        train_total_s: train.total_wall_s,
        frame0_s: scored.frames.iter().find(|f| f.frame == 0).and_then(seconds),
        later_frame_mean_s: (!later.is_empty())
            .then(|| later.iter().sum::<f64>() / later.len() as f64),
        iterations: scored.frames.iter().map(|f| f.train.iterations).collect(),
        scores: scored.summary,
        rows: scored.frames,
        files,
    })
}
