//! A predicted mesh sequence (the output folder of `tagsplat train`) scored against a
//! hard-motion benchmark's ground truth ([`ground_truth`]), as the benchmarks' README defines
//! the scores. Every length is divided by the ground truth's `size` (unitless: a fraction of
//! the subject's largest side).
//! - Tracking: `points.csv` bound to the predicted frame-0 mesh at its closest surface point
//!   (however far: nothing is refused), followed through the predicted frames
//!   ([`crate::track::track`]); RMSE and largest distance to `tracks.csv` per frame and over
//!   all points and frames ([`crate::eval::tracking_error`]); the same error split into the
//!   points' distance to the true surface and the rest, along it ([`crate::eval::split_on_surface`]);
//!   and split into points that at least [`SEEN_VIEWS`](crate::eval::SEEN_VIEWS) training cameras
//!   see at frame 0 and at the frame, and the rest ([`crate::eval::sight`]), when the ground
//!   truth sits in its dataset (`DIR/gt`, the cameras read from `DIR`); with those cameras, the
//!   same error in pixels ([`crate::eval::pixels`]).
//! - Chamfer: point-to-surface, per frame ([`crate::eval::chamfer_to_surface`]).
//! - Held-out PSNR, iterations, wall time, stop reason: `OUT/report.json` ([`train_report`]).
//!
//! Frames the prediction lacks are listed and skipped; only frame 0 is required.

pub mod files;
pub mod ground_truth;
pub mod train_report;

pub use files::write_sequence_eval;
pub use ground_truth::{find_ground_truth, GroundTruth};
pub use train_report::{read_train_report, FrameTrainStats};

use crate::camera::Camera;
use crate::dataset::Dataset;
use crate::eval::{
    cameras_seeing, chamfer_to_surface, seen_in_both, split_on_surface, tracking_error, EvalError,
    PixelSplit, SightSplit, SurfaceSplit, TrackingReport,
};
use crate::io::trajectories::{TrackPoint, TrajectoriesError};
use crate::mesh::{MeshError, TriMesh};
use crate::sequence::{check_same_topology, MeshSequence, SequenceError};
use crate::track::{track, Queries, TrackError, TrackReport, TrackedPoint};
use crate::train::output::mesh_path;
use serde::Serialize;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Why a sequence could not be scored; every variant names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum SequenceEvalError {
    /// A file that reads but does not fit: a missing frame 0, an unbindable point, a bad frame
    /// range or ground truth.
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The file (or folder) at fault.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A metric failed on the data of a file.
    #[error("{}: {source}", path.display())]
    Metric {
        /// The file.
        path: PathBuf,
        /// The metric's error.
        source: EvalError,
    },
    /// A reader's error that names its file already.
    #[error(transparent)]
    Read(TrajectoriesError),
    /// The ground truth's `points.csv` could not be read.
    #[error(transparent)]
    Query(TrackError),
    /// A mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A predicted frame's vertex count or faces differ from frame 0's.
    #[error(transparent)]
    Sequence(#[from] SequenceError),
}

/// Options of [`evaluate_sequence`].
#[derive(Clone, Debug)]
pub struct SequenceEvalOptions {
    /// Area-uniform samples per mesh for Chamfer (the benchmarks' score, docs/benchmarks.md: 5000).
    pub chamfer_samples: usize,
    /// Seeds the Chamfer samples.
    pub seed: u64,
    /// Frames to score (default: every ground-truth frame).
    pub frames: Option<Range<usize>>,
}

impl Default for SequenceEvalOptions {
    fn default() -> Self {
        Self { chamfer_samples: 5000, seed: 0, frames: None }
    }
}

/// One frame's scores, fractions of `size`.
#[derive(Clone, Debug, Serialize)]
pub struct FrameScores {
    /// The frame index.
    pub frame: usize,
    /// None when `tracks.csv` has no row for the frame.
    pub tracking_rmse_over_size: Option<f64>,
    /// Largest tracking error of the frame (None as `tracking_rmse_over_size`).
    pub tracking_max_over_size: Option<f64>,
    /// The RMSE's part off the true surface: the tracked points' distance to it (None as the
    /// RMSE). Its square and the next one's add up to the RMSE's.
    pub tracking_off_surface_over_size: Option<f64>,
    /// The RMSE's part along the true surface: points on the right surface, in the wrong place.
    pub tracking_along_surface_over_size: Option<f64>,
    /// RMSE of the points the training cameras see at frame 0 and here, of the rest, and the
    /// seen points' share (None without the dataset's cameras or without such points).
    #[serde(flatten)]
    pub sight: SightScores,
    /// The tracking error in pixels ([`crate::eval::pixels`]): RMS over the frame's points of
    /// each one's median over the training cameras that see it (None without cameras).
    pub tracking_rmse_px: Option<f64>,
    /// Point-to-surface Chamfer, and its halves (prediction → truth, truth → prediction).
    pub chamfer_over_size: f64,
    /// Chamfer's prediction → truth half.
    pub chamfer_pred_to_gt_over_size: f64,
    /// Chamfer's truth → prediction half.
    pub chamfer_gt_to_pred_over_size: f64,
    /// The frame's entry of the training report (all None without one).
    #[serde(flatten)]
    pub train: FrameTrainStats,
}

/// The tracking error split by sight ([`crate::eval::sight`]), fractions of `size`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SightScores {
    /// RMSE of the points at least `SEEN_VIEWS` training cameras see at frame 0 and at t.
    pub tracking_seen_over_size: Option<f64>,
    /// RMSE of the other points: what no image term can pin.
    pub tracking_unseen_over_size: Option<f64>,
    /// The seen points' share of the scored (point, frame) pairs.
    pub seen_share: Option<f64>,
}

