//! `tagsplat eval`: metrics of a prediction folder against a ground-truth folder: a
//! benchmark's `gt/` (with `info.json`) scores a trained sequence; any other folder is compared
//! file by file (the layout `tagsplat synth` writes).

use anyhow::{Context, Result};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tagsplat::embed::{evaluate, EvalOptions, Evaluation};
use tagsplat::eval::FolderReport;
use tagsplat::gpu::GpuContext;
use tagsplat::score::{write_sequence_eval, FrameScores, FrameValue, SequenceSummary};
use tagsplat::train::pipeline::write_html_report;

#[derive(clap::Args)]
pub struct EvalArgs {
    /// Prediction folder: meshes/<t>.ply, report.json (from `tagsplat train`), trajectories.csv,
    /// images/<camera>/<t>.png (any of them).
    #[arg(long)]
    pred: PathBuf,
    /// Ground truth: a benchmark dataset (DIR/gt/info.json) or its gt/ folder; otherwise a
    /// folder in the prediction's layout (e.g. written by `tagsplat synth`).
    #[arg(long)]
    gt: PathBuf,
    /// Surface samples per mesh for Chamfer (default: 5000 on a benchmark, 30 000 otherwise).
    #[arg(long)]
    chamfer_samples: Option<usize>,
    /// Surface samples per mesh for EMD (exact assignment, O(n³)); not on a benchmark.
    #[arg(long, default_value_t = 1000)]
    emd_samples: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Benchmark only: frames A..B to score (default: all of the ground truth's).
    #[arg(long, value_parser = crate::train::parse_range)]
    frames: Option<Range<usize>>,
    /// Benchmark only: folder for eval.csv, eval.json and eval.svg (default: --pred). When it
    /// holds a training run (report.json), its report.html is rebuilt to show the scores.
    #[arg(long)]
    out: Option<PathBuf>,
    #[arg(long)]
    json: bool,
}

pub fn run(gpu: impl FnOnce() -> Result<Arc<GpuContext>>, a: EvalArgs) -> Result<()> {
    let options = EvalOptions {
        chamfer_samples: a.chamfer_samples,
        emd_samples: Some(a.emd_samples),
        seed: a.seed,
        frames: a.frames.clone(),
    };
    match evaluate(&a.pred, &a.gt, &options)? {
        Evaluation::Sequence(eval) => {
            let context = || format!("eval --pred {} --gt {}", a.pred.display(), a.gt.display());
            let dir = a.out.as_deref().unwrap_or(&a.pred);
            let mut files = write_sequence_eval(dir, &eval).with_context(context)?;
            if dir.join("report.json").is_file() {
                files.extend(rebuild_report(gpu, dir));
            }
            if a.json {
                crate::figures::print_result(&eval, None)?;
            } else {
                println!("{} against {}", eval.pred.display(), eval.ground_truth.display());
                print_scores(&eval.pred, &eval.summary, &eval.frames);
                files.iter().for_each(|f| println!("wrote {}", f.display()));
            }
            Ok(())
        }
        Evaluation::Folders(report) => print_folders(&report, a.json),
    }
}

/// Rebuilds the report.html of the training run in `dir` so it shows the scores just written
/// there. The scores stand without it, so a report that cannot be rebuilt (its dataset path
/// relative to another directory, say) is a warning.
fn rebuild_report(gpu: impl FnOnce() -> Result<Arc<GpuContext>>, dir: &Path) -> Option<PathBuf> {
    let rebuilt = gpu().and_then(|ctx| Ok(write_html_report(&ctx, dir)?));
    let page = dir.join("report.html");
    rebuilt.map_err(|e| eprintln!("warning: {} not rebuilt: {e:#}", page.display())).ok()
}

/// The file-by-file comparison of two folders in the same layout.
fn print_folders(r: &FolderReport, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(r)?);
        return Ok(());
    }
    if let (Some(sq), Some(m), Some(e)) = (r.chamfer_squared_mean, r.chamfer_mean, r.emd_mean) {
        println!(
            "meshes    {} frames; {} Chamfer samples, {} EMD samples per mesh",
            r.meshes.len(),
            r.chamfer_samples,
            r.emd_samples
        );
        println!("  Chamfer (mean of squared NN distances)  {sq:.6e} scene units²");
        println!("  Chamfer (mean of NN distances)          {m:.6e} scene units ({:.4e} of the GT bounding-box diagonal)", r.meshes.iter().map(|f| f.chamfer.mean_fraction).sum::<f64>() / r.meshes.len() as f64);
        println!("  EMD (mean matched distance, exact)      {e:.6e} scene units");
    }
    if let Some(t) = &r.tracking {
        println!("tracking  {} points × {} frames: MSE {:.6e} scene units², RMSE {:.6e} scene units, max {:.6e} scene units", t.points, t.frames, t.mse, t.rmse, t.max);
    }
    if let Some(i) = &r.images {
        println!("images    {}: PSNR {:.3} dB, SSIM {:.5}", i.images, i.psnr_db, i.ssim);
    }
    Ok(())
}

