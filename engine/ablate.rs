//! `tagsplat ablate --temporal`: the temporal stage's parts switched off one at a time on a
//! benchmark with ground truth (`DIR/gt/`, see `score`), every variant continuing
//! one finished frame 0, so the rows differ only in what happens after it.

use crate::demo::Ablation;
use crate::gpu::GpuContext;
use crate::score::{
    evaluate_sequence, find_ground_truth, GroundTruth, SequenceEvalError, SequenceEvalOptions,
};
use crate::train::output::SequenceOutput;
use crate::train::pipeline::{run_train, ReferencePose, TrainConfig, TrainJob, TrainProgress};
use crate::train::TrainError;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The temporal stage's parts, each off in turn, and the stage they replaced.
pub fn temporal_ablations() -> Vec<Ablation> {
    vec![
        Ablation { name: "full model", apply: |_| {} },
        Ablation { name: "w/o deformation graph", apply: |c| c.temporal.graph.nodes = 0 },
        Ablation {
            name: "graph on frame 0",
            apply: |c| c.temporal.graph.rest = ReferencePose::Frame0,
        },
        Ablation {
            name: "regularizers against frame 0",
            apply: |c| c.temporal.regularizer_reference = ReferencePose::Frame0,
        },
        Ablation { name: "w/o coarse level", apply: |c| c.temporal.graph.levels = vec![1] },
        Ablation { name: "w/o coarse graph", apply: |c| c.temporal.graph.coarse_nodes = 0 },
        Ablation { name: "w/o silhouette term", apply: |c| c.temporal.silhouette = 0.0 },
        Ablation { name: "w/o coverage term", apply: |c| c.temporal.coverage = 0.0 },
        Ablation { name: "w/o limb stiffness", apply: |c| c.temporal.limb_thickness = 0.0 },
        Ablation { name: "w/o Huber strain", apply: |c| c.loss.huber = 0.0 },
        Ablation { name: "w/o colour fit", apply: |c| c.temporal.colour_iterations = 0 },
        Ablation { name: "with anchor term", apply: |c| c.temporal.anchor = ANCHOR_WEIGHT },
        Ablation { name: "with flow term", apply: |c| c.temporal.flow = FLOW_WEIGHT },
        Ablation {
            name: "w/o adaptive iterations",
            apply: |c| {
                (c.temporal.min_iterations, c.temporal.graph.min_iterations) =
                    (c.temporal.iterations, c.temporal.graph.iterations)
            },
        },
        Ablation { name: "previous temporal stage", apply: previous_temporal_stage },
    ]
}

/// The anchor term's weight in its ablation row and for textured captures (off by default: on
/// textured skin it gains only over the first frames, and it costs flat-coloured skin 6–8 %;
/// docs/log/2026-11-28-image-anchors.md, docs/log/2026-11-28-correspondence-oracles.md).
pub const ANCHOR_WEIGHT: f32 = 3000.0;

/// The flow term's weight in its ablation row (off by default: on fox_run_textured it moved
/// the score within the run-to-run spread, docs/log/2026-11-28-image-anchors.md).
const FLOW_WEIGHT: f32 = 300.0;

/// The temporal stage before the deformation graph, the silhouette and coverage terms, the
/// limb stiffness, the Huber strain, the adaptive stop, the colour fit and the anchor and flow
/// terms: 300 per-vertex iterations per frame from the extrapolated pose.
pub fn previous_temporal_stage(c: &mut TrainConfig) {
    c.loss.huber = 0.0;
    (c.temporal.anchor, c.temporal.flow) = (0.0, 0.0);
    (
        c.temporal.graph.nodes,
        c.temporal.silhouette,
        c.temporal.coverage,
        c.temporal.limb_thickness,
        c.temporal.iterations,
        c.temporal.min_iterations,
        c.temporal.colour_iterations,
    ) = (0, 0.0, 0.0, 0.0, 300, 300, 0);
}

/// The temporal ablations of one benchmark; see [`run_temporal_ablations`].
pub struct TemporalAblationJob {
    /// A benchmark dataset (with `gt/info.json`).
    pub data: PathBuf,
    /// The folder that receives one train output per variant and the tables.
    pub out: PathBuf,
    /// The configuration every variant changes.
    pub base: TrainConfig,
    /// A `tagsplat train` output whose frame 0 every variant continues.
    pub frame0: PathBuf,
    /// The frames each variant trains and is scored on; frame 0 comes from `frame0`.
    pub frames: Range<usize>,
    /// The variants to run, by name (see [`temporal_ablations`]); empty: all of them.
    pub variants: Vec<String>,
}

