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
    #[error("{0}")]
    Input(String),
    #[error("cannot write {}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
}
