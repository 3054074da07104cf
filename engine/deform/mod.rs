//! The coarse deformation model of the temporal stage: an embedded deformation graph (a few
//! hundred nodes on the surface, each a rotation and a translation; each vertex blended from
//! its geodesically nearest nodes) with an as-rigid-as-possible term between nodes, optimised
//! on the GPU against the same image and mask losses before the per-vertex refinement.
//!
//! [`graph`] builds it on the CPU from a rest pose, [`fit`] starts its nodes from a posed copy,
//! [`GraphDeformer`] runs it on the GPU, [`reference`](mod@reference) is the f64 CPU reference of its kernels.

pub mod fit;
pub mod graph;
mod kernels;
pub mod reference;

pub use fit::fit_nodes;
pub use graph::{build_graph, DeformGraph, NODES_PER_VERTEX};
pub use kernels::GraphDeformer;
pub use reference::NodeTransforms;

/// Why building or running a [`GraphDeformer`] failed.
#[derive(Debug, thiserror::Error)]
pub enum DeformError {
    /// A GPU allocation, pipeline or submission failed.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// Creating the node-transform Gaussian buffers failed.
    #[error(transparent)]
    Splat(#[from] crate::splat::SplatError),
    /// The graph and the Gaussians disagree in size (the graph was built over another vertex
    /// count).
    #[error("mismatched buffers: {0}")]
    Shape(String),
}
