//! The views of one frame as training targets: colour composited over the fit's background
//! with the mask, the mask in the fourth channel (what a render's rgba is scored against).

use super::TrainError;
use crate::camera::Camera;
use crate::dataset::Dataset;
use crate::io::host::parallel_map;
use crate::io::image::Image;
use crate::loss::silhouette::mask_distance;

/// One view of one frame as a training target (see the module docs).
#[derive(Clone)]
pub struct ViewTarget {
    /// The camera's name.
    pub name: String,
    /// The view's camera; `target` is its width × height.
    pub camera: Camera,
    /// Per pixel, row-major: rgb · mask + background · (1 − mask), mask.
    pub target: Vec<[f32; 4]>,
    /// Per pixel, the image loss's weight ([`Self::with_outline_band`]); None: 1 everywhere.
    pub weight: Option<Vec<f32>>,
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

    /// The view with its image loss weighted 0 within `band` pixels of the mask's outline, on
    /// either side, and 1 elsewhere: a capture's mask, thresholded and jittered, may put the
    /// outline a pixel in or out, and there neither its colour (background or subject) nor its
    /// alpha can be trusted. Pixel centres count from the nearest centre across the outline,
    /// less half a pixel ([`mask_distance`]), so `band` 1 drops one ring of pixels each side.
    /// A band of 0, or a mask without foreground or background, leaves the weight as it was.
    pub fn with_outline_band(mut self, band: f32) -> Self {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let mask = self.mask();
        let inverse: Vec<f32> = mask.iter().map(|m| 1.0 - m).collect();
        let (Some(outside), Some(inside)) =
            (mask_distance(&mask, w, h), mask_distance(&inverse, w, h))
        else {
            return self;
        };
        if band <= 0.0 {
            return self;
        }
        let weight =
            outside.iter().zip(&inside).map(|(&o, &i)| if o.max(i) < band { 0.0 } else { 1.0 });
        self.weight = Some(weight.collect());
        self
    }

    /// Whether the mask has a foreground pixel (> 0.5).
    pub fn has_subject(&self) -> bool {
        self.target.iter().any(|p| p[3] > 0.5)
    }

    /// The view at 1/`factor` resolution: each pixel (target and weight) the mean of a
    /// `factor × factor` block (a partial block at the right or bottom edge is dropped), the
    /// camera scaled to match (pixel edges scale from 0, so fx, fy, cx, cy scale by the same
    /// factor).
    pub fn downsampled(&self, factor: u32) -> Self {
        let f = factor.max(1);
        let (w, h) = (self.camera.width / f, self.camera.height / f);
        let target = block_means(&self.target, self.camera.width, f, (w, h));
        let weight = self.weight.as_ref().map(|weight| {
            let single: Vec<[f32; 1]> = weight.iter().map(|&v| [v]).collect();
            block_means(&single, self.camera.width, f, (w, h)).into_iter().map(|[v]| v).collect()
        });
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
        Self { name: self.name.clone(), camera, target, weight }
    }
}

/// The means of `factor × factor` blocks of `values` (row-major, `width` wide) as a `w × h`
/// image.
fn block_means<const C: usize>(
    values: &[[f32; C]],
    width: u32,
    factor: u32,
    (w, h): (u32, u32),
) -> Vec<[f32; C]> {
    let mut out = vec![[0.0f32; C]; (w * h) as usize];
    let scale = 1.0 / (factor * factor) as f32;
    for (i, mean) in out.iter_mut().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        for dy in 0..factor {
            let row = ((y * factor + dy) * width + x * factor) as usize;
            for p in &values[row..row + factor as usize] {
                (0..C).for_each(|c| mean[c] += p[c] * scale);
            }
        }
    }
    out
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
    parallel_map(&chosen, |&(index, view)| {
        let image = dataset.image(frame, index)?;
        let mask = if use_masks { Some(dataset.mask(frame, index)?) } else { None };
        Ok(ViewTarget {
            name: dataset.camera_names[view.camera].clone(),
            camera: dataset.cameras[view.camera],
            target: composite(&image, mask.as_deref(), background),
            weight: None,
        })
    })
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
    use glam::DVec3;

    /// A 10 × 10 view whose mask is the 6 × 6 square at (2..8, 2..8).
    fn square_view() -> ViewTarget {
        let camera =
            Camera::look_at(10, 10, 10.0, 10.0, 5.0, 5.0, DVec3::NEG_Z, DVec3::ZERO, DVec3::Y)
                .unwrap();
        let inside = |p: usize| (2..8).contains(&(p % 10)) && (2..8).contains(&(p / 10));
        let target = (0..100).map(|p| [0.5, 0.5, 0.5, if inside(p) { 1.0 } else { 0.0 }]);
        ViewTarget { name: "square".into(), camera, target: target.collect(), weight: None }
    }

    #[test]
    fn the_outline_band_drops_one_ring_each_side() {
        let weight = square_view().with_outline_band(1.0).weight.unwrap();
        // The square's own border (36 − 16 pixels) and the ring around it, diagonals included
        // (8² − 36): their centres lie within 1.5 pixels of one across the outline.
        let dropped: Vec<usize> = (0..100).filter(|&p| weight[p] == 0.0).collect();
        assert_eq!(dropped.len(), 20 + 28);
        let ring = |p: usize| (1..9).contains(&(p % 10)) && (1..9).contains(&(p / 10));
        let core = |p: usize| (3..7).contains(&(p % 10)) && (3..7).contains(&(p / 10));
        assert!(dropped.iter().all(|&p| ring(p) && !core(p)));
        assert!(weight.iter().all(|&w| w == 0.0 || w == 1.0));
        // Two pixels wide, the band keeps the square's centre 2 × 2 and the image's corners,
        // √8 pixels from the square's (2.33 after the half pixel).
        let wide = square_view().with_outline_band(2.0).weight.unwrap();
        let kept: Vec<usize> = (0..100).filter(|&p| wide[p] == 1.0).collect();
        assert_eq!(kept, [0, 9, 44, 45, 54, 55, 90, 99]);
    }

    #[test]
    fn no_band_without_a_width_or_an_outline() {
        assert!(square_view().with_outline_band(0.0).weight.is_none());
        let mut full = square_view();
        full.target.iter_mut().for_each(|p| p[3] = 1.0);
        assert!(full.with_outline_band(1.0).weight.is_none());
    }

    #[test]
    fn a_downsampled_view_averages_its_weight() {
        let view = square_view().with_outline_band(1.0);
        let half = view.downsampled(2);
        let weight = half.weight.unwrap();
        assert_eq!(weight.len(), 25);
        // Block (1, 1) covers pixels (2..4, 2..4): three of the square's border, one of its core.
        assert_eq!(weight[6], 0.25);
        // Block (2, 2) covers (4..6, 4..6): the core. Block (0, 0): (1, 1) touches the corner.
        assert_eq!(weight[12], 1.0);
        assert_eq!(weight[0], 0.75);
    }
}
