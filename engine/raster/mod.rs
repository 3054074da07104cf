//! Differentiable mesh rasterizer with a 64-bit visibility buffer, on Vulkan compute.
//!
//! # The maths (the kernels in shaders/raster/ and [`mod@reference`] follow this)
//! Camera: OpenCV pinhole ([`crate::camera::Camera`]); `W`, `t` the rotation and translation of
//! `world_to_camera`; vertex `v = W p + t` in camera space.
//! - Raster: each triangle is clipped against `z ≥ near` (up to two sub-triangles), projected to
//!   pixels `(fx x / z + cx, fy y / z + cy)`, snapped to 1/256 pixel and tested at pixel
//!   centres `(i + ½, j + ½)` with exact 64-bit edge functions and the top-left rule (a centre
//!   on an edge belongs to the triangle whose edge goes up, or is horizontal going right, in
//!   y-down pixels). Depth `1/z` is interpolated affinely on screen; each pixel keeps
//!   `min((depth bits << 32) | triangle)` (`atomicMin`), so ties go to the lower triangle id.
//!   Triangles with zero snapped area are not drawn; sub-triangles leaving a guard band of
//!   ±2²² pixels are dropped and counted ([`MeshRasterizer::read_counters`]).
//! - Resolve: with `d = ((i + ½ − cx)/fx, (j + ½ − cy)/fy, 1)` and corners `v0, v1, v2`,
//!   `s0 = d·(v1 × v2)` and cyclic, barycentrics `b = s / Σs` (perspective-correct, the ray's
//!   hit on the triangle's plane); colour `Σ bₖ cₖ`, mask 1, depth `(Σ bₖ vₖ).z`, normal the unit
//!   world-space `(p1 − p0) × (p2 − p0)`. Uncovered pixels: id `u32::MAX`, everything 0.
//! - Anti-aliasing (nvdiffrast's `antialias` idea): for neighbours a, b (horizontal or
//!   vertical) with different ids, take the triangle of the nearer pixel (then the other's) and
//!   its first outline edge (no neighbour across it, or one facing the other way) crossing the
//!   segment between the centres, at `t = E(a) / (E(a) − E(b))` from its covered pixel a
//!   (E: the edge's screen edge function). With `c = (rgb, mask)` resolved:
//!   `t ≥ ½: out_b += (t − ½)(c_a − c_b)`, `t < ½: out_a += (½ − t)(c_b − c_a)`. Triangles with
//!   a corner behind the near plane give no crossing.
//! - Backward: the exact derivative of the above for fixed ids, from dL/d(rgb) and dL/dmask of
//!   the anti-aliased image to vertex colours and world positions (interior through `b`,
//!   outline through `t`); gradients are added to the caller's buffers.

mod kernels;
mod mesh;
mod params;
mod rasterizer;
mod record;
pub mod reference;

pub use mesh::{edge_adjacency, RasterMesh};
pub use params::{RasterParams, RasterSettings, SubTriangle, NO_TRIANGLE};
pub use rasterizer::{MeshRasterizer, RasterFrame};
pub use record::VertexGradients;

use crate::gpu::GpuError;

/// Why a mesh, a setting or a render was rejected, or the GPU failed.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    /// A GPU allocation, upload, pipeline or submission failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A mesh with no triangles, which draws nothing.
    #[error("has no triangles (faces) to render")]
    NoTriangles,
    /// A vertex position has a NaN or infinite coordinate (the first such vertex).
    #[error("vertex {vertex} has a non-finite position {position:?}")]
    NonFinite {
        /// Index of the vertex.
        vertex: usize,
        /// Its position as given.
        position: [f32; 3],
    },
    /// A face names a vertex index at or past the vertex count (the first such face).
    #[error("face {face} {indices:?} indexes past the {vertices} vertices")]
    FaceIndex {
        /// Index of the face.
        face: usize,
        /// Its three vertex indices.
        indices: [u32; 3],
        /// The mesh's vertex count.
        vertices: usize,
    },
    /// A per-vertex or per-pixel array has the wrong length.
    #[error("{what}: {len} values where {expected} are needed")]
    Length {
        /// What the array holds.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The length needed.
        expected: usize,
    },
    /// The mesh has more triangles than the visibility buffer's ids can name (`u32::MAX / 2`).
    #[error("{triangles} triangles: at most {max} fit the visibility buffer's 32-bit ids")]
    TooManyTriangles {
        /// The mesh's triangle count.
        triangles: usize,
        /// The most triangles allowed.
        max: usize,
    },
    /// The camera's (or parameters') width × height differs from the rasterizer's image size.
    #[error("camera is {camera:?} pixels but the rasterizer's images are {images:?}")]
    CameraSize {
        /// The camera's (width, height) in pixels.
        camera: (u32, u32),
        /// The rasterizer's (width, height) in pixels.
        images: (u32, u32),
    },
    /// The settings are invalid (near plane not positive and finite), or the parameters were
    /// made for another mesh.
    #[error("invalid raster settings: {0}")]
    Settings(String),
}
