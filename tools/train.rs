//! `tagsplat train`: the reconstruction pipeline over a dataset, resumable.

use crate::dataset::PixelCentersArg;
use crate::track::UpArg;
use anyhow::{bail, Context, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use tagsplat::dataset::LoadOptions;
use tagsplat::gpu::GpuContext;
use tagsplat::train::pipeline::{
    run_train, Stage, TrainConfig, TrainJob, TrainProgress, TrainReport,
};

#[derive(clap::Args)]
pub struct TrainArgs {
    /// Dataset folder (own layout, Panoptic or nerfstudio).
    #[arg(long, required_unless_present = "print_config")]
    data: Option<PathBuf>,
    /// Output folder: meshes/, gaussians/, sequence.obj + .pc2, sequence.glb, report.json.
    /// Running again with the same folder resumes after the last complete frame.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
    /// Frame-0 mesh (PLY or OBJ); without it the mesh is built from the masks.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// TOML config; keys left out take their defaults (see --print-config).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Frames A..B (B excluded); frames before A must be complete in --out.
    #[arg(long, value_parser = parse_range)]
    frames: Option<std::ops::Range<usize>>,
    /// Up axis of sequence.glb, .usda and .obj + .pc2. Default: the GLB Y-up (glTF's up), the
    /// others Z-up when the capture is Z-up and Y-up otherwise; either way the capture's up
    /// (the axis nearest its cameras' mean up) is turned onto it. meshes/ keeps the dataset's axes.
    #[arg(long, value_enum)]
    up: Option<UpArg>,
    /// Where the dataset's intrinsics put pixel centres (default: the layout's own, see
    /// `tagsplat dataset info`).
    #[arg(long, value_enum)]
    pixel_centers: Option<PixelCentersArg>,
    /// Scale the views' images, masks and intrinsics together by this factor in (0, 1] (a 4K
    /// capture at 0.25 trains at 1K; meshes stay in the capture's units).
    #[arg(long)]
    scale: Option<f64>,
    /// Frame rate of the exports (GLB, USD, PC2). Default: the layout's (the own layout's `fps`,
    /// Panoptic's 29.97), 30 when it has none (nerfstudio / D-NeRF).
    #[arg(long, value_parser = parse_fps)]
    fps: Option<f64>,
    /// Print the default config as TOML and exit.
    #[arg(long)]
    print_config: bool,
}

fn parse_fps(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(fps) if fps.is_finite() && fps > 0.0 => Ok(fps),
        _ => Err(format!("'{text}' is not a positive frame rate")),
    }
}

pub(crate) fn parse_range(text: &str) -> Result<std::ops::Range<usize>, String> {
    let (a, b) = text.split_once("..").ok_or_else(|| format!("'{text}' is not A..B"))?;
    let parse = |s: &str| s.trim().parse::<usize>().map_err(|e| format!("'{s}' in '{text}': {e}"));
    let (a, b) = (parse(a)?, parse(b)?);
    if a >= b {
        return Err(format!("'{text}' is empty (A must be below B)"));
    }
    Ok(a..b)
}

pub fn train(context: impl FnOnce() -> Result<Arc<GpuContext>>, args: TrainArgs) -> Result<()> {
    let config = match &args.config {
        Some(path) => TrainConfig::load(path)?,
        None => TrainConfig::default(),
    };
    if args.print_config {
        print!("{}", config.to_toml());
        return Ok(());
    }
    let (Some(data), Some(out)) = (args.data, args.out) else {
        bail!("--data and --out are required")
    };
    let job = TrainJob {
        mesh: args.mesh,
        frames: args.frames,
        up: args.up.map(Into::into),
        load: LoadOptions { pixel_centers: args.pixel_centers.map(Into::into), scale: args.scale },
        fps: args.fps,
        ..TrainJob::new(data, out, config)
    };
    let report = run_with_progress(&context()?, &job)?;
    print_report(&report);
    Ok(())
}

