//! `tagsplat eval`: metrics of a prediction folder against a ground-truth folder.

use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::eval::{evaluate_folders, FolderOptions};

#[derive(clap::Args)]
pub struct EvalArgs {
    /// Prediction folder: meshes/<t>.ply, trajectories.csv, images/<camera>/<t>.png (any of them).
    #[arg(long)]
    pred: PathBuf,
    /// Ground-truth folder (e.g. written by `tagsplat synth`), same layout.
    #[arg(long)]
    gt: PathBuf,
    /// Surface samples per mesh for Chamfer.
    #[arg(long, default_value_t = 30_000)]
    chamfer_samples: usize,
    /// Surface samples per mesh for EMD (exact assignment, O(n³)).
    #[arg(long, default_value_t = 1000)]
    emd_samples: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[arg(long)]
    json: bool,
}

pub fn run(a: EvalArgs) -> Result<()> {
    let options = FolderOptions { chamfer_samples: a.chamfer_samples, emd_samples: a.emd_samples, seed: a.seed };
    let r = evaluate_folders(&a.pred, &a.gt, &options).with_context(|| format!("eval --pred {} --gt {}", a.pred.display(), a.gt.display()))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    if let (Some(sq), Some(m), Some(e)) = (r.chamfer_squared_mean, r.chamfer_mean, r.emd_mean) {
        println!("meshes    {} frames; {} Chamfer samples, {} EMD samples per mesh", r.meshes.len(), r.chamfer_samples, r.emd_samples);
        println!("  Chamfer (mean of squared NN distances)  {sq:.6e} scene units²");
        println!("  Chamfer (mean of NN distances)          {m:.6e} scene units ({:.4e} of the GT bounding-box diagonal)", r.meshes.iter().map(|f| f.chamfer.mean_fraction).sum::<f64>() / r.meshes.len() as f64);
        println!("  EMD (mean matched distance, exact)      {e:.6e} scene units");
    }
    if let Some(t) = &r.tracking {
        println!("tracking  {} points × {} frames: MSE {:.6e} scene units², RMSE {:.6e} scene units, max {:.6e} scene units", t.points, t.frames, t.mse, t.rmse, t.max);
    }
    if let Some(i) = &r.images {
        println!("images    {}: PSNR {:.3} dB, SSIM {:.5}", i.images, i.psnr_db, i.ssim);
    }
    Ok(())
}
