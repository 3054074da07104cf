//! tagsplat: topology-consistent mesh sequences from multi-view video, on Vulkan compute.
//!
//! The engine is a library first; the `tagsplat` command-line program is a thin layer over it,
//! and everything it does goes through the modules below. What an embedding program needs to
//! reconstruct a sequence, read it, track points through it and score it is re-exported at the
//! crate root (`tests/embed.rs` and `examples/reconstruct.rs` use nothing else). The public
//! modules, bottom layer first (docs/architecture.md; a module uses only modules below it, and
//! `tests/layers.rs` fails on a cycle):
//! - foundations: [`io`]: file formats without domain types (PLY, PNG/JPEG/EXR, PC2, the
//!   trajectory CSV, SVG plots) and atomic writes.
//! - GPU core: [`gpu`]: Vulkan context and device choice, buffers, compute pipelines, command
//!   recording, timestamps, validation.
//! - data: [`camera`]: the pinhole camera (OpenCV axes) and its `cam.json` form; [`mesh`]:
//!   triangle meshes as plain arrays, with PLY input and output; [`dataset`]: synchronized
//!   multi-view video (own layout, Panoptic, nerfstudio / D-NeRF); [`sequence`]: mesh sequences
//!   (one face list, positions per frame) and their formats.
//! - kernels: [`splat`]: differentiable Gaussian splatting (forward, backward, CPU reference);
//!   [`raster`]: the differentiable visibility-buffer mesh rasterizer (forward, backward, CPU
//!   reference).
//! - method: [`init`]: the first mesh of a frame from its masks (visual hull, marching
//!   tetrahedra, vertex colours), when no mesh is given; [`train`]: the training loops (the
//!   sequence pipeline, the single-frame fit); [`track`](mod@track): surface points bound on
//!   frame 0 and followed through a mesh sequence; [`eval`]: image, surface and tracking
//!   metrics; [`synth`]: synthetic dynamic scenes with ground truth (procedural body, glTF
//!   skinning).
//! - whole jobs: [`score`]: a reconstruction's output folder scored against a benchmark's
//!   ground truth; [`bench`](mod@bench): benchmarks measured against bounds from the same run;
//!   [`ablate`]: the temporal stage's ablations on a benchmark with ground truth; [`demo`]: the
//!   whole job on generated data, scored against its ground truth; [`embed`]: what the Python
//!   and C fronts call (jobs on a thread of their own, errors classified once, dataset info).
//!
//! Internal, with no stability promise: `rng`, `geometry`, `sort`, `loss`, `optim`,
//! `regularize`, `deform`, `topology` and `shaders` (public but hidden, for the tests and
//! benchmarks), `ssim_window`, `flow` and `panic_payload` (private).

// Every public item says what it is: `scripts/test.sh` builds the docs with warnings as errors.
#![warn(missing_docs)]

// The public modules by layer, bottom first (as in the list above).
pub mod io;

pub mod gpu;

pub mod camera;
pub mod dataset;
pub mod mesh;
pub mod sequence;

pub mod raster;
pub mod splat;

pub mod eval;
pub mod init;
pub mod synth;
pub mod track;
pub mod train;

pub mod ablate;
pub mod bench;
pub mod demo;
pub mod embed;
pub mod score;

// Internal stages: public only so that the integration tests and the benchmarks can reach them
// (the command-line program uses none of them); hidden from the docs, no stability promise.
#[doc(hidden)]
pub mod deform;
#[doc(hidden)]
pub mod geometry;
#[doc(hidden)]
pub mod loss;
#[doc(hidden)]
pub mod optim;
#[doc(hidden)]
pub mod regularize;
#[doc(hidden)]
pub mod rng;
#[doc(hidden)]
pub mod sort;
#[doc(hidden)]
pub mod topology;

// Used inside the crate only.
mod flow;
mod panic_payload;
mod ssim_window;

// The embedding API: what a program needs to reconstruct a sequence, read it, track points
// through it and score it, at the crate root (tests/embed.rs uses nothing else). The public
// modules above serve programs that drive single stages (splatting, the rasterizer, the first
// mesh) or whole jobs (benchmarks, the demo), as the command-line program does.
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
pub use train::pipeline::{
    run_train, run_train_with, TrainConfig, TrainJob, TrainProgress, TrainReport,
};
pub use train::TrainError;

/// SPIR-V of every compute shader, compiled from `shaders/` by `build.rs`. Internal like the
/// modules above: tests build pipelines from it.
#[doc(hidden)]
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