/// Runs the job with a bar per frame and one overall, or, when stderr is not a terminal (a log
/// file, CI), a line as each frame starts.
pub fn run_with_progress(ctx: &Arc<GpuContext>, job: &TrainJob) -> Result<TrainReport> {
    let bars = MultiProgress::new();
    let style = |template| {
        ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar())
    };
    let overall =
        bars.add(ProgressBar::new(0).with_style(style("frames {bar:30} {pos}/{len}  {elapsed}")));
    let frame_bar = bars
        .add(ProgressBar::new(0).with_style(style("{msg:>10} {bar:30} {pos}/{len}  {per_sec}")));
    let (plain, started, mut current) = (!std::io::stderr().is_terminal(), Instant::now(), None);
    let mut progress = |p: TrainProgress| {
        let (frame, end, s) = (p.frame, p.frames_end, started.elapsed().as_secs_f64());
        if plain && p.stage == Stage::Plates && p.iteration == 0 {
            eprintln!("background plates of {} cameras started at {s:.1} s", p.iterations);
        }
        if plain && p.stage == Stage::Frame && current != Some(frame) {
            current = Some(frame);
            eprintln!("frame {frame} (of {end}) started at {s:.1} s");
        }
        overall.set_length(p.frames_end as u64);
        overall.set_position(p.frame as u64);
        frame_bar.set_message(match p.stage {
            Stage::Plates => "plates".to_string(),
            Stage::Views => format!("views {frame}"),
            Stage::Frame => format!("frame {frame}"),
        });
        frame_bar.set_length(p.iterations as u64);
        frame_bar.set_position(p.iteration as u64);
    };
    let report = run_train(ctx, job, &mut progress)
        .with_context(|| format!("train {} → {}", job.data.display(), job.out.display()))?;
    frame_bar.finish_and_clear();
    overall.finish_and_clear();
    Ok(report)
}

pub fn print_report(r: &TrainReport) {
    println!(
        "{} frames in {:.1} s on {} ({} vertices, {} faces; {} evaluation views)",
        // Frames trained by this run (an earlier run's report may lack frames it finished).
        r.frames.iter().filter(|f| !r.resumed_frames.contains(&f.frame)).count(),
        r.total_wall_s,
        r.device,
        r.vertices,
        r.faces,
        r.eval_views
    );
    if !r.resumed_frames.is_empty() {
        println!("resumed: frames {:?} were complete", r.resumed_frames);
    }
    println!(
        "frame  graph iters  iters  colour  stopped         seconds  host  Gaussians  PSNR gs  PSNR mesh"
    );
    for f in &r.frames {
        let graph = f.graph.as_ref().map_or("-".into(), |g| {
            g.levels.iter().map(|l| l.iterations.to_string()).collect::<Vec<_>>().join("+")
        });
        let stop = serde_json::to_value(f.stop_reason)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        // The share of the frame's wall time the device waited for the host.
        let host = match (f.host_s, f.device_s) {
            (Some(h), Some(d)) if h + d > 0.0 => format!("{:.0}%", 100.0 * h / (h + d)),
            _ => "-".into(),
        };
        println!(
            "{:>5}  {graph:>11}  {:>5}  {:>6}  {stop:<14}  {:>7.1}  {host:>4}  {:>9}  {:>7.2}  {:>9.2}",
            f.frame,
            f.iterations,
            f.colour_iterations,
            f.wall_s,
            f.gaussians,
            f.psnr_gs,
            f.psnr_mesh
        );
    }
    for f in r.frames.iter().filter(|f| !f.lost_views.is_empty()) {
        println!(
            "frame {}: no subject in view(s) {} (left out of the frame{})",
            f.frame,
            f.lost_views.join(", "),
            if f.graph.is_none() && f.iterations == 0 {
                "; no view left, the pose is extrapolated"
            } else {
                ""
            }
        );
    }
    for f in r.frames.iter().filter(|f| !f.colour_left_out.is_empty()) {
        let views = f.colour_left_out.join("; ");
        println!("frame {}: colours left out, the masks kept: {views}", f.frame);
    }
    for path in &r.outputs {
        println!("wrote {}", path.display());
    }
    println!("exports: {}", r.export);
}
