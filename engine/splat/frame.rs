//! What every splatting kernel shares with the host: the per-render push constants and the
//! projected-Gaussian record. Mirrors shaders/splat/frame.glsl and grad2d.glsl.

use super::{RenderSettings, TILE_SIZE};
use crate::camera::Camera;
use crate::gpu::push_layout;
use bytemuck::{Pod, Zeroable};

/// Gradient floats per Gaussian from the rasterizer backward: mean (2), conic (3), opacity,
/// colour (3), depth.
pub const GRAD2D_STRIDE: usize = 10;

/// One camera and the render settings, 128 bytes (`FrameParams` in frame.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameParams {
    view_rows: [[f32; 4]; 3],
    intrinsics: [f32; 4],
    center_near: [f32; 4],
    background_far: [f32; 4],
    size: [u32; 4],
    options: [u32; 4],
}
push_layout!(
    FrameParams: [
        SPLAT_PROJECT,
        SPLAT_PROJECT_BACKWARD,
        SPLAT_EMIT_INTERSECTIONS,
        SPLAT_RASTERIZE,
        SPLAT_RASTERIZE_BACKWARD,
    ],
    [view_rows, intrinsics, center_near, background_far, size, options]
);

impl FrameParams {
    /// `sh_stride` is the scene's SH coefficients per channel; the active degree is the
    /// settings' degree, capped at the scene's.
    pub fn new(
        camera: &Camera,
        settings: &RenderSettings,
        gaussians: usize,
        scene_sh_degree: u32,
    ) -> Self {
        let m = camera.world_to_camera;
        let row =
            |r: usize| [m.row(r).x as f32, m.row(r).y as f32, m.row(r).z as f32, m.row(r).w as f32];
        let center = camera.center();
        let [r, g, b] = settings.background;
        let (tiles_x, tiles_y) = tile_grid(camera.width, camera.height);
        let degree = settings.sh_degree.min(scene_sh_degree);
        Self {
            view_rows: [row(0), row(1), row(2)],
            intrinsics: [camera.fx as f32, camera.fy as f32, camera.cx as f32, camera.cy as f32],
            center_near: [center.x as f32, center.y as f32, center.z as f32, settings.near],
            background_far: [r, g, b, settings.far],
            size: [camera.width, camera.height, tiles_x, tiles_y],
            options: [
                gaussians as u32,
                degree,
                super::sh_coefficients(scene_sh_degree) as u32,
                settings.mask_mode as u32,
            ],
        }
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.size[0]
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.size[1]
    }

    /// Width × height.
    pub fn pixels(&self) -> usize {
        self.size[0] as usize * self.size[1] as usize
    }

    /// Tiles across and down the image ([`TILE_SIZE`] pixels square).
    pub fn tiles(&self) -> (u32, u32) {
        (self.size[2], self.size[3])
    }

    /// The number of Gaussians the render was set up for.
    pub fn gaussians(&self) -> usize {
        self.options[0] as usize
    }
}

/// Tiles across and down an image.
pub fn tile_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE_SIZE), height.div_ceil(TILE_SIZE))
}

/// A projected Gaussian (`Splat` in frame.glsl). Culled ones have an empty `tile_rect`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Splat {
    /// Projected mean, in pixels.
    pub mean: [f32; 2],
    /// View-space depth z.
    pub depth: f32,
    /// Opacity after the sigmoid (1 in mask mode).
    pub opacity: f32,
    /// Inverse 2D covariance Q as (Q00, Q01, Q11), in 1/pixel².
    pub conic: [f32; 3],
    /// ln(255 · opacity): the footprint is σ ≤ extent.
    pub extent: f32,
    /// RGB colour; the fourth float is unused.
    pub color: [f32; 4],
    /// Tiles [x0, x1) × [y0, y1) of the footprint's bounding box.
    pub tile_rect: [u32; 4],
}

impl Splat {
    /// Culled, or entirely off screen.
    pub fn touches_no_tile(&self) -> bool {
        self.tile_rect[0] >= self.tile_rect[1] || self.tile_rect[2] >= self.tile_rect[3]
    }
}
