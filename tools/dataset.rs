//! `tagsplat dataset info`: what a dataset folder holds and what it lacks.

use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::dataset::background::{background_share, BACKGROUND_SHARE};
use tagsplat::dataset::{Dataset, LoadOptions, PixelCenters};
use tagsplat::gpu::GpuContext;
use tagsplat::io::host::total_memory_bytes;
use tagsplat::train::memory::{mib, refusal, CaptureMemory};

#[derive(clap::Subcommand)]
pub enum DatasetCommand {
    /// Cameras, frames, resolution, the memory a run needs on the chosen device, whether the
    /// images carry a background, and missing files (with --check: every file decoded).
    Info {
        #[arg(long)]
        data: PathBuf,
        /// The scale a run would use (`train --scale`), for the memory it needs.
        #[arg(long, default_value_t = 1.0)]
        scale: f64,
        /// Decode every image and mask: sizes, corrupt files, frames with empty masks.
        #[arg(long)]
        check: bool,
        #[arg(long)]
        json: bool,
        /// Where the layout's intrinsics put pixel centres (default: the layout's own, integer
        /// for Panoptic K matrices, half-integer for nerfstudio and this project's layout).
        #[arg(long, value_enum)]
        pixel_centers: Option<PixelCentersArg>,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum PixelCentersArg {
    /// Centre of pixel (i, j) at (i, j), as OpenCV calibrations.
    Integer,
    /// Centre of pixel (i, j) at (i + 0.5, j + 0.5).
    HalfInteger,
}

impl From<PixelCentersArg> for PixelCenters {
    fn from(arg: PixelCentersArg) -> Self {
        match arg {
            PixelCentersArg::Integer => PixelCenters::Integer,
            PixelCentersArg::HalfInteger => PixelCenters::HalfInteger,
        }
    }
}

pub fn run(command: DatasetCommand, ctx: &GpuContext) -> Result<()> {
    let DatasetCommand::Info { data, scale, check, json, pixel_centers } = command;
    let options = LoadOptions { pixel_centers: pixel_centers.map(Into::into), scale: Some(scale) };
    let d = Dataset::load_with(&data, &options)
        .with_context(|| format!("cannot load the dataset in {}", data.display()))?;
    let host_shared = ctx.info().shares_host_memory();
    let memory = CaptureMemory::of_dataset(&d, ctx.limits(), host_shared, scale);
    let at = |s| CaptureMemory::of_dataset(&d, ctx.limits(), host_shared, s);
    let refused = refusal(at, scale, ctx.limits(), total_memory_bytes());
    let background = background_share(&d, 0)
        .with_context(|| format!("cannot read frame 0 of {}", data.display()))?;
    let missing: Vec<String> = d.missing_files().iter().map(|p| p.display().to_string()).collect();
    let problems: Vec<String> =
        if check { d.check().iter().map(ToString::to_string).collect() } else { Vec::new() };
    let cameras: Vec<_> = d
        .cameras
        .iter()
        .zip(&d.camera_names)
        .enumerate()
        .map(|(i, (c, name))| {
            let center = c.center();
            serde_json::json!({ "name": name, "width": c.width, "height": c.height, "fx": c.fx, "fy": c.fy, "cx": c.cx, "cy": c.cy,
                "center": [center.x, center.y, center.z], "split": if d.test.contains(&i) { "test" } else { "train" } })
        })
        .collect();
    let views: usize = d.frames.iter().map(|f| f.views.len()).sum();
    if json {
        let out = serde_json::json!({ "root": d.root, "format": d.format, "pixel_centers": d.pixel_centers, "cameras": cameras, "frames": d.frames.len(), "views": views,
            "scale": scale, "device": ctx.info().name, "memory": memory, "refused": refused, "background_share": background,
            "times": [d.frames.first().map(|f| f.time), d.frames.last().map(|f| f.time)], "missing": missing, "problems": problems });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!("dataset   {} ({:?})", d.root.display(), d.format);
    let centres = match d.pixel_centers {
        PixelCenters::Integer => "integer (OpenCV): cx and cy shifted by +0.5",
        PixelCenters::HalfInteger => "half-integer: cx and cy as written",
    };
    println!("pixels    centres of the intrinsics at {centres}");
    println!(
        "frames    {} (time {:.4} .. {:.4}), {} images",
        d.frames.len(),
        d.frames[0].time,
        d.frames[d.frames.len() - 1].time,
        views
    );
    println!("cameras   {} ({} train, {} test)", d.cameras.len(), d.train.len(), d.test.len());
    for c in &cameras {
        println!(
            "  {:<10} {}×{}  fx {:.2} fy {:.2}  cx {:.2} cy {:.2}  {}",
            c["name"].as_str().unwrap_or(""),
            c["width"],
            c["height"],
            c["fx"].as_f64().unwrap_or(0.0),
            c["fy"].as_f64().unwrap_or(0.0),
            c["cx"].as_f64().unwrap_or(0.0),
            c["cy"].as_f64().unwrap_or(0.0),
            c["split"].as_str().unwrap_or("")
        );
    }
    println!(
        "memory    up to {} on the device, {} on the host at scale {scale} ({}{}; an upper estimate)",
        mib(memory.device_bytes),
        mib(memory.host_bytes),
        ctx.info().name,
        if host_shared { ", whose memory is the host's" } else { "" }
    );
    match (&refused, memory.streaming()) {
        (Some(why), _) => println!("          refused there: {why}"),
        (None, Some(streaming)) => println!("          streamed: {streaming}"),
        (None, None) => {}
    }
    let said = if background > BACKGROUND_SHARE {
        "a background behind the subject: the masks say what is subject; train refines them along the outline against each camera's plate"
    } else {
        "none: composited over black"
    };
    println!(
        "backdrop  {said} ({:.0} % of frame 0's background pixels are not black)",
        100.0 * background
    );
    println!("missing   {} file(s)", missing.len());
    for m in missing.iter().take(20) {
        println!("  {m}");
    }
    if check {
        println!("problems  {}", problems.len());
        for p in problems.iter().take(20) {
            println!("  {p}");
        }
    }
    Ok(())
}
