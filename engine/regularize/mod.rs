//! The topology regularizers (the paper's §3.2–3.3) as GPU kernels with
//! analytic gradients, and their f64 CPU [`mod@reference`].
//!
//! # The terms (n Gaussians, N(i) the 1-ring of i with m_i members, primes: frame t − 1)
//! Parameters as stored: position μ, log-scale s, quaternion q = (w, x, y, z), q̂ = q / |q|.
//! - `scale_2d` = Σᵢ exp(s_{i,z}) (the scale along the Gaussian's own z axis, eq. 4).
//! - `laplacian` = (1/n) Σᵢ ‖δᵢ‖², δᵢ = μᵢ − (1/mᵢ) Σ_{j∈N(i)} μⱼ (eq. 5).
//! - `normal` = Σᵢ ‖R(q̂ᵢ) e_z − Nᵢ/‖Nᵢ‖‖, Nᵢ = Σ over faces (i, b, c) of (b − i) × (c − i):
//!   the area-weighted vertex normal from the current positions (eq. 6).
//! - `edge_length` = Σ over edges ½(sᵢ + sⱼ) h(|lᵢⱼ − l'ᵢⱼ|) (eq. 9).
//! - `rigidity` = Σᵢ sᵢ Σ_{j∈N(i)} ωᵢⱼ h(‖(μ'ⱼ − μ'ᵢ) − ΔRᵢ (μⱼ − μᵢ)‖), ΔRᵢ = R(q̂'ᵢ) R(q̂ᵢ)ᵀ
//!   (eq. 10–11).
//! - h(r) = r²/(2δ) for r < δ, r − δ/2 beyond: the Huber penalty, δ = `huber` × l̄. δ = 0 is the
//!   paper's h(r) = r, whose constant slope is indifferent to how a stretch spreads along a
//!   chain of edges; below δ the penalty is quadratic, so a stretch spreads evenly.
//! - sᵢ: vertex i's stiffness (1 in the paper; [`stiffness`] lowers it on thick parts).
//! - `rotation` = Σᵢ Σ_{j∈N(i)} ωᵢⱼ ‖q̂ⱼ ⊗ q̂'ⱼ⁻¹ − q̂ᵢ ⊗ q̂'ᵢ⁻¹‖ (eq. 12).
//! - ωᵢⱼ = exp(−λ_w · l'ᵢⱼ / l̄), l̄ the mean edge length when the neighbourhoods were built:
//!   λ_w is dimensionless (scale-free), default 1 (an average edge weighs e⁻¹).
//!
//! A norm at zero passes no gradient. Losses are reported unweighted; gradients are weighted
//! and ADDED to the caller's gradient buffers (positions, log-scales, rotations).

mod kernels;
mod neighbourhoods;
pub mod reference;
pub mod stiffness;

pub use kernels::{Regularizers, Temporal};
pub use neighbourhoods::{Neighbourhoods, BOUNDARY_BIT};

/// Loss weights (defaults 1, 5, 1, 4, 4, 20 in field order), the temporal weight falloff λ_w
/// (default 1) and the Huber δ (default 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Weight of the flatness term (eq. 4).
    pub scale_2d: f32,
    /// Weight of the Laplacian smoothness term (eq. 5).
    pub laplacian: f32,
    /// Weight of the normal-alignment term (eq. 6).
    pub normal: f32,
    /// Weight of the temporal edge-length term (eq. 9).
    pub edge_length: f32,
    /// Weight of the temporal local-rigidity term (eq. 10–11).
    pub rigidity: f32,
    /// Weight of the temporal rotation-similarity term (eq. 12).
    pub rotation: f32,
    /// Falloff of ωᵢⱼ per mean edge length.
    pub lambda_w: f32,
    /// δ of the Huber penalty h on the edge-length and rigidity residuals, in mean edge
    /// lengths (0: the paper's absolute values).
    pub huber: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Self {
            scale_2d: 1.0,
            laplacian: 5.0,
            normal: 1.0,
            edge_length: 4.0,
            rigidity: 4.0,
            rotation: 20.0,
            lambda_w: 1.0,
            huber: 0.0,
        }
    }
}

/// Unweighted value of every term (temporal ones 0 without a previous frame).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Losses<T> {
    /// Σᵢ exp(s_{i,z}): the Gaussians' extent along their own z axis (eq. 4).
    pub scale_2d: T,
    /// Mean squared Laplacian of the positions (eq. 5).
    pub laplacian: T,
    /// Misalignment of each Gaussian's z axis with its area-weighted vertex normal (eq. 6).
    pub normal: T,
    /// Change of edge lengths since the previous frame (eq. 9).
    pub edge_length: T,
    /// Deviation of each 1-ring from a rigid motion since the previous frame (eq. 10–11).
    pub rigidity: T,
    /// Disagreement between neighbours' rotations since the previous frame (eq. 12).
    pub rotation: T,
}

/// Number of loss slots in the GPU loss buffer, in the order of [`Losses`].
pub const LOSS_SLOTS: usize = 6;

impl<T: Copy> Losses<T> {
    /// From the loss buffer's slots, in field order.
    pub fn from_slots(s: [T; LOSS_SLOTS]) -> Self {
        Self {
            scale_2d: s[0],
            laplacian: s[1],
            normal: s[2],
            edge_length: s[3],
            rigidity: s[4],
            rotation: s[5],
        }
    }

    /// The values as loss-buffer slots, in field order.
    pub fn slots(&self) -> [T; LOSS_SLOTS] {
        [self.scale_2d, self.laplacian, self.normal, self.edge_length, self.rigidity, self.rotation]
    }
}

/// Why uploading neighbourhoods or recording the regularizers failed.
#[derive(Debug, thiserror::Error)]
pub enum RegularizeError {
    /// A GPU allocation, upload, pipeline or submission failed.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// A parameter, gradient or previous-frame buffer holds a different Gaussian count than the
    /// uploaded neighbourhoods.
    #[error("mismatched buffers: {0}")]
    Shape(String),
}
