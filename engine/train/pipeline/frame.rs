//! One frame's optimisation: every term of the paper in one submission per iteration —
//! Gaussian colour and mask losses, the mesh (the Gaussians as vertices, the topology as faces)
//! rendered and scored for colour and mask, the regularizers (temporal ones against the
//! previous frame) — then Adam. Frame 0 also densifies and prunes through the topology.

use super::camera_colour::{learned_maps, trainer_for, CameraMaps, ColourUse};
use super::config::{TemporalConfig, TrainConfig};
use super::correspondences::{correspondences, Correspondences, SeenPose, VertexTracks};
use super::graph_stage::{solve_graph, GraphInput, GraphReport, ImageWeights};
use crate::camera::Camera;
use crate::eval::{affine_corrected_psnr, psnr};
use crate::gpu::{GpuContext, Recorder};
use crate::loss::flow::FlowTerm;
use crate::loss::silhouette::{CoverageTerm, SilhouetteTerm, SilhouetteView};
use crate::mesh::bounding_diagonal;
use crate::optim::LearningRates;
use crate::regularize::stiffness::limb_stiffness;
use crate::regularize::{Losses, Neighbourhoods, Regularizers, Temporal};
use crate::rng::SplitMix64;
use crate::splat::{FrameParams, GaussianBuffers, GaussianScene, RenderSettings};
use crate::topology::{
    compose, densify, face_scores, prune, DensifyConfig, ManifoldMesh, PruneConfig,
};
use crate::train::fit::{self, learning_rates, scene_extent};
use crate::train::in_flight::StepTerms;
use crate::train::mesh_term::MeshTerm;
use crate::train::optimize::{optimize, ColourRefit, LoopOutcome, Schedule, Stage};
use crate::train::plateau::{Plateau, StopReason};
use crate::train::schedule::DensifyWindow;
use crate::train::{TrainError, Trainer, ViewTarget};
use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

/// What a frame's optimisation reports.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FrameReport {
    /// The frame index.
    pub frame: usize,
    /// Per-vertex iterations (the graph stage's are in `graph`).
    pub iterations: u32,
    /// Iterations of the colour fit after them (`temporal.colour_iterations`).
    #[serde(default)]
    pub colour_iterations: u32,
    /// Why the per-vertex stage stopped.
    pub stop_reason: StopReason,
    /// The deformation graph's levels (later frames with a graph).
    pub graph: Option<GraphReport>,
    /// What the flow and anchor terms matched (later frames with either on).
    #[serde(default)]
    pub correspondences: Option<CorrespondenceReport>,
    /// Training views left out of this frame: their mask is empty (the subject is lost there).
    pub lost_views: Vec<String>,
    /// Training views whose colours this frame leaves out (their masks still count), each
    /// "name: why": a dark or saturated image ([`ViewTarget::appearance_flaw`]).
    #[serde(default)]
    pub colour_left_out: Vec<String>,
    /// Optimisation wall time (evaluation excluded), seconds.
    pub wall_s: f64,
    /// The whole frame's wall time (setup and evaluation included) split into the device's
    /// busy time (its submissions' spans) and the rest, the time the device waited for the host;
    /// None where the queue writes no timestamps.
    #[serde(default)]
    pub device_s: Option<f64>,
    /// The wall time of the frame the device waited for the host (see `device_s`).
    #[serde(default)]
    pub host_s: Option<f64>,
    /// Gaussians at the end of the frame.
    pub gaussians: usize,
    /// Held-out (or training, see the run report) PSNR and SSIM of the Gaussian and mesh renders.
    pub psnr_gs: f64,
    /// Mean SSIM of the Gaussian renders.
    pub ssim_gs: f64,
    /// Mean PSNR of the Gaussian renders after each view's own affine colour map
    /// ([`affine_corrected_psnr`]): what remains when exposure and white balance are forgiven.
    #[serde(default)]
    pub psnr_gs_affine: f64,
    /// [`Self::psnr_gs_affine`] with each render seen through its view's mask (blended with
    /// the background as the target is): a held-out mask thresholded inside the subject's
    /// outline then costs nothing; one outside it still does (its extra ring holds the
    /// background the target shows).
    #[serde(default)]
    pub psnr_gs_affine_masked: f64,
    /// Mean PSNR of the mesh renders, dB.
    pub psnr_mesh: f64,
    /// Mean weighted losses of the last statistics interval.
    pub loss_gs: f32,
    /// The mesh renders' loss (`loss_gs` is the Gaussian renders').
    pub loss_mesh: f32,
    /// Silhouette and coverage terms, weighted, mean per iteration (later frames).
    pub loss_silhouette: f32,
    /// Unweighted regularizer values of the last statistics check.
    pub regularizers: [f32; 6],
    /// Mean GPU ms per iteration, by pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// (iteration, faces split, Gaussians pruned, Gaussians after) per topology step.
    pub topology_steps: Vec<(u32, usize, usize, usize)>,
    /// Per-vertex iterations whose intersections outgrew the splatter's buffers (rendered without
    /// the excess; see [`Trainer::finish_step`](crate::train::Trainer::finish_step)).
    pub truncated_steps: u32,
    /// Targets uploaded for a step when the device's memory could not hold every training
    /// view's (`train::targets`); None when it could.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_uploads: Option<u64>,
    /// The training cameras' colour maps frame 0 learned, by name (`[camera_colour]`; each
    /// row `(A_k0, A_k1, A_k2, b_k)`: the camera sees `A p + b α` of the subject's colour `p`).
    #[serde(default, skip_serializing_if = "CameraMaps::is_empty")]
    pub camera_colour: CameraMaps,
}

