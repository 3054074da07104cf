//! The views of one frame as training targets: colour composited over the fit's background
//! with the mask, the mask in the fourth channel (what a render's rgba is scored against).

use super::TrainError;
use crate::camera::Camera;
use crate::dataset::Dataset;
use crate::io::host::parallel_map_counted;
use crate::io::image::Image;
use std::sync::Arc;

/// A view's subject is too dark to match when its brightest channel averages less than this
/// under the mask (about 5 of 255): a frame the camera lost, or one its light missed.
pub const DARK_LEVEL: f32 = 0.02;

/// A view's subject is too saturated to match when more than this share of the mask's pixels
/// are clipped in every channel: the bands and shading a render is scored on are gone there.
pub const SATURATED_SHARE: f32 = 0.5;

/// A channel at or above this is clipped (254 of 255 and up).
const CLIPPED: f32 = 254.0 / 255.0;

/// Why the image terms cannot match a view's colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AppearanceFlaw {
    /// The mean of the brightest channel under the mask, under [`DARK_LEVEL`].
    Dark(f32),
    /// The share of the mask's pixels clipped in every channel, over [`SATURATED_SHARE`].
    Saturated(f32),
}

impl std::fmt::Display for AppearanceFlaw {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Self::Dark(level) => {
                write!(f, "dark (its brightest channel averages {level:.3} under the mask)")
            }
            Self::Saturated(share) => {
                write!(f, "saturated ({:.0} % of the mask's pixels clipped)", 100.0 * share)
            }
        }
    }
}

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

    /// Why the image terms cannot match this view's colours, if they cannot: the subject is
    /// dark ([`DARK_LEVEL`]) or mostly clipped ([`SATURATED_SHARE`]). Only the pixels the mask
    /// covers (> 0.5) count; a view without any has no flaw here (see [`Self::has_subject`]).
    pub fn appearance_flaw(&self) -> Option<AppearanceFlaw> {
        let subject = self.target.iter().filter(|p| p[3] > 0.5);
        let (mut count, mut brightest, mut clipped) = (0usize, 0.0f64, 0usize);
        for p in subject {
            count += 1;
            brightest += p[0].max(p[1]).max(p[2]) as f64;
            clipped += (p[0].min(p[1]).min(p[2]) >= CLIPPED) as usize;
        }
        if count == 0 {
            return None;
        }
        let (level, share) = ((brightest / count as f64) as f32, clipped as f32 / count as f32);
        if level < DARK_LEVEL {
            Some(AppearanceFlaw::Dark(level))
        } else if share > SATURATED_SHARE {
            Some(AppearanceFlaw::Saturated(share))
        } else {
            None
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 × 10 view whose left half is subject (mask 1) of colour `subject` and whose right
    /// half is background of colour `background`.
    fn view(subject: [f32; 3], background: [f32; 3]) -> ViewTarget {
        let target = (0..100)
            .map(|i| match i % 10 < 5 {
                true => [subject[0], subject[1], subject[2], 1.0],
                false => [background[0], background[1], background[2], 0.0],
            })
            .collect();
        let camera = Camera {
            width: 10,
            height: 10,
            fx: 10.0,
            fy: 10.0,
            cx: 5.0,
            cy: 5.0,
            world_to_camera: glam::DMat4::IDENTITY,
        };
        ViewTarget { name: "cam".into(), camera, target: Arc::new(target) }
    }

    #[test]
    fn a_dark_or_clipped_subject_is_flawed_and_only_the_mask_counts() {
        assert_eq!(view([0.4, 0.3, 0.2], [0.0; 3]).appearance_flaw(), None);
        // A bright background does not save a dark subject, nor a dark one spoil a bright one.
        let dark = view([0.01, 0.015, 0.005], [1.0; 3]).appearance_flaw();
        assert!(matches!(dark, Some(AppearanceFlaw::Dark(l)) if (l - 0.015).abs() < 1e-6));
        assert_eq!(
            view([1.0; 3], [0.0; 3]).appearance_flaw(),
            Some(AppearanceFlaw::Saturated(1.0))
        );
        // One channel clipped is colour, not saturation; dark in two channels is not dark.
        assert_eq!(view([1.0, 0.5, 0.5], [0.0; 3]).appearance_flaw(), None);
        assert_eq!(view([0.0, 0.0, 0.3], [0.0; 3]).appearance_flaw(), None);
        // No subject in the mask: nothing to judge.
        let mut empty = view([0.0; 3], [0.0; 3]);
        empty.target = Arc::new(vec![[0.0; 4]; 100]);
        assert_eq!(empty.appearance_flaw(), None);
    }
}
