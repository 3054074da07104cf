//! The optimisation loop that `fit` and every frame of `train` run: one training view per
//! iteration (each view once per pass, in a seeded order), the SH degree ramp, Adam with the
//! stage's learning rates, the losses read at the end of every statistics interval, the
//! densification window and the stop test. What differs between the stages (terms beyond the
//! splatting loss, how their losses are read, how the Gaussians densify, what is measured along
//! the way) is a [`Stage`].
//!
//! One non-finite policy for every stage: at the first statistics interval whose loss is not
//! finite the loop stops, and the outcome names the iterations, the terms and the non-finite
//! parameter groups. A stage that keeps the last good Gaussians (`fit`) asks for checkpoints:
//! after every finite interval whose Gaussians are all finite (the interval's loss saw them
//! before its last Adam step, not after) the trainer copies them. `train` fails the frame
//! instead and keeps the finished ones, so it takes no checkpoints.
//! (The deformation graph solves other parameters, node rotations and translations, with its
//! own optimiser in pipeline/graph_stage.rs and keeps its own loop; it follows the same
//! non-finite policy with [`non_finite_detail`], without checkpoints, as `train` does.)

use super::in_flight::{StepRing, StepTerms};
use super::plateau::{Plateau, StopReason};
use super::schedule::{sh_degree_at, DensifyWindow, ViewCycle};
use super::{TrainError, Trainer};
use crate::gpu::PassTimes;
use crate::optim::{AdamParams, LearningRates};
use crate::rng::SplitMix64;
use crate::splat::{GaussianScene, RenderSettings};
use std::collections::BTreeMap;
use std::time::Instant;

/// The iteration plan shared by every stage.
pub(crate) struct Schedule {
    /// Iterations at most.
    pub iterations: u32,
    /// Highest SH degree and the iterations between rises; `None` keeps the settings' degree.
    pub sh_ramp: Option<(u32, u32)>,
    /// When densification runs; `None`: never.
    pub densify: Option<DensifyWindow>,
    /// Weights of the splatting loss per rgba channel.
    pub splat_weights: [f32; 4],
    /// Whether the trainer checkpoints the last finite Gaussians (see the module docs).
    pub checkpoint: bool,
    /// When the cameras' colour maps are refitted (trainers that learn camera colour).
    pub colour_refit: Option<ColourRefit>,
}

/// Refits of the cameras' colour maps: at the end of every statistics interval from
/// `from_iteration` on (the moments of earlier intervals are dropped), pulled toward the
/// identity by `ridge` ([`Trainer::refit_camera_colour`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ColourRefit {
    pub from_iteration: u32,
    pub ridge: f64,
}

/// What a stage adds to the loop (beyond the terms of its steps).
pub(crate) trait Stage: StepTerms {
    /// The learning rates of iteration `it` of `iterations`.
    fn rates(&self, it: u32, iterations: u32) -> LearningRates;

    /// The mean weighted loss over iterations `first..=last` (all summed on the GPU since the
    /// last call, which restarts the sums), or what went non-finite.
    fn read_losses(
        &mut self,
        trainer: &Trainer,
        first: u32,
        last: u32,
    ) -> Result<Result<f64, String>, TrainError>;

    /// One densification step after iteration `it`.
    fn densify(
        &mut self,
        trainer: &mut Trainer,
        it: u32,
        rng: &mut SplitMix64,
    ) -> Result<(), TrainError>;

    /// Whether [`Self::iteration_done`] after iteration `it` of `iterations` uses the GPU (an
    /// evaluation): the loop first finishes every step in flight. None by default.
    fn evaluates_after(&self, _it: u32, _iterations: u32) -> bool {
        false
    }

    /// After every iteration (and its densification): evaluation curves, progress.
    /// `progress` is (iteration, of iterations). It may use the GPU only where
    /// [`Self::evaluates_after`] says so.
    fn iteration_done(
        &mut self,
        trainer: &mut Trainer,
        settings: &RenderSettings,
        progress: (u32, u32),
        train_s: f64,
    ) -> Result<(), TrainError>;
}

/// How the loop ended.
pub(crate) struct LoopOutcome {
    /// Iterations run.
    pub iterations: u32,
    /// Why it stopped (a non-finite loss stops it too: see `non_finite`).
    pub stop_reason: StopReason,
    /// What went non-finite, and where; the trainer's checkpoint holds the last finite state.
    pub non_finite: Option<String>,
    /// The iteration the checkpoint holds (0: the starting Gaussians).
    pub checkpoint_iteration: u32,
    /// Optimisation wall time (densification included), seconds.
    pub train_s: f64,
    /// Mean GPU ms per iteration, by pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// Iterations whose intersections outgrew the splatter's buffers.
    pub truncated_steps: u32,
}

