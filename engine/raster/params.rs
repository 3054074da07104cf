//! What every raster kernel shares with the host: the push constants and the screen
//! sub-triangle record. Mirrors shaders/raster/raster.glsl.

use super::RasterError;
use crate::camera::Camera;
use crate::gpu::push_layout;
use bytemuck::{Pod, Zeroable};

/// Tile edge of the large-triangle raster and the per-pixel kernels' workgroups.
pub const TILE_SIZE: u32 = 16;
/// Large sub-triangles listed per tile (`TILE_LIST_CAPACITY` in raster.glsl).
pub(crate) const TILE_LIST_CAPACITY: usize = 256;
/// Triangle id of an uncovered pixel.
pub const NO_TRIANGLE: u32 = u32::MAX;
/// Bit of `counts[2]`: count every covering write per pixel (a test mode).
pub(crate) const FLAG_COUNT_WRITES: u32 = 1;

/// How to rasterize.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterSettings {
    /// Camera-space depth of the near clipping plane (> 0).
    pub near: f32,
    /// Count the covering writes per pixel ([`super::MeshRasterizer::read_write_counts`]).
    pub count_writes: bool,
}

impl RasterSettings {
    /// A near plane at 10⁻³ of the extent (bounding-box diagonal) of `positions`, so the
    /// setting scales with the scene; 10⁻³ for an empty or single-point mesh.
    pub fn scaled_to(positions: &[[f32; 3]]) -> Self {
        let extent = crate::mesh::bounding_diagonal(positions) as f32;
        let extent = if extent.is_finite() && extent > 0.0 { extent } else { 1.0 };
        Self { near: 1e-3 * extent, count_writes: false }
    }

    fn check(&self) -> Result<(), RasterError> {
        if !(self.near.is_finite() && self.near > 0.0) {
            return Err(RasterError::Settings(format!(
                "near must be positive and finite, got {}",
                self.near
            )));
        }
        Ok(())
    }
}

/// One camera and the mesh sizes, 112 bytes (`RasterParams` in raster.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RasterParams {
    view_rows: [[f32; 4]; 3],
    intrinsics: [f32; 4],
    clip: [f32; 4],
    size: [u32; 4],
    counts: [u32; 4],
}
push_layout!(
    RasterParams: [
        RASTER_TRANSFORM,
        RASTER_OUTLINE,
        RASTER_SETUP,
        RASTER_RASTER_LARGE,
        RASTER_RESOLVE,
        RASTER_AA_PAIRS,
        RASTER_AA_FORWARD,
        RASTER_AA_BACKWARD,
        RASTER_INTERIOR_BACKWARD,
    ],
    [view_rows, intrinsics, clip, size, counts]
);

impl RasterParams {
    /// The push constants for rendering a mesh of `vertices` vertices and `triangles` triangles
    /// from `camera`; fails with [`RasterError::Settings`] when `settings.near` is not positive
    /// and finite.
    pub fn new(
        camera: &Camera,
        settings: &RasterSettings,
        vertices: usize,
        triangles: usize,
    ) -> Result<Self, RasterError> {
        settings.check()?;
        let m = camera.world_to_camera;
        let row =
            |r: usize| [m.row(r).x as f32, m.row(r).y as f32, m.row(r).z as f32, m.row(r).w as f32];
        let flags = if settings.count_writes { FLAG_COUNT_WRITES } else { 0 };
        Ok(Self {
            view_rows: [row(0), row(1), row(2)],
            intrinsics: [camera.fx as f32, camera.fy as f32, camera.cx as f32, camera.cy as f32],
            clip: [settings.near, 0.0, 0.0, 0.0],
            size: [
                camera.width,
                camera.height,
                camera.width.div_ceil(TILE_SIZE),
                camera.height.div_ceil(TILE_SIZE),
            ],
            counts: [vertices as u32, triangles as u32, flags, 0],
        })
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.size[0]
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.size[1]
    }

    /// Tiles of `TILE_SIZE` × `TILE_SIZE` pixels covering the image, as a dispatch size (x, y, 1).
    pub fn tiles(&self) -> [u32; 3] {
        [self.size[2], self.size[3], 1]
    }

    pub(crate) fn counts_writes(&self) -> bool {
        self.counts[2] & FLAG_COUNT_WRITES != 0
    }

    /// The vertex count these parameters were made for.
    pub fn vertices(&self) -> usize {
        self.counts[0] as usize
    }

    /// The triangle count these parameters were made for.
    pub fn triangles(&self) -> usize {
        self.counts[1] as usize
    }
}

/// A screen triangle after near clipping (`SubTriangle` in raster.glsl): corners in 1/256
/// pixel, counter-clockwise in y-down pixels, `1/z` per corner; id `NO_TRIANGLE` when unused.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SubTriangle {
    /// x0, y0, x1, y1 of corners 0 and 1, in 1/256 pixel.
    pub xy01: [i32; 4],
    /// x2, y2 of corner 2 (1/256 pixel), the triangle id, and one unused slot.
    pub xy2_id: [i32; 4],
    /// 1/z (camera space) at the three corners, and one unused slot.
    pub inv_depth: [f32; 4],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_fit_push_constants() {
        assert_eq!(size_of::<RasterParams>(), 112);
        assert_eq!(size_of::<SubTriangle>(), 48);
    }

    #[test]
    fn near_scales_with_the_mesh_and_bad_near_is_refused() {
        let s = RasterSettings::scaled_to(&[[0.0; 3], [3.0, 4.0, 0.0]]);
        assert!((s.near - 5e-3).abs() < 1e-9);
        assert_eq!(RasterSettings::scaled_to(&[]).near, 1e-3);
        assert!(RasterSettings { near: 0.0, count_writes: false }.check().is_err());
        assert!(RasterSettings { near: f32::NAN, count_writes: false }.check().is_err());
    }
}