impl SightScores {
    fn of(split: &SightSplit, size: f64) -> Self {
        Self {
            tracking_seen_over_size: split.seen_rms().map(|v| v / size),
            tracking_unseen_over_size: split.unseen_rms().map(|v| v / size),
            seen_share: split.seen_share(),
        }
    }
}

/// A value and the frame it belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameValue {
    /// The frame index.
    pub frame: usize,
    /// The value.
    pub value: f64,
}

/// The sequence's scores; lengths are fractions of `size`.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceSummary {
    /// The ground truth's `size`, scene units.
    pub size: f64,
    /// Ground-truth points tracked.
    pub points: usize,
    /// Chamfer samples per mesh.
    pub chamfer_samples: usize,
    /// Frames scored, and frames of the requested range the prediction lacks.
    pub frames: Vec<usize>,
    /// Frames of the requested range the prediction lacks.
    pub missing_frames: Vec<usize>,
    /// Distance from the ground-truth points to the predicted frame-0 surface: mean, largest.
    pub binding_mean_over_size: f64,
    /// Largest distance from a ground-truth point to the predicted frame-0 surface.
    pub binding_max_over_size: f64,
    /// Over all points and scored frames (None without a track row in them).
    pub tracking_rmse_over_size: Option<f64>,
    /// Largest tracking error over all points and scored frames (None as the RMSE).
    pub tracking_max_over_size: Option<f64>,
    /// The RMSE's parts off and along the true surface, over all points and scored frames.
    pub tracking_off_surface_over_size: Option<f64>,
    /// The RMSE's part along the true surface.
    pub tracking_along_surface_over_size: Option<f64>,
    /// The RMSE split by sight over all points and scored frames.
    #[serde(flatten)]
    pub sight: SightScores,
    /// The tracking error in pixels over all points and scored frames (None without cameras).
    pub tracking_rmse_px: Option<f64>,
    /// (Point, frame) pairs no training camera sees, left out of `tracking_rmse_px`.
    pub tracking_px_unmeasured: usize,
    /// The frame of the highest tracking RMSE.
    pub tracking_worst_frame: Option<FrameValue>,
    /// Mean over the scored frames, and the worst frame (None when no frame was scored).
    pub chamfer_mean_over_size: Option<f64>,
    /// The frame of the highest Chamfer distance.
    pub chamfer_worst_frame: Option<FrameValue>,
    /// PSNR of the first and the last scored frame, dB (None when the report lacks it).
    pub psnr_gs_first_db: Option<f64>,
    /// Gaussian-render PSNR of the last scored frame, dB.
    pub psnr_gs_last_db: Option<f64>,
    /// Mesh-render PSNR of the first scored frame, dB.
    pub psnr_mesh_first_db: Option<f64>,
    /// Mesh-render PSNR of the last scored frame, dB.
    pub psnr_mesh_last_db: Option<f64>,
    /// The training report read, None when the prediction has none.
    pub train_report: Option<PathBuf>,
}

/// What [`evaluate_sequence`] returns.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceEval {
    /// The prediction folder.
    pub pred: PathBuf,
    /// The ground truth's folder.
    pub ground_truth: PathBuf,
    /// The sequence's scores.
    pub summary: SequenceSummary,
    /// Every scored frame's scores, in frame order.
    pub frames: Vec<FrameScores>,
}

