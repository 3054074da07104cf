//! A Gaussian scene on the host: parameters as stored for optimisation (docs/conventions.md), one
//! row per Gaussian, and its de-facto 3DGS PLY form.

use super::{sh_coefficients, MAX_SH_DEGREE};
use crate::io::ply::{write_ply, ColumnOut, ElementOut, Ply, PlyElement, PlyError};
use std::path::{Path, PathBuf};

/// Why a scene is inconsistent or its PLY file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Reading or writing a scene file failed, or the file is no valid 3DGS PLY.
    #[error("{}: {problem}", path.display())]
    File {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// An array's length does not fit the Gaussian count, or the SH degree is above
    /// [`MAX_SH_DEGREE`].
    #[error("invalid Gaussian scene: {0}")]
    Invalid(String),
}

impl From<PlyError> for SceneError {
    fn from(e: PlyError) -> Self {
        SceneError::File { path: e.path, problem: e.problem }
    }
}

/// Gaussians as plain arrays. `sh` holds `sh_coefficients(sh_degree)` RGB triples per Gaussian,
/// coefficient-major: `sh[(i * coefficients + k) * 3 + channel]`, DC first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GaussianScene {
    /// Position per Gaussian, world units.
    pub positions: Vec<[f32; 3]>,
    /// Natural log of the scale along each of the Gaussian's own axes.
    pub log_scales: Vec<[f32; 3]>,
    /// (w, x, y, z), not necessarily normalised.
    pub rotations: Vec<[f32; 4]>,
    /// Opacity before the sigmoid.
    pub opacity_logits: Vec<f32>,
    /// SH coefficients: RGB triples per Gaussian, coefficient-major, DC first (see above).
    pub sh: Vec<f32>,
    /// SH degree, 0 to [`MAX_SH_DEGREE`].
    pub sh_degree: u32,
}

impl GaussianScene {
    /// The number of Gaussians (rows of `positions`).
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no Gaussians.
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
            return Err(SceneError::Invalid(format!(
                "SH degree {} is above {MAX_SH_DEGREE}",
                self.sh_degree
            )));
        }
        let rows = [
            ("log_scales", self.log_scales.len()),
            ("rotations", self.rotations.len()),
            ("opacity_logits", self.opacity_logits.len()),
        ];
        for (name, len) in rows {
            if len != n {
                return Err(SceneError::Invalid(format!("{len} {name} for {n} positions")));
            }
        }
        if self.sh.len() != n * self.coefficients() * 3 {
            return Err(SceneError::Invalid(format!(
                "{} SH values for {n} Gaussians of degree {} (expected {})",
                self.sh.len(),
                self.sh_degree,
                n * self.coefficients() * 3
            )));
        }
        Ok(())
    }
}

