//! The f64 CPU reference of the splatting maths in [`crate::splat`]: projection, exact tile
//! binning, compositing and the exact analytic backward, term for term, plain and slow on
//! purpose. It is the oracle the GPU kernels are tested against.
//!
//! Boundary conventions (the GPU follows the same): a clamp passes gradient only where it is
//! strictly inactive — the 0.99 alpha cap when `o·G < 0.99`, the colour clamp when
//! `0.5 + SH > 0`, the guard band when `lo ≤ v.x / v.z ≤ hi`; a Gaussian is skipped where
//! `α < 1/255`; the pixel stops before the Gaussian with `T (1 − α) < 1e-4`.

mod mat;
mod projection;
mod projection_backward;
mod sh;
mod tiles;

pub use projection::{project, Projected};
pub use tiles::tiles_touched;

use super::{
    GaussianScene, RenderSettings, ALPHA_MAX, ALPHA_MIN, DEPTH_ALPHA_MIN, TILE_SIZE,
    TRANSMITTANCE_MIN,
};
use crate::camera::Camera;
use projection::{forward, Forward, View};
use projection_backward::{project_backward, ProjectedGradient};
use std::array::from_fn;

/// A rendered image, row-major: pixel (x, y) at `y * width + x`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// `C + T · background`.
    pub color: Vec<[f64; 3]>,
    /// `1 − T`.
    pub alpha: Vec<f64>,
    /// Expected view depth `D / A`, 0 where `A <` [`DEPTH_ALPHA_MIN`].
    pub depth: Vec<f64>,
}

/// dL/d(every stored parameter), laid out as [`GaussianScene`]'s arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradients {
    /// dL/dposition per Gaussian.
    pub positions: Vec<[f64; 3]>,
    /// dL/dlog-scale per Gaussian.
    pub log_scales: Vec<[f64; 3]>,
    /// dL/dquaternion (w, x, y, z) per Gaussian, with respect to the stored q.
    pub rotations: Vec<[f64; 4]>,
    /// dL/dopacity logit per Gaussian.
    pub opacity_logits: Vec<f64>,
    /// Same layout as [`GaussianScene::sh`].
    pub sh: Vec<f64>,
}

impl Gradients {
    fn zeros(scene: &GaussianScene) -> Self {
        let n = scene.len();
        Self {
            positions: vec![[0.0; 3]; n],
            log_scales: vec![[0.0; 3]; n],
            rotations: vec![[0.0; 4]; n],
            opacity_logits: vec![0.0; n],
            sh: vec![0.0; scene.sh.len()],
        }
    }
}

/// One Gaussian's part in one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contribution {
    /// Index of the Gaussian in the scene.
    pub gaussian: usize,
    /// `α = min(0.99, o·exp(−σ))` at the pixel centre.
    pub alpha: f64,
    /// Transmittance in front of this Gaussian.
    pub transmittance: f64,
    /// `o·exp(−σ) ≥ 0.99`: the cap is active and α passes no gradient.
    pub capped: bool,
}

/// Renders `scene`. Binning is the GPU's: a pixel sees the Gaussians whose
/// [`tiles_touched`] holds its tile, ordered by (depth as f32, index).
///
/// # Panics
/// If `scene.check()` fails (a programming error: scenes are checked when they are built).
pub fn render(scene: &GaussianScene, camera: &Camera, settings: &RenderSettings) -> Image {
    let frame = Frame::new(scene, camera, settings);
    let background = settings.background.map(f64::from);
    let pixels = frame.pixels();
    let mut image = Image {
        width: camera.width,
        height: camera.height,
        color: Vec::with_capacity(pixels),
        alpha: Vec::with_capacity(pixels),
        depth: Vec::with_capacity(pixels),
    };
    for pixel in 0..pixels {
        let sums = frame.accumulate(&frame.composite(pixel));
        let alpha = 1.0 - sums.transmittance;
        image.color.push(from_fn(|ch| sums.color[ch] + sums.transmittance * background[ch]));
        image.alpha.push(alpha);
        image.depth.push(if alpha < DEPTH_ALPHA_MIN { 0.0 } else { sums.depth / alpha });
    }
    image
}