/// Scores the prediction folder `pred` against `gt` (see the module docs). Errors name the
/// file: no predicted frame 0, a frame whose vertex count or faces differ from frame 0's, an
/// unreadable mesh or report, a range past the ground truth.
pub fn evaluate_sequence(
    pred: &Path,
    gt: &GroundTruth,
    options: &SequenceEvalOptions,
) -> Result<SequenceEval, SequenceEvalError> {
    let range = frame_range(gt, options)?;
    let (present, missing): (Vec<usize>, Vec<usize>) =
        range.partition(|&t| mesh_path(pred, t).is_file());
    // Frame 0 binds the points even when the range starts later.
    let loaded: Vec<usize> =
        std::iter::once(0).chain(present.iter().copied().filter(|&t| t > 0)).collect();
    let sequence = read_predicted(pred, &loaded)?;
    let tracked = bind_points(pred, gt, &sequence)?;
    let tracking = tracking_scores(gt, &tracked, &loaded, &present)?;
    let report_path = pred.join("report.json");
    let train = read_train_report(&report_path)?;
    let mut frames = Vec::with_capacity(present.len());
    let mut totals = (SurfaceSplit::default(), SightSplit::default(), PixelSplit::default());
    let by_id: HashMap<&str, &TrackedPoint> =
        tracked.points.iter().map(|p| (p.id.as_str(), p)).collect();
    let sight = Sight::new(gt)?;
    for (i, &t) in loaded.iter().enumerate().filter(|(_, t)| present.contains(t)) {
        let truth = TriMesh::read_ply(&gt.mesh_path(t))?;
        let chamfer =
            chamfer_frame(pred, gt, t, (&sequence.frames[i], &sequence.faces), &truth, options)?;
        let (split, seen, px) = split_frame(gt, &by_id, (i, t), &truth, &sight)?;
        totals = (totals.0 + split, totals.1 + seen, totals.2 + px);
        let per_frame = |list: &[(u32, f64)]| {
            list.iter().find(|(f, _)| *f as usize == t).map(|(_, v)| v / gt.size)
        };
        let (off, along) = split.rms().map(|(o, a)| (o / gt.size, a / gt.size)).unzip();
        frames.push(FrameScores {
            frame: t,
            tracking_rmse_over_size: tracking.as_ref().and_then(|r| per_frame(&r.rmse_per_frame)),
            tracking_max_over_size: tracking.as_ref().and_then(|r| per_frame(&r.max_per_frame)),
            tracking_off_surface_over_size: off,
            tracking_along_surface_over_size: along,
            sight: SightScores::of(&seen, gt.size),
            tracking_rmse_px: px.rms(),
            chamfer_over_size: chamfer.mean / gt.size,
            chamfer_pred_to_gt_over_size: chamfer.pred_to_gt / gt.size,
            chamfer_gt_to_pred_over_size: chamfer.gt_to_pred / gt.size,
            train: train.as_ref().and_then(|m| m.get(&t).cloned()).unwrap_or_default(),
        });
    }
    let summary = summarize(
        gt,
        options,
        &tracked,
        (tracking.as_ref(), totals),
        &frames,
        missing,
        train.is_some().then_some(report_path),
    );
    Ok(SequenceEval { pred: pred.to_owned(), ground_truth: gt.root.clone(), summary, frames })
}

/// The requested frames, checked against the ground truth's.
fn frame_range(
    gt: &GroundTruth,
    options: &SequenceEvalOptions,
) -> Result<Range<usize>, SequenceEvalError> {
    let range = options.frames.clone().unwrap_or(0..gt.frames);
    if range.is_empty() || range.end > gt.frames {
        let problem = format!(
            "frames {}..{} requested, the ground truth has frames 0..{}",
            range.start, range.end, gt.frames
        );
        return Err(SequenceEvalError::Invalid { path: gt.root.join("meshes"), problem });
    }
    Ok(range)
}

/// The predicted meshes of `frames` (frame 0 first) as one sequence: frame 0's faces, and
/// every frame with its vertex count and faces.
fn read_predicted(pred: &Path, frames: &[usize]) -> Result<MeshSequence, SequenceEvalError> {
    let first = mesh_path(pred, 0);
    if !first.is_file() {
        return Err(SequenceEvalError::Invalid {
            path: first,
            problem: "missing: frame 0 binds the ground-truth points".into(),
        });
    }
    let mut sequence = MeshSequence::default();
    for &t in frames {
        let path = mesh_path(pred, t);
        let mesh = TriMesh::read_ply(&path)?;
        if sequence.frames.is_empty() {
            sequence.faces = mesh.faces;
        } else {
            check_same_topology(&sequence, &mesh, t, &path, &first)?;
        }
        sequence.frames.push(mesh.positions);
    }
    Ok(sequence)
}

