//! The views of one frame as training targets: colour composited over the fit's background
//! with the mask, the mask in the fourth channel (what a render's rgba is scored against).

use super::TrainError;
use crate::camera::Camera;
use crate::dataset::Dataset;
use crate::io::host::parallel_map_counted;
use crate::io::image::Image;
use std::sync::Arc;

/// One view of one frame as a training target (see the module docs).
#[derive(Clone)]
pub struct ViewTarget {
    /// The camera's name.
    pub name: String,
    /// The view's camera; `target` is its width × height.
    pub camera: Camera,
    /// Per pixel, row-major: rgb · mask + background · (1 − mask), mask. Shared: a trainer
    /// that streams its targets uploads from it (`train::targets`) without a copy of its own.
    pub target: Arc<Vec<[f32; 4]>>,
}

impl ViewTarget {
    /// The colour channels as an RGB image.
    pub fn rgb(&self) -> Vec<f32> {
        self.target.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
    }

    /// The mask channel.
    pub fn mask(&self) -> Vec<f32> {
        self.target.iter().map(|p| p[3]).collect()
    }

    /// Whether the mask has a foreground pixel (> 0.5).
    pub fn has_subject(&self) -> bool {
        self.target.iter().any(|p| p[3] > 0.5)
    }

    /// The view at 1/`factor` resolution: each pixel the mean of a `factor × factor` block (a
    /// partial block at the right or bottom edge is dropped), the camera scaled to match
    /// (pixel edges scale from 0, so fx, fy, cx, cy scale by the same factor).
    pub fn downsampled(&self, factor: u32) -> Self {
        let f = factor.max(1);
        let (w, h) = (self.camera.width / f, self.camera.height / f);
        let mut target = vec![[0.0f32; 4]; (w * h) as usize];
        let scale = 1.0 / (f * f) as f32;
        for (i, out) in target.iter_mut().enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            for dy in 0..f {
                let row = ((y * f + dy) * self.camera.width + x * f) as usize;
                for p in &self.target[row..row + f as usize] {
                    (0..4).for_each(|c| out[c] += p[c] * scale);
                }
            }
        }
        let c = &self.camera;
        let s = 1.0 / f as f64;
        let camera = Camera {
            width: w,
            height: h,
            fx: c.fx * s,
            fy: c.fy * s,
            cx: c.cx * s,
            cy: c.cy * s,
            world_to_camera: c.world_to_camera,
        };
        Self { name: self.name.clone(), camera, target: Arc::new(target) }
    }
}

/// Loads the views of `frame` whose cameras are in `cameras`. Without masks (`use_masks`
/// false) every pixel counts as foreground.
pub fn load_targets(
    dataset: &Dataset,
    frame: usize,
    cameras: &[usize],
    background: [f32; 3],
    use_masks: bool,
) -> Result<Vec<ViewTarget>, TrainError> {
    load_targets_counted(dataset, frame, cameras, (background, use_masks), &mut |_| {})
}

/// [`load_targets`], calling `decoded(views done)` as each view is decoded.
pub fn load_targets_counted(
    dataset: &Dataset,
    frame: usize,
    cameras: &[usize],
    (background, use_masks): ([f32; 3], bool),
    decoded: &mut dyn FnMut(usize),
) -> Result<Vec<ViewTarget>, TrainError> {
    let views = &dataset
        .frames
        .get(frame)
        .ok_or_else(|| {
            let (frames, data, available) =
                (frame..frame + 1, dataset.root.clone(), dataset.frames.len());
            TrainError::FrameRange { frames, data, available }
        })?
        .views;
    let chosen: Vec<(usize, &crate::dataset::View)> =
        views.iter().enumerate().filter(|(_, v)| cameras.contains(&v.camera)).collect();
    // Decoding dominates loading a capture; the views decode side by side.
    parallel_map_counted(
        &chosen,
        |&(index, view)| {
            let image = dataset.image(frame, index)?;
            let mask = if use_masks { Some(dataset.mask(frame, index)?) } else { None };
            Ok(ViewTarget {
                name: dataset.camera_names[view.camera].clone(),
                camera: dataset.cameras[view.camera],
                target: Arc::new(composite(&image, mask.as_deref(), background)),
            })
        },
        decoded,
    )
}

fn composite(image: &Image, mask: Option<&[f32]>, background: [f32; 3]) -> Vec<[f32; 4]> {
    let pixels = image.width as usize * image.height as usize;
    let channels = image.channels as usize;
    (0..pixels)
        .map(|p| {
            let m = mask.map_or(1.0, |m| m[p].clamp(0.0, 1.0));
            let c = |k: usize| image.data[p * channels + k.min(channels - 1)];
            let [r, g, b] = [0, 1, 2].map(|k| c(k) * m + background[k] * (1.0 - m));
            [r, g, b, m]
        })
        .collect()
}