/// Per pixel (row-major), the Gaussians composited there, front to back: the piecewise-smooth
/// structure of [`render`] (tests compare it to find perturbations that cross a discontinuity).
///
/// # Panics
/// As [`render`].
pub fn contributions(
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
) -> Vec<Vec<Contribution>> {
    let frame = Frame::new(scene, camera, settings);
    (0..frame.pixels()).map(|pixel| frame.composite(pixel)).collect()
}

/// The exact derivative of [`render`] for `L` with the given per-pixel dL/dcolour, dL/dalpha
/// and dL/ddepth (row-major, one per pixel). Culled Gaussians get zero gradients.
///
/// # Panics
/// As [`render`], and when a gradient slice does not hold one entry per pixel.
pub fn backward(
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
    d_color: &[[f64; 3]],
    d_alpha: &[f64],
    d_depth: &[f64],
) -> Gradients {
    let frame = Frame::new(scene, camera, settings);
    let pixels = frame.pixels();
    assert!(
        d_color.len() == pixels && d_alpha.len() == pixels && d_depth.len() == pixels,
        "reference::backward: gradients for {pixels} pixels expected"
    );
    let mut d_projected = vec![ProjectedGradient::default(); scene.len()];
    for pixel in 0..pixels {
        let contributions = frame.composite(pixel);
        frame.pixel_backward(
            pixel,
            &contributions,
            PixelGradient { color: d_color[pixel], alpha: d_alpha[pixel], depth: d_depth[pixel] },
            &mut d_projected,
        );
    }
    let mut gradients = Gradients::zeros(scene);
    for (i, f) in frame.forwards.iter().enumerate() {
        if let Some(f) = f {
            project_backward(f, &d_projected[i], &frame.view, scene, settings, i, &mut gradients);
        }
    }
    gradients
}

/// dL/d(one output pixel).
struct PixelGradient {
    color: [f64; 3],
    alpha: f64,
    depth: f64,
}

/// What compositing sums up in one pixel: `C`, `D` and the final `T`.
struct Sums {
    color: [f64; 3],
    depth: f64,
    transmittance: f64,
}

/// Every Gaussian projected, and each tile's Gaussians in compositing order.
struct Frame<'a> {
    view: View,
    forwards: Vec<Option<Forward>>,
    bins: Vec<Vec<usize>>,
    width: u32,
    height: u32,
    settings: &'a RenderSettings,
}

impl<'a> Frame<'a> {
    fn new(scene: &GaussianScene, camera: &Camera, settings: &'a RenderSettings) -> Self {
        if let Err(e) = scene.check() {
            panic!("splat reference: {e}");
        }
        let view = View::new(camera);
        let forwards: Vec<_> =
            (0..scene.len()).map(|i| forward(scene, &view, settings, i)).collect();
        let (width, height) = (camera.width, camera.height);
        let tiles = (width.div_ceil(TILE_SIZE) * height.div_ceil(TILE_SIZE)) as usize;
        let mut bins = vec![Vec::new(); tiles];
        for (i, f) in forwards.iter().enumerate() {
            if let Some(f) = f {
                for tile in tiles_touched(&f.projected, width, height) {
                    bins[tile as usize].push(i);
                }
            }
        }
        let depth = |i: usize| forwards[i].as_ref().map_or(0.0, |f| f.projected.depth as f32);
        for bin in &mut bins {
            bin.sort_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(a.cmp(&b)));
        }
        Self { view, forwards, bins, width, height, settings }
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    fn projected(&self, i: usize) -> &Projected {
        &self.forwards[i].as_ref().expect("only projected Gaussians are binned").projected
    }

    /// Pixel centre `(x + 0.5, y + 0.5)`.
    fn center(&self, pixel: usize) -> [f64; 2] {
        let width = self.width as usize;
        [(pixel % width) as f64 + 0.5, (pixel / width) as f64 + 0.5]
    }

