//! Evaluation metrics, each with its exact definition and unit in its own file:
//! - [`psnr`]: peak signal-to-noise ratio of images in [0, 1], in dB.
//! - [`ssim`]: structural similarity (11×11 Gaussian window, σ = 1.5), unitless; equals
//!   scikit-image's `structural_similarity(gaussian_weights=True, sigma=1.5,
//!   use_sample_covariance=False, data_range=1)`.
//! - [`chamfer`]: symmetric Chamfer distance between area-uniform surface samples of two meshes.
//! - [`surface_chamfer`]: symmetric Chamfer distance from the samples of each mesh to the other
//!   mesh's surface (point to triangle: no sampling noise floor).
//! - [`emd`]: earth mover's distance between equal-size surface samples (exact assignment).
//! - [`tracking`]: MSE / RMSE of tracked points against ground-truth trajectories.
//!
//! Inputs are plain arrays; [`sample`] draws the surface samples, [`folder`] compares a
//! prediction folder with a ground-truth folder. Scoring a whole trained sequence against a
//! benchmark is [`crate::score`]'s, above this module and the tracker.

pub mod assignment;
pub mod chamfer;
pub mod emd;
pub mod folder;
pub mod psnr;
pub mod sample;
pub mod ssim;
pub mod surface_chamfer;
pub mod tracking;

pub use chamfer::{chamfer_distance, chamfer_meshes, ChamferReport};
pub use emd::{emd_meshes, emd_points, EmdReport};
pub use folder::{evaluate_folders, FolderError, FolderOptions, FolderReport};
pub use psnr::psnr;
pub use sample::{sample_surface, surface_points, SurfaceSample};
pub use ssim::ssim;
pub use surface_chamfer::{chamfer_to_surface, SurfaceChamferReport};
pub use tracking::{tracking_error, TrackingReport};

/// Why a metric could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error("inputs differ in size: {0} vs {1} values")]
    SizeMismatch(usize, usize),
    #[error("empty input: {0}")]
    Empty(&'static str),
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    #[error("image {width}×{height} is smaller than the {window}×{window} SSIM window")]
    ImageTooSmall { width: usize, height: usize, window: usize },
    #[error("image buffer holds {len} values, expected {width}×{height}×{channels}")]
    ImageShape { len: usize, width: usize, height: usize, channels: usize },
    #[error("face {face} refers to vertex {index}, but the mesh has {vertices} vertices")]
    FaceIndex { face: usize, index: u32, vertices: usize },
    #[error("a surface sample lies on face {face}, but the mesh has {faces} faces")]
    SampleFace { face: u32, faces: usize },
    #[error("the mesh has no surface area to sample")]
    NoArea,
    #[error("ground-truth point `{id}` at frame {frame} has no prediction")]
    MissingPrediction { id: String, frame: u32 },
}
