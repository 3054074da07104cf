//! `tagsplat fit`: plain 3DGS on one frame, the splatting loss alone with 3DGS densification,
//! run by the loop every stage shares (optimize.rs).

use super::config::{FitConfig, LearningRateConfig};
use super::densify::{densify_and_prune, DensifyRules};
use super::in_flight::StepTerms;
use super::optimize::{optimize, Schedule, Stage};
use super::plateau::Plateau;
use super::report::{CurvePoint, DensifyEvent, FitReport};
use super::schedule::DensifyWindow;
use super::step::Trainer;
use super::views::ViewTarget;
use super::TrainError;
use crate::camera::Camera;
use crate::eval::{psnr, ssim};
use crate::gpu::GpuContext;
use crate::io::image::Image;
use crate::optim::{exponential_decay, LearningRates};
use crate::rng::SplitMix64;
use crate::splat::{GaussianScene, RenderSettings};
use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

/// What the loop tells its caller after every iteration (the CLI draws a progress bar).
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// The iteration just finished, 1-based.
    pub iteration: u32,
    /// The run's iteration count.
    pub iterations: u32,
    /// The mean loss of the last statistics interval.
    pub loss: Option<f32>,
    /// Gaussians after the iteration (densification changes the count).
    pub gaussians: usize,
    /// Seconds of optimisation so far (densification included).
    pub elapsed_s: f64,
}

/// What [`fit`] returns.
pub struct FitOutcome {
    /// The final Gaussians, or the last ones with a finite loss when the run stopped early.
    pub scene: GaussianScene,
    /// The run's report.
    pub report: FitReport,
    /// Final renders of the evaluation views, by camera name.
    pub renders: Vec<(String, Image)>,
}

/// Fits `initial` to the `train` views of one frame, evaluating on `eval` (held-out views, or
/// the training views when the dataset has none: `eval_is_held_out` says which). `progress`
/// sees every iteration; answering `Break` ends the fit there with [`TrainError::Cancelled`].
pub fn fit(
    ctx: &Arc<GpuContext>,
    train: &[ViewTarget],
    eval: &[ViewTarget],
    eval_is_held_out: bool,
    initial: GaussianScene,
    config: &FitConfig,
    progress: &mut dyn FnMut(Progress) -> ControlFlow<()>,
) -> Result<FitOutcome, TrainError> {
    config.check()?;
    if train.is_empty() {
        return Err(TrainError::NoViews { frame: None, problem: "no training views" });
    }
    let started = Instant::now();
    let extent = scene_extent(&train.iter().map(|v| &v.camera).collect::<Vec<_>>());
    let mut settings = RenderSettings {
        background: config.background,
        near: (extent * 1e-3) as f32,
        far: (extent * 1e3) as f32,
        sh_degree: 0,
        mask_mode: false,
    };
    let mut trainer = Trainer::new(ctx, &initial, train)?;
    let (initial_psnr, _, _) = evaluate(
        &mut trainer,
        eval,
        &RenderSettings { sh_degree: config.sh_degree, ..settings },
        false,
    )?;
    let d = &config.densify;
    let schedule = Schedule {
        iterations: config.iterations,
        sh_ramp: Some((config.sh_degree, config.sh_increase_every)),
        densify: d.enabled.then_some(DensifyWindow {
            from: d.from,
            until: d.until,
            every: d.every,
        }),
        splat_weights: config.loss.channels(),
        checkpoint: true,
        colour_refit: None,
    };
    let stats_every = config.report.stats_every as usize;
    let plateau = Plateau::new(config.iterations, config.iterations, stats_every, 0.0);
    let mut stage = FitStage {
        config,
        extent,
        eval,
        densify_camera: train[0].camera,
        last_loss: None,
        loss_log: Vec::new(),
        curve: Vec::new(),
        densify_log: Vec::new(),
        progress,
    };
    let mut rng = SplitMix64::new(config.seed);
    let run = optimize(&mut trainer, &mut stage, &schedule, plateau, &mut settings, &mut rng)?;
    let stopped = run.non_finite.map(|detail| {
        format!("{detail}; the Gaussians of iteration {} are kept", run.checkpoint_iteration)
    });
    let FitStage { loss_log, curve, densify_log, .. } = stage;
    let (done, train_s, passes, truncated_steps) =
        (run.iterations, run.train_s, run.passes_ms, run.truncated_steps);
    let (targets_on_device, target_uploads) =
        (trainer.targets_on_device(), trainer.target_uploads());
    let (psnr, ssim, renders) = evaluate(&mut trainer, eval, &settings, stopped.is_some())?;
    let scene = if stopped.is_some() { trainer.last_good_scene()? } else { trainer.scene()? };
    let report = FitReport {
        device: ctx.info().name.clone(),
        frame: 0, // the caller knows which frame its views show
        iterations: done,
        gaussians: scene.len(),
        eval_views: if eval_is_held_out { "held-out" } else { "training" },
        initial_psnr,
        psnr,
        ssim,
        wall_s: started.elapsed().as_secs_f64(),
        train_wall_s: train_s,
        iterations_per_s: done as f64 / train_s.max(1e-9),
        passes_ms: passes,
        loss: loss_log,
        curve,
        densify: densify_log,
        truncated_steps,
        targets_on_device,
        target_uploads,
        stopped,
    };
    let names = eval.iter().map(|v| v.name.clone());
    Ok(FitOutcome { scene, report, renders: names.zip(renders).collect() })
}

/// `fit`'s part of the loop: the splatting loss alone, 3DGS densification, an evaluation curve.
struct FitStage<'a> {
    config: &'a FitConfig,
    extent: f64,
    eval: &'a [ViewTarget],
    densify_camera: Camera,
    last_loss: Option<f32>,
    loss_log: Vec<(u32, f32)>,
    curve: Vec<CurvePoint>,
    densify_log: Vec<DensifyEvent>,
    progress: &'a mut dyn FnMut(Progress) -> ControlFlow<()>,
}