/// What a later frame's correspondence terms found in its images.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct CorrespondenceReport {
    /// (vertex, view) pairs followed from frame t − 1's images.
    pub flow_pairs: usize,
    /// (vertex, view) pairs whose frame-0 pixel is still tracked in the view.
    pub anchor_pairs: usize,
    /// Views where nothing could be matched (dark, saturated or textureless there, or the
    /// subject hidden), "flow:" or "anchor:" before the name: the terms skip them.
    pub unmatched_views: Vec<String>,
}

/// A frame to optimise: its views, where it starts, and what it keeps fixed.
pub struct FrameTask<'a> {
    /// The frame index.
    pub frame: usize,
    /// The training views.
    pub train: &'a [ViewTarget],
    /// The views the report's PSNR and SSIM are measured on (held-out, or the training views).
    pub eval: &'a [ViewTarget],
    /// The Gaussians it starts from: on the initial mesh (frame 0), or frame t − 1 extrapolated.
    pub start: GaussianScene,
    /// The topology (positions are overwritten by the Gaussians'); frame 0 changes it.
    pub mesh: &'a mut ManifoldMesh,
    /// Frame t − 1's Gaussians for the temporal terms (None on frame 0).
    pub previous: Option<&'a GaussianScene>,
    /// Frame 0's Gaussians, for a graph or regularizers configured against frame 0 (None on
    /// frame 0).
    pub frame0: Option<&'a GaussianScene>,
    /// What the flow and anchor terms match frame t's images against (nothing on frame 0 or
    /// with the terms off).
    pub sources: MatchSources<'a>,
    /// How the renders meet the cameras' colour responses: learned on frame 0, applied later.
    pub colour: ColourUse<'a>,
}

/// What the correspondence terms match a later frame's images against.
#[derive(Clone, Copy, Default)]
pub struct MatchSources<'a> {
    /// Frame t − 1's training views (the flow term).
    pub previous: &'a [ViewTarget],
    /// Frame 0's vertices tracked through the images up to frame t (the anchor term).
    pub tracks: Option<&'a VertexTracks>,
}

