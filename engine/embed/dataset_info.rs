//! What `tagsplat dataset info` says of a dataset folder: its cameras, frames and files, the
//! memory a run on it needs, and what it lacks. One gathering serves the CLI's text and JSON
//! and the fronts' dictionaries.

use crate::dataset::background::background_share;
use crate::dataset::{Dataset, DatasetError, LoadOptions, PixelCenters};
use crate::gpu::GpuContext;
use crate::io::host::total_memory_bytes;
use crate::train::memory::{refusal, CaptureMemory};
use std::path::PathBuf;

/// A dataset folder as `tagsplat dataset info --json` describes it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DatasetInfo {
    /// The folder.
    pub root: PathBuf,
    /// Its layout (own, Panoptic, nerfstudio).
    pub format: crate::dataset::Format,
    /// Where the intrinsics put pixel centres.
    pub pixel_centers: PixelCenters,
    /// Every camera, in the dataset's order.
    pub cameras: Vec<CameraInfo>,
    /// Frames.
    pub frames: usize,
    /// Images over all frames.
    pub views: usize,
    /// The factor the views are scaled by.
    pub scale: f64,
    /// The device the memory is estimated for.
    pub device: String,
    /// Whether the device's memory is the host's.
    #[serde(skip)]
    pub device_is_host: bool,
    /// The memory a run needs at `scale` (an upper estimate).
    pub memory: CaptureMemory,
    /// Why a run would be refused there, with the scale that would fit; None when it fits.
    pub refused: Option<String>,
    /// The share of frame 0's background pixels that are not black (a backdrop when large).
    pub background_share: f64,
    /// The first and last frame's times.
    pub times: [Option<f64>; 2],
    /// Files the layout names that are not there.
    pub missing: Vec<String>,
    /// What `--check` found (each view's mask against its image); empty without it.
    pub problems: Vec<String>,
}

/// One camera of a [`DatasetInfo`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct CameraInfo {
    /// Its name.
    pub name: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (half-integer centres).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// The camera's centre in world space.
    pub center: [f64; 3],
    /// "train" or "test".
    pub split: &'static str,
}

impl DatasetInfo {
    /// Loads `data` with `options` and describes it for `ctx`'s device; `check` also reads
    /// every view's mask against its image (slow on large captures).
    pub fn gather(
        ctx: &GpuContext,
        data: &std::path::Path,
        options: &LoadOptions,
        check: bool,
    ) -> Result<Self, DatasetError> {
        let d = Dataset::load_with(data, options)?;
        let scale = options.scale.unwrap_or(1.0);
        let device_is_host = ctx.info().shares_host_memory();
        let at = |s| CaptureMemory::of_dataset(&d, ctx.limits(), device_is_host, s);
        let refused = refusal(at, scale, ctx.limits(), total_memory_bytes());
        let problems =
            if check { d.check().iter().map(ToString::to_string).collect() } else { vec![] };
        Ok(Self {
            root: d.root.clone(),
            format: d.format,
            pixel_centers: d.pixel_centers,
            cameras: cameras(&d),
            frames: d.frames.len(),
            views: d.frames.iter().map(|f| f.views.len()).sum(),
            scale,
            device: ctx.info().name.clone(),
            device_is_host,
            memory: at(scale),
            refused,
            background_share: background_share(&d, 0)?,
            times: [d.frames.first().map(|f| f.time), d.frames.last().map(|f| f.time)],
            missing: d.missing_files().iter().map(|p| p.display().to_string()).collect(),
            problems,
        })
    }

    /// The training cameras, and the held-out ones.
    pub fn splits(&self) -> (usize, usize) {
        let test = self.cameras.iter().filter(|c| c.split == "test").count();
        (self.cameras.len() - test, test)
    }
}

fn cameras(d: &Dataset) -> Vec<CameraInfo> {
    let cameras = d.cameras.iter().zip(&d.camera_names).enumerate();
    cameras
        .map(|(i, (c, name))| CameraInfo {
            name: name.clone(),
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            center: c.center().to_array(),
            split: if d.test.contains(&i) { "test" } else { "train" },
        })
        .collect()
}
