//! The views of one frame as training targets: colour composited over the fit's background
//! with the mask, the mask in the fourth channel (what a render's rgba is scored against).

use super::TrainError;
use crate::camera::Camera;
use crate::io::dataset::Dataset;
use crate::io::image::Image;

pub struct ViewTarget {
    pub name: String,
    pub camera: Camera,
    /// Per pixel, row-major: rgb · mask + background · (1 − mask), mask.
    pub target: Vec<[f32; 4]>,
}

impl ViewTarget {
    /// The colour channels as an RGB image.
    pub fn rgb(&self) -> Vec<f32> {
        self.target.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
    }
}

/// Loads the views of `frame` whose cameras are in `cameras`. Without masks (`use_masks`
/// false) every pixel counts as foreground.
pub fn load_targets(dataset: &Dataset, frame: usize, cameras: &[usize], background: [f32; 3], use_masks: bool) -> Result<Vec<ViewTarget>, TrainError> {
    let views = &dataset.frames.get(frame).ok_or_else(|| TrainError::Input(format!("frame {frame} is past the dataset's {} frames", dataset.frames.len())))?.views;
    let mut targets = Vec::new();
    for (index, view) in views.iter().enumerate().filter(|(_, v)| cameras.contains(&v.camera)) {
        let image = dataset.image(frame, index)?;
        let mask = if use_masks { Some(dataset.mask(frame, index)?) } else { None };
        targets.push(ViewTarget {
            name: dataset.camera_names[view.camera].clone(),
            camera: dataset.cameras[view.camera],
            target: composite(&image, mask.as_deref(), background),
        });
    }
    Ok(targets)
}

fn composite(image: &Image, mask: Option<&[f32]>, background: [f32; 3]) -> Vec<[f32; 4]> {
    let pixels = image.width as usize * image.height as usize;
    let channels = image.channels as usize;
    (0..pixels)
        .map(|p| {
            let m = mask.map_or(1.0, |m| m[p].clamp(0.0, 1.0));
            let c = |k: usize| image.data[p * channels + k.min(channels - 1)];
            [0, 1, 2].map(|k| c(k) * m + background[k] * (1.0 - m)).into_iter().chain([m]).collect::<Vec<_>>().try_into().unwrap_or([0.0; 4])
        })
        .collect()
}