/// The optimised Gaussians (or, after a non-finite loss, the error naming it). Later frames
/// first solve the deformation graph (when configured), then refine per vertex until the loss
/// stops improving; frame 0 runs its fixed iterations with densification and pruning.
pub fn optimize_frame(
    ctx: &Arc<GpuContext>,
    mut task: FrameTask,
    config: &TrainConfig,
    progress: &mut FrameProgress<'_>,
) -> Result<(GaussianScene, FrameReport), TrainError> {
    let (started, clock) = (Instant::now(), ctx.clock());
    let canonical = task.previous.is_none();
    let (w, t) = (&config.loss, &config.temporal);
    let flaws: Vec<_> = task.train.iter().map(ViewTarget::appearance_flaw).collect();
    let colourless = flaws.iter().map(Option::is_some).collect();
    let (gaussians, mesh) = (w.gaussians.channels(), w.mesh.channels());
    let weights = ImageWeights { gaussians, mesh, colourless };
    let extent = scene_extent(&task.train.iter().map(|v| &v.camera).collect::<Vec<_>>());
    let first = task
        .train
        .first()
        .ok_or(TrainError::NoViews { frame: Some(task.frame), problem: "no training views" })?;
    let mut settings = render_settings(config, extent);
    let mut rng = SplitMix64::new(config.seed ^ task.frame as u64);
    let mut report = empty_report(task.frame);
    report.colour_left_out = (task.train.iter().zip(&flaws))
        .filter_map(|(v, flaw)| Some(format!("{}: {}", v.name, flaw.as_ref()?)))
        .collect();

    let silhouette = silhouette_term(ctx, &task, canonical, t)?;
    let matches = match_terms(ctx, &task, &task.start, t)?;
    report.correspondences = matches.report.clone();
    let (mut start, mut graph_s) = (std::mem::take(&mut task.start), 0.0);
    if !canonical && t.graph.nodes > 0 {
        let t0 = Instant::now();
        let graph = GraphRun {
            silhouette: silhouette.as_ref(),
            matches: &matches,
            weights: weights.clone(),
            settings: &settings,
        };
        let (moved, graph) = deform_start(ctx, &task, &start, config, graph, &mut rng)?;
        (start, report.graph, graph_s) = (moved, Some(graph), t0.elapsed().as_secs_f64());
    }

    let mut trainer = trainer_for(ctx, &start, task.train, task.colour, settings.background)?;
    task.mesh.positions = start.positions.clone();
    let terms = frame_terms(ctx, &task, &start, &first.camera, t, (silhouette, matches))?;
    let learn = matches!(task.colour, ColourUse::Learn);
    let (schedule, plateau) =
        frame_schedule(config, (canonical, learn), &weights, task.train.len());
    let budget = match config.canonical.budget {
        0 => covered_pixels(task.train),
        b => b as usize,
    };
    let mut stage = FrameStage {
        config,
        extent,
        diagonal: bounding_diagonal(&start.positions) as f32,
        near: settings.near,
        canonical,
        colour_only: false,
        weights,
        terms,
        mesh: task.mesh,
        densify_camera: (first.camera, budget),
        report: &mut report,
        progress,
        loss: None,
    };
    let run = optimize(&mut trainer, &mut stage, &schedule, plateau, &mut settings, &mut rng)?;
    let run = finite(run, task.frame)?;
    let (colour_iterations, colour_s) = if canonical || t.colour_iterations == 0 {
        (0, 0.0)
    } else {
        let schedule = Schedule { iterations: t.colour_iterations, ..schedule };
        let fit = fit_colours(&mut trainer, &mut stage, &schedule, &mut settings, &mut rng)?;
        let fit = finite(fit, task.frame)?;
        (fit.iterations, fit.train_s)
    };
    let FrameStage { terms, mesh, .. } = stage;
    let scene = trainer.scene()?;
    mesh.positions = scene.positions.clone();
    report.stop_reason = run.stop_reason;
    report.truncated_steps = run.truncated_steps;
    let streamed = trainer.targets_on_device() < trainer.views();
    report.target_uploads = streamed.then_some(trainer.target_uploads());
    report.colour_iterations = colour_iterations;
    if learn {
        report.camera_colour = learned_maps(&trainer, task.train)?;
    }
    (report.iterations, report.wall_s, report.gaussians, report.passes_ms) =
        (run.iterations, graph_s + run.train_s + colour_s, scene.len(), run.passes_ms);
    let held_out = evaluate(&mut trainer, &terms.mesh_term, task.eval, &settings)?;
    (report.psnr_gs, report.ssim_gs, report.psnr_mesh) =
        (held_out.psnr_gs, held_out.ssim_gs, held_out.psnr_mesh);
    (report.psnr_gs_affine, report.psnr_gs_affine_masked) =
        (held_out.psnr_gs_affine, held_out.psnr_gs_affine_masked);
    let (wall, clock) = (started.elapsed().as_secs_f64(), ctx.clock().since(&clock));
    if clock.host_share(wall).is_some() {
        (report.device_s, report.host_s) = (Some(clock.device_s), Some(wall - clock.device_s));
    }
    Ok((scene, report))
}

/// Render settings with the near and far planes at 1e-3 and 1e3 × the cameras' `extent`.
fn render_settings(config: &TrainConfig, extent: f64) -> RenderSettings {
    RenderSettings {
        background: config.background,
        near: (extent * 1e-3) as f32,
        far: (extent * 1e3) as f32,
        sh_degree: config.sh_degree,
        mask_mode: false,
    }
}

/// `run`, or the error naming what went non-finite in it.
fn finite(mut run: LoopOutcome, frame: usize) -> Result<LoopOutcome, TrainError> {
    match run.non_finite.take() {
        None => Ok(run),
        Some(detail) => Err(TrainError::NonFinite {
            frame: Some(frame),
            detail: format!("{detail}; the finished frames are kept"),
        }),
    }
}

