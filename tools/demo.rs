//! `tagsplat demo`: generate, reconstruct, track and score a synthetic sequence.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::sync::Arc;
use tagsplat::demo::{run_demo, DemoOptions};
use tagsplat::gpu::GpuContext;

#[derive(clap::Args)]
pub struct DemoArgs {
    /// Working folder: data/ (generated), out/ (reconstruction, trajectories.csv), demo.json.
    #[arg(long, default_value = "demo")]
    out: PathBuf,
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
    frames: u64,
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(32..=4096))]
    resolution: u32,
    /// Print the report as one JSON object with the run's provenance (a result file for
    /// `tagsplat figures`) instead of the tables.
    #[arg(long)]
    json: bool,
}

pub fn demo(ctx: &Arc<GpuContext>, args: &DemoArgs) -> Result<()> {
    let options = DemoOptions {
        frames: args.frames as usize,
        resolution: args.resolution,
        ..Default::default()
    };
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("frame {msg} {bar:30} {pos}/{len} it  {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut progress = |p: tagsplat::train::pipeline::TrainProgress| {
        bar.set_message(format!("{}/{}", p.frame, p.frames_end));
        bar.set_length(p.iterations as u64);
        bar.set_position(p.iteration as u64);
    };
    let r = run_demo(ctx, &args.out, &options, &mut progress)
        .with_context(|| format!("demo in {}", args.out.display()))?;
    bar.finish_and_clear();
    if args.json {
        return crate::figures::print_result(&r, Some(ctx.info()));
    }
    super::train::print_report(&r.train);
    println!();
    println!(
        "against the ground truth ({} frames, {} views at {}², {} tracked points):",
        options.frames, options.views, options.resolution, r.scores.tracked_points
    );
    let s = &r.scores;
    println!(
        "  held-out PSNR       Gaussians {:.2} dB, mesh {:.2} dB (mean over frames)",
        s.psnr_gs, s.psnr_mesh
    );
    println!(
        "  Chamfer / diagonal  {:.5}  (mean nearest-neighbour distance, 20 000 samples per mesh)",
        s.chamfer_per_diagonal
    );
    println!("  EMD / diagonal      {:.5}  (exact, 500 samples per mesh)", s.emd_per_diagonal);
    println!(
        "  tracking RMSE       {:.5} of the subject's height (MSE {:.3e} scene units²)",
        s.tracking_rmse_per_height, s.tracking_mse
    );
    println!(
        "wrote {}, {}, {}",
        r.data.display(),
        r.out.display(),
        args.out.join("demo.json").display()
    );
    Ok(())
}

#[derive(clap::Args)]
pub struct AblateArgs {
    /// Dataset with ground truth (meshes/, points.csv, trajectories.csv: `tagsplat synth`).
    #[arg(long)]
    data: PathBuf,
    /// Output folder: one reconstruction per variant, ablation.md and ablation.json.
    #[arg(long)]
    out: PathBuf,
    /// Base TOML config (see `tagsplat train --print-config`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// The temporal stage's ablations instead of the paper's, on a benchmark dataset with
    /// ground truth (DIR/gt/info.json); every variant continues the frame 0 of --frame0.
    #[arg(long, requires = "frame0")]
    temporal: bool,
    /// A finished `tagsplat train` output whose frame 0 the temporal variants continue.
    #[arg(long)]
    frame0: Option<PathBuf>,
    /// Frames of the temporal variants, A..B (default: all).
    #[arg(long, value_parser = crate::train::parse_range)]
    frames: Option<std::ops::Range<usize>>,
    /// Only these temporal variants, comma-separated names as the table shows them (default:
    /// all), e.g. --variants "full model,w/o colour fit".
    #[arg(long, requires = "temporal", value_delimiter = ',')]
    variants: Vec<String>,
}

pub fn ablate(ctx: &Arc<GpuContext>, args: &AblateArgs) -> Result<()> {
    let base = match &args.config {
        Some(path) => tagsplat::train::pipeline::TrainConfig::load(path)?,
        None => tagsplat::train::pipeline::TrainConfig::default(),
    };
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} it")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut progress = |name: &str, p: tagsplat::train::pipeline::TrainProgress| {
        bar.set_message(format!("{name}: frame {}/{}", p.frame, p.frames_end));
        bar.set_length(p.iterations as u64);
        bar.set_position(p.iteration as u64);
    };
    match &args.frame0 {
        Some(frame0) if args.temporal => {
            let frames = match &args.frames {
                Some(range) => range.clone(),
                None => 0..tagsplat::dataset::Dataset::load(&args.data)?.frames.len(),
            };
            let job = tagsplat::ablate::TemporalAblationJob {
                data: args.data.clone(),
                out: args.out.clone(),
                base,
                frame0: frame0.clone(),
                frames,
                variants: args.variants.clone(),
            };
            tagsplat::ablate::run_temporal_ablations(ctx, &job, &mut progress)
                .with_context(|| format!("temporal ablations of {}", args.data.display()))?;
        }
        _ => {
            tagsplat::demo::run_ablations(ctx, &args.data, &args.out, &base, &mut progress)
                .with_context(|| format!("ablations of {}", args.data.display()))?;
        }
    }
    bar.finish_and_clear();
    print!("{}", std::fs::read_to_string(args.out.join("ablation.md"))?);
    println!("wrote {}", args.out.join("ablation.md").display());
    Ok(())
}
