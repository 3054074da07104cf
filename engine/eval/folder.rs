//! `tagsplat eval --pred DIR --gt DIR`: every metric the two folders allow.
//!
//! Layout (both folders; the generator writes the ground-truth side, the tracker and the
//! trainer the prediction side):
//! - `meshes/<t>.ply`: one mesh per frame (six-digit frame index). When the prediction has a
//!   `meshes/` folder, every ground-truth frame needs a prediction; Chamfer and EMD per frame,
//!   then their means over frames.
//! - `trajectories.csv` (`id,frame,x,y,z`): tracking error, when both folders have one.
//! - `images/<camera>/<t>.png`: PSNR and SSIM for every predicted image that has a
//!   ground-truth image of the same name (RGB; an alpha channel is ignored).

use super::{
    chamfer_meshes, emd_meshes, psnr, ssim, tracking_error, ChamferReport, EmdReport, EvalError,
    TrackingReport,
};
use crate::io::image::{read_image, Image, ImageError};
use crate::io::trajectories::{read_trajectories_csv, TrajectoriesError};
use crate::mesh::{MeshError, TriMesh};
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug)]
pub struct FolderOptions {
    /// Surface samples per mesh for Chamfer, and for EMD (exact, O(n³)).
    pub chamfer_samples: usize,
    pub emd_samples: usize,
    pub seed: u64,
}

impl Default for FolderOptions {
    fn default() -> Self {
        Self { chamfer_samples: 30_000, emd_samples: 1000, seed: 0 }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    #[error("{}: {source}", path.display())]
    Metric { path: PathBuf, source: EvalError },
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error(transparent)]
    Trajectories(#[from] TrajectoriesError),
    #[error("missing prediction {} (the ground truth has {})", pred.display(), gt.display())]
    Missing { pred: PathBuf, gt: PathBuf },
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("nothing to compare: {} has no meshes/*.ply, trajectories.csv or images/", .0.display())]
    Nothing(PathBuf),
}

#[derive(Clone, Debug, Serialize)]
pub struct MeshFrameReport {
    pub frame: String,
    pub chamfer: ChamferReport,
    pub emd: EmdReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct ImageReport {
    pub images: usize,
    /// Means over images, dB and unitless.
    pub psnr_db: f64,
    pub ssim: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct FolderReport {
    pub meshes: Vec<MeshFrameReport>,
    /// Means over frames: squared scene units, scene units, scene units.
    pub chamfer_squared_mean: Option<f64>,
    pub chamfer_mean: Option<f64>,
    pub emd_mean: Option<f64>,
    pub chamfer_samples: usize,
    pub emd_samples: usize,
    pub tracking: Option<TrackingReport>,
    pub images: Option<ImageReport>,
}

fn list(dir: &Path, ext: &str) -> Result<Vec<PathBuf>, FolderError> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let entries = std::fs::read_dir(dir)
        .map_err(|source| FolderError::Io { path: dir.to_owned(), source })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == ext) && p.is_file())
        .collect();
    files.sort();
    Ok(files)
}

pub fn evaluate_folders(
    pred: &Path,
    gt: &Path,
    o: &FolderOptions,
) -> Result<FolderReport, FolderError> {
    let mut meshes = Vec::new();
    // Mesh metrics when the prediction has a meshes/ folder at all (a tracking-only result
    // has none); then every ground-truth frame needs its prediction.
    let gt_meshes =
        if pred.join("meshes").is_dir() { list(&gt.join("meshes"), "ply")? } else { Vec::new() };
    for gt_path in gt_meshes {
        let name = gt_path.file_name().expect("listed files have names");
        let pred_path = pred.join("meshes").join(name);
        if !pred_path.is_file() {
            return Err(FolderError::Missing { pred: pred_path, gt: gt_path });
        }
        let (a, b) = (TriMesh::read_ply(&pred_path)?, TriMesh::read_ply(&gt_path)?);
        let metric = |source| FolderError::Metric { path: pred_path.clone(), source };
        let chamfer = chamfer_meshes(
            (&a.positions, &a.faces),
            (&b.positions, &b.faces),
            o.chamfer_samples,
            o.seed,
        )
        .map_err(metric)?;
        let emd =
            emd_meshes((&a.positions, &a.faces), (&b.positions, &b.faces), o.emd_samples, o.seed)
                .map_err(metric)?;
        meshes.push(MeshFrameReport {
            frame: name.to_string_lossy().trim_end_matches(".ply").to_owned(),
            chamfer,
            emd,
        });
    }
    let mean = |f: &dyn Fn(&MeshFrameReport) -> f64| {
        (!meshes.is_empty()).then(|| meshes.iter().map(f).sum::<f64>() / meshes.len() as f64)
    };
    let tracking = match (pred.join("trajectories.csv"), gt.join("trajectories.csv")) {
        (p, g) if p.is_file() && g.is_file() => {
            let (a, b) = (read_trajectories_csv(&p)?, read_trajectories_csv(&g)?);
            Some(tracking_error(&a, &b).map_err(|source| FolderError::Metric { path: p, source })?)
        }
        _ => None,
    };
    let images = compare_images(pred, gt)?;
    if meshes.is_empty() && tracking.is_none() && images.is_none() {
        return Err(FolderError::Nothing(gt.to_owned()));
    }
    Ok(FolderReport {
        chamfer_squared_mean: mean(&|m| m.chamfer.squared),
        chamfer_mean: mean(&|m| m.chamfer.mean),
        emd_mean: mean(&|m| m.emd.mean),
        meshes,
        chamfer_samples: o.chamfer_samples,
        emd_samples: o.emd_samples,
        tracking,
        images,
    })
}

/// RGB values of an image (the first three channels; grey repeated).
fn rgb(image: &Image) -> Vec<f32> {
    image
        .data
        .chunks_exact(image.channels as usize)
        .flat_map(|p| if p.len() >= 3 { [p[0], p[1], p[2]] } else { [p[0]; 3] })
        .collect()
}

fn compare_images(pred: &Path, gt: &Path) -> Result<Option<ImageReport>, FolderError> {
    let root = pred.join("images");
    if !root.is_dir() {
        return Ok(None);
    }
    let cameras = std::fs::read_dir(&root)
        .map_err(|source| FolderError::Io { path: root.clone(), source })?;
    let mut dirs: Vec<PathBuf> =
        cameras.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_dir()).collect();
    dirs.sort();
    let (mut n, mut p_sum, mut s_sum) = (0usize, 0.0, 0.0);
    for dir in dirs {
        let camera = dir.file_name().expect("listed dirs have names").to_owned();
        for path in list(&dir, "png")? {
            let gt_path = gt
                .join("images")
                .join(&camera)
                .join(path.file_name().expect("listed files have names"));
            if !gt_path.is_file() {
                continue;
            }
            let (a, b) = (read_image(&path)?, read_image(&gt_path)?);
            let metric = |source| FolderError::Metric { path: path.clone(), source };
            if (a.width, a.height) != (b.width, b.height) {
                return Err(metric(EvalError::ImageShape {
                    len: a.data.len(),
                    width: b.width as usize,
                    height: b.height as usize,
                    channels: a.channels as usize,
                }));
            }
            let (w, h) = (b.width as usize, b.height as usize);
            let (a, b) = (rgb(&a), rgb(&b));
            p_sum += psnr(&a, &b).map_err(metric)?;
            s_sum += ssim(&a, &b, w, h, 3).map_err(metric)?;
            n += 1;
        }
    }
    Ok((n > 0).then(|| ImageReport {
        images: n,
        psnr_db: p_sum / n as f64,
        ssim: s_sum / n as f64,
    }))
}
