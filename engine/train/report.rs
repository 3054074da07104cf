//! What a fit reports: held-out quality, speed, per-pass GPU time and the speed-against-error
//! curve (CSV and a PNG plot).

use super::densify::DensifyCounts;
use super::TrainError;
use crate::io::plot::{write_svg, Panel, Series};
use crate::io::{write_atomically, write_json_atomically};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// One point of the speed-against-error curve.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    /// The iteration evaluated after.
    pub iteration: u32,
    /// Training time so far (evaluation excluded), seconds.
    pub wall_s: f64,
    /// Mean PSNR of the evaluation views (RGB), dB.
    pub psnr: f64,
    /// Mean SSIM of the evaluation views (RGB).
    pub ssim: f64,
    /// Gaussians at that iteration.
    pub gaussians: usize,
}

/// One densification step of a fit.
#[derive(Clone, Debug, Serialize)]
pub struct DensifyEvent {
    /// The iteration it ran after.
    pub iteration: u32,
    /// Gaussians cloned, split and pruned.
    #[serde(flatten)]
    pub counts: DensifyCounts,
    /// Gaussians after the step.
    pub gaussians: usize,
}

/// What a fit reports (`OUT/report.json` of `tagsplat fit`).
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// The GPU's name.
    pub device: String,
    /// The dataset frame fitted ([`run_fit_job`](super::run_fit_job) sets it;
    /// [`fit`](super::fit) leaves 0).
    pub frame: usize,
    /// Iterations run (fewer than configured when the run stopped early).
    pub iterations: u32,
    /// Gaussians in the final scene.
    pub gaussians: usize,
    /// Which views the PSNR/SSIM are on: "held-out" or "training" (a dataset with no held-out
    /// camera).
    pub eval_views: &'static str,
    /// Mean PSNR of the evaluation views before the first iteration, dB.
    pub initial_psnr: f64,
    /// Mean PSNR of the evaluation views at the end, dB.
    pub psnr: f64,
    /// Mean SSIM of the evaluation views at the end.
    pub ssim: f64,
    /// Whole run, evaluation and densification included, seconds.
    pub wall_s: f64,
    /// Optimisation steps only, seconds.
    pub train_wall_s: f64,
    /// Iterations per second of optimisation time (`train_wall_s`).
    pub iterations_per_s: f64,
    /// Mean GPU milliseconds per iteration, by pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// Mean loss of each statistics interval, by the interval's last iteration.
    pub loss: Vec<(u32, f32)>,
    /// The speed-against-error curve: one point every `report.eval_every` iterations and at
    /// the last configured iteration.
    pub curve: Vec<CurvePoint>,
    /// Every densification step, in order.
    pub densify: Vec<DensifyEvent>,
    /// Steps whose intersections outgrew the splatter's buffers (rendered without the excess;
    /// the buffers then grew).
    pub truncated_steps: u32,
    /// Training views whose targets were on the device at once: all of them unless the
    /// device's memory could not hold them (`train::targets`).
    pub targets_on_device: usize,
    /// Targets uploaded for a step because they were streamed (0 when all were on the device).
    pub target_uploads: u64,
    /// Why the run stopped before its last iteration (a non-finite loss), if it did.
    pub stopped: Option<String>,
}

impl FitReport {
    /// Writes the report as pretty JSON to `path`, atomically; fails with [`TrainError::Io`].
    pub fn write_json(&self, path: &Path) -> Result<(), TrainError> {
        write_json_atomically(path, self)
            .map_err(|error| TrainError::Io { path: path.to_owned(), error })
    }
}

/// `iteration,wall_s,psnr,ssim,gaussians` per curve point.
pub fn write_curve_csv(path: &Path, curve: &[CurvePoint]) -> Result<(), TrainError> {
    write_atomically(path, |w| {
        writeln!(w, "iteration,wall_s,psnr,ssim,gaussians")?;
        for p in curve {
            writeln!(
                w,
                "{},{:.4},{:.4},{:.6},{}",
                p.iteration, p.wall_s, p.psnr, p.ssim, p.gaussians
            )?;
        }
        Ok(())
    })
    .map_err(|error| TrainError::Io { path: path.to_owned(), error })
}

/// PSNR against training seconds as an SVG plot; the CSV beside it carries every number.
pub fn write_curve_plot(path: &Path, curve: &[CurvePoint]) -> Result<(), TrainError> {
    let psnr =
        Series { name: "PSNR".into(), points: curve.iter().map(|p| [p.wall_s, p.psnr]).collect() };
    let panel = Panel {
        title: "Training curve".into(),
        x_label: "training time (s)".into(),
        y_label: "PSNR (dB)".into(),
        series: vec![psnr],
        equal_scale: false,
    };
    write_svg(path, &[panel]).map_err(|error| TrainError::Io { path: path.to_owned(), error })
}
