//! Surface geometry that several stages share: the first mesh (`init`), scoring (`eval`) and
//! tracking (`track`) all ask for the closest surface point or a ray's first hit.
//! - [`triangle`]: closest point on a triangle and ray–triangle intersection, in f64.
//! - [`bvh`]: `obvhs` BVH over a mesh's triangles with exact closest-point and ray queries.
//! - [`brute`]: the same queries by testing every triangle (the reference for tests and bench).
//! - [`sphere`]: a subdivided-octahedron sphere, the surface of tests and benchmarks.
//! - [`thickness`]: how far the inside reaches from each vertex (shape diameter function).

pub mod brute;
pub mod bvh;
pub mod sphere;
pub mod thickness;
pub mod triangle;

pub use bvh::{triangles, SurfaceBvh, SurfacePoint};

/// A mesh that cannot be queried.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// The mesh has no faces.
    #[error("the mesh has no faces")]
    EmptyMesh,
    /// A vertex position (used by a face or not) has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A face refers to a vertex past the end of the positions.
    #[error("face {face} uses vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        /// Index of the face.
        face: usize,
        /// The vertex index it holds.
        index: u32,
        /// Number of vertices in the mesh.
        vertices: usize,
    },
}
