//! The coarse stage of a later frame: the embedded deformation graph (`crate::deform`) solved
//! against the frame's image, mask, silhouette and coverage losses before any vertex moves
//! alone, level by level. A level renders the training views downsampled by its factor (coarse
//! to fine when configured, so a limb that moved many pixels is within reach of the loss);
//! every level stops at its plateau.

use super::camera_colour::{trainer_for, ColourUse};
use super::config::{ReferencePose, TrainConfig};
use super::frame::MatchTerms;
use crate::deform::{build_graph, fit_nodes, GraphDeformer};
use crate::gpu::{GpuContext, HostRing, Recorder};
use crate::loss::silhouette::{CoverageTerm, SilhouetteTerm};
use crate::mesh::bounding_diagonal;
use crate::optim::AdamParams;
use crate::regularize::Neighbourhoods;
use crate::rng::SplitMix64;
use crate::splat::{FrameParams, GaussianScene, RenderSettings};
use crate::train::in_flight::{StepRing, StepTerms};
use crate::train::mesh_term::MeshTerm;
use crate::train::optimize::non_finite_detail;
use crate::train::plateau::{Plateau, StopReason};
use crate::train::schedule::ViewCycle;
use crate::train::{TrainError, Trainer, ViewTarget};
use std::sync::Arc;
use std::time::Instant;

/// One level of the graph stage.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct LevelReport {
    /// Image downsampling factor.
    pub factor: u32,
    /// Graph nodes of the level.
    #[serde(default)]
    pub nodes: usize,
    /// Iterations run.
    pub iterations: u32,
    /// Why the level stopped.
    pub stop_reason: StopReason,
    /// Wall time of the level (its graph building included), seconds.
    pub wall_s: f64,
    /// Mean total loss over the level's last pass through the views.
    pub loss: f64,
}

/// What a later frame's graph stage reports.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct GraphReport {
    /// Nodes of the last level's graph.
    pub nodes: usize,
    /// Every level run, coarse first.
    pub levels: Vec<LevelReport>,
}

/// What the stage works on: the frame (for errors), its training views, where it starts (the extrapolated
/// previous frame), frame 0's surface, the topology, and the silhouette term of the training views.
pub struct GraphInput<'a> {
    pub frame: usize,
    pub train: &'a [ViewTarget],
    pub start: &'a GaussianScene,
    pub frame0: &'a GaussianScene,
    pub faces: &'a [[u32; 3]],
    pub neighbourhoods: &'a Neighbourhoods,
    pub silhouette: &'a SilhouetteTerm,
    /// The flow and anchor terms (empty when off).
    pub matches: &'a MatchTerms,
    /// The cameras' colour maps the renders are scored through.
    pub colour: ColourUse<'a>,
}

/// The loss weights of a step: λ per rgba channel of the Gaussian and mesh renders, and per
/// training view whether its colours are left out (a dark or saturated image,
/// [`ViewTarget::appearance_flaw`]).
#[derive(Clone)]
pub struct ImageWeights {
    pub gaussians: [f32; 4],
    pub mesh: [f32; 4],
    pub colourless: Arc<[bool]>,
}

impl ImageWeights {
    /// The Gaussian (`gaussians`, as the schedule gives them) and mesh weights of a step on
    /// training view `view`: where its colours are left out, their λ is 0 and the mask's stays.
    pub fn of_view(&self, view: usize, gaussians: [f32; 4]) -> [[f32; 4]; 2] {
        let colourless = self.colourless.get(view).copied().unwrap_or(false);
        let keep = |w: [f32; 4]| if colourless { [0.0, 0.0, 0.0, w[3]] } else { w };
        [keep(gaussians), keep(self.mesh)]
    }
}

