//! The mesh rasterizer: owns the mesh's GPU buffers, the per-image buffers the passes exchange,
//! and records forward and backward into a caller's [`Recorder`] so they can share one
//! submission with other work.

use super::kernels::Kernels;
use super::mesh::{check_positions, edge_adjacency, RasterMesh};
use super::params::{RasterParams, RasterSettings, SubTriangle, TILE_LIST_CAPACITY, TILE_SIZE};
use super::RasterError;
use crate::camera::Camera;
use crate::gpu::{FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult};
use std::sync::Arc;

/// Everything one forward pass produced, read back (row-major, `width × height` pixels).
#[derive(Clone, Debug, Default)]
pub struct RasterFrame {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Triangle per pixel, [`super::NO_TRIANGLE`] where uncovered.
    pub ids: Vec<u32>,
    /// Perspective-correct barycentrics (b0, b1, b2).
    pub barycentrics: Vec<[f32; 3]>,
    /// Interpolated colour and coverage before anti-aliasing.
    pub resolved: Vec<[f32; 4]>,
    /// Interpolated camera-space depth z; 0 where uncovered.
    pub depth: Vec<f32>,
    /// World-space unit face normals.
    pub normals: Vec<[f32; 3]>,
    /// The anti-aliased colour and mask: what the backward differentiates.
    pub color: Vec<[f32; 3]>,
    /// The anti-aliased mask (coverage), one value per pixel.
    pub mask: Vec<f32>,
}

pub(super) struct MeshBuffers {
    pub(super) positions: GpuBuffer<f32>,
    pub(super) colors: GpuBuffer<f32>,
    pub(super) faces: GpuBuffer<u32>,
    pub(super) adjacency: GpuBuffer<i32>,
    pub(super) camera_positions: GpuBuffer<[f32; 4]>,
    /// Per triangle: outline edges (bits 0-2) and in front of the near plane (bit 3).
    pub(super) outline_flags: GpuBuffer<u32>,
    /// Two per triangle: the near clip can split one in two.
    pub(super) subs: GpuBuffer<SubTriangle>,
    pub(super) large: GpuBuffer<u32>,
    /// [large sub-triangles, sub-triangles dropped at the guard band].
    pub(super) counters: GpuBuffer<u32>,
    /// The backward's gradients per vertex (3 each) as order-independent sums.
    pub(super) grad_position_sums: FixedSums,
    pub(super) grad_color_sums: FixedSums,
}

pub(super) struct ImageBuffers {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) visibility: GpuBuffer<u64>,
    pub(super) write_counts: GpuBuffer<u32>,
    pub(super) ids: GpuBuffer<u32>,
    pub(super) barycentrics: GpuBuffer<[f32; 4]>,
    pub(super) rgba: GpuBuffer<[f32; 4]>,
    pub(super) depth: GpuBuffer<f32>,
    pub(super) normals: GpuBuffer<[f32; 4]>,
    pub(super) color: GpuBuffer<f32>,
    pub(super) mask: GpuBuffer<f32>,
    pub(super) grad_rgba: GpuBuffer<[f32; 4]>,
    /// Per 16x16 tile: large sub-triangles binned to it, and their slots (capacity per tile).
    pub(super) tile_counts: GpuBuffer<u32>,
    pub(super) tile_lists: GpuBuffer<u32>,
    /// Two per pixel (pair with the right, then the lower neighbour): `PairRecord` in blend.glsl.
    pub(super) pairs: GpuBuffer<[u32; 4]>,
}

/// A mesh on the GPU with the pipelines and per-image buffers to rasterize it at one image
/// size and differentiate the result.
pub struct MeshRasterizer {
    pub(super) ctx: Arc<GpuContext>,
    pub(super) kernels: Kernels,
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    pub(super) mesh: MeshBuffers,
    pub(super) image: ImageBuffers,
}

fn flat3(values: &[[f32; 3]]) -> &[f32] {
    bytemuck::cast_slice(values)
}

impl MeshBuffers {
    fn new(ctx: &Arc<GpuContext>, mesh: &RasterMesh) -> GpuResult<Self> {
        let faces: &[u32] = bytemuck::cast_slice(&mesh.faces);
        let (t, n) = (mesh.faces.len(), mesh.positions.len());
        Ok(Self {
            positions: GpuBuffer::from_slice(ctx, "mesh positions", flat3(&mesh.positions))?,
            colors: GpuBuffer::from_slice(ctx, "mesh colours", flat3(&mesh.colors))?,
            faces: GpuBuffer::from_slice(ctx, "mesh faces", faces)?,
            adjacency: GpuBuffer::from_slice(ctx, "mesh adjacency", &edge_adjacency(&mesh.faces))?,
            camera_positions: GpuBuffer::new(ctx, "mesh camera positions", mesh.positions.len())?,
            outline_flags: GpuBuffer::new(ctx, "mesh outline flags", t)?,
            subs: GpuBuffer::new(ctx, "raster sub-triangles", 2 * t)?,
            large: GpuBuffer::new(ctx, "raster large list", 2 * t)?,
            counters: GpuBuffer::new(ctx, "raster counters", 2)?,
            grad_position_sums: FixedSums::new(
                ctx,
                "raster position gradient sums",
                3 * n,
                FixedPrecision::Gradient,
            )?,
            grad_color_sums: FixedSums::new(
                ctx,
                "raster colour gradient sums",
                3 * n,
                FixedPrecision::Gradient,
            )?,
        })
    }
}

