//! tagsplat: topology-consistent mesh sequences from multi-view video, on Vulkan compute.
//!
//! The engine is a library first; the `tagsplat` command-line program is a thin layer over it.
//! Modules follow the pipeline stages (see docs/architecture.md); a module uses only modules below
//! it (`tests/layers.rs` fails on a cycle):
//! - [`gpu`]: Vulkan context, buffers, compute pipelines, command recording, timestamps,
//!   validation.
//! - [`sort`]: exclusive prefix scan and LSD radix sort on the GPU.
//! - [`ablate`]: the temporal stage's ablations on a benchmark with ground truth.
//! - [`bench`](mod@bench): benchmarks measured against bounds from the same run.
//! - [`demo`]: the whole job on generated data, scored against its ground truth.
//! - [`rng`]: a small deterministic generator for tests, benchmarks and synthetic data.
//! - [`camera`]: the pinhole camera (OpenCV axes) and its `cam.json` form.
//! - [`io`]: file formats without domain types (PLY, PNG/EXR, PC2, the trajectory CSV) and
//!   atomic writes.
//! - [`dataset`]: synchronized multi-view video (own layout, Panoptic, nerfstudio / D-NeRF).
//! - [`sequence`]: mesh sequences (one face list, positions per frame) and their formats.
//! - [`geometry`]: closest point and ray casts on a mesh (BVH, f64 triangle routines).
//! - [`flow`]: optical flow between two images of one camera (sparse pyramidal Lucas–Kanade).
//! - [`ssim_window`]: the SSIM window and formula the metric and the loss share.
//! - [`splat`]: differentiable Gaussian splatting (forward, backward, CPU reference).
//! - [`mesh`]: triangle meshes as plain arrays, with PLY input and output.
//! - [`raster`]: differentiable visibility-buffer mesh rasterizer (forward, backward, CPU reference).
//! - [`train`]: the training loops (single-frame fit with the 3DGS baseline densification).
//! - [`track`](mod@track): surface points bound on frame 0 and followed through a mesh sequence.
//! - [`loss`]: the fused image loss (L1 + SSIM) with its gradient.
//! - [`optim`]: fused Adam with moments that survive Gaussian-set changes, schedules.
//! - [`eval`]: image, surface and tracking metrics.
//! - [`score`]: a reconstruction's output folder scored against a benchmark's ground truth.
//! - [`regularize`]: the topology regularizers on the GPU and their f64 CPU reference.
//! - [`deform`]: the embedded deformation graph the temporal stage solves first in every frame.
//! - [`topology`]: the manifold mesh the Gaussians live on, its local operations and remap.
//! - [`synth`]: synthetic dynamic scenes with ground truth (procedural body, glTF skinning).
//! - [`init`]: the first mesh of a frame from its masks (visual hull, marching tetrahedra,
//!   vertex colours), when no mesh is given.

// Every public item says what it is: `scripts/test.sh` builds the docs with warnings as errors.
#![warn(missing_docs)]

pub mod ablate;
pub mod bench;
pub mod camera;
pub mod dataset;
pub mod deform;
pub mod demo;
pub mod eval;
pub mod flow;
pub mod geometry;
pub mod gpu;
pub mod init;
pub mod io;
pub mod loss;
pub mod mesh;
pub mod optim;
pub mod raster;
pub mod regularize;
pub mod rng;
pub mod score;
pub mod sequence;
pub mod sort;
pub mod splat;
pub mod ssim_window;
pub mod synth;
pub mod topology;
pub mod track;
pub mod train;

// The embedding API: what a program needs to reconstruct a sequence, read it, track points
// through it and score it, at the crate root (tests/embed.rs uses nothing else). The modules
// stay public for programs that drive single stages (splatting, the rasterizer, the sort).
pub use camera::Camera;
pub use dataset::{Dataset, DatasetError};
pub use eval::psnr;
pub use gpu::{ContextOptions, GpuContext, GpuError};
pub use mesh::TriMesh;
pub use score::{
    evaluate_sequence, find_ground_truth, GroundTruth, SequenceEval, SequenceEvalOptions,
};
pub use sequence::{FrameFormat, MeshSequence, SequenceError};
pub use splat::{GaussianBuffers, GaussianScene, RenderSettings, SplatError, Splatter};
pub use track::queries::read_points;
pub use track::{track, Queries, TrackError, TrackReport};
pub use train::pipeline::{run_train, TrainConfig, TrainJob, TrainProgress, TrainReport};
pub use train::TrainError;

/// SPIR-V of every compute shader, compiled from `shaders/` by `build.rs`.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
