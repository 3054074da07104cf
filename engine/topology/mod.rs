//! Gaussian topology: the Gaussians are the vertices of a manifold triangle mesh, and every
//! change of the Gaussian set keeps that mesh manifold (docs/architecture.md).
//!
//! # The structure
//! [`ManifoldMesh`] keeps `positions: Vec<[f32; 3]>` (public, one row per vertex index) beside
//! an implicit half-edge connectivity: face `f` owns half-edges `3f..3f + 3`, half-edge `3f + k`
//! runs from corner `k` to corner `k + 1`; [`next`]/[`prev`] are arithmetic, twins are stored
//! ([`NONE`] on the boundary), and every vertex stores one outgoing half-edge. Faces are
//! counter-clockwise seen from outside (docs/conventions.md).
//!
//! - Build: [`ManifoldMesh::new`]`(positions, faces)` for consistently oriented faces, with a
//!   [`TopologyError`] naming the first non-manifold edge or vertex; [`orient_faces`] makes the
//!   orientation consistent first; [`weld`](fn@weld) merges duplicate positions;
//!   [`import`](fn@import) does all of it for a [`TriMesh`] read from PLY/OBJ and reports each
//!   repair.
//! - Walk: [`ManifoldMesh::faces`], [`ManifoldMesh::vertices`], [`ManifoldMesh::edges`] (one
//!   half-edge per edge), [`ManifoldMesh::outgoing`] and [`ManifoldMesh::ring`] (1-rings,
//!   counter-clockwise), [`ManifoldMesh::is_boundary_vertex`], [`ManifoldMesh::is_boundary_edge`],
//!   [`ManifoldMesh::find_edge`], [`ManifoldMesh::origin`]/[`ManifoldMesh::dest`]/[`ManifoldMesh::twin`].
//! - Edit (each keeps the mesh manifold; legality checks return refusal reasons):
//!   [`ManifoldMesh::split_edge`] (new vertex at a given point), [`ManifoldMesh::split_face`]
//!   (1→3) (both refuse with [`SplitRefusal`] a point that would make a degenerate or folded
//!   triangle), [`ManifoldMesh::flip_edge`] / [`ManifoldMesh::can_flip`] ([`FlipRefusal`]),
//!   [`ManifoldMesh::collapse_edge`] / [`ManifoldMesh::can_collapse`] ([`CollapseRefusal`]: link
//!   condition, boundary pinch, dangling vertex, normal flip, degenerate face, > 4 vertices kept).
//!   Removed faces and vertices are tombstones; new vertices are appended rows.
//! - Finish: [`ManifoldMesh::compact`] drops tombstones and returns `old_of_new`, the vertex
//!   remap ([`ManifoldMesh::into_arrays`] also hands back plain positions and faces); [`remap_rows`] / [`remap_strided`] apply it to any per-vertex host array (new rows
//!   filled by the caller's closure). [`ManifoldMesh::live_faces`] gives plain face arrays.
//! - Check: [`ManifoldMesh::problem`] (every invariant, O(V + F)),
//!   [`ManifoldMesh::euler_characteristic`].
//!
//! # Gaussians on the mesh
//! - [`gaussians_from_mesh`]: one Gaussian per vertex (z axis on the area-weighted
//!   [`vertex_normals`], s_x = s_y from 1-ring distances, s_z small, opacity high, SH DC from
//!   vertex colours).
//! - [`densify`](fn@densify): faces whose [`face_scores`] pass a threshold split 1→3 at the
//!   centroid (new Gaussian = average of its corners, [`average_quaternion`]; scale rule), then
//!   [`improve_angles`] flips edges that raise the minimum angle.
//! - [`prune`](fn@prune): Gaussians meeting [`should_prune`] merge into the 1-ring neighbour of
//!   cheapest legal collapse, C = w_g·‖pᵢ − pⱼ‖ / mean edge + w_a·‖cᵢ − cⱼ‖; refusals are counted.
//! - Both compact the mesh, remap the [`GaussianScene`](crate::splat::GaussianScene) with
//!   [`remap_scene`] and return `old_of_new`: the caller applies that same array to every other
//!   per-vertex array it keeps (optimizer moments: new rows zero; gradient statistics;
//!   keypoint bindings) with [`remap_rows`] / [`remap_strided`], then re-uploads the 1-rings
//!   (`regularize::Neighbourhoods::from_mesh`).

