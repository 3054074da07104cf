//! `tagsplat bench sequence`: train on a benchmark dataset, score against its ground truth.

use anyhow::{Context, Result};
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;
use tagsplat::bench::{bench_sequence, SequenceBenchReport};
use tagsplat::gpu::GpuContext;
use tagsplat::score::SequenceEvalOptions;
use tagsplat::train::pipeline::{write_html_report, Stage, TrainConfig, TrainJob, TrainProgress};

#[derive(clap::Args)]
pub struct BenchSequenceArgs {
    /// Benchmark dataset: Panoptic layout with gt/ (meshes/, points.csv, tracks.csv, info.json).
    #[arg(long)]
    data: PathBuf,
    /// Frames A..B (B excluded) to train and score (default: all).
    #[arg(long, value_parser = crate::train::parse_range)]
    frames: Option<Range<usize>>,
    /// Training output folder; frames already complete there are resumed, not retrained
    /// (default: a new folder in the system's temporary directory).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Training TOML config (see `tagsplat train --print-config`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Surface samples per mesh for Chamfer.
    #[arg(long, default_value_t = 5000)]
    chamfer_samples: usize,
    /// Print one JSON object instead of a table, with the run's provenance (a result file for
    /// `tagsplat figures`).
    #[arg(long)]
    json: bool,
}

pub fn run(context: impl FnOnce() -> Result<Arc<GpuContext>>, a: BenchSequenceArgs) -> Result<()> {
    let config = a.config.as_deref().map(TrainConfig::load).transpose()?.unwrap_or_default();
    let name = a.data.file_name().map_or("data".into(), |n| n.to_string_lossy().into_owned());
    let out = a.out.unwrap_or_else(|| {
        std::env::temp_dir().join(format!("tagsplat-bench-{name}-{}", std::process::id()))
    });
    let job = TrainJob { frames: a.frames, ..TrainJob::new(a.data, out, config) };
    let eval = SequenceEvalOptions { chamfer_samples: a.chamfer_samples, ..Default::default() };
    // One line per frame on stderr, so stdout stays one JSON object with --json.
    let mut current = None;
    let mut progress = |p: TrainProgress| {
        if p.stage == Stage::Frame && current.replace(p.frame) != Some(p.frame) {
            eprintln!(
                "training frame {} of {} ({} iterations)",
                p.frame, p.frames_end, p.iterations
            );
        }
    };
    let what =
        || format!("bench sequence --data {} --out {}", job.data.display(), job.out.display());
    let ctx = context()?;
    let mut report = bench_sequence(&ctx, &job, &eval, &mut progress).with_context(what)?;
    // Rebuilt now that the output folder holds the scores.
    report.files.push(write_html_report(&ctx, &job.out).with_context(what)?);
    if a.json {
        crate::figures::print_result(&report, Some(ctx.info()))?;
    } else {
        print_report(&report);
    }
    Ok(())
}

fn print_report(r: &SequenceBenchReport) {
    let seconds = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1} s"));
    println!("device          {}", r.device);
    println!("host CPU        {}", r.cpu.as_deref().unwrap_or("unknown"));
    println!("data, output    {}, {}", r.data.display(), r.out.display());
    println!(
        "training        {:.1} s in all; frame 0 {}, later frames {} each (mean)",
        r.train_total_s,
        seconds(r.frame0_s),
        seconds(r.later_frame_mean_s)
    );
    println!("ground truth    {}", r.ground_truth.display());
    crate::eval::print_scores(&r.out, &r.scores, &r.rows);
    r.files.iter().for_each(|f| println!("wrote {}", f.display()));
}