/// A value or `-` when absent, with `digits` decimals (percentages when `percent`).
fn cell(v: Option<f64>, digits: usize, percent: bool) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{:.digits$}", if percent { v * 100.0 } else { v }))
}

/// The per-frame table and the summary of a benchmark evaluation of the folder `pred`.
pub fn print_scores(pred: &Path, s: &SequenceSummary, frames: &[FrameScores]) {
    println!(
        "size {:.4} scene units; {} points, {} Chamfer samples per mesh",
        s.size, s.points, s.chamfer_samples
    );
    println!("frame  track RMSE %  track px  off surface %  along %  track max %  Chamfer %  PSNR gs dB  PSNR mesh dB  iters  seconds  stop reason");
    for f in frames {
        let t = &f.train;
        println!(
            "{:>5}  {:>12}  {:>8}  {:>13}  {:>7}  {:>11}  {:>9}  {:>10}  {:>12}  {:>5}  {:>7}  {}",
            f.frame,
            cell(f.tracking_rmse_over_size, 3, true),
            cell(f.tracking_rmse_px, 2, false),
            cell(f.tracking_off_surface_over_size, 3, true),
            cell(f.tracking_along_surface_over_size, 3, true),
            cell(f.tracking_max_over_size, 3, true),
            cell(Some(f.chamfer_over_size), 3, true),
            cell(t.psnr_gs_db, 2, false),
            cell(t.psnr_mesh_db, 2, false),
            t.iterations.map_or("-".into(), |i| i.to_string()),
            cell(t.wall_s, 1, false),
            t.stop_reason.as_deref().unwrap_or("-")
        );
    }
    println!("(% = per cent of size)");
    if !s.missing_frames.is_empty() {
        println!(
            "missing frames   {:?} (not in {})",
            s.missing_frames,
            pred.join("meshes").display()
        );
    }
    let frame_value = |v: Option<FrameValue>| {
        v.map_or("-".into(), |v| format!("{:.3}% at frame {}", v.value * 100.0, v.frame))
    };
    println!(
        "tracking RMSE    {}% over all points and frames; worst frame {}; max {}%",
        cell(s.tracking_rmse_over_size, 3, true),
        frame_value(s.tracking_worst_frame),
        cell(s.tracking_max_over_size, 3, true)
    );
    println!(
        "  of which        {}% off the true surface (a surface in the wrong place), {}% along it (points slid on it); squares add up",
        cell(s.tracking_off_surface_over_size, 3, true),
        cell(s.tracking_along_surface_over_size, 3, true)
    );
    println!(
        "  in pixels       {} px: each point's median over the training cameras that see it, RMS over points and frames ({} pairs no camera sees left out)",
        cell(s.tracking_rmse_px, 2, false),
        s.tracking_px_unmeasured
    );
    let share = s.sight.seen_share.map_or("-".into(), |v| format!("{:.0}", v * 100.0));
    println!(
        "  by sight        {}% on the points {} training cameras see at frame 0 and at the frame ({share}% of them), {}% on the rest",
        cell(s.sight.tracking_seen_over_size, 3, true),
        tagsplat::eval::SEEN_VIEWS,
        cell(s.sight.tracking_unseen_over_size, 3, true)
    );
    println!("binding          {:.3}% mean, {:.3}% max distance of the points to the predicted frame-0 surface", s.binding_mean_over_size * 100.0, s.binding_max_over_size * 100.0);
    println!(
        "Chamfer          {}% mean over frames; worst frame {}",
        cell(s.chamfer_mean_over_size, 3, true),
        frame_value(s.chamfer_worst_frame)
    );
    println!(
        "PSNR gs          {} dB first frame, {} dB last",
        cell(s.psnr_gs_first_db, 2, false),
        cell(s.psnr_gs_last_db, 2, false)
    );
    println!(
        "PSNR mesh        {} dB first frame, {} dB last",
        cell(s.psnr_mesh_first_db, 2, false),
        cell(s.psnr_mesh_last_db, 2, false)
    );
    if s.train_report.is_none() {
        println!("no report.json in {}: PSNR, iterations and seconds are absent", pred.display());
    }
}
