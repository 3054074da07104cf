//! Evaluation metrics, each with its exact definition and unit in its own file:
//! - [`psnr`](mod@psnr): peak signal-to-noise ratio of images in [0, 1], in dB.
//! - [`affine_psnr`]: PSNR after each view's own least-squares affine colour map (exposure and
//!   white balance forgiven).
//! - [`ssim`](mod@ssim): structural similarity (11×11 Gaussian window, σ = 1.5), unitless; equals
//!   scikit-image's `structural_similarity(gaussian_weights=True, sigma=1.5,
//!   use_sample_covariance=False, data_range=1)`.
//! - [`chamfer`]: symmetric Chamfer distance between area-uniform surface samples of two meshes.
//! - [`surface_chamfer`]: symmetric Chamfer distance from the samples of each mesh to the other
//!   mesh's surface (point to triangle: no sampling noise floor).
//! - [`emd`]: earth mover's distance between equal-size surface samples (exact assignment).
//! - [`tracking`]: MSE / RMSE of tracked points against ground-truth trajectories.
//! - [`tracking_split`]: that error split into a part off the true surface and a part along it.
//! - [`sight`]: that error split into points the cameras see in both frames and the rest.
//! - [`pixels`]: the tracking error in pixels of the training cameras that see each point.
//!
//! Inputs are plain arrays; [`sample`] draws the surface samples, [`folder`] compares a
//! prediction folder with a ground-truth folder. Scoring a whole trained sequence against a
//! benchmark is [`crate::score`]'s, above this module and the tracker.

pub mod affine_psnr;
pub mod assignment;
pub mod chamfer;
pub mod emd;
pub mod folder;
pub mod pixels;
pub mod psnr;
pub mod sample;
pub mod sight;
pub mod ssim;
pub mod surface_chamfer;
pub mod tracking;
pub mod tracking_split;

pub use affine_psnr::affine_corrected_psnr;
pub use chamfer::{chamfer_distance, chamfer_meshes, ChamferReport};
pub use emd::{emd_meshes, emd_points, EmdReport};
pub use folder::{evaluate_folders, FolderError, FolderOptions, FolderReport};
pub use pixels::{pixel_error, PixelSplit};
pub use psnr::psnr;
pub use sample::{sample_surface, surface_points, SurfaceSample};
pub use sight::{cameras_seeing, seen_in_both, SightSplit, SEEN_VIEWS};
pub use ssim::ssim;
pub use surface_chamfer::{chamfer_to_surface, SurfaceChamferReport};
pub use tracking::{tracking_error, TrackingReport};
pub use tracking_split::{split_on_surface, SurfaceSplit};

/// Why a metric could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// Prediction and ground truth differ in length (the prediction's first).
    #[error("inputs differ in size: {0} vs {1} values")]
    SizeMismatch(usize, usize),
    /// An input is empty, or a sample count is zero (the input named).
    #[error("empty input: {0}")]
    Empty(&'static str),
    /// An input holds a NaN or infinity (the input named).
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// An image is smaller than the SSIM window in width or height.
    #[error("image {width}×{height} is smaller than the {window}×{window} SSIM window")]
    ImageTooSmall {
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
        /// The window's side, pixels.
        window: usize,
    },
    /// An image buffer's length is not width × height × channels.
    #[error("image buffer holds {len} values, expected {width}×{height}×{channels}")]
    ImageShape {
        /// Values in the buffer.
        len: usize,
        /// Image width, pixels.
        width: usize,
        /// Image height, pixels.
        height: usize,
        /// Values per pixel.
        channels: usize,
    },
    /// A face refers to a vertex past the mesh's vertex count.
    #[error("face {face} refers to vertex {index}, but the mesh has {vertices} vertices")]
    FaceIndex {
        /// The face's index.
        face: usize,
        /// The vertex index it holds.
        index: u32,
        /// The mesh's vertex count.
        vertices: usize,
    },
    /// A surface sample names a face past the mesh's face count.
    #[error("a surface sample lies on face {face}, but the mesh has {faces} faces")]
    SampleFace {
        /// The face the sample names.
        face: u32,
        /// The mesh's face count.
        faces: usize,
    },
    /// A mesh has no face of positive area (nothing to sample, or to measure against).
    #[error("the mesh has no surface area to sample")]
    NoArea,
    /// A ground-truth trajectory point has no predicted point of the same id and frame.
    #[error("ground-truth point `{id}` at frame {frame} has no prediction")]
    MissingPrediction {
        /// The point's id.
        id: String,
        /// The frame.
        frame: u32,
    },
}
