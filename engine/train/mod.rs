//! Training: one frame of static multi-view (`fit`: forward → fused loss → backward → fused
//! Adam in one submission per iteration, the plain topology-free 3DGS densification, held-out
//! evaluation and a speed-against-error curve), and the reconstruction [`pipeline`] built on
//! the same step.

pub mod config;
pub mod densify;
mod fit;
pub(crate) mod in_flight;
pub mod init;
mod job;
pub mod memory;
mod mesh_term;
pub(crate) mod optimize;
pub mod output;
pub mod pipeline;
pub(crate) mod plateau;
pub mod report;
pub mod schedule;
mod step;
mod targets;
pub mod temporal;
mod views;

pub use config::{ConfigError, ConfigText, FitConfig};
pub use fit::{fit, FitOutcome, Progress};
pub use job::{initial_gaussians, run_fit_job, write_fit_outputs, FitJob};
pub use report::{write_curve_csv, write_curve_plot, CurvePoint, FitReport};
pub use step::Trainer;
pub use views::{
    load_targets, load_targets_counted, AppearanceFlaw, ViewTarget, DARK_LEVEL, SATURATED_SHARE,
};

use std::path::PathBuf;

/// Why training (a fit or a pipeline run) failed.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The dataset could not be loaded or read.
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    /// The Gaussian splatter failed.
    #[error(transparent)]
    Splat(#[from] crate::splat::SplatError),
    /// A GPU operation failed.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// An evaluation metric (PSNR, SSIM, ...) failed.
    #[error(transparent)]
    Eval(#[from] crate::eval::EvalError),
    /// The mesh rasterizer failed.
    #[error(transparent)]
    Raster(#[from] crate::raster::RasterError),
    /// A second render was given to a trainer built without the loss for two.
    #[error("Trainer::record_splat with a second render needs a trainer built with Trainer::with_second_render")]
    NoSecondRender,
    /// Camera colour maps given for another number of views than the trainer has.
    #[error("{maps} camera colour maps for {views} training views (one per view)")]
    ColourMaps {
        /// Maps given.
        maps: usize,
        /// Training views.
        views: usize,
    },
    /// A regularizer failed.
    #[error(transparent)]
    Regularize(#[from] crate::regularize::RegularizeError),
    /// A topology operation failed: import, densification or pruning.
    #[error(transparent)]
    Topology(#[from] crate::topology::TopologyError),
    /// A mesh file could not be read or written.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A Gaussian scene could not be read, written or built.
    #[error(transparent)]
    Scene(#[from] crate::splat::SceneError),
    /// A mesh sequence could not be assembled or exported.
    #[error(transparent)]
    Sequence(#[from] crate::sequence::SequenceError),
    /// The USD export failed.
    #[error(transparent)]
    Usd(#[from] crate::sequence::usd::UsdError),
    /// An image could not be read or written.
    #[error(transparent)]
    Image(#[from] crate::io::image::ImageError),
    /// A PLY file could not be read or written.
    #[error(transparent)]
    Ply(#[from] crate::io::ply::PlyError),
    /// The deformation graph could not be built or solved.
    #[error(transparent)]
    Deform(#[from] crate::deform::DeformError),
    /// A frame's surface could not be ray cast (non-finite or no faces).
    #[error("surface: {0}")]
    Surface(#[from] crate::geometry::SurfaceError),
    /// The initial mesh could not be built from the masks.
    #[error("initial mesh from the masks: {0}")]
    InitMesh(#[from] crate::init::InitError),
    /// A loss went non-finite; `detail` names the iterations and the terms. The frames (or
    /// Gaussians) finished before are kept.
    #[error("{}{detail}", frame.map_or(String::new(), |t| format!("frame {t}: ")))]
    NonFinite {
        /// The frame being optimised (None outside a pipeline frame, and in the graph stage).
        frame: Option<usize>,
        /// The iterations and the loss terms' values.
        detail: String,
    },
    /// Nothing to train on: no view, or no view whose mask holds the subject.
    #[error("{}{problem}", frame.map_or(String::new(), |t| format!("frame {t}: ")))]
    NoViews {
        /// The frame (None for a plain fit or an initialisation).
        frame: Option<usize>,
        /// What is missing.
        problem: &'static str,
    },
    /// Initial Gaussians could not be placed (e.g. the masks do not meet in space).
    #[error("initialisation: {0}")]
    Init(String),
    /// The requested frames are empty or run past the dataset's.
    #[error("frames {}..{}: {} has frames 0..{available}", frames.start, frames.end, data.display())]
    FrameRange {
        /// The frames requested.
        frames: std::ops::Range<usize>,
        /// The dataset's folder.
        data: PathBuf,
        /// The dataset's frame count.
        available: usize,
    },
    /// A frame cannot start before the frame it continues from is complete in the output.
    #[error("frame {frame} needs frame {needs} in {}; run from an earlier frame", out.display())]
    MissingFrame {
        /// The frame that was to start.
        frame: usize,
        /// The frame it needs complete.
        needs: usize,
        /// The output folder.
        out: PathBuf,
    },
    /// A file that reads but does not fit: faces that differ between frames, a bad point cloud.
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The file at fault.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// A file or folder could not be written (or a run's log opened for appending).
    #[error("cannot write {}: {error}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The capture cannot fit this device even at its smallest working set.
    #[error("{}: {problem}", data.display())]
    TooLarge {
        /// The dataset's folder.
        data: PathBuf,
        /// The memory or buffer limit it breaks and the scale that would fit.
        problem: String,
    },
    /// A file of an earlier run (its report, its evaluation) could not be read.
    #[error("cannot read {}: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The caller cancelled the run (its progress callback answered `Break`); the frames
    /// finished before are kept, and the next run on the same output resumes after them.
    #[error("cancelled")]
    Cancelled,
    /// Another run, in this process or another, is writing into the same output folder.
    #[error(transparent)]
    OutputInUse(#[from] crate::io::lock::LockError),
}