/// Solves the graph level by level; returns the start moved by the graph (appearance
/// unchanged) and what each level did.
pub fn solve_graph(
    ctx: &Arc<GpuContext>,
    input: &GraphInput,
    config: &TrainConfig,
    weights: ImageWeights,
    settings: &RenderSettings,
    rng: &mut SplitMix64,
) -> Result<(GaussianScene, GraphReport), TrainError> {
    let g = &config.temporal.graph;
    let diagonal = bounding_diagonal(&input.start.positions) as f32;
    let mut report = GraphReport { nodes: 0, levels: Vec::new() };
    let mut moved = input.start.clone();
    // The graph in use and the node count it was built for.
    let mut built: Option<(usize, GraphDeformer)> = None;
    let mut adam_step = 0;
    for (level, &factor) in g.levels.iter().enumerate() {
        let t0 = Instant::now();
        let wanted = g.nodes_at(level) as usize;
        // A level with another node count starts its own graph on the pose reached so far.
        if built.as_ref().is_none_or(|(nodes, _)| *nodes != wanted) {
            built = Some((wanted, graph_on(ctx, input, &moved, wanted, config)?));
            adam_step = 0;
        }
        let (_, deformer) = built.as_mut().expect("a graph was built just above");
        report.nodes = deformer.nodes();
        let views: Vec<ViewTarget> = input.train.iter().map(|v| v.downsampled(factor)).collect();
        let mut trainer = trainer_for(ctx, &moved, &views, input.colour, settings.background)?;
        let (width, height) = (views[0].camera.width, views[0].camera.height);
        let mesh_term = MeshTerm::new(ctx, &moved.positions, input.faces, width, height)?;
        let coverage = CoverageTerm::new(
            ctx,
            moved.len(),
            (width * height) as usize,
            config.temporal.coverage_radius,
        )?;
        let mut rec = Recorder::new(ctx)?;
        deformer.record_blend(&mut rec, trainer.params())?;
        rec.submit_and_wait()?;

        let mut plateau =
            Plateau::new(g.min_iterations, g.iterations, views.len(), config.temporal.tolerance);
        let (mut cycle, mut pass_start) = (ViewCycle::default(), 1);
        deformer.reserve_step_slots(ctx.steps_in_flight())?;
        let mut ring = StepRing::new(&mut trainer, ctx.steps_in_flight())?;
        let deformer = &*deformer;
        let terms = GraphStep {
            input,
            config,
            deformer,
            mesh_term: &mesh_term,
            coverage: &coverage,
            weights: weights.clone(),
            settings,
        };
        let step = (&terms as &dyn StepTerms, weights.gaussians);
        for it in 1.. {
            let view = cycle.next(views.len(), rng);
            adam_step += 1;
            // Tenfold decay over the level's cap.
            let decay = 0.1f32.powf(it as f32 / g.iterations as f32);
            let rates = (g.translation_lr * diagonal * decay, g.rotation_lr * decay);
            let adam = deformer.adam_params(rates.0, rates.1, adam_step);
            ring.step(&mut trainer, step, view, settings, &adam)?;
            let pass_loss = if plateau.pass_ends(it) {
                ring.drain(&mut trainer)?;
                let terms = [
                    ("Gaussian image", trainer.take_terms()?.total(weights.gaussians)),
                    ("mesh image", mesh_term.take_terms()?.total(weights.mesh)),
                    ("silhouette", input.silhouette.take_loss()?),
                    ("coverage", coverage.take_loss()?),
                    ("flow and anchor", input.matches.take_loss()?),
                    ("ARAP", deformer.take_arap_loss()?),
                ];
                // The policy of every training loop: stop at the first non-finite pass and
                // say where, which terms, and which parameters.
                let bad: Vec<&str> =
                    terms.iter().filter(|(_, v)| !v.is_finite()).map(|(n, _)| *n).collect();
                if !bad.is_empty() {
                    let terms = format!("graph level {factor}: {}", bad.join(", "));
                    let detail = non_finite_detail(&trainer.scene()?, pass_start, it, &terms);
                    return Err(TrainError::NonFinite { frame: Some(input.frame), detail });
                }
                let total: f64 = terms.iter().map(|&(_, v)| v as f64).sum();
                let mean = total / (it + 1 - pass_start) as f64;
                pass_start = it + 1;
                Some(mean)
            } else {
                None
            };
            if let Some(stop_reason) = plateau.check(it, pass_loss) {
                let loss = pass_loss.unwrap_or(f64::NAN);
                report.levels.push(LevelReport {
                    factor,
                    nodes: deformer.nodes(),
                    iterations: it,
                    stop_reason,
                    wall_s: t0.elapsed().as_secs_f64(),
                    loss,
                });
                break;
            }
        }
        ring.drain(&mut trainer)?;
        moved = trainer.scene()?;
    }
    Ok((moved, report))
}

/// A step of the graph solve: the Gaussian and mesh image terms, silhouette, coverage, flow
/// and anchors on the blended Gaussians, their position gradients carried to the nodes; its
/// tail moves the nodes (Adam) and blends the Gaussians from them.
struct GraphStep<'a> {
    input: &'a GraphInput<'a>,
    config: &'a TrainConfig,
    deformer: &'a GraphDeformer,
    mesh_term: &'a MeshTerm,
    coverage: &'a CoverageTerm,
    weights: ImageWeights,
    settings: &'a RenderSettings,
}

impl StepTerms for GraphStep<'_> {
    fn record_step<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        view: usize,
        frame: &FrameParams,
        splat_weights: [f32; 4],
    ) -> Result<(), TrainError> {
        let (t, near) = (&self.config.temporal, self.settings.near);
        let (params, grads) = (trainer.params(), trainer.grads());
        let weights = self.weights.of_view(view, splat_weights);
        let background = self.settings.background;
        self.mesh_term.record_step_with(trainer, rec, (view, frame), weights, background)?;
        self.input.silhouette.record(
            rec,
            &params.positions,
            &grads.positions,
            t.silhouette,
            near,
        )?;
        let images = (trainer.target(view), trainer.rendered());
        let camera = trainer.camera(view);
        let positions = (&params.positions, &grads.positions);
        self.coverage.record(rec, camera, images, positions.0, positions.1, t.coverage, near)?;
        self.input.matches.record(rec, positions, t, near)?;
        Ok(self.deformer.record_gradients(rec, &grads.positions)?)
    }

    fn record_tail<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        counts: (&'a HostRing<u32>, usize),
    ) -> Result<(), TrainError> {
        self.deformer.record_adam_from(rec, counts.1)?;
        self.deformer.record_blend(rec, trainer.params())?;
        trainer.record_count_copy(rec, frame, counts);
        Ok(())
    }

    fn set_step(&self, _: &Trainer, slot: usize, adam: &AdamParams) {
        self.deformer.set_step(slot, adam);
    }
}

/// A graph of `nodes` nodes over the configured rest pose (`pose`, the surface reached so far,
/// or frame 0's), its nodes started where they carry the rest onto `pose`.
fn graph_on(
    ctx: &Arc<GpuContext>,
    input: &GraphInput,
    pose: &GaussianScene,
    nodes: usize,
    config: &TrainConfig,
) -> Result<GraphDeformer, TrainError> {
    let g = &config.temporal.graph;
    let rest = g.rest.pick(pose, input.frame0);
    let graph = build_graph(&rest.positions, |i| input.neighbourhoods.neighbours(i), nodes);
    let mut deformer = GraphDeformer::new(ctx, &graph, rest, g.arap)?;
    if g.rest == ReferencePose::Frame0 {
        deformer.write_nodes(&fit_nodes(&rest.positions, &pose.positions, &graph))?;
    }
    Ok(deformer)
}
