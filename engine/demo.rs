//! The whole job on generated data with known ground truth. `tagsplat demo` generates a
//! deforming subject seen by a camera ring, reconstructs its mesh sequence, tracks its
//! ground-truth surface points through the result and scores everything against the truth;
//! `tagsplat ablate` does the same for the paper's ablations of one dataset.

use crate::eval::{evaluate_folders, FolderOptions, FolderReport};
use crate::gpu::GpuContext;
use crate::sequence::orient::{Orientation, UpAxis};
use crate::sequence::usd::{write_usda, UsdTracks};
use crate::sequence::{MeshSequence, ReadOptions};
use crate::synth::{generate, SubjectSource, SynthOptions};
use crate::track::clock::Clock;
use crate::track::output::write_pinned_tracks_csv;
use crate::track::queries::read_points;
use crate::track::{track, Queries};
use crate::train::pipeline::{run_train, TrainConfig, TrainJob, TrainProgress, TrainReport};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The demo's size: small enough for a minute on a 2-core CPU through lavapipe.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoOptions {
    /// Cameras in the ring (default 10).
    pub views: usize,
    /// Frames generated (default 5).
    pub frames: usize,
    /// Image size, pixels (default 128).
    pub resolution: u32,
    /// Frame 0's iterations (default 600); densification ends at three quarters of them.
    pub canonical_iterations: u32,
    /// Most per-vertex iterations of every later frame (default 200).
    pub temporal_iterations: u32,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            views: 10,
            frames: 5,
            resolution: 128,
            canonical_iterations: 600,
            temporal_iterations: 200,
        }
    }
}

/// A reconstruction scored against its ground truth, relative where the paper is.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Scores {
    /// Means over frames of the evaluation-view PSNR of Gaussian and mesh renders, dB.
    pub psnr_gs: f64,
    /// Mean PSNR of the mesh renders over frames, dB.
    pub psnr_mesh: f64,
    /// Chamfer (mean nearest-neighbour distance) and EMD as fractions of the ground truth's
    /// bounding-box diagonal, means over frames.
    pub chamfer_per_diagonal: f64,
    /// EMD as a fraction of the ground truth's bounding-box diagonal, mean over frames.
    pub emd_per_diagonal: f64,
    /// Tracking MSE (squared scene units) and RMSE as a fraction of the subject's height (its
    /// ground-truth frame-0 extent along y).
    pub tracking_mse: f64,
    /// Tracking RMSE as a fraction of the subject's height.
    pub tracking_rmse_per_height: f64,
    /// Ground-truth points bound to the reconstruction and tracked.
    pub tracked_points: usize,
    /// Wall time of reconstruction, tracking and scoring, seconds.
    pub seconds: f64,
    /// Every metric of the output folder against the data folder.
    pub eval: FolderReport,
}

/// What [`run_demo`] reports (also written to `demo.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoReport {
    /// The demo's size.
    pub options: DemoOptions,
    /// The generated dataset (`dir/data`).
    pub data: PathBuf,
    /// The reconstruction (`dir/out`).
    pub out: PathBuf,
    /// The reconstruction's scores.
    pub scores: Scores,
    /// The training run's report.
    pub train: TrainReport,
}