/// The silhouette term of a later frame's training masks (None on frame 0 or when its
/// weight is 0).
fn silhouette_term(
    ctx: &Arc<GpuContext>,
    task: &FrameTask,
    canonical: bool,
    t: &TemporalConfig,
) -> Result<Option<SilhouetteTerm>, TrainError> {
    if canonical || t.silhouette == 0.0 {
        return Ok(None);
    }
    let views: Vec<_> =
        task.train.iter().map(|v| SilhouetteView::from_mask(v.camera, &v.mask())).collect();
    Ok(Some(SilhouetteTerm::new(ctx, &views)?))
}

/// A later frame's flow and anchor terms (None where off) and what they matched.
#[derive(Default)]
pub struct MatchTerms {
    pub flow: Option<FlowTerm>,
    pub anchor: Option<FlowTerm>,
    report: Option<CorrespondenceReport>,
}

impl MatchTerms {
    /// Records both terms with their weights (see [`FlowTerm::record`]).
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        (positions, grads): (&'a crate::gpu::GpuBuffer<f32>, &'a crate::gpu::GpuBuffer<f32>),
        t: &TemporalConfig,
        near: f32,
    ) -> crate::gpu::GpuResult<()> {
        for (term, weight) in [(&self.flow, t.flow), (&self.anchor, t.anchor)] {
            if let Some(term) = term {
                term.record(rec, positions, grads, weight, near)?;
            }
        }
        Ok(())
    }

    /// Both terms' weighted losses summed since the last call.
    pub fn take_loss(&self) -> crate::gpu::GpuResult<f32> {
        let mut sum = 0.0;
        for term in [&self.flow, &self.anchor].into_iter().flatten() {
            sum += term.take_loss()?;
        }
        Ok(sum)
    }
}

/// The flow and anchor terms of a later frame starting at `start` (none on frame 0 or where
/// a weight is 0), matched from the task's source views.
fn match_terms(
    ctx: &Arc<GpuContext>,
    task: &FrameTask,
    start: &GaussianScene,
    t: &TemporalConfig,
) -> Result<MatchTerms, TrainError> {
    let Some(previous) = task.previous else { return Ok(MatchTerms::default()) };
    if t.flow <= 0.0 && t.anchor <= 0.0 {
        return Ok(MatchTerms::default());
    }
    let faces = task.mesh.live_faces();
    let sources = task.sources;
    let flow = (t.flow > 0.0).then(|| {
        let source = SeenPose { positions: &previous.positions, views: sources.previous };
        correspondences(source, &start.positions, &faces, task.train)
    });
    let anchor = (sources.tracks.filter(|_| t.anchor > 0.0))
        .map(|tracks| tracks.targets(&start.positions, &faces, task.train));
    let mut report = CorrespondenceReport::default();
    let mut upload = |found: Option<Correspondences>, name: &str| -> Result<_, TrainError> {
        let Some(found) = found else { return Ok((None, 0)) };
        let names = found.unmatched_views.iter().map(|v| format!("{name}: {v}"));
        report.unmatched_views.extend(names);
        let term = FlowTerm::new(ctx, &found.cameras, &found.targets)?;
        let pairs = term.pairs();
        Ok((Some(term), pairs))
    };
    let (flow, flow_pairs) = upload(flow, "flow")?;
    let (anchor, anchor_pairs) = upload(anchor, "anchor")?;
    (report.flow_pairs, report.anchor_pairs) = (flow_pairs, anchor_pairs);
    Ok(MatchTerms { flow, anchor, report: Some(report) })
}

/// What the graph stage shares with the refinement.
struct GraphRun<'a> {
    /// None when the silhouette weight is 0: the graph then runs with an empty term.
    silhouette: Option<&'a SilhouetteTerm>,
    matches: &'a MatchTerms,
    weights: ImageWeights,
    settings: &'a RenderSettings,
}