mod check;
mod compact;
mod densify;
mod flips;
mod gaussians;
mod geometry;
mod import;
mod mesh;
mod ops;
mod orient;
mod prune;
mod remap;
mod scene_remap;
pub mod shapes;
mod weld;

pub use densify::{densify, face_scores, DensifyConfig, DensifyReport};
pub use flips::improve_angles;
pub use gaussians::{
    dc_colors, gaussian_normal, gaussians_from_mesh, vertex_normals, InitConfig, SH_C0,
};
pub use import::{import, ImportReport, Imported};
pub use mesh::{face_of, next, prev, ManifoldMesh, Outgoing, NONE};
pub use ops::{CollapseRefusal, FlipRefusal, SplitRefusal};
pub use orient::orient_faces;
pub use prune::{mean_edge_length, prune, should_prune, PruneConfig, PruneReport};
pub use remap::{compose, remap_rows, remap_strided, NEW_ROW};
pub use scene_remap::{average_quaternion, remap_scene};
pub use weld::{weld, Welded};

use crate::mesh::TriMesh;
use std::path::PathBuf;

/// Why a mesh could not be built, imported, densified or pruned. Vertex and face numbers index
/// the arrays checked at that step: [`import`](fn@import) checks positions and indices on the
/// file's rows and everything else after welding.
#[derive(Debug, thiserror::Error)]
pub enum TopologyError {
    /// A face names a vertex index at or past the number of positions.
    #[error("face {face} {corners:?} indexes past the {vertices} vertices")]
    IndexOutOfRange {
        /// The offending face.
        face: u32,
        /// Its corner indices.
        corners: [u32; 3],
        /// The number of vertex rows.
        vertices: usize,
    },
    /// A face names the same vertex at two corners.
    #[error("face {face} {corners:?} repeats a vertex")]
    DegenerateFace {
        /// The offending face.
        face: u32,
        /// Its corner indices.
        corners: [u32; 3],
    },
    /// An edge has more than two faces, or two faces that run it in the same direction.
    #[error("non-manifold edge {a}–{b}: faces {faces:?} (more than two faces, or two faces running it the same way)")]
    NonManifoldEdge {
        /// One end of the edge.
        a: u32,
        /// The other end of the edge.
        b: u32,
        /// The faces found on the edge.
        faces: Vec<u32>,
    },
    /// [`orient_faces`] found no orientation on which all faces agree.
    #[error("the surface is not orientable (face {face} cannot agree with its neighbours)")]
    NonOrientable {
        /// The face whose orientation conflicted.
        face: u32,
    },
    /// A vertex's faces form more than one fan.
    #[error("non-manifold vertex {vertex}: its faces form more than one fan (pinched)")]
    PinchedVertex {
        /// The pinched vertex.
        vertex: u32,
    },
    /// A vertex row is used by no face.
    #[error("vertex {vertex} is used by no face")]
    UnusedVertex {
        /// The unused vertex.
        vertex: u32,
    },
    /// A position has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite position")]
    NonFinite {
        /// The first vertex with a non-finite coordinate.
        vertex: u32,
    },
    /// [`import`](fn@import) was asked for a closed mesh and found a boundary edge.
    #[error("the mesh is open (edge {a}–{b} has one face) where a closed one is needed")]
    Open {
        /// One end of the boundary edge.
        a: u32,
        /// The other end of the boundary edge.
        b: u32,
    },
    /// [`import`](fn@import) was left with fewer than 4 faces after welding.
    #[error("the mesh has {faces} faces; at least 4 are needed")]
    TooSmall {
        /// The number of faces left.
        faces: usize,
    },
    /// Inputs that must agree do not ([`densify`](fn@densify), [`prune`](fn@prune)): a mesh
    /// that is not compact, a scene whose row count differs from the vertex count or that fails
    /// its own check, or scores whose length differs from the face rows. The string says which.
    #[error("mismatched inputs: {0}")]
    Mismatch(String),
    /// Another error, tagged with the file it came from.
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file the mesh came from.
        path: PathBuf,
        /// The underlying error.
        source: Box<TopologyError>,
    },
}
