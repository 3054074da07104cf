//! Training: one frame of static multi-view (`fit`: forward → fused loss → backward → fused
//! Adam in one submission per iteration, the plain topology-free 3DGS densification, held-out
//! evaluation and a speed-against-error curve), and the reconstruction [`pipeline`] built on
//! the same step.

pub mod config;
pub mod densify;
mod fit;
pub mod init;
mod job;
mod mesh_term;
pub mod output;
pub mod pipeline;
pub mod report;
pub mod schedule;
mod step;
pub mod temporal;
mod views;

pub use config::{ConfigError, FitConfig};
pub use fit::{fit, FitOutcome, Progress};
pub use job::{initial_gaussians, run_fit_job, write_fit_outputs, FitJob};
pub use report::{write_curve_csv, write_curve_plot, CurvePoint, FitReport};
pub use step::Trainer;
pub use views::{load_targets, ViewTarget};

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error(transparent)]
    Dataset(#[from] crate::dataset::DatasetError),
    #[error(transparent)]
    Splat(#[from] crate::splat::SplatError),
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    #[error(transparent)]
    Eval(#[from] crate::eval::EvalError),
    #[error(transparent)]
    Raster(#[from] crate::raster::RasterError),
    #[error(transparent)]
    Regularize(#[from] crate::regularize::RegularizeError),
    #[error(transparent)]
    Topology(#[from] crate::topology::TopologyError),
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    #[error(transparent)]
    Scene(#[from] crate::splat::SceneError),
    #[error(transparent)]
    Sequence(#[from] crate::sequence::SequenceError),
    #[error(transparent)]
    Usd(#[from] crate::sequence::usd::UsdError),
    #[error(transparent)]
    Image(#[from] crate::io::image::ImageError),
    #[error(transparent)]
    Ply(#[from] crate::io::ply::PlyError),
    #[error(transparent)]
    Deform(#[from] crate::deform::DeformError),
    #[error("initial mesh from the masks: {0}")]
    InitMesh(#[from] crate::init::InitError),
    /// A loss went non-finite; `detail` names the iterations and the terms. The frames (or
    /// Gaussians) finished before are kept.
    #[error("{}{detail}", frame.map_or(String::new(), |t| format!("frame {t}: ")))]
    NonFinite { frame: Option<usize>, detail: String },
    /// Nothing to train on: no view, or no view whose mask holds the subject.
    #[error("{}{problem}", frame.map_or(String::new(), |t| format!("frame {t}: ")))]
    NoViews { frame: Option<usize>, problem: &'static str },
    /// Initial Gaussians could not be placed (e.g. the masks do not meet in space).
    #[error("initialisation: {0}")]
    Init(String),
    #[error("frames {}..{}: {} has frames 0..{available}", frames.start, frames.end, data.display())]
    FrameRange { frames: std::ops::Range<usize>, data: PathBuf, available: usize },
    /// A frame cannot start before the frame it continues from is complete in the output.
    #[error("frame {frame} needs frame {needs} in {}; run from an earlier frame", out.display())]
    MissingFrame { frame: usize, needs: usize, out: PathBuf },
    /// A file that reads but does not fit: faces that differ between frames, a bad point cloud.
    #[error("{}: {problem}", path.display())]
    Invalid { path: PathBuf, problem: String },
    #[error("cannot write {}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
}
