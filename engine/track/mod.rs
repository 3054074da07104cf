//! Tracking surface points through a topology-consistent mesh sequence.
//!
//! A query point is bound once, on frame 0, to (face, barycentric) — by the closest surface point
//! for a 3D point, by the first hit of the pixel's ray for a 2D point — and followed through
//! every frame as Σ bₖ·vₖ(t) (`CONVENTIONS.md`, "Tracking").
//! - [`triangle`]: closest point on a triangle and ray–triangle intersection, in f64.
//! - [`bvh`]: `obvhs` BVH over the frame-0 triangles with exact closest-point and ray queries.
//! - [`brute`]: the same queries by testing every triangle (the reference for tests and bench).
//! - [`bind`]: query points → bindings, refusing points too far from the surface.
//! - [`trajectory`]: bindings → positions in every frame.
//! - [`queries`]: `points.csv` / `pixels.csv` readers; [`output`]: `tracks.csv` / JSON writers.
//! - [`plot`]: a PNG of the trajectories.
//! - [`run`]: one tracking run from queries to report.
//! - [`sphere`]: a subdivided-octahedron sphere; [`bench`]: the `bench track` measurement.

pub mod bench;
pub mod bind;
pub mod brute;
pub mod bvh;
pub mod output;
pub mod plot;
pub mod queries;
pub mod run;
pub mod sphere;
pub mod trajectory;
pub mod triangle;

pub use bind::{bind_point, bind_ray, Binding, Unbound};
pub use bvh::{SurfaceBvh, SurfacePoint};
pub use output::{TrackReport, TrackedPoint, UnboundPoint};
pub use run::{track, Queries};
pub use trajectory::trajectories;

use std::path::PathBuf;

/// What can go wrong while tracking; file errors name the file.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    #[error("the mesh has no faces")]
    EmptyMesh,
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition { vertex: usize },
    #[error("face {face} uses vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange { face: usize, index: u32, vertices: usize },
    #[error("frame {frame} has {found} vertices, frame 0 has {expected}")]
    FrameVertexCount { frame: usize, found: usize, expected: usize },
    #[error("binding {binding} refers to face {face}, which is not among the {faces} faces or uses a vertex the frame lacks")]
    FaceOutOfRange { binding: usize, face: u32, faces: usize },
    #[error("{path}: line {line}: {message}")]
    Csv { path: PathBuf, line: usize, message: String },
    #[error("{path}: {error}")]
    Io { path: PathBuf, error: std::io::Error },
}
