//! The single-frame fit loop.

use super::config::{FitConfig, LearningRateConfig};
use super::densify::{densify_and_prune, DensifyRules};
use super::report::{CurvePoint, DensifyEvent, FitReport};
use super::schedule::{channel_weights, sh_degree_at, DensifyWindow, ViewCycle};
use super::step::Trainer;
use super::views::ViewTarget;
use super::TrainError;
use crate::camera::Camera;
use crate::eval::{psnr, ssim};
use crate::gpu::{GpuContext, PassTimes};
use crate::io::image::Image;
use crate::loss::LossTerms;
use crate::optim::{exponential_decay, AdamParams, LearningRates};
use crate::rng::SplitMix64;
use crate::splat::{GaussianScene, RenderSettings};
use std::collections::BTreeMap;
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
/// the training views when the dataset has none: `eval_is_held_out` says which).
pub fn fit(
    ctx: &Arc<GpuContext>,
    train: &[ViewTarget],
    eval: &[ViewTarget],
    eval_is_held_out: bool,
    initial: GaussianScene,
    config: &FitConfig,
    progress: &mut dyn FnMut(Progress),
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
    let lambda = channel_weights(config.loss.color, config.loss.mask);
    let mut rng = SplitMix64::new(config.seed);
    let mut views = ViewCycle::default();
    let mut passes: BTreeMap<String, f64> = BTreeMap::new();
    let (mut train_s, mut loss_log, mut curve, mut densify_log) =
        (0.0, Vec::new(), Vec::new(), Vec::new());
    let (mut last_loss, mut stopped, mut interval_start, mut done, mut truncated_steps) =
        (None, None, 1, 0, 0);
    for it in 1..=config.iterations {
        let step_start = Instant::now();
        let view = views.next(train.len(), &mut rng);
        settings.sh_degree = sh_degree_at(config.sh_degree, config.sh_increase_every, it);
        let adam = AdamParams::new(
            &learning_rates(&config.learning_rates, extent, it, config.iterations),
            it,
            trainer.gaussians(),
            trainer.sh_degree(),
        );
        let (times, complete) = trainer.step(view, &settings, lambda, &adam)?;
        add_times(&mut passes, &times);
        truncated_steps += (!complete) as u32;
        train_s += step_start.elapsed().as_secs_f64();
        done = it;

        if it % config.report.stats_every == 0 || it == config.iterations {
            let terms = trainer.take_terms()?;
            let mean = terms.total(lambda) / (it - interval_start + 1) as f32;
            if !mean.is_finite() {
                stopped = Some(non_finite_message(&trainer.scene()?, interval_start, it, &terms));
                break;
            }
            trainer.checkpoint()?;
            (last_loss, interval_start) = (Some(mean), it + 1);
            loss_log.push((it, mean));
        }
        let d = &config.densify;
        let window = DensifyWindow { from: d.from, until: d.until, every: d.every };
        if d.enabled && window.due(it, config.iterations) {
            let t = Instant::now();
            densify_log.push(densify(
                &mut trainer,
                config,
                extent,
                &train[0].camera,
                it,
                &mut rng,
            )?);
            train_s += t.elapsed().as_secs_f64();
        }
        if it % config.report.eval_every == 0 || it == config.iterations {
            let (psnr, ssim, _) = evaluate(&mut trainer, eval, &settings, false)?;
            curve.push(CurvePoint {
                iteration: it,
                wall_s: train_s,
                psnr,
                ssim,
                gaussians: trainer.gaussians(),
            });
        }
        progress(Progress {
            iteration: it,
            iterations: config.iterations,
            loss: last_loss,
            gaussians: trainer.gaussians(),
        });
    }

    let (psnr, ssim, renders) = evaluate(&mut trainer, eval, &settings, stopped.is_some())?;
    let scene = if stopped.is_some() { trainer.last_good_scene()? } else { trainer.scene()? };
    for ms in passes.values_mut() {
        *ms /= done.max(1) as f64;
    }
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
        stopped,
    };
    let names = eval.iter().map(|v| v.name.clone());
    Ok(FitOutcome { scene, report, renders: names.zip(renders).collect() })
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

pub(crate) fn add_times(total: &mut BTreeMap<String, f64>, times: &PassTimes) {
    for pass in times.passes.iter().filter(|p| p.depth == 0) {
        *total.entry(pass.name.clone()).or_default() += pass.ms;
    }
}

/// Names the iterations and what went non-finite: the loss terms, and any parameter group.
fn non_finite_message(scene: &GaussianScene, first: u32, last: u32, terms: &LossTerms) -> String {
    let bad = |values: &mut dyn Iterator<Item = f32>| values.filter(|v| !v.is_finite()).count();
    let groups = [
        ("positions", bad(&mut scene.positions.iter().flatten().copied())),
        ("log-scales", bad(&mut scene.log_scales.iter().flatten().copied())),
        ("rotations", bad(&mut scene.rotations.iter().flatten().copied())),
        ("opacity logits", bad(&mut scene.opacity_logits.iter().copied())),
        ("SH", bad(&mut scene.sh.iter().copied())),
    ];
    let params: Vec<String> =
        groups.iter().filter(|(_, n)| *n > 0).map(|(g, n)| format!("{n} {g} values")).collect();
    let which = if params.is_empty() { "no parameter yet".to_string() } else { params.join(", ") };
    format!(
        "the loss went non-finite between iterations {first} and {last} (L1 terms {:?}, SSIM terms {:?}; non-finite parameters: {which}); the Gaussians of iteration {} are kept",
        terms.l1,
        terms.dssim,
        first - 1
    )
}
