//! A fit as a job on disk: dataset folder and frame in, `OUT/` written (the library side of
//! `tagsplat fit`).

use super::config::FitConfig;
use super::fit::{fit, FitOutcome, Progress};
use super::init::{gaussians_at_points, points_inside_masks, MaskedView};
use super::report::{write_curve_csv, write_curve_plot};
use super::views::{load_targets, ViewTarget};
use super::TrainError;
use crate::dataset::{Dataset, LoadOptions};
use crate::gpu::GpuContext;
use crate::io::image::write_png;
use crate::io::ply::Ply;
use crate::mesh::TriMesh;
use crate::splat::GaussianScene;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A fit of one dataset frame (`tagsplat fit`); see [`run_fit_job`].
pub struct FitJob {
    /// The dataset folder.
    pub data: PathBuf,
    /// The frame to fit.
    pub frame: usize,
    /// A point cloud or mesh (PLY or OBJ) whose vertices seed the Gaussians; without one,
    /// points are sampled inside the masks.
    pub init: Option<PathBuf>,
    /// The fit configuration.
    pub config: FitConfig,
    /// What the dataset's files leave open (the intrinsics' pixel centres).
    pub load: LoadOptions,
}

/// Loads the dataset, initialises, fits. The report's `frame` is the job's. `progress` sees every
/// iteration and may cancel the fit ([`fit`]).
pub fn run_fit_job(
    ctx: &Arc<GpuContext>,
    job: &FitJob,
    progress: &mut dyn FnMut(Progress) -> ControlFlow<()>,
) -> Result<FitOutcome, TrainError> {
    job.config.check()?;
    let mut dataset = Dataset::load_with(&job.data, &job.load)?;
    dataset.refine_masks_when(job.config.refine_masks, job.frame, &mut |_, _| {})?;
    let use_masks = job.config.loss.mask > 0.0 || job.init.is_none();
    let train =
        load_targets(&dataset, job.frame, &dataset.train, job.config.background, use_masks)?;
    let held_out =
        load_targets(&dataset, job.frame, &dataset.test, job.config.background, use_masks)?;
    let initial = initial_gaussians(&train, job.init.as_deref(), &job.config)?;
    let (eval, held) = if held_out.is_empty() { (&train, false) } else { (&held_out, true) };
    let mut outcome = fit(ctx, &train, eval, held, initial, &job.config, progress)?;
    outcome.report.frame = job.frame;
    Ok(outcome)
}

/// Gaussians at the vertices of `init`, or at points sampled inside the views' masks.
pub fn initial_gaussians(
    views: &[ViewTarget],
    init: Option<&Path>,
    config: &FitConfig,
) -> Result<GaussianScene, TrainError> {
    let (points, colors) = match init {
        Some(path) => read_points(path)?,
        None => {
            let masks: Vec<Vec<f32>> =
                views.iter().map(|v| v.target.iter().map(|p| p[3]).collect()).collect();
            let rgbs: Vec<Vec<[f32; 3]>> = views
                .iter()
                .map(|v| v.target.iter().map(|p| [p[0], p[1], p[2]]).collect())
                .collect();
            let masked: Vec<MaskedView> = views
                .iter()
                .zip(&masks)
                .zip(&rgbs)
                .map(|((v, mask), rgb)| MaskedView { camera: &v.camera, mask, rgb })
                .collect();
            let (points, colors) =
                points_inside_masks(&masked, config.init.points as usize, config.seed)?;
            (points, Some(colors))
        }
    };
    Ok(gaussians_at_points(&points, colors.as_deref(), config.sh_degree))
}

/// Points, with colours (linear RGB in [0, 1]) when the file has them.
type PointsAndColors = (Vec<[f32; 3]>, Option<Vec<[f32; 3]>>);

/// Vertex positions (and colours when present) of a PLY point cloud or mesh, or an OBJ mesh.
fn read_points(path: &Path) -> Result<PointsAndColors, TrainError> {
    let bad = |problem: String| TrainError::Invalid { path: path.to_owned(), problem };
    let is_obj = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    let (points, colors) = if is_obj {
        let mesh = TriMesh::read_obj(path).map_err(|e| bad(e.to_string()))?;
        (mesh.positions, mesh.colors)
    } else {
        let ply = Ply::read(path).map_err(|e| bad(e.to_string()))?;
        let vertex = ply.require("vertex").map_err(|e| bad(e.to_string()))?;
        let column = |name| vertex.column_f32(name).map_err(|e| bad(e.to_string()));
        let (x, y, z) = (column("x")?, column("y")?, column("z")?);
        let points = (0..vertex.len()).map(|i| [x[i], y[i], z[i]]).collect();
        let colors = if vertex.has("red") && vertex.has("green") && vertex.has("blue") {
            let channel = |name| vertex.column_u8(name).map_err(|e| bad(e.to_string()));
            let (r, g, b) = (channel("red")?, channel("green")?, channel("blue")?);
            Some((0..vertex.len()).map(|i| [r[i], g[i], b[i]]).collect())
        } else {
            None
        };
        (points, colors)
    };
    if points.is_empty() {
        return Err(bad("has no vertices to start from".into()));
    }
    if let Some(i) = points.iter().position(|p: &[f32; 3]| !p.iter().all(|c| c.is_finite())) {
        return Err(bad(format!("vertex {i} is not finite")));
    }
    let colors =
        colors.map(|c: Vec<[u8; 3]>| c.iter().map(|p| p.map(|v| v as f32 / 255.0)).collect());
    Ok((points, colors))
}

/// Writes `OUT/gaussians.ply`, `OUT/renders/<camera>.png`, `OUT/report.json`,
/// `OUT/curve.csv` and `OUT/curve.svg`, each atomically; returns the paths written.
pub fn write_fit_outputs(out: &Path, outcome: &FitOutcome) -> Result<Vec<PathBuf>, TrainError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |error| TrainError::Io { path, error }
    };
    let renders = out.join("renders");
    std::fs::create_dir_all(&renders).map_err(io(&renders))?;
    let mut written = Vec::new();
    let splats = out.join("gaussians.ply");
    outcome.scene.write_ply(&splats)?;
    written.push(splats);
    for (name, image) in &outcome.renders {
        let path = renders.join(format!("{name}.png"));
        write_png(&path, image)?;
        written.push(path);
    }
    let report = out.join("report.json");
    outcome.report.write_json(&report)?;
    let csv = out.join("curve.csv");
    write_curve_csv(&csv, &outcome.report.curve)?;
    let plot = out.join("curve.svg");
    write_curve_plot(&plot, &outcome.report.curve)?;
    written.extend([report, csv, plot]);
    Ok(written)
}
