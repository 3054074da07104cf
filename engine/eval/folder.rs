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

/// Sample counts and seed of [`evaluate_folders`].
#[derive(Clone, Copy, Debug)]
pub struct FolderOptions {
    /// Surface samples per mesh for Chamfer, and for EMD (exact, O(n³)).
    pub chamfer_samples: usize,
    /// Surface samples per mesh for EMD (default 1000).
    pub emd_samples: usize,
    /// Seeds the surface samples.
    pub seed: u64,
}

impl Default for FolderOptions {
    fn default() -> Self {
        Self { chamfer_samples: 30_000, emd_samples: 1000, seed: 0 }
    }
}

/// Why two folders could not be compared.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// A metric failed on a predicted file (images of different sizes included).
    #[error("{}: {source}", path.display())]
    Metric {
        /// The predicted file.
        path: PathBuf,
        /// The metric's error.
        source: EvalError,
    },
    /// A mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An image could not be read.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// A `trajectories.csv` could not be read.
    #[error(transparent)]
    Trajectories(#[from] TrajectoriesError),
    /// A ground-truth mesh has no prediction of the same name.
    #[error("missing prediction {} (the ground truth has {})", pred.display(), gt.display())]
    Missing {
        /// The predicted mesh expected.
        pred: PathBuf,
        /// The ground-truth mesh.
        gt: PathBuf,
    },
    /// A folder could not be listed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The folders share no metric: no meshes, trajectories or images to compare.
    #[error("nothing to compare: {} has no meshes/*.ply, trajectories.csv or images/", .0.display())]
    Nothing(PathBuf),
}

/// One frame's mesh metrics.
#[derive(Clone, Debug, Serialize)]
pub struct MeshFrameReport {
    /// The mesh's file name without `.ply` (the six-digit frame index).
    pub frame: String,
    /// Chamfer distance of the prediction to the ground truth.
    pub chamfer: ChamferReport,
    /// Earth mover's distance of the prediction to the ground truth.
    pub emd: EmdReport,
}

/// Image metrics over every predicted image with a ground-truth counterpart.
#[derive(Clone, Debug, Serialize)]
pub struct ImageReport {
    /// Images compared.
    pub images: usize,
    /// Means over images, dB and unitless.
    pub psnr_db: f64,
    /// Mean SSIM (RGB).
    pub ssim: f64,
}

/// Every metric the two folders allow (see the module docs).
#[derive(Clone, Debug, Serialize)]
pub struct FolderReport {
    /// Per ground-truth frame, in file-name order (empty without a predicted `meshes/`).
    pub meshes: Vec<MeshFrameReport>,
    /// Means over frames: squared scene units, scene units, scene units.
    pub chamfer_squared_mean: Option<f64>,
    /// Mean Chamfer distance over frames, scene units (None without meshes).
    pub chamfer_mean: Option<f64>,
    /// Mean EMD over frames, scene units (None without meshes).
    pub emd_mean: Option<f64>,
    /// Surface samples per mesh for Chamfer.
    pub chamfer_samples: usize,
    /// Surface samples per mesh for EMD.
    pub emd_samples: usize,
    /// Tracking error, when both folders have a `trajectories.csv`.
    pub tracking: Option<TrackingReport>,
    /// Image metrics, when some predicted image has a ground-truth counterpart.
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

/// Compares the prediction folder `pred` with the ground-truth folder `gt` (see the module
/// docs). Fails on the first unreadable file or failing metric, on a ground-truth mesh without
/// its prediction, and when nothing can be compared.
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
            // Capped as the trainer's evaluation caps it: identical images would make it infinite.
            p_sum += psnr(&a, &b).map_err(metric)?.min(100.0);
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