/// Runs `stage` on `trainer` until `plateau` stops it, the schedule's cap, or a non-finite loss.
pub(crate) fn optimize(
    trainer: &mut Trainer,
    stage: &mut dyn Stage,
    schedule: &Schedule,
    mut plateau: Plateau,
    settings: &mut RenderSettings,
    rng: &mut SplitMix64,
) -> Result<LoopOutcome, TrainError> {
    let mut outcome = LoopOutcome {
        iterations: 0,
        stop_reason: StopReason::MaxIterations,
        non_finite: None,
        checkpoint_iteration: 0,
        train_s: 0.0,
        passes_ms: BTreeMap::new(),
        truncated_steps: 0,
    };
    let (iterations, mut views, mut interval_start) =
        (schedule.iterations, ViewCycle::default(), 1);
    let mut ring = StepRing::new(trainer, trainer.context().steps_in_flight())?;
    for it in 1..=iterations {
        let t0 = Instant::now();
        let view = views.next(trainer.views(), rng);
        if let Some((max, every)) = schedule.sh_ramp {
            settings.sh_degree = sh_degree_at(max, every, it);
        }
        let rates = stage.rates(it, iterations);
        let adam = AdamParams::new(&rates, it, trainer.gaussians(), trainer.sh_degree());
        let terms: (&dyn StepTerms, _) = (&*stage, schedule.splat_weights);
        let mut finished = ring.step(trainer, terms, view, settings, &adam)?;
        let pass_ends = plateau.pass_ends(it);
        let densify = schedule.densify.is_some_and(|window| window.due(it, iterations));
        // The host reads or changes the trainer's buffers after this iteration: finish all.
        if pass_ends || densify || stage.evaluates_after(it, iterations) || it == iterations {
            finished.extend(ring.drain(trainer)?);
        }
        for step in finished {
            add_times(&mut outcome.passes_ms, &step.times);
            outcome.truncated_steps += !step.complete as u32;
        }
        outcome.train_s += t0.elapsed().as_secs_f64();
        outcome.iterations = it;

        let mut pass_loss = None;
        if pass_ends {
            match stage.read_losses(trainer, interval_start, it)? {
                Ok(mean) => pass_loss = Some(mean),
                Err(terms) => {
                    let detail = non_finite_detail(&trainer.scene()?, interval_start, it, &terms);
                    outcome.non_finite = Some(detail);
                    break;
                }
            }
            if let Some(refit) = schedule.colour_refit {
                trainer.refit_camera_colour((it >= refit.from_iteration).then_some(refit.ridge))?;
            }
            if schedule.checkpoint && all_finite(&trainer.scene()?) {
                trainer.checkpoint()?;
                outcome.checkpoint_iteration = it;
            }
            interval_start = it + 1;
        }
        if densify {
            let t0 = Instant::now();
            stage.densify(trainer, it, rng)?;
            outcome.train_s += t0.elapsed().as_secs_f64();
        }
        stage.iteration_done(trainer, settings, (it, iterations), outcome.train_s)?;
        if let Some(reason) = plateau.check(it, pass_loss) {
            outcome.stop_reason = reason;
            break;
        }
    }
    for ms in outcome.passes_ms.values_mut() {
        *ms /= outcome.iterations.max(1) as f64;
    }
    Ok(outcome)
}

/// Per parameter group, its name and how many of its values are not finite.
fn non_finite_counts(scene: &GaussianScene) -> [(&'static str, usize); 5] {
    let bad = |values: &mut dyn Iterator<Item = f32>| values.filter(|v| !v.is_finite()).count();
    [
        ("positions", bad(&mut scene.positions.iter().flatten().copied())),
        ("log-scales", bad(&mut scene.log_scales.iter().flatten().copied())),
        ("rotations", bad(&mut scene.rotations.iter().flatten().copied())),
        ("opacity logits", bad(&mut scene.opacity_logits.iter().copied())),
        ("SH", bad(&mut scene.sh.iter().copied())),
    ]
}

fn all_finite(scene: &GaussianScene) -> bool {
    non_finite_counts(scene).iter().all(|&(_, n)| n == 0)
}

/// Names the iterations, the terms, and any parameter group that went non-finite.
pub(crate) fn non_finite_detail(
    scene: &GaussianScene,
    first: u32,
    last: u32,
    terms: &str,
) -> String {
    let groups = non_finite_counts(scene);
    let params: Vec<String> =
        groups.iter().filter(|(_, n)| *n > 0).map(|(g, n)| format!("{n} {g} values")).collect();
    let which = if params.is_empty() { "no parameter yet".to_string() } else { params.join(", ") };
    format!(
        "the loss went non-finite between iterations {first} and {last} ({terms}; non-finite parameters: {which})"
    )
}

/// Adds the GPU ms of each top-level pass of one submission to `total`.
fn add_times(total: &mut BTreeMap<String, f64>, times: &PassTimes) {
    for pass in times.passes.iter().filter(|p| p.depth == 0) {
        *total.entry(pass.name.clone()).or_default() += pass.ms;
    }
}
