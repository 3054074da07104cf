//! What a fit reports: held-out quality, speed, per-pass GPU time and the speed-against-error
//! curve (CSV and a PNG plot).

use super::densify::DensifyCounts;
use super::TrainError;
use crate::io::plot::{write_svg, Panel, Series};
use crate::io::write_atomically;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// One point of the speed-against-error curve.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    pub iteration: u32,
    /// Training time so far (evaluation excluded), seconds.
    pub wall_s: f64,
    pub psnr: f64,
    pub ssim: f64,
    pub gaussians: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct DensifyEvent {
    pub iteration: u32,
    #[serde(flatten)]
    pub counts: DensifyCounts,
    pub gaussians: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    pub device: String,
    pub frame: usize,
    pub iterations: u32,
    pub gaussians: usize,
    /// Which views the PSNR/SSIM are on: "held-out" or "training" (a dataset with no held-out
    /// camera).
    pub eval_views: &'static str,
    pub initial_psnr: f64,
    pub psnr: f64,
    pub ssim: f64,
    /// Whole run, evaluation and densification included, seconds.
    pub wall_s: f64,
    /// Optimisation steps only, seconds.
    pub train_wall_s: f64,
    pub iterations_per_s: f64,
    /// Mean GPU milliseconds per iteration, by pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// Mean loss of each statistics interval, by the interval's last iteration.
    pub loss: Vec<(u32, f32)>,
    pub curve: Vec<CurvePoint>,
    pub densify: Vec<DensifyEvent>,
    /// Steps whose intersections outgrew the splatter's buffers (rendered without the excess;
    /// the buffers then grew).
    pub truncated_steps: u32,
    /// Why the run stopped before its last iteration (a non-finite loss), if it did.
    pub stopped: Option<String>,
}

impl FitReport {
    pub fn write_json(&self, path: &Path) -> Result<(), TrainError> {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::other)?;
            writeln!(w)
        })
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