/// Every ground-truth point bound to the predicted frame 0 and followed through the sequence.
fn bind_points(
    pred: &Path,
    gt: &GroundTruth,
    sequence: &MeshSequence,
) -> Result<TrackReport, SequenceEvalError> {
    let frame0 = mesh_path(pred, 0);
    let queries = Queries::Points(gt.points.clone());
    // No distance limit: a point far from the predicted surface is an error to score, not to drop.
    let tracked = track(&sequence.faces, &sequence.frames, &queries, f64::INFINITY)
        .map_err(|e| SequenceEvalError::Invalid { path: frame0.clone(), problem: e.to_string() })?;
    match tracked.unbound.first() {
        Some(u) => Err(SequenceEvalError::Invalid {
            path: frame0,
            problem: format!("ground-truth point `{}` could not be bound: {}", u.id, u.reason),
        }),
        None => Ok(tracked),
    }
}

/// Tracking errors over the `tracks.csv` rows of the `present` frames (None when there are
/// none); `loaded[i]` is the frame of trajectory entry i.
fn tracking_scores(
    gt: &GroundTruth,
    tracked: &TrackReport,
    loaded: &[usize],
    present: &[usize],
) -> Result<Option<TrackingReport>, SequenceEvalError> {
    let predicted: Vec<TrackPoint> = tracked
        .points
        .iter()
        .flat_map(|p| {
            p.trajectory.iter().zip(loaded).map(|(&position, &t)| TrackPoint {
                id: p.id.clone(),
                frame: t as u32,
                position,
            })
        })
        .collect();
    let truth: Vec<TrackPoint> =
        gt.tracks.iter().filter(|r| present.contains(&(r.frame as usize))).cloned().collect();
    if truth.is_empty() {
        return Ok(None);
    }
    let report = tracking_error(&predicted, &truth)
        .map_err(|source| SequenceEvalError::Metric { path: gt.root.join("tracks.csv"), source })?;
    Ok(Some(report))
}

/// The tracking error of frame `t` (entry `i` of the trajectories) split against the true
/// mesh `truth` and by sight, and in pixels; every `tracks.csv` row of the frame whose point
/// was tracked (`by_id`).
fn split_frame(
    gt: &GroundTruth,
    by_id: &HashMap<&str, &TrackedPoint>,
    (i, t): (usize, usize),
    truth: &TriMesh,
    sight: &Sight,
) -> Result<(SurfaceSplit, SightSplit, PixelSplit), SequenceEvalError> {
    let rows: Vec<(&str, [f64; 3], [f64; 3])> = gt
        .tracks
        .iter()
        .filter(|r| r.frame as usize == t)
        .filter_map(|r| {
            by_id.get(r.id.as_str()).map(|p| (r.id.as_str(), p.trajectory[i], r.position))
        })
        .collect();
    let metric = |source| SequenceEvalError::Metric { path: gt.mesh_path(t), source };
    let pairs: Vec<([f64; 3], [f64; 3])> = rows.iter().map(|&(_, p, g)| (p, g)).collect();
    let split = split_on_surface(&pairs, (&truth.positions, &truth.faces)).map_err(metric)?;
    let (mut seen, mut px) = (SightSplit::default(), PixelSplit::default());
    if !sight.cameras.is_empty() {
        let truths: Vec<[f64; 3]> = rows.iter().map(|&(_, _, g)| g).collect();
        let now = cameras_seeing(&truths, (&truth.positions, &truth.faces), &sight.cameras)
            .map_err(metric)?;
        for ((id, p, g), now) in rows.iter().zip(&now) {
            let before = sight.frame0.get(*id).map_or(&[][..], Vec::as_slice);
            let (p, g) = (glam::DVec3::from(*p), glam::DVec3::from(*g));
            seen.add_pair(p.distance_squared(g), seen_in_both(before, now));
            px.add_pair(p, g, &sight.cameras, now);
        }
    }
    Ok((split, seen, px))
}

/// The training cameras of the ground truth's dataset and which of them see each point at
/// frame 0 (no cameras when the ground truth is not inside a dataset that loads).
struct Sight {
    cameras: Vec<Camera>,
    frame0: HashMap<String, Vec<bool>>,
}