/// `start`, a later frame's extrapolated pose (`task.start` has been taken from the task),
/// moved by the deformation graph, and the graph's report.
fn deform_start(
    ctx: &Arc<GpuContext>,
    task: &FrameTask,
    start: &GaussianScene,
    config: &TrainConfig,
    run: GraphRun,
    rng: &mut SplitMix64,
) -> Result<(GaussianScene, GraphReport), TrainError> {
    let no_silhouette;
    let silhouette = match run.silhouette {
        Some(s) => s,
        None => {
            no_silhouette = SilhouetteTerm::new(ctx, &[])?;
            &no_silhouette
        }
    };
    let (faces, neighbourhoods) = (task.mesh.live_faces(), Neighbourhoods::from_mesh(task.mesh));
    let input = GraphInput {
        frame: task.frame,
        train: task.train,
        start,
        frame0: task.frame0.unwrap_or(start),
        faces: &faces,
        neighbourhoods: &neighbourhoods,
        silhouette,
        matches: run.matches,
        colour: task.colour,
    };
    solve_graph(ctx, &input, config, run.weights, run.settings, rng)
}

/// The mesh (rendered at `camera`'s size), regularizer, temporal-reference and coverage terms
/// of a frame starting at `start`, with its silhouette term.
fn frame_terms(
    ctx: &Arc<GpuContext>,
    task: &FrameTask,
    start: &GaussianScene,
    camera: &Camera,
    t: &TemporalConfig,
    (silhouette, matches): (Option<SilhouetteTerm>, MatchTerms),
) -> Result<FrameTerms, TrainError> {
    let canonical = task.previous.is_none();
    let faces = task.mesh.live_faces();
    let mesh_term = MeshTerm::new(ctx, &start.positions, &faces, camera.width, camera.height)?;
    let mut regs = Regularizers::new(ctx)?;
    regs.upload(&refinement_neighbourhoods(task.mesh, canonical, t)?)?;
    let reference = t
        .regularizer_reference
        .pick(task.previous, task.frame0)
        .map(|p| GaussianBuffers::from_scene(ctx, p))
        .transpose()?;
    let pixels = task.train.iter().map(|v| v.target.len()).max().unwrap_or(0);
    let coverage = match canonical {
        true => None,
        false => Some(CoverageTerm::new(ctx, start.len(), pixels, t.coverage_radius)?),
    };
    Ok(FrameTerms { mesh_term, regs, reference, silhouette, coverage, matches })
}

/// The refinement's schedule and stopping rule: frame 0 runs all its iterations with the SH
/// ramp and densification, reading the losses every `stats_every`; a later frame stops at
/// its plateau, tested once per pass through its `views`.
fn frame_schedule(
    config: &TrainConfig,
    (canonical, learn_colour): (bool, bool),
    weights: &ImageWeights,
    views: usize,
) -> (Schedule, Plateau) {
    let (c, t) = (&config.canonical, &config.temporal);
    let iterations = if canonical { c.iterations } else { t.iterations };
    let schedule = Schedule {
        iterations,
        sh_ramp: canonical.then_some((config.sh_degree, config.sh_increase_every)),
        densify: canonical.then_some(DensifyWindow {
            from: c.densify_from,
            until: c.densify_until,
            every: c.densify_every,
        }),
        splat_weights: weights.gaussians,
        checkpoint: false,
        colour_refit: learn_colour.then_some(ColourRefit {
            from_iteration: config.camera_colour.from_iteration,
            ridge: config.camera_colour.ridge as f64,
        }),
    };
    let plateau = if canonical {
        Plateau::new(iterations, iterations, config.report.stats_every as usize, 0.0)
    } else {
        Plateau::new(t.min_iterations, iterations, views, t.tolerance)
    };
    (schedule, plateau)
}

/// A later frame's colour fit once its shape is found: `schedule.iterations` steps of the same
/// loss in which only the SH coefficients move.
fn fit_colours(
    trainer: &mut Trainer,
    stage: &mut FrameStage,
    schedule: &Schedule,
    settings: &mut RenderSettings,
    rng: &mut SplitMix64,
) -> Result<LoopOutcome, TrainError> {
    stage.colour_only = true;
    let (steps, views) = (schedule.iterations, trainer.views());
    optimize(trainer, stage, schedule, Plateau::new(steps, steps, views, 0.0), settings, rng)
}

/// The terms a frame adds to the splatting loss, on the GPU.
struct FrameTerms {
    mesh_term: MeshTerm,
    regs: Regularizers,
    /// The pose the temporal regularizers compare against (later frames).
    reference: Option<GaussianBuffers>,
    silhouette: Option<SilhouetteTerm>,
    coverage: Option<CoverageTerm>,
    /// The flow and anchor terms (later frames with either on).
    matches: MatchTerms,
}

