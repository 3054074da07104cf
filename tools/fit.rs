//! `tagsplat fit`: Gaussians for one frame of a multi-view dataset (static multi-view).

use crate::dataset::PixelCentersArg;
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::sync::Arc;
use tagsplat::dataset::LoadOptions;
use tagsplat::gpu::GpuContext;
use tagsplat::train::{run_fit_job, write_fit_outputs, FitConfig, FitJob, Progress};

#[derive(clap::Args)]
pub struct FitArgs {
    /// Dataset folder (own layout, Panoptic or nerfstudio; see `tagsplat dataset info`).
    #[arg(long, required_unless_present = "print_config")]
    data: Option<PathBuf>,
    /// Frame index.
    #[arg(long, default_value_t = 0)]
    frame: usize,
    /// Output folder: gaussians.ply, renders/, report.json, curve.csv, curve.svg.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
    /// Iterations (overrides the config's).
    #[arg(long)]
    iters: Option<u32>,
    /// TOML config; keys left out take their defaults (see --print-config).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Point cloud or mesh (PLY or OBJ) whose vertices seed the Gaussians; without it, points
    /// are sampled inside the masks.
    #[arg(long)]
    init: Option<PathBuf>,
    /// Where the dataset's intrinsics put pixel centres (default: the layout's own, see
    /// `tagsplat dataset info`).
    #[arg(long, value_enum)]
    pixel_centers: Option<PixelCentersArg>,
    /// Print the default config as TOML and exit.
    #[arg(long)]
    print_config: bool,
}

pub fn fit(context: impl FnOnce() -> Result<Arc<GpuContext>>, args: FitArgs) -> Result<()> {
    let mut config = match &args.config {
        Some(path) => FitConfig::load(path)?,
        None => FitConfig::default(),
    };
    if args.print_config {
        print!("{}", config.to_toml());
        return Ok(());
    }
    if let Some(iters) = args.iters {
        config.iterations = iters;
    }
    let (Some(data), Some(out)) = (args.data, args.out) else {
        bail!("--data and --out are required")
    };
    let ctx = context()?;
    let bar = ProgressBar::new(config.iterations as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} it  {per_sec}  {msg}  ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut progress = |p: Progress| {
        bar.set_position(p.iteration as u64);
        if let Some(loss) = p.loss {
            bar.set_message(format!("loss {loss:.4}  {} Gaussians", p.gaussians));
        }
        std::ops::ControlFlow::Continue(())
    };
    let load = LoadOptions { pixel_centers: args.pixel_centers.map(Into::into), scale: None };
    let job = FitJob { data: data.clone(), frame: args.frame, init: args.init, config, load };
    let outcome = run_fit_job(&ctx, &job, &mut progress)
        .with_context(|| format!("fit of {} frame {}", data.display(), args.frame))?;
    bar.finish_and_clear();
    let written = write_fit_outputs(&out, &outcome)?;
    let r = &outcome.report;
    println!(
        "{} iterations in {:.1} s ({:.1} it/s, {} Gaussians) on {}",
        r.iterations, r.train_wall_s, r.iterations_per_s, r.gaussians, r.device
    );
    println!(
        "{} PSNR {:.2} dB (from {:.2} dB), SSIM {:.4}",
        r.eval_views, r.psnr, r.initial_psnr, r.ssim
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    if let Some(reason) = &r.stopped {
        bail!("{reason}");
    }
    Ok(())
}