impl StepTerms for FitStage<'_> {}

impl Stage for FitStage<'_> {
    fn rates(&self, it: u32, iterations: u32) -> LearningRates {
        learning_rates(&self.config.learning_rates, self.extent, it, iterations)
    }

    fn read_losses(
        &mut self,
        trainer: &Trainer,
        first: u32,
        last: u32,
    ) -> Result<Result<f64, String>, TrainError> {
        let terms = trainer.take_terms()?;
        let mean = terms.total(self.config.loss.channels()) / (last - first + 1) as f32;
        if !mean.is_finite() {
            return Ok(Err(format!("L1 terms {:?}, SSIM terms {:?}", terms.l1, terms.dssim)));
        }
        self.last_loss = Some(mean);
        self.loss_log.push((last, mean));
        Ok(Ok(mean as f64))
    }

    fn densify(
        &mut self,
        trainer: &mut Trainer,
        it: u32,
        rng: &mut SplitMix64,
    ) -> Result<(), TrainError> {
        let event = densify(trainer, self.config, self.extent, &self.densify_camera, it, rng)?;
        self.densify_log.push(event);
        Ok(())
    }

    fn evaluates_after(&self, it: u32, iterations: u32) -> bool {
        it.is_multiple_of(self.config.report.eval_every) || it == iterations
    }

    fn iteration_done(
        &mut self,
        trainer: &mut Trainer,
        settings: &RenderSettings,
        (it, iterations): (u32, u32),
        train_s: f64,
    ) -> Result<(), TrainError> {
        if self.evaluates_after(it, iterations) {
            let (psnr, ssim, _) = evaluate(trainer, self.eval, settings, false)?;
            let gaussians = trainer.gaussians();
            self.curve.push(CurvePoint { iteration: it, wall_s: train_s, psnr, ssim, gaussians });
        }
        let report = Progress {
            iteration: it,
            iterations,
            loss: self.last_loss,
            gaussians: trainer.gaussians(),
            elapsed_s: train_s,
        };
        match (self.progress)(report) {
            ControlFlow::Continue(()) => Ok(()),
            ControlFlow::Break(()) => Err(TrainError::Cancelled),
        }
    }
}

/// One 3DGS densification step on the trainer's Gaussians.
fn densify(
    trainer: &mut Trainer,
    config: &FitConfig,
    extent: f64,
    camera: &Camera,
    it: u32,
    rng: &mut SplitMix64,
) -> Result<DensifyEvent, TrainError> {
    let d = &config.densify;
    // The statistic is in pixels; 3DGS's threshold is in NDC units (a pixel is 2 / size).
    let ndc_scale = 0.5 * camera.width.max(camera.height) as f32;
    let rules = DensifyRules {
        grad_threshold: d.grad_threshold,
        clone_max_scale: d.percent_dense * extent as f32,
        prune_opacity: d.prune_opacity,
        prune_max_scale: d.prune_scale * extent as f32,
        budget: d.budget as usize,
    };
    let mean_grads: Vec<f32> =
        trainer.densify_stats()?.iter().map(|&[sum, seen]| ndc_scale * sum / seen).collect();
    let (scene, old_of_new, counts) =
        densify_and_prune(&trainer.scene()?, &mean_grads, &rules, rng);
    trainer.replace(&scene, &old_of_new)?;
    Ok(DensifyEvent { iteration: it, counts, gaussians: scene.len() })
}

/// The learning rates of iteration `it` of `iterations`: positions scaled by the extent and
/// decaying.
pub(crate) fn learning_rates(
    r: &LearningRateConfig,
    extent: f64,
    it: u32,
    iterations: u32,
) -> LearningRates {
    let positions = exponential_decay(
        r.positions as f64 * extent,
        r.positions_final as f64 * extent,
        it as u64,
        iterations as u64,
    );
    LearningRates {
        positions: positions as f32,
        log_scales: r.log_scales,
        rotations: r.rotations,
        opacity_logits: r.opacity_logits,
        sh_dc: r.sh_dc,
        sh_rest: r.sh_rest,
    }
}

/// 3DGS's scene extent: 1.1 × the largest distance of a camera from the cameras' mean.
pub(crate) fn scene_extent(cameras: &[&Camera]) -> f64 {
    let mean =
        cameras.iter().map(|c| c.center()).sum::<glam::DVec3>() / cameras.len().max(1) as f64;
    let radius = cameras.iter().map(|c| c.center().distance(mean)).fold(0.0, f64::max);
    // One camera (or cameras at one point) still needs a scale: its distance to nothing is 0.
    1.1 * if radius > 0.0 { radius } else { 1.0 }
}

/// Mean PSNR and SSIM over `views` (RGB), and each view's render.
pub(crate) fn evaluate(
    trainer: &mut Trainer,
    views: &[ViewTarget],
    settings: &RenderSettings,
    last_good: bool,
) -> Result<(f64, f64, Vec<Image>), TrainError> {
    let (mut psnr_sum, mut ssim_sum, mut renders) = (0.0, 0.0, Vec::new());
    for v in views {
        let render = trainer.render(&v.camera, settings, last_good)?;
        let target = v.rgb();
        psnr_sum += psnr(&render, &target)?.min(100.0);
        ssim_sum += ssim(&render, &target, v.camera.width as usize, v.camera.height as usize, 3)?;
        renders.push(Image {
            width: v.camera.width,
            height: v.camera.height,
            channels: 3,
            data: render,
        });
    }
    let n = views.len().max(1) as f64;
    Ok((psnr_sum / n, ssim_sum / n, renders))
}