/// A frame's part of the loop: the mesh, regularizer, silhouette and coverage terms, frame 0's
/// densification through the topology, and the report's losses.
struct FrameStage<'a, 'm> {
    config: &'a TrainConfig,
    extent: f64,
    /// The subject's size (its starting mesh's bounding-box diagonal), which scales the
    /// Laplacian.
    diagonal: f32,
    /// The render settings' near plane, which the silhouette and coverage terms share.
    near: f32,
    canonical: bool,
    /// The colour fit after a later frame's shape: only the SH coefficients move.
    colour_only: bool,
    weights: ImageWeights,
    terms: FrameTerms,
    mesh: &'m mut ManifoldMesh,
    /// The camera whose size turns the densification statistic into NDC units, and the most
    /// Gaussians densification may reach.
    densify_camera: (Camera, usize),
    report: &'a mut FrameReport,
    progress: &'a mut FrameProgress<'a>,
    /// The mean loss of the last statistics interval, for `progress`.
    loss: Option<f64>,
}

/// After every iteration of a frame: (iteration, of iterations) and the last statistics
/// interval's mean loss; `Break` cancels the frame ([`TrainError::Cancelled`]).
pub type FrameProgress<'a> = dyn FnMut((u32, u32), Option<f64>) -> ControlFlow<()> + 'a;

impl StepTerms for FrameStage<'_, '_> {
    fn record_step<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        view: usize,
        frame: &FrameParams,
        splat_weights: [f32; 4],
    ) -> Result<(), TrainError> {
        let (terms, config) = (&self.terms, self.config);
        let (camera, target) = (trainer.camera(view), trainer.target(view));
        let (params, grads) = (trainer.params(), trainer.grads());
        let weights = self.weights.of_view(view, splat_weights);
        terms.mesh_term.record_step_with(
            trainer,
            rec,
            (view, frame),
            weights,
            config.background,
        )?;
        rec.begin_pass("regularizers");
        let regularizers = config.loss.regularizers(trainer.gaussians(), self.diagonal);
        let reference = terms.reference.as_ref().map(Temporal::of);
        terms.regs.record(rec, params, grads, &regularizers, reference)?;
        let (t, near) = (&config.temporal, self.near);
        if let Some(s) = &terms.silhouette {
            s.record(rec, &params.positions, &grads.positions, t.silhouette, near)?;
        }
        if let Some(c) = &terms.coverage {
            let images = (target, trainer.rendered());
            c.record(rec, camera, images, &params.positions, &grads.positions, t.coverage, near)?;
        }
        terms.matches.record(rec, (&params.positions, &grads.positions), t, near)?;
        rec.end_pass();
        Ok(())
    }
}

impl Stage for FrameStage<'_, '_> {
    fn rates(&self, it: u32, iterations: u32) -> LearningRates {
        if !self.colour_only {
            return frame_rates(self.config, self.extent, it, iterations, self.canonical);
        }
        let rates = learning_rates(&self.config.learning_rates, self.extent, it, iterations);
        let scale = self.config.temporal.colour_lr_scale;
        LearningRates {
            positions: 0.0,
            log_scales: 0.0,
            rotations: 0.0,
            opacity_logits: 0.0,
            sh_dc: scale * rates.sh_dc,
            sh_rest: scale * rates.sh_rest,
        }
    }

    fn read_losses(
        &mut self,
        trainer: &Trainer,
        first: u32,
        last: u32,
    ) -> Result<Result<f64, String>, TrainError> {
        let mean = read_losses(trainer, &self.terms, &self.weights, (first, last), self.report)?;
        self.loss = mean.as_ref().ok().copied().or(self.loss);
        Ok(mean)
    }

    fn densify(
        &mut self,
        trainer: &mut Trainer,
        it: u32,
        _rng: &mut SplitMix64,
    ) -> Result<(), TrainError> {
        let terms = (&mut self.terms.mesh_term, &mut self.terms.regs);
        let (camera, budget) = self.densify_camera;
        let step = topology_step(trainer, terms, self.mesh, self.config, (&camera, budget), it)?;
        self.report.topology_steps.push(step);
        Ok(())
    }

    fn iteration_done(
        &mut self,
        _trainer: &mut Trainer,
        _settings: &RenderSettings,
        (it, iterations): (u32, u32),
        _train_s: f64,
    ) -> Result<(), TrainError> {
        match (self.progress)((it, iterations), self.loss) {
            ControlFlow::Continue(()) => Ok(()),
            ControlFlow::Break(()) => Err(TrainError::Cancelled),
        }
    }
}

