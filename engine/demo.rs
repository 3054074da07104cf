//! `tagsplat demo`: the whole job on generated data with known ground truth — generate a
//! deforming subject seen by a camera ring, reconstruct its mesh sequence, track its
//! ground-truth surface points through the result, and score everything against the truth.

use crate::eval::{evaluate_folders, FolderOptions, FolderReport};
use crate::gpu::GpuContext;
use crate::io::sequence::MeshSequence;
use crate::synth::{generate, SubjectSource, SynthOptions};
use crate::track::output::write_tracks_csv;
use crate::track::queries::read_points;
use crate::track::{track, Queries};
use crate::train::pipeline::{run_train, TrainConfig, TrainJob, TrainProgress, TrainReport};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The demo's size: small enough for minutes on a 2-core CPU through lavapipe.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoOptions {
    pub views: usize,
    pub frames: usize,
    pub resolution: u32,
    pub canonical_iterations: u32,
    pub temporal_iterations: u32,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self { views: 10, frames: 5, resolution: 128, canonical_iterations: 600, temporal_iterations: 200 }
    }
}

/// The demo's scores against the ground truth, relative where the paper is.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoReport {
    pub options: DemoOptions,
    pub data: PathBuf,
    pub out: PathBuf,
    /// Means over frames of the held-out PSNR of Gaussian and mesh renders, dB.
    pub psnr_gs: f64,
    pub psnr_mesh: f64,
    /// Chamfer (mean nearest-neighbour distance) and EMD as fractions of the ground truth's
    /// bounding-box diagonal, means over frames.
    pub chamfer_per_diagonal: f64,
    pub emd_per_diagonal: f64,
    /// Tracking RMSE as a fraction of the subject's height (its bounding-box extent along y).
    pub tracking_rmse_per_height: f64,
    pub tracked_points: usize,
    pub train: TrainReport,
    pub eval: FolderReport,
}

#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    #[error("generating the data: {0}")]
    Synth(#[from] crate::synth::generate::SynthError),
    #[error("reconstructing: {0}")]
    Train(#[from] crate::train::TrainError),
    #[error("tracking: {0}")]
    Track(#[from] crate::track::TrackError),
    #[error("evaluating: {0}")]
    Eval(#[from] crate::eval::FolderError),
    #[error("reading the result: {0}")]
    Sequence(#[from] crate::io::sequence::SequenceError),
}

/// Runs the demo in `dir` (`data/`, `out/`, `out/trajectories.csv`, `demo.json`). A finished
/// reconstruction in `dir/out` is resumed, not redone.
pub fn run_demo(ctx: &Arc<GpuContext>, dir: &Path, options: &DemoOptions, progress: &mut dyn FnMut(TrainProgress)) -> Result<DemoReport, DemoError> {
    let (data, out) = (dir.join("data"), dir.join("out"));
    if !data.join("dataset.json").is_file() {
        let synth = SynthOptions { subject: SubjectSource::Procedural { subdivisions: 3 }, views: options.views, frames: options.frames, resolution: options.resolution, ..Default::default() };
        generate(&synth, &data)?;
    }
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = options.canonical_iterations;
    config.canonical.densify_until = options.canonical_iterations * 3 / 4;
    config.temporal.iterations = options.temporal_iterations;
    let train = run_train(ctx, &TrainJob { data: data.clone(), out: out.clone(), mesh: None, config, frames: None }, progress)?;

    let sequence = MeshSequence::read(&out.join("meshes"))?;
    let queries = Queries::Points(read_points(&data.join("points.csv"))?);
    let tracked = track(&sequence.faces, &sequence.frames, &queries, 0.05)?;
    write_tracks_csv(&out.join("trajectories.csv"), &tracked.points)?;
    let eval = evaluate_folders(&out, &data, &FolderOptions { chamfer_samples: 20_000, emd_samples: 500, seed: 0 })?;

    let truth = MeshSequence::read(&data.join("meshes"))?;
    let (diagonal, height) = extent(&truth.frames[0]);
    let frames = train.frames.len().max(1) as f64;
    let report = DemoReport {
        options: options.clone(),
        data,
        out,
        psnr_gs: train.frames.iter().map(|f| f.psnr_gs).sum::<f64>() / frames,
        psnr_mesh: train.frames.iter().map(|f| f.psnr_mesh).sum::<f64>() / frames,
        chamfer_per_diagonal: eval.chamfer_mean.unwrap_or(f64::NAN) / diagonal,
        emd_per_diagonal: eval.emd_mean.unwrap_or(f64::NAN) / diagonal,
        tracking_rmse_per_height: eval.tracking.as_ref().map_or(f64::NAN, |t| t.rmse) / height,
        tracked_points: tracked.points.len(),
        train,
        eval,
    };
    let path = dir.join("demo.json");
    crate::io::write_atomically(&path, |w| serde_json::to_writer_pretty(w, &report).map_err(std::io::Error::other))
        .map_err(|error| crate::train::TrainError::Io { path, error })?;
    Ok(report)
}

/// Bounding-box diagonal and height (y extent) of a point set.
fn extent(points: &[[f32; 3]]) -> (f64, f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] as f64);
            hi[k] = hi[k].max(p[k] as f64);
        }
    }
    let d: Vec<f64> = (0..3).map(|k| (hi[k] - lo[k]).max(0.0)).collect();
    ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(f64::MIN_POSITIVE), d[1].max(f64::MIN_POSITIVE))
}