impl Sight {
    fn new(gt: &GroundTruth) -> Result<Self, SequenceEvalError> {
        let dataset = gt.root.parent().and_then(|dir| Dataset::load(dir).ok());
        let Some(dataset) = dataset else {
            return Ok(Self { cameras: Vec::new(), frame0: HashMap::new() });
        };
        let cameras: Vec<Camera> = dataset.train.iter().map(|&c| dataset.cameras[c]).collect();
        let truth = TriMesh::read_ply(&gt.mesh_path(0))?;
        let points: Vec<[f64; 3]> = gt.points.iter().map(|(_, p)| *p).collect();
        let seen = cameras_seeing(&points, (&truth.positions, &truth.faces), &cameras)
            .map_err(|source| SequenceEvalError::Metric { path: gt.mesh_path(0), source })?;
        let frame0 = gt.points.iter().map(|(id, _)| id.clone()).zip(seen).collect();
        Ok(Self { cameras, frame0 })
    }
}

/// Point-to-surface Chamfer of predicted frame `t` against the true mesh `truth`, scene units.
fn chamfer_frame(
    pred: &Path,
    gt: &GroundTruth,
    t: usize,
    mesh: (&[[f32; 3]], &[[u32; 3]]),
    truth: &TriMesh,
    options: &SequenceEvalOptions,
) -> Result<crate::eval::SurfaceChamferReport, SequenceEvalError> {
    chamfer_to_surface(
        mesh,
        (&truth.positions, &truth.faces),
        options.chamfer_samples,
        options.seed,
    )
    .map_err(|e| SequenceEvalError::Invalid {
        path: mesh_path(pred, t),
        problem: format!("against {}: {e}", gt.mesh_path(t).display()),
    })
}

/// The sequence's summary; `tracking` is the tracking error and its splits (surface, sight,
/// pixels) over every scored frame.
fn summarize(
    gt: &GroundTruth,
    options: &SequenceEvalOptions,
    tracked: &TrackReport,
    (tracking, (split, sight, px)): (
        Option<&TrackingReport>,
        (SurfaceSplit, SightSplit, PixelSplit),
    ),
    frames: &[FrameScores],
    missing_frames: Vec<usize>,
    train_report: Option<PathBuf>,
) -> SequenceSummary {
    let bindings: Vec<f64> = tracked.points.iter().map(|p| p.binding.distance / gt.size).collect();
    let worst = |value: &dyn Fn(&FrameScores) -> Option<f64>| {
        frames
            .iter()
            .filter_map(|f| Some(FrameValue { frame: f.frame, value: value(f)? }))
            .max_by(|a, b| a.value.total_cmp(&b.value))
    };
    let (first, last) = (frames.first().map(|f| &f.train), frames.last().map(|f| &f.train));
    SequenceSummary {
        size: gt.size,
        points: bindings.len(),
        chamfer_samples: options.chamfer_samples,
        frames: frames.iter().map(|f| f.frame).collect(),
        missing_frames,
        binding_mean_over_size: bindings.iter().sum::<f64>() / bindings.len().max(1) as f64,
        binding_max_over_size: bindings.iter().copied().fold(0.0, f64::max),
        tracking_rmse_over_size: tracking.map(|r| r.rmse / gt.size),
        tracking_max_over_size: tracking.map(|r| r.max / gt.size),
        tracking_off_surface_over_size: split.rms().map(|(o, _)| o / gt.size),
        tracking_along_surface_over_size: split.rms().map(|(_, a)| a / gt.size),
        sight: SightScores::of(&sight, gt.size),
        tracking_rmse_px: px.rms(),
        tracking_px_unmeasured: px.unmeasured,
        tracking_worst_frame: worst(&|f| f.tracking_rmse_over_size),
        chamfer_mean_over_size: (!frames.is_empty())
            .then(|| frames.iter().map(|f| f.chamfer_over_size).sum::<f64>() / frames.len() as f64),
        chamfer_worst_frame: worst(&|f| Some(f.chamfer_over_size)),
        psnr_gs_first_db: first.and_then(|s| s.psnr_gs_db),
        psnr_gs_last_db: last.and_then(|s| s.psnr_gs_db),
        psnr_mesh_first_db: first.and_then(|s| s.psnr_mesh_db),
        psnr_mesh_last_db: last.and_then(|s| s.psnr_mesh_db),
        train_report,
    }
}