    /// Front to back through the pixel's tile: skip `α < 1/255`, stop before `T (1 − α) < 1e-4`.
    fn composite(&self, pixel: usize) -> Vec<Contribution> {
        let width = self.width as usize;
        let (x, y) = (pixel % width, pixel / width);
        let tile = (y / TILE_SIZE as usize) * self.width.div_ceil(TILE_SIZE) as usize
            + x / TILE_SIZE as usize;
        let u = self.center(pixel);
        let mut transmittance = 1.0;
        let mut contributions = Vec::new();
        for &gaussian in &self.bins[tile] {
            let p = self.projected(gaussian);
            let raw = p.opacity * (-p.sigma(u)).exp();
            let alpha = raw.min(ALPHA_MAX);
            if alpha < ALPHA_MIN {
                continue;
            }
            let next = transmittance * (1.0 - alpha);
            if next < TRANSMITTANCE_MIN {
                break;
            }
            contributions.push(Contribution {
                gaussian,
                alpha,
                transmittance,
                capped: raw >= ALPHA_MAX,
            });
            transmittance = next;
        }
        contributions
    }

    /// `C += c α T`, `D += v.z α T`, `T ← T (1 − α)` over the contributions, front to back.
    fn accumulate(&self, contributions: &[Contribution]) -> Sums {
        let mut sums = Sums { color: [0.0; 3], depth: 0.0, transmittance: 1.0 };
        for c in contributions {
            let p = self.projected(c.gaussian);
            let weight = c.alpha * c.transmittance;
            for ch in 0..3 {
                sums.color[ch] += p.color[ch] * weight;
            }
            sums.depth += p.depth * weight;
            sums.transmittance *= 1.0 - c.alpha;
        }
        sums
    }

    /// Adds one pixel's dL/d(projected quantities) of its contributors, back to front.
    fn pixel_backward(
        &self,
        pixel: usize,
        contributions: &[Contribution],
        g: PixelGradient,
        out: &mut [ProjectedGradient],
    ) {
        let sums = self.accumulate(contributions);
        let final_t = sums.transmittance;
        let alpha_out = 1.0 - final_t;
        // Expected depth D / A: its gradient reaches D and A (none below DEPTH_ALPHA_MIN).
        let (d_depth_sum, d_alpha_out) = if alpha_out < DEPTH_ALPHA_MIN {
            (0.0, g.alpha)
        } else {
            (g.depth / alpha_out, g.alpha - g.depth * sums.depth / (alpha_out * alpha_out))
        };
        // Output colour C + T·background and alpha 1 − T.
        let d_final_t = -d_alpha_out
            + (0..3).map(|ch| g.color[ch] * f64::from(self.settings.background[ch])).sum::<f64>();
        let u = self.center(pixel);
        let (mut behind_color, mut behind_depth) = ([0.0; 3], 0.0);
        for c in contributions.iter().rev() {
            let p = self.projected(c.gaussian);
            let weight = c.alpha * c.transmittance;
            let one_minus = 1.0 - c.alpha;
            // T_final and every later contribution carry a factor (1 − α).
            let mut d_alpha = -d_final_t * final_t / one_minus
                + d_depth_sum * (p.depth * c.transmittance - behind_depth / one_minus);
            for ((behind, color), d_color) in behind_color.iter_mut().zip(p.color).zip(g.color) {
                d_alpha += d_color * (color * c.transmittance - *behind / one_minus);
                *behind += color * weight;
            }
            behind_depth += p.depth * weight;
            let d = &mut out[c.gaussian];
            for ch in 0..3 {
                d.color[ch] += g.color[ch] * weight;
            }
            d.depth += d_depth_sum * weight;
            if !c.capped {
                // α = o G, G = exp(−σ).
                let falloff = (-p.sigma(u)).exp();
                d.opacity += d_alpha * falloff;
                let d_sigma = -d_alpha * p.opacity * falloff;
                let [q00, q01, q11] = p.conic;
                let (dx, dy) = (u[0] - p.mean[0], u[1] - p.mean[1]);
                d.conic[0] += d_sigma * 0.5 * dx * dx;
                d.conic[1] += d_sigma * dx * dy;
                d.conic[2] += d_sigma * 0.5 * dy * dy;
                d.mean[0] -= d_sigma * (q00 * dx + q01 * dy);
                d.mean[1] -= d_sigma * (q01 * dx + q11 * dy);
            }
        }
    }
}
