//! A Gaussian scene on the host: parameters as stored for optimisation (CONVENTIONS.md), one
//! row per Gaussian, and its de-facto 3DGS PLY form.

use super::{sh_coefficients, MAX_SH_DEGREE};
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: {problem}", path.display())]
    File { path: PathBuf, problem: String },
    #[error("invalid Gaussian scene: {0}")]
    Invalid(String),
}

/// Gaussians as plain arrays. `sh` holds `sh_coefficients(sh_degree)` RGB triples per Gaussian,
/// coefficient-major: `sh[(i * coefficients + k) * 3 + channel]`, DC first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GaussianScene {
    pub positions: Vec<[f32; 3]>,
    pub log_scales: Vec<[f32; 3]>,
    /// (w, x, y, z), not necessarily normalised.
    pub rotations: Vec<[f32; 4]>,
    pub opacity_logits: Vec<f32>,
    pub sh: Vec<f32>,
    pub sh_degree: u32,
}

impl GaussianScene {
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// SH coefficients per channel.
    pub fn coefficients(&self) -> usize {
        sh_coefficients(self.sh_degree)
    }

    /// Every array has one row per Gaussian and the degree is supported. Non-finite values are
    /// allowed here: the renderer skips such Gaussians (they never poison their neighbours).
    pub fn check(&self) -> Result<(), SceneError> {
        let n = self.len();
        if self.sh_degree > MAX_SH_DEGREE {
            return Err(SceneError::Invalid(format!("SH degree {} is above {MAX_SH_DEGREE}", self.sh_degree)));
        }
        let rows = [("log_scales", self.log_scales.len()), ("rotations", self.rotations.len()), ("opacity_logits", self.opacity_logits.len())];
        for (name, len) in rows {
            if len != n {
                return Err(SceneError::Invalid(format!("{len} {name} for {n} positions")));
            }
        }
        if self.sh.len() != n * self.coefficients() * 3 {
            return Err(SceneError::Invalid(format!("{} SH values for {n} Gaussians of degree {} (expected {})", self.sh.len(), self.sh_degree, n * self.coefficients() * 3)));
        }
        Ok(())
    }
}