impl ImageBuffers {
    fn new(ctx: &Arc<GpuContext>, width: u32, height: u32) -> GpuResult<Self> {
        let n = width as usize * height as usize;
        let tiles = width.div_ceil(TILE_SIZE) as usize * height.div_ceil(TILE_SIZE) as usize;
        Ok(Self {
            width,
            height,
            visibility: GpuBuffer::new(ctx, "visibility buffer", n)?,
            write_counts: GpuBuffer::new(ctx, "raster write counts", n)?,
            ids: GpuBuffer::new(ctx, "raster ids", n)?,
            barycentrics: GpuBuffer::new(ctx, "raster barycentrics", n)?,
            rgba: GpuBuffer::new(ctx, "raster resolved colour", n)?,
            depth: GpuBuffer::new(ctx, "raster depth", n)?,
            normals: GpuBuffer::new(ctx, "raster normals", n)?,
            color: GpuBuffer::new(ctx, "raster colour", 3 * n)?,
            mask: GpuBuffer::new(ctx, "raster mask", n)?,
            grad_rgba: GpuBuffer::new(ctx, "raster resolved colour gradient", n)?,
            pairs: GpuBuffer::new(ctx, "raster anti-aliasing crossings", 2 * n)?,
            tile_counts: GpuBuffer::new(ctx, "raster tile counts", tiles)?,
            tile_lists: GpuBuffer::new(ctx, "raster tile lists", tiles * TILE_LIST_CAPACITY)?,
        })
    }

    pub(super) fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

impl MeshRasterizer {
    /// A rasterizer for `mesh` rendering `width × height` images.
    pub fn new(
        ctx: &Arc<GpuContext>,
        mesh: &RasterMesh,
        width: u32,
        height: u32,
    ) -> Result<Self, RasterError> {
        Ok(Self {
            ctx: ctx.clone(),
            kernels: Kernels::new(ctx)?,
            vertices: mesh.positions.len(),
            triangles: mesh.faces.len(),
            mesh: MeshBuffers::new(ctx, mesh)?,
            image: ImageBuffers::new(ctx, width, height)?,
        })
    }

    /// Replaces the mesh (new buffers, adjacency rebuilt).
    pub fn set_mesh(&mut self, mesh: &RasterMesh) -> Result<(), RasterError> {
        self.mesh = MeshBuffers::new(&self.ctx, mesh)?;
        self.vertices = mesh.positions.len();
        self.triangles = mesh.faces.len();
        Ok(())
    }

    /// Changes the image size (new image buffers when it differs).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RasterError> {
        if (width, height) != (self.image.width, self.image.height) {
            self.image = ImageBuffers::new(&self.ctx, width, height)?;
        }
        Ok(())
    }

    /// New vertex positions for the same faces.
    pub fn write_positions(&mut self, positions: &[[f32; 3]]) -> Result<(), RasterError> {
        self.check_vertex_count("positions", positions.len())?;
        check_positions(positions)?;
        Ok(self.mesh.positions.write(flat3(positions))?)
    }

    /// New vertex colours.
    pub fn write_colors(&mut self, colors: &[[f32; 3]]) -> Result<(), RasterError> {
        self.check_vertex_count("vertex colours", colors.len())?;
        Ok(self.mesh.colors.write(flat3(colors))?)
    }

    /// Vertex positions on the GPU (x, y, z per vertex), e.g. for an optimizer to update.
    pub fn positions(&self) -> &GpuBuffer<f32> {
        &self.mesh.positions
    }

    /// Vertex colours on the GPU (r, g, b per vertex).
    pub fn colors(&self) -> &GpuBuffer<f32> {
        &self.mesh.colors
    }

    /// The mesh's vertex count.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// The mesh's triangle count.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// The push constants of one render; the camera must match the image size.
    pub fn params(
        &self,
        camera: &Camera,
        settings: &RasterSettings,
    ) -> Result<RasterParams, RasterError> {
        let images = (self.image.width, self.image.height);
        if (camera.width, camera.height) != images {
            return Err(RasterError::CameraSize { camera: (camera.width, camera.height), images });
        }
        RasterParams::new(camera, settings, self.vertices, self.triangles)
    }

    fn check_vertex_count(&self, what: &'static str, len: usize) -> Result<(), RasterError> {
        if len != self.vertices {
            return Err(RasterError::Length { what, len, expected: self.vertices });
        }
        Ok(())
    }
}
