//! The project's own layout (written by `tagsplat synth`, documented in docs/datasets.md):
//!
//! ```text
//! DIR/dataset.json            {"format": "tagsplat-dataset", "version": 1, "frames": T,
//!                              "fps": 30, "cameras": ["cam000", ...], "test_cameras": [...]}
//! DIR/cameras/<name>.json     one cam.json per camera (see `camera`)
//! DIR/images/<name>/<t>.png   RGB (or RGBA), t = frame index as 6 digits
//! DIR/masks/<name>/<t>.png    first channel is the mask
//! ```
//! Ground truth, when present, sits beside it: `meshes/<t>.ply`, `bindings.csv`,
//! `trajectories.csv` (see `synth::generate`).

use super::{inside_dataset, read_json, Dataset, DatasetError, Format, Frame, MaskSource, View};
use crate::camera::Camera;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Name of the metadata file in the dataset folder.
pub const META: &str = "dataset.json";
/// The value of `format` in [`META`].
pub const FORMAT_NAME: &str = "tagsplat-dataset";

/// The contents of `dataset.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OwnMeta {
    /// [`FORMAT_NAME`]; the loader refuses anything else.
    pub format: String,
    /// Layout version; the loader reads version 1 only.
    pub version: u32,
    /// Number of frames; every camera has one image and one mask per frame.
    pub frames: usize,
    /// Frames per second (positive): frame t is at time t / fps seconds.
    pub fps: f64,
    /// Camera names: each has `cameras/<name>.json` and a folder under `images/` and `masks/`.
    pub cameras: Vec<String>,
    /// The cameras (from `cameras`) held out for evaluation; the others train.
    pub test_cameras: Vec<String>,
}

/// `<t>` of the file names: the frame index as six digits.
pub fn frame_name(t: usize) -> String {
    format!("{t:06}")
}

/// `dir/cameras/<camera>.json`.
pub fn camera_path(dir: &Path, camera: &str) -> PathBuf {
    dir.join("cameras").join(format!("{camera}.json"))
}

/// `dir/images/<camera>/<t>.png`, `<t>` as in [`frame_name`].
pub fn image_path(dir: &Path, camera: &str, t: usize) -> PathBuf {
    dir.join("images").join(camera).join(format!("{}.png", frame_name(t)))
}

/// The image of `camera` at frame `t` as stored: `<t>.png`, else `<t>.jpg` or `<t>.jpeg` (a
/// capture kept as JPEG); the `.png` name when none exists, so the missing-file report names it.
fn stored_image_path(dir: &Path, camera: &str, t: usize) -> PathBuf {
    let png = image_path(dir, camera, t);
    let found =
        ["png", "jpg", "jpeg"].into_iter().map(|e| png.with_extension(e)).find(|p| p.is_file());
    found.unwrap_or(png)
}

/// `dir/masks/<camera>/<t>.png`, `<t>` as in [`frame_name`].
pub fn mask_path(dir: &Path, camera: &str, t: usize) -> PathBuf {
    dir.join("masks").join(camera).join(format!("{}.png", frame_name(t)))
}

/// Reads the layout from `dir`, checking `dataset.json`, every camera, and that `images/` of the
/// first camera holds at least `frames` files. The intrinsics stay as written;
/// [`Dataset::load`](super::Dataset::load) is the entry point that converts them.
pub(crate) fn load(dir: &Path) -> Result<Dataset, DatasetError> {
    let meta_path = dir.join(META);
    let meta: OwnMeta = read_json(&meta_path)?;
    let bad = |problem: String| DatasetError::File { path: meta_path.clone(), problem };
    if meta.format != FORMAT_NAME || meta.version != 1 {
        return Err(bad(format!(
            "format `{}` version {} is not {FORMAT_NAME} version 1",
            meta.format, meta.version
        )));
    }
    if !(meta.fps > 0.0 && meta.fps.is_finite()) {
        return Err(bad(format!("fps {} must be positive", meta.fps)));
    }
    if meta.cameras.is_empty() {
        return Err(bad("lists no cameras".into()));
    }
    for (i, name) in meta.cameras.iter().enumerate() {
        inside_dataset(&meta_path, "camera name", name)?;
        // Each name is one folder under images/ and masks/, on any platform.
        if name.contains(['/', '\\']) || name.starts_with('.') || meta.cameras[..i].contains(name) {
            return Err(bad(format!(
                "camera name `{name}` is not one folder name, is hidden, or is repeated"
            )));
        }
    }
    let mut cameras = Vec::with_capacity(meta.cameras.len());
    for name in &meta.cameras {
        let path = camera_path(dir, name);
        cameras.push(Camera::load_json(&path).map_err(|e| DatasetError::Camera {
            path,
            camera: name.clone(),
            problem: e.to_string(),
        })?);
    }
    let mut test = Vec::new();
    for name in &meta.test_cameras {
        test.push(
            meta.cameras
                .iter()
                .position(|c| c == name)
                .ok_or_else(|| bad(format!("test camera `{name}` is not in `cameras`")))?,
        );
    }
    let train = (0..cameras.len()).filter(|i| !test.contains(i)).collect();
    // Views are built for every frame the metadata claims, so the claim is checked against
    // the files that back it: one edited number must not make the loader build a trillion.
    let images = dir.join("images").join(&meta.cameras[0]);
    let found = std::fs::read_dir(&images).map_or(0, |files| files.take(meta.frames).count());
    if found < meta.frames {
        return Err(bad(format!(
            "`frames` is {}, but {} holds {found} files",
            meta.frames,
            images.display()
        )));
    }
    let frames = (0..meta.frames)
        .map(|t| Frame {
            time: t as f64 / meta.fps,
            views: meta
                .cameras
                .iter()
                .enumerate()
                .map(|(c, name)| View {
                    camera: c,
                    image: stored_image_path(dir, name, t),
                    mask: MaskSource::File(mask_path(dir, name, t)),
                })
                .collect(),
        })
        .collect();
    let dataset = Dataset::assemble(
        dir,
        &meta_path,
        Format::Own,
        meta.cameras.clone(),
        cameras,
        frames,
        train,
        test,
    )?;
    Ok(Dataset { fps: Some(meta.fps), ..dataset })
}