/// One variant's scores (fractions of the benchmark's size, dB, seconds).
#[derive(Clone, Debug, serde::Serialize)]
pub struct TemporalRow {
    /// The variant's name.
    pub variant: String,
    /// Tracking RMSE over all points and scored frames (NaN without track rows).
    pub tracking_rmse: f64,
    /// Tracking RMSE of the worst frame (NaN without track rows).
    pub tracking_worst_frame: f64,
    /// Point-to-surface Chamfer of the worst frame (NaN when no frame was scored).
    pub chamfer_worst_frame: f64,
    /// Mesh-render PSNR of the last scored frame, dB (NaN when the train report lacks it).
    pub psnr_mesh_last_db: f64,
    /// Means over the later frames.
    pub seconds_per_frame: f64,
    /// Iterations per later frame, the graph levels' and the per-vertex ones together.
    pub iterations_per_frame: f64,
}

/// Why the temporal ablations failed.
#[derive(Debug, thiserror::Error)]
pub enum AblateError {
    /// The dataset has no ground truth to score against.
    #[error("{0} has no gt/info.json: temporal ablations need a benchmark with ground truth")]
    NoGroundTruth(PathBuf),
    /// A variant asked for by name is not one of [`temporal_ablations`].
    #[error("no temporal ablation is named {name:?}; the variants are: {known}")]
    UnknownVariant {
        /// The name asked for.
        name: String,
        /// Every variant's name, comma-separated.
        known: String,
    },
    /// The given train output has no complete frame 0.
    #[error("{}: no finished frame 0 to continue", .0.display())]
    NoFrame0(PathBuf),
    /// A variant's training failed, or its output folder could not be created.
    #[error(transparent)]
    Train(#[from] TrainError),
    /// A variant could not be scored, or the ground truth read.
    #[error(transparent)]
    Eval(#[from] SequenceEvalError),
    /// A file could not be copied or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// The variants named in `names` (every one when empty), each with its place in
/// [`temporal_ablations`], in that list's order and once each whatever the order and repeats
/// of `names`. The place numbers the variant's output folder, so a row run alone lands where
/// a run of all of them puts it.
pub fn select_temporal_ablations(names: &[String]) -> Result<Vec<(usize, Ablation)>, AblateError> {
    let all = temporal_ablations();
    let mut chosen = Vec::new();
    for name in names {
        let place = all.iter().position(|a| a.name == name).ok_or_else(|| {
            let known = all.iter().map(|a| a.name).collect::<Vec<_>>().join(", ");
            AblateError::UnknownVariant { name: name.clone(), known }
        })?;
        chosen.push(place);
    }
    chosen.sort_unstable();
    chosen.dedup();
    let keep = |i: &usize| names.is_empty() || chosen.binary_search(i).is_ok();
    Ok(all.into_iter().enumerate().filter(|(i, _)| keep(i)).collect())
}

/// Runs the job's variants into `out/<n>_<name>/` (a finished variant is resumed, not redone)
/// and writes their rows to `out/ablation.md` and `out/ablation.json`.
pub fn run_temporal_ablations(
    ctx: &Arc<GpuContext>,
    job: &TemporalAblationJob,
    progress: &mut dyn FnMut(&str, TrainProgress),
) -> Result<Vec<TemporalRow>, AblateError> {
    let gt = GroundTruth::read(
        &find_ground_truth(&job.data)
            .ok_or_else(|| AblateError::NoGroundTruth(job.data.clone()))?,
    )?;
    let mut rows = Vec::new();
    for (i, ablation) in select_temporal_ablations(&job.variants)? {
        let mut config = job.base.clone();
        (ablation.apply)(&mut config);
        let dir = job.out.join(format!("{i}_{}", ablation.name.replace(['/', ' '], "_")));
        copy_frame0(&job.frame0, &dir)?;
        let train = run_train(
            ctx,
            &TrainJob {
                frames: Some(job.frames.clone()),
                ..TrainJob::new(&job.data, &dir, config)
            },
            &mut |p| progress(ablation.name, p),
        )?;
        let eval = evaluate_sequence(
            &dir,
            &gt,
            &SequenceEvalOptions { frames: Some(job.frames.clone()), ..Default::default() },
        )?;
        let later: Vec<_> = train.frames.iter().filter(|f| f.frame > 0).collect();
        let mean = |v: &dyn Fn(&crate::train::pipeline::FrameReport) -> f64| {
            later.iter().map(|f| v(f)).sum::<f64>() / later.len().max(1) as f64
        };
        let s = &eval.summary;
        rows.push(TemporalRow {
            variant: ablation.name.to_string(),
            tracking_rmse: s.tracking_rmse_over_size.unwrap_or(f64::NAN),
            tracking_worst_frame: s.tracking_worst_frame.map_or(f64::NAN, |v| v.value),
            chamfer_worst_frame: s.chamfer_worst_frame.map_or(f64::NAN, |v| v.value),
            psnr_mesh_last_db: s.psnr_mesh_last_db.unwrap_or(f64::NAN),
            seconds_per_frame: mean(&|f| f.wall_s),
            iterations_per_frame: mean(&|f| {
                f.iterations as f64
                    + f.graph
                        .as_ref()
                        .map_or(0.0, |g| g.levels.iter().map(|l| l.iterations as f64).sum())
            }),
        });
    }
    write_tables(&job.out, &rows)?;
    Ok(rows)
}

/// Frame 0 of the train output `from` into the train output `to` (its camera colour maps
/// and Gaussians first: the mesh marks the frame complete), unless `to` has it already; a run
/// into `to` then continues it.
pub fn copy_frame0(from: &Path, to: &Path) -> Result<(), AblateError> {
    let (source, target) = (SequenceOutput::create(from)?, SequenceOutput::create(to)?);
    if target.is_complete(0) {
        return Ok(());
    }
    if !source.is_complete(0) {
        return Err(AblateError::NoFrame0(from.to_owned()));
    }
    let maps = (source.camera_colour_path(), target.camera_colour_path());
    let maps = maps.0.is_file().then_some(maps);
    for (a, b) in maps.into_iter().chain([
        (source.gaussians_path(0), target.gaussians_path(0)),
        (source.mesh_path(0), target.mesh_path(0)),
    ]) {
        crate::io::write_atomically(&b, |w| {
            std::io::copy(&mut std::fs::File::open(&a)?, w).map(drop)
        })
        .map_err(|source| AblateError::Io { path: b.clone(), source })?;
    }
    Ok(())
}

fn write_tables(out: &Path, rows: &[TemporalRow]) -> Result<(), AblateError> {
    let mut table = String::from("| variant | tracking RMSE / size | worst frame | Chamfer / size, worst frame | last-frame mesh PSNR (dB) | s per later frame | iterations per later frame |\n|---|---|---|---|---|---|---|\n");
    for r in rows {
        table += &format!(
            "| {} | {:.2} % | {:.2} % | {:.3} % | {:.2} | {:.1} | {:.0} |\n",
            r.variant,
            100.0 * r.tracking_rmse,
            100.0 * r.tracking_worst_frame,
            100.0 * r.chamfer_worst_frame,
            r.psnr_mesh_last_db,
            r.seconds_per_frame,
            r.iterations_per_frame
        );
    }
    let io = |path: PathBuf| move |source| AblateError::Io { path, source };
    let md = out.join("ablation.md");
    crate::io::write_atomically(&md, |w| std::io::Write::write_all(w, table.as_bytes()))
        .map_err(io(md.clone()))?;
    let json = out.join("ablation.json");
    crate::io::write_json_atomically(&json, rows).map_err(io(json.clone()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(chosen: &[(usize, Ablation)]) -> Vec<(usize, &'static str)> {
        chosen.iter().map(|(i, a)| (*i, a.name)).collect()
    }

    #[test]
    fn no_names_select_every_variant_in_order() {
        let all = temporal_ablations();
        let chosen = select_temporal_ablations(&[]).unwrap();
        let expected: Vec<_> = all.iter().enumerate().map(|(i, a)| (i, a.name)).collect();
        assert_eq!(names(&chosen), expected);
    }

    #[test]
    fn named_variants_keep_their_place_once_each() {
        let all = temporal_ablations();
        let (a, b) = (all[1].name.to_string(), all[all.len() - 1].name.to_string());
        let chosen = select_temporal_ablations(&[b.clone(), a.clone(), b]).unwrap();
        assert_eq!(
            names(&chosen),
            vec![(1, all[1].name), (all.len() - 1, all[all.len() - 1].name)]
        );
    }

    #[test]
    fn an_unknown_name_is_refused_with_the_known_ones() {
        let err = select_temporal_ablations(&["full model".into(), "w/o luck".into()]).err();
        let message = err.expect("an unknown name is refused").to_string();
        assert!(message.contains("\"w/o luck\""), "{message}");
        assert!(message.contains("full model, w/o deformation graph"), "{message}");
    }
}