/// Why the demo (or an ablation run) failed; each variant names the step.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// The synthetic data could not be generated.
    #[error("generating the data: {0}")]
    Synth(#[from] crate::synth::generate::SynthError),
    /// The reconstruction failed (writing the demo's own files included).
    #[error("reconstructing: {0}")]
    Train(#[from] crate::train::TrainError),
    /// The ground-truth points could not be read or tracked.
    #[error("tracking: {0}")]
    Track(#[from] crate::track::TrackError),
    /// The output could not be scored.
    #[error("evaluating: {0}")]
    Eval(#[from] crate::eval::FolderError),
    /// A mesh sequence (reconstructed or ground truth) could not be read.
    #[error("reading the result: {0}")]
    Sequence(#[from] crate::sequence::SequenceError),
    /// The tracks' USD stage could not be written.
    #[error("writing the tracks: {0}")]
    Usd(#[from] crate::sequence::usd::UsdError),
}

/// Runs the demo in `dir` (`data/`, `out/`, `out/trajectories.csv`, `demo.json`). A finished
/// reconstruction in `dir/out` is resumed, not redone.
pub fn run_demo(
    ctx: &Arc<GpuContext>,
    dir: &Path,
    options: &DemoOptions,
    progress: &mut dyn FnMut(TrainProgress),
) -> Result<DemoReport, DemoError> {
    let (data, out) = (dir.join("data"), dir.join("out"));
    if !data.join("dataset.json").is_file() {
        let synth = SynthOptions {
            subject: SubjectSource::Procedural { subdivisions: 3 },
            views: options.views,
            frames: options.frames,
            width: options.resolution,
            height: options.resolution,
            ..Default::default()
        };
        generate(&synth, &data)?;
    }
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = options.canonical_iterations;
    config.canonical.densify_until = options.canonical_iterations * 3 / 4;
    config.temporal.iterations = options.temporal_iterations;
    let (train, scores) = train_and_score(ctx, &data, &out, config, progress)?;
    let report = DemoReport { options: options.clone(), data, out, scores, train };
    write_json(&dir.join("demo.json"), &report)?;
    Ok(report)
}

/// The reconstructed sequence with the tracked points, as one USD stage (the generator's rig is
/// Y-up, so nothing is turned).
fn write_tracks_usda(
    path: &Path,
    sequence: &MeshSequence,
    points: &[crate::track::output::TrackedPoint],
) -> Result<(), DemoError> {
    let ids: Vec<String> = points.iter().map(|p| p.id.clone()).collect();
    let trajectories: Vec<_> = points.iter().map(|p| p.trajectory.clone()).collect();
    let tracks = UsdTracks { ids: &ids, trajectories: &trajectories };
    Ok(write_usda(
        path,
        sequence,
        crate::synth::gltf::FPS,
        Orientation::keep(UpAxis::Y),
        Some(&tracks),
    )?)
}

/// Reconstructs `data` into `out` (resuming what is there), tracks the ground-truth points
/// (`data/points.csv`) into `out/trajectories.csv` and, with the mesh, `out/tracks.usda`, and
/// scores the result against `data`.
pub fn train_and_score(
    ctx: &Arc<GpuContext>,
    data: &Path,
    out: &Path,
    config: TrainConfig,
    progress: &mut dyn FnMut(TrainProgress),
) -> Result<(TrainReport, Scores), DemoError> {
    let started = std::time::Instant::now();
    let train = run_train(ctx, &TrainJob::new(data, out, config), progress)?;
    let (sequence, info) = MeshSequence::read_with(&out.join("meshes"), &ReadOptions::default())?;
    let queries = Queries::Points(read_points(&data.join("points.csv"))?);
    // Bind within 5% of the extent: the reconstruction is not the ground-truth surface.
    let tracked = track(&sequence.faces, &sequence.frames, &queries, 0.05)?;
    let clock = Clock::of(&info, sequence.frames.len())?;
    write_pinned_tracks_csv(&out.join("trajectories.csv"), &tracked.points, &clock)?;
    write_tracks_usda(&out.join("tracks.usda"), &sequence, &tracked.points)?;
    let eval = evaluate_folders(
        out,
        data,
        &FolderOptions { chamfer_samples: 20_000, emd_samples: 500, seed: 0 },
    )?;
    let truth = MeshSequence::read(&data.join("meshes"))?;
    let (lo, hi) = crate::mesh::bounding_box(&truth.frames[0]).unwrap_or_default();
    let (diagonal, height) =
        (lo.distance(hi).max(f64::MIN_POSITIVE), (hi.y - lo.y).max(f64::MIN_POSITIVE));
    let frames = train.frames.len().max(1) as f64;
    let tracking = eval.tracking.as_ref();
    let scores = Scores {
        psnr_gs: train.frames.iter().map(|f| f.psnr_gs).sum::<f64>() / frames,
        psnr_mesh: train.frames.iter().map(|f| f.psnr_mesh).sum::<f64>() / frames,
        chamfer_per_diagonal: eval.chamfer_mean.unwrap_or(f64::NAN) / diagonal,
        emd_per_diagonal: eval.emd_mean.unwrap_or(f64::NAN) / diagonal,
        tracking_mse: tracking.map_or(f64::NAN, |t| t.mse),
        tracking_rmse_per_height: tracking.map_or(f64::NAN, |t| t.rmse) / height,
        tracked_points: tracked.points.len(),
        seconds: started.elapsed().as_secs_f64(),
        eval,
    };
    Ok((train, scores))
}

/// One ablation: a name and what it switches off.
pub struct Ablation {
    /// The variant's name, as its table row shows it; its output folder is named after it.
    pub name: &'static str,
    /// Changes the base configuration into the variant's.
    pub apply: fn(&mut TrainConfig),
}

/// The paper's ablations (its tables 3 and 4): canonical terms and the topology-preserving
/// densification, then the temporal terms.
pub fn paper_ablations() -> Vec<Ablation> {
    vec![
        Ablation { name: "full model", apply: |_| {} },
        Ablation {
            name: "w/o mesh loss",
            apply: |c| (c.loss.mesh.color, c.loss.mesh.mask) = (0.0, 0.0),
        },
        Ablation { name: "w/o normal loss", apply: |c| c.loss.normal = 0.0 },
        Ablation { name: "w/o smoothness loss", apply: |c| c.loss.laplacian = 0.0 },
        Ablation {
            name: "w/o topology D&P",
            apply: |c| c.canonical.densify_from = c.canonical.densify_until,
        },
        Ablation { name: "w/o length loss", apply: |c| c.loss.edge_length = 0.0 },
        Ablation { name: "w/o rigid loss", apply: |c| c.loss.rigidity = 0.0 },
        Ablation { name: "w/o rotation loss", apply: |c| c.loss.rotation = 0.0 },
    ]
}

/// Runs every ablation of `base` on `data` into `out/<n>_<name>/` and writes `out/ablation.md`
/// and `out/ablation.json`; returns the rows.
pub fn run_ablations(
    ctx: &Arc<GpuContext>,
    data: &Path,
    out: &Path,
    base: &TrainConfig,
    progress: &mut dyn FnMut(&str, TrainProgress),
) -> Result<Vec<(String, Scores)>, DemoError> {
    let mut rows = Vec::new();
    for (i, ablation) in paper_ablations().iter().enumerate() {
        let mut config = base.clone();
        (ablation.apply)(&mut config);
        let dir = out.join(format!("{i}_{}", ablation.name.replace(['/', ' ', '&'], "_")));
        let (_, scores) =
            train_and_score(ctx, data, &dir, config, &mut |p| progress(ablation.name, p))?;
        rows.push((ablation.name.to_string(), scores));
    }
    let mut table = String::from("| variant | PSNR gs (dB) | PSNR mesh (dB) | Chamfer / diagonal | EMD / diagonal | tracking MSE | tracking RMSE / height | seconds |\n|---|---|---|---|---|---|---|---|\n");
    for (name, s) in &rows {
        table += &format!(
            "| {name} | {:.2} | {:.2} | {:.5} | {:.5} | {:.3e} | {:.5} | {:.0} |\n",
            s.psnr_gs,
            s.psnr_mesh,
            s.chamfer_per_diagonal,
            s.emd_per_diagonal,
            s.tracking_mse,
            s.tracking_rmse_per_height,
            s.seconds
        );
    }
    let path = out.join("ablation.md");
    crate::io::write_atomically(&path, |w| std::io::Write::write_all(w, table.as_bytes()))
        .map_err(|error| crate::train::TrainError::Io { path, error })?;
    let json: Vec<_> =
        rows.iter().map(|(name, s)| serde_json::json!({ "variant": name, "scores": s })).collect();
    write_json(&out.join("ablation.json"), &json)?;
    Ok(rows)
}

fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), DemoError> {
    crate::io::write_json_atomically(path, value)
        .map_err(|error| crate::train::TrainError::Io { path: path.to_owned(), error }.into())
}