/// The 3DGS PLY form (the reference implementation's `vertex` layout): `x y z nx ny nz f_dc_0..2
/// f_rest_0.. opacity scale_0..2 rot_0..3`, all float. `f_rest` is channel-major:
/// `f_rest_{ch (K − 1) + k − 1}` holds coefficient `k ≥ 1` of channel `ch`; its count
/// (0, 9, 24, 45) gives the degree. Opacity is the logit, scales are logs, rot is (w, x, y, z).
impl GaussianScene {
    /// Reads a 3DGS PLY (ascii or binary; normals ignored). Errors name the file and the
    /// problem: no `vertex` element, a missing property, an `f_rest` count of no SH degree,
    /// a truncated body.
    pub fn read_ply(path: &Path) -> Result<Self, SceneError> {
        let ply = Ply::read(path)?;
        let vertex = ply.element("vertex").ok_or_else(|| SceneError::File {
            path: path.to_path_buf(),
            problem: "no 'vertex' element: not a Gaussian scene".into(),
        })?;
        let rest = vertex.properties.iter().filter(|p| p.name.starts_with("f_rest_")).count();
        let sh_degree = (0..=MAX_SH_DEGREE).find(|&d| 3 * (sh_coefficients(d) - 1) == rest).ok_or_else(|| SceneError::File {
            path: path.to_path_buf(),
            problem: format!("{rest} 'f_rest_*' properties; a 3DGS scene has 0, 9, 24 or 45 (SH degree 0 to 3)"),
        })?;
        let rows = |names: &[&str]| -> Result<Vec<Vec<f32>>, SceneError> {
            Ok(names.iter().map(|n| vertex.column_f32(n)).collect::<Result<_, _>>()?)
        };
        let positions = rows(&["x", "y", "z"])?;
        let log_scales = rows(&["scale_0", "scale_1", "scale_2"])?;
        let rotations = rows(&["rot_0", "rot_1", "rot_2", "rot_3"])?;
        let opacity_logits = vertex.column_f32("opacity")?;
        let sh = read_sh(vertex, sh_degree)?;
        let n = vertex.len();
        Ok(Self {
            positions: (0..n).map(|i| std::array::from_fn(|a| positions[a][i])).collect(),
            log_scales: (0..n).map(|i| std::array::from_fn(|a| log_scales[a][i])).collect(),
            rotations: (0..n).map(|i| std::array::from_fn(|a| rotations[a][i])).collect(),
            opacity_logits,
            sh,
            sh_degree,
        })
    }

    /// Writes the scene as a binary 3DGS PLY, atomically (normals written as 0).
    pub fn write_ply(&self, path: &Path) -> Result<(), SceneError> {
        self.check().map_err(|e| SceneError::File {
            path: path.to_path_buf(),
            problem: format!("not written: {e}"),
        })?;
        let k = self.coefficients();
        let column =
            |value: &dyn Fn(usize) -> f32| ColumnOut::F32((0..self.len()).map(value).collect());
        let mut vertex = ElementOut::new("vertex");
        for (a, name) in ["x", "y", "z"].into_iter().enumerate() {
            vertex = vertex.with(name, column(&|i| self.positions[i][a]));
        }
        for name in ["nx", "ny", "nz"] {
            vertex = vertex.with(name, column(&|_| 0.0));
        }
        for ch in 0..3 {
            vertex = vertex.with(&format!("f_dc_{ch}"), column(&|i| self.sh[i * k * 3 + ch]));
        }
        for (ch, coefficient) in (0..3).flat_map(|ch| (1..k).map(move |c| (ch, c))) {
            vertex = vertex.with(
                &format!("f_rest_{}", ch * (k - 1) + coefficient - 1),
                column(&|i| self.sh[(i * k + coefficient) * 3 + ch]),
            );
        }
        vertex = vertex.with("opacity", column(&|i| self.opacity_logits[i]));
        for a in 0..3 {
            vertex = vertex.with(&format!("scale_{a}"), column(&|i| self.log_scales[i][a]));
        }
        for a in 0..4 {
            vertex = vertex.with(&format!("rot_{a}"), column(&|i| self.rotations[i][a]));
        }
        Ok(write_ply(path, &["tagsplat Gaussian scene (3DGS layout)"], &[vertex])?)
    }
}

/// SH coefficients, coefficient-major, from `f_dc_*` and the channel-major `f_rest_*`.
fn read_sh(vertex: &PlyElement, degree: u32) -> Result<Vec<f32>, PlyError> {
    let k = sh_coefficients(degree);
    let mut sh = vec![0.0; vertex.len() * k * 3];
    for ch in 0..3 {
        for coefficient in 0..k {
            let name = if coefficient == 0 {
                format!("f_dc_{ch}")
            } else {
                format!("f_rest_{}", ch * (k - 1) + coefficient - 1)
            };
            for (i, value) in vertex.column_f32(&name)?.into_iter().enumerate() {
                sh[(i * k + coefficient) * 3 + ch] = value;
            }
        }
    }
    Ok(sh)
}