/// Reads back the losses summed over iterations `first..=last` into the report (mean weighted
/// image terms, silhouette and coverage, unweighted regularizers) and returns their weighted
/// mean total, or the terms when one is not finite.
fn read_losses(
    trainer: &Trainer,
    terms: &FrameTerms,
    weights: &ImageWeights,
    (first, last): (u32, u32),
    report: &mut FrameReport,
) -> Result<Result<f64, String>, TrainError> {
    let steps = (last - first + 1) as f32;
    let (gs, mesh) = (
        trainer.take_terms()?.total(weights.gaussians) / steps,
        terms.mesh_term.take_terms()?.total(weights.mesh) / steps,
    );
    let sil = (terms.silhouette.as_ref().map(|s| s.take_loss()).transpose()?.unwrap_or(0.0)
        + terms.coverage.as_ref().map(|c| c.take_loss()).transpose()?.unwrap_or(0.0)
        + terms.matches.take_loss()?)
        / steps;
    let regularizers: Losses<f32> = terms.regs.read_losses()?;
    if !(gs.is_finite()
        && mesh.is_finite()
        && sil.is_finite()
        && regularizers.slots().iter().all(|v| v.is_finite()))
    {
        let slots = regularizers.slots();
        return Ok(Err(format!(
            "Gaussian {gs}, mesh {mesh}, silhouette {sil}, regularizers {slots:?}"
        )));
    }
    (report.loss_gs, report.loss_mesh, report.loss_silhouette, report.regularizers) =
        (gs, mesh, sil, regularizers.slots());
    Ok(Ok((gs + mesh + sil) as f64))
}

impl FrameReport {
    /// A frame that was not optimised: no training view shows the subject (`lost_views`).
    pub fn without_views(frame: usize, gaussians: usize, lost_views: Vec<String>) -> Self {
        Self { gaussians, lost_views, stop_reason: StopReason::NoViews, ..empty_report(frame) }
    }
}

fn empty_report(frame: usize) -> FrameReport {
    FrameReport {
        frame,
        iterations: 0,
        colour_iterations: 0,
        stop_reason: StopReason::MaxIterations,
        graph: None,
        correspondences: None,
        lost_views: Vec::new(),
        colour_left_out: Vec::new(),
        wall_s: 0.0,
        device_s: None,
        host_s: None,
        gaussians: 0,
        psnr_gs: 0.0,
        ssim_gs: 0.0,
        psnr_gs_affine: 0.0,
        psnr_gs_affine_masked: 0.0,
        psnr_mesh: 0.0,
        loss_gs: 0.0,
        loss_mesh: 0.0,
        loss_silhouette: 0.0,
        regularizers: [0.0; 6],
        passes_ms: BTreeMap::new(),
        topology_steps: Vec::new(),
        truncated_steps: 0,
        target_uploads: None,
        camera_colour: CameraMaps::new(),
    }
}

/// The learning rates of iteration `it`; later frames may keep their appearance.
fn frame_rates(
    config: &TrainConfig,
    extent: f64,
    it: u32,
    iterations: u32,
    canonical: bool,
) -> LearningRates {
    let scaled = crate::train::config::LearningRateConfig {
        positions: config.learning_rates.positions * config.position_lr_scale,
        positions_final: config.learning_rates.positions_final * config.position_lr_scale,
        ..config.learning_rates.clone()
    };
    let rates = learning_rates(&scaled, extent, it, iterations);
    if canonical || !config.temporal.freeze_appearance {
        return rates;
    }
    LearningRates { log_scales: 0.0, opacity_logits: 0.0, sh_dc: 0.0, sh_rest: 0.0, ..rates }
}

/// One densify-and-prune step through the topology; every per-Gaussian array follows the one
/// remap (parameters and optimizer moments in the trainer, the mesh, the 1-rings).
fn topology_step(
    trainer: &mut Trainer,
    (mesh_term, regs): (&mut MeshTerm, &mut Regularizers),
    mesh: &mut ManifoldMesh,
    config: &TrainConfig,
    (camera, budget): (&Camera, usize),
    it: u32,
) -> Result<(u32, usize, usize, usize), TrainError> {
    let c = &config.canonical;
    let mut scene = trainer.scene()?;
    mesh.positions = scene.positions.clone();
    // The statistic is in pixels; the threshold, as 3DGS's, in NDC units (a pixel is 2 / size).
    let ndc_scale = 0.5 * camera.width.max(camera.height) as f32;
    let vertex_scores: Vec<f32> = trainer
        .densify_stats()?
        .iter()
        .map(|&[sum, seen]| if seen > 0.0 { ndc_scale * sum / seen } else { 0.0 })
        .collect();
    let scores = face_scores(mesh, &vertex_scores);
    // Each split adds one Gaussian.
    let room = budget.saturating_sub(scene.len());
    let densified = densify(
        mesh,
        &mut scene,
        &scores,
        &DensifyConfig { threshold: c.densify_threshold, max_splits: room, ..Default::default() },
    )?;
    let pruned = prune(
        mesh,
        &mut scene,
        &PruneConfig {
            min_opacity: c.prune_opacity,
            max_scale: c.prune_scale,
            ..Default::default()
        },
    )?;
    trainer.replace(&scene, &compose(&densified.old_of_new, &pruned.old_of_new))?;
    mesh_term.set_mesh(&scene.positions, &mesh.live_faces())?;
    regs.upload(&Neighbourhoods::from_mesh(mesh))?;
    Ok((it, densified.split_faces, pruned.pruned, scene.len()))
}

