//! `tagsplat dataset info`: what a dataset folder holds and what it lacks.

use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::dataset::background::BACKGROUND_SHARE;
use tagsplat::dataset::{LoadOptions, PixelCenters};
use tagsplat::embed::DatasetInfo;
use tagsplat::gpu::GpuContext;
use tagsplat::train::memory::mib;

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
    let info = DatasetInfo::gather(ctx, &data, &options, check)
        .with_context(|| format!("cannot load the dataset in {}", data.display()))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&info)?);
        return Ok(());
    }
    println!("dataset   {} ({:?})", info.root.display(), info.format);
    let centres = match info.pixel_centers {
        PixelCenters::Integer => "integer (OpenCV): cx and cy shifted by +0.5",
        PixelCenters::HalfInteger => "half-integer: cx and cy as written",
    };
    println!("pixels    centres of the intrinsics at {centres}");
    let [first, last] = info.times.map(|t| t.unwrap_or(0.0));
    println!("frames    {} (time {first:.4} .. {last:.4}), {} images", info.frames, info.views);
    let (train, test) = info.splits();
    println!("cameras   {} ({train} train, {test} test)", info.cameras.len());
    for c in &info.cameras {
        println!(
            "  {:<10} {}×{}  fx {:.2} fy {:.2}  cx {:.2} cy {:.2}  {}",
            c.name, c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.split
        );
    }
    let memory = &info.memory;
    println!(
        "memory    up to {} on the device, {} on the host at scale {scale} ({}{}; an upper estimate)",
        mib(memory.device_bytes),
        mib(memory.host_bytes),
        info.device,
        if info.device_is_host { ", whose memory is the host's" } else { "" }
    );
    match (&info.refused, memory.streaming()) {
        (Some(why), _) => println!("          refused there: {why}"),
        (None, Some(streaming)) => println!("          streamed: {streaming}"),
        (None, None) => {}
    }
    let said = if info.background_share > BACKGROUND_SHARE {
        "a background behind the subject: the masks say what is subject; train refines them along the outline against each camera's plate"
    } else {
        "none: composited over black"
    };
    println!(
        "backdrop  {said} ({:.0} % of frame 0's background pixels are not black)",
        100.0 * info.background_share
    );
    println!("missing   {} file(s)", info.missing.len());
    for m in info.missing.iter().take(20) {
        println!("  {m}");
    }
    if check {
        println!("problems  {}", info.problems.len());
        for p in info.problems.iter().take(20) {
            println!("  {p}");
        }
    }
    Ok(())
}
