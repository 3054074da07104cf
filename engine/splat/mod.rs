//! Differentiable Gaussian splatting: scene, projection, tile binning, rasterization and their
//! backward passes on Vulkan compute, with an f64 CPU reference of the very same maths.
//!
//! # The maths (every kernel and [`mod@reference`] follow this, term for term)
//! Camera: OpenCV pinhole ([`crate::camera::Camera`]), `W` = rotation and `t` = translation of
//! `world_to_camera`, camera centre `o`.
//!
//! Projection of Gaussian i (parameters as stored: position p, log-scale s, quaternion
//! q = (w, x, y, z) not necessarily normalised, opacity logit ℓ, SH coefficients k):
//! - `v = W p + t` (view space); culled unless `near < v.z < far`.
//! - `R` = rotation of `q / |q|` (culled if |q|² is not positive and finite), `S = diag(exp s)`,
//!   `Σ = R S Sᵀ Rᵀ`.
//! - Mean in pixels `m = (fx v.x / v.z + cx, fy v.y / v.z + cy)`.
//! - Jacobian with the view ray clamped to a guard band reaching 30% of the image width (height) past each edge:
//!   `tx = v.z · clamp(v.x / v.z, −(cx / fx + 0.3 w / fx), (w − cx) / fx + 0.3 w / fx)`, same for
//!   y; `J = [[fx / v.z, 0, −fx tx / v.z²], [0, fy / v.z, −fy ty / v.z²]]`; the clamp passes no
//!   gradient to the clamped coordinate.
//! - `Σ' = J W Σ Wᵀ Jᵀ + 0.3 I` (low-pass dilation, no opacity compensation);
//!   culled unless `det Σ' > 0`; conic `Q = Σ'⁻¹`.
//! - Opacity `o = sigmoid(ℓ)` (mask mode: `o = 1`); culled unless `o ≥ 1/255`.
//! - Colour: `d = (p − o_cam) / |p − o_cam|`, `c = max(0, 0.5 + Σ_l≤L SH_l(d) k_l)` per channel
//!   with the real SH basis and constants of the 3DGS reference (`L` the active degree). Mask
//!   mode: `c = (1, 1, 1)`.
//! - Extent: pixel u gets `σ(u) = ½ (u − m)ᵀ Q (u − m)` and `α(u) = min(0.99, o · exp(−σ))`;
//!   `α ≥ 1/255` exactly where `σ ≤ ln(255 o)`, so the ellipse `σ ≤ ln(255 o)` is the
//!   Gaussian's exact footprint: it goes into the 16×16 tiles whose pixel centres that ellipse
//!   reaches, and nowhere else. Culled Gaussians touch no tile.
//!
//! Rasterization of pixel u (centre at (i + 0.5, j + 0.5)): the Gaussians of its tile in
//! increasing view depth `v.z` (ties by index), front to back, `T₀ = 1`:
//! skip if `α < 1/255`; stop before the Gaussian whose `T (1 − α) < 1e-4`; otherwise
//! `C += c α T`, `D += v.z α T`, `T ← T (1 − α)`. Outputs: colour `C + T·background`, alpha
//! `A = 1 − T`, expected depth `D / A` (0 where `A <` [`DEPTH_ALPHA_MIN`]).
//!
//! Backward: the exact derivative of the above (a clamp or a `min` that is active passes no
//! gradient), from dL/dcolour, dL/dalpha and dL/ddepth to every stored parameter.

mod buffers;
mod frame;
pub mod reference;
mod scene;
mod splatter;
mod stages;

pub use buffers::GaussianBuffers;
pub use frame::{FrameParams, Splat, GRAD2D_STRIDE};
pub use scene::{GaussianScene, SceneError};
pub use splatter::Splatter;

/// Why a scene, a setting or a render was rejected, or the GPU failed.
#[derive(Debug, thiserror::Error)]
pub enum SplatError {
    /// The scene's arrays are inconsistent, or its file could not be read or written.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A GPU allocation, upload, pipeline or submission failed.
    #[error(transparent)]
    Gpu(crate::gpu::GpuError),
    /// The render settings are invalid (see [`RenderSettings::check`]).
    #[error("invalid render settings: {0}")]
    Settings(String),
    /// A buffer passed to the backward does not match the size of the forward it differentiates.
    #[error("mismatched buffers: {0}")]
    Shape(String),
    /// A backward or a readback was asked for before any forward pass.
    #[error("backward or readback before any forward pass")]
    NoForward,
    /// A backward was asked of a splatter built by `Splatter::renderer`.
    #[error("backward asked of a render-only splatter (built by Splatter::renderer)")]
    RenderOnly,
}

/// Tiles are 16×16 pixels.
pub const TILE_SIZE: u32 = 16;
/// Contributions below this alpha are skipped (and define a Gaussian's extent).
pub const ALPHA_MIN: f64 = 1.0 / 255.0;
/// Alpha never exceeds this, so transmittance never reaches zero.
pub const ALPHA_MAX: f64 = 0.99;
/// A pixel stops before the Gaussian that would bring its transmittance below this.
pub const TRANSMITTANCE_MIN: f64 = 1e-4;
/// Low-pass dilation added to the diagonal of every 2D covariance, pixels².
pub const DILATION: f64 = 0.3;
/// Expected depth is reported as 0 where the accumulated alpha is below this.
pub const DEPTH_ALPHA_MIN: f64 = 1e-6;
/// Highest SH degree.
pub const MAX_SH_DEGREE: u32 = 3;

/// Per-render settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Colour behind all Gaussians, added with the final transmittance.
    pub background: [f32; 3],
    /// View-depth range kept; Gaussians outside are culled. Scene-relative: callers derive it
    /// from the scene extent.
    pub near: f32,
    /// Far end of the kept view-depth range (see `near`).
    pub far: f32,
    /// SH degree used (at most the scene's).
    pub sh_degree: u32,
    /// Every Gaussian white with opacity 1: the silhouette I_m of the paper.
    pub mask_mode: bool,
}

impl RenderSettings {
    /// Finite background, `0 < near < far`, degree at most [`MAX_SH_DEGREE`].
    pub fn check(&self) -> Result<(), SplatError> {
        let fine = self.background.iter().all(|c| c.is_finite())
            && self.near > 0.0
            && self.far > self.near
            && self.sh_degree <= MAX_SH_DEGREE;
        if fine {
            Ok(())
        } else {
            Err(SplatError::Settings(format!(
                "{self:?} (need a finite background, 0 < near < far, SH degree <= {MAX_SH_DEGREE})"
            )))
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            background: [0.0; 3],
            near: 0.01,
            far: 1e4,
            sh_degree: MAX_SH_DEGREE,
            mask_mode: false,
        }
    }
}

/// Number of SH coefficients per colour channel for a degree.
#[inline]
pub const fn sh_coefficients(degree: u32) -> usize {
    ((degree + 1) * (degree + 1)) as usize
}