/// The 1-rings the refinement's regularizers read, with the temporal terms' stiffness on later
/// frames (all 1 when `limb_thickness` is 0: `limb_stiffness` says so).
fn refinement_neighbourhoods(
    mesh: &ManifoldMesh,
    canonical: bool,
    t: &TemporalConfig,
) -> Result<Neighbourhoods, TrainError> {
    let nb = Neighbourhoods::from_mesh(mesh);
    if canonical {
        return Ok(nb);
    }
    Ok(Neighbourhoods { stiffness: limb_stiffness(mesh, t.limb_thickness as f64)?, ..nb })
}

/// Pixels the subject covers (mask > 0.5) in the median training view.
fn covered_pixels(views: &[ViewTarget]) -> usize {
    let mut counts: Vec<usize> =
        views.iter().map(|v| v.target.iter().filter(|p| p[3] > 0.5).count()).collect();
    counts.sort_unstable();
    counts.get(counts.len() / 2).copied().unwrap_or(0)
}

/// The evaluation views' mean scores, as [`FrameReport`] names them.
struct HeldOutScores {
    psnr_gs: f64,
    ssim_gs: f64,
    psnr_gs_affine: f64,
    psnr_gs_affine_masked: f64,
    psnr_mesh: f64,
}

/// Mean PSNR, SSIM and colour-corrected PSNR (as rendered, and through each view's mask) of
/// the Gaussian renders and PSNR of the mesh renders over `views`.
fn evaluate(
    trainer: &mut Trainer,
    mesh_term: &MeshTerm,
    views: &[ViewTarget],
    settings: &RenderSettings,
) -> Result<HeldOutScores, TrainError> {
    let (psnr_gs, ssim_gs, renders) = fit::evaluate(trainer, views, settings, false)?;
    let (mut affine, mut masked, mut mesh) = (0.0, 0.0, 0.0);
    for (render, v) in renders.iter().zip(views) {
        let rgb = v.rgb();
        affine += affine_corrected_psnr(&render.data, &rgb)?.min(100.0);
        let seen = through_mask(&render.data, &v.target, settings.background);
        masked += affine_corrected_psnr(&seen, &rgb)?.min(100.0);
        let mesh_render = mesh_term.render(trainer.params(), &v.camera, settings.background)?;
        mesh += psnr(&mesh_render, &rgb)?.min(100.0);
    }
    let n = views.len().max(1) as f64;
    let (psnr_gs_affine, psnr_gs_affine_masked, psnr_mesh) = (affine / n, masked / n, mesh / n);
    Ok(HeldOutScores { psnr_gs, ssim_gs, psnr_gs_affine, psnr_gs_affine_masked, psnr_mesh })
}

/// `rgb` (interleaved, one pixel per target pixel) blended over `background` by the target's
/// mask, as the target's own colours are.
fn through_mask(rgb: &[f32], target: &[[f32; 4]], background: [f32; 3]) -> Vec<f32> {
    let pixels = rgb.chunks_exact(3).zip(target);
    pixels
        .flat_map(|(c, t)| [0, 1, 2].map(|k| c[k] * t[3] + background[k] * (1.0 - t[3])))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::through_mask;

    #[test]
    fn a_render_seen_through_the_mask_blends_with_the_background_as_the_target() {
        let render = [0.8, 0.4, 0.2, 0.8, 0.4, 0.2];
        let target = [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.25]];
        let seen = through_mask(&render, &target, [0.0, 1.0, 0.0]);
        let expected = [0.8, 0.4, 0.2, 0.2, 0.85, 0.05];
        assert!(seen.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6), "{seen:?}");
    }
}
