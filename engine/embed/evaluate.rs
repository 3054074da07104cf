//! `tagsplat eval`'s choice, once: a benchmark's ground truth scores a trained sequence; any
//! other folder is compared with the prediction file by file.

use super::failure::Failure;
use crate::eval::{evaluate_folders, FolderOptions, FolderReport};
use crate::score::{evaluate_sequence, find_ground_truth, GroundTruth};
use crate::score::{SequenceEval, SequenceEvalOptions};
use std::ops::Range;
use std::path::Path;

/// What an evaluation measured.
#[derive(Clone, Debug, serde::Serialize)]
#[serde(untagged)]
pub enum Evaluation {
    /// A trained sequence scored against a benchmark (`GT/gt/info.json`).
    Sequence(Box<SequenceEval>),
    /// Two folders in the same layout, compared file by file.
    Folders(Box<FolderReport>),
}

/// How to evaluate; the defaults are `tagsplat eval`'s.
#[derive(Clone, Debug, Default)]
pub struct EvalOptions {
    /// Surface samples per mesh for Chamfer (None: 5000 on a benchmark, 30 000 otherwise).
    pub chamfer_samples: Option<usize>,
    /// Surface samples per mesh for EMD, folders only (None: 1000).
    pub emd_samples: Option<usize>,
    /// The samples' seed.
    pub seed: u64,
    /// Benchmark only: the frames to score (None: all of the ground truth's).
    pub frames: Option<Range<usize>>,
}

/// Scores `pred` against `gt` as `tagsplat eval --json` does (and writes nothing).
pub fn evaluate(pred: &Path, gt: &Path, options: &EvalOptions) -> Result<Evaluation, Failure> {
    let context = |e: &(dyn std::error::Error + 'static)| {
        let failure = Failure::of(e);
        let (p, g) = (pred.display(), gt.display());
        Failure { message: format!("eval --pred {p} --gt {g}: {}", failure.message), ..failure }
    };
    if let Some(root) = find_ground_truth(gt) {
        let truth = GroundTruth::read(&root).map_err(|e| context(&e))?;
        let scoring = SequenceEvalOptions {
            chamfer_samples: options.chamfer_samples.unwrap_or(5000),
            seed: options.seed,
            frames: options.frames.clone(),
        };
        let eval = evaluate_sequence(pred, &truth, &scoring).map_err(|e| context(&e))?;
        return Ok(Evaluation::Sequence(Box::new(eval)));
    }
    let compare = FolderOptions {
        chamfer_samples: options.chamfer_samples.unwrap_or(30_000),
        emd_samples: options.emd_samples.unwrap_or(1000),
        seed: options.seed,
    };
    let report = evaluate_folders(pred, gt, &compare).map_err(|e| context(&e))?;
    Ok(Evaluation::Folders(Box::new(report)))
}
