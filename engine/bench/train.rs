//! `tagsplat bench train`: full training iterations (forward, fused loss, backward, fused
//! Adam) on the splatting bench's scene, against the splatting forward + backward alone
//! measured in the same run (the floor the loss and optimizer add to).

use super::splat::{bench_splat, random_scene, ring_cameras, SplatBenchConfig};
use crate::gpu::{ClockReading, GpuBuffer, GpuContext, Recorder};
use crate::loss::{ImageLoss, LossTarget, LossTerms, ScoredRender};
use crate::optim::{AdamParams, LearningRates};
use crate::splat::{GaussianBuffers, RenderSettings, Splatter};
use crate::train::in_flight::{Finished, StepRing, StepTerms};
use crate::train::{TrainError, Trainer, ViewTarget};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

/// What the training benchmark runs.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct TrainBenchConfig {
    /// Scene, cameras and frame size (as the splatting benchmark's; its `rounds` is unused).
    pub scene: SplatBenchConfig,
    /// Timed iterations, after one warm-up round over the views.
    pub iterations: usize,
    /// Training steps on the queue at once (`GpuContext::steps_in_flight`).
    pub in_flight: usize,
}

impl TrainBenchConfig {
    /// The defaults with the steps in flight `train` uses on `ctx`.
    pub fn for_device(ctx: &GpuContext) -> Self {
        Self {
            scene: SplatBenchConfig::default(),
            iterations: 24,
            in_flight: ctx.steps_in_flight(),
        }
    }
}

/// Timings of [`bench_train`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct TrainBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// The configuration that ran.
    pub config: TrainBenchConfig,
    /// Wall seconds of one full iteration: the timed iterations' wall time over their number
    /// (with steps in flight, one iteration's own wall time means nothing).
    pub s_per_iter: f64,
    /// Iterations per second (1 / s_per_iter; 0 when that is 0).
    pub iters_per_s: f64,
    /// Median GPU ms per iteration of each top-level pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// Median wall seconds of splatting forward + backward alone, same scene, same run.
    pub splat_fwd_bwd_s: f64,
    /// What loss, optimizer and step overhead add: 1 − splat_fwd_bwd_s / s_per_iter.
    pub overhead_fraction: f64,
    /// Median GPU ms over 4 × `iterations` runs of the image loss (L1 + SSIM, forward and
    /// backward) alone on one view, scoring one render, and two renders against the same target
    /// in one run (a view's Gaussian and mesh renders, as `train` does), same run.
    pub loss_ms: [f64; 2],
    /// Where the timed iterations' wall time went, summed over them: submissions, recording,
    /// waiting and device time ([`ClockReading`]).
    pub clock: ClockReading,
    /// Wall ms per iteration the device was not running a submission (recording, submitting,
    /// waiting to wake up, reading back, the host's own work): mean over the timed iterations.
    pub host_ms_per_iter: f64,
    /// That time's share of the iterations' wall time (None where submissions go untimed).
    pub host_fraction: Option<f64>,
    /// Views whose targets the timed trainer kept on the device (all unless the device's
    /// memory, or `--device-memory`, could not hold them).
    pub targets_on_device: usize,
    /// Wall seconds of one iteration, the same steps, with only two targets on the device
    /// (`train::targets`): seven steps of every eight upload their view's target first.
    pub streamed_s_per_iter: f64,
}

/// Learning rates of the fit's defaults (their values do not change the work).
const RATES: LearningRates = LearningRates {
    positions: 1.6e-4,
    log_scales: 5e-3,
    rotations: 1e-3,
    opacity_logits: 0.05,
    sh_dc: 2.5e-3,
    sh_rest: 1.25e-4,
};

/// Trains [`random_scene`] against renders of another random scene for one warm-up round
/// over the views plus `iterations` timed steps, replayed as `train` replays them with
/// `in_flight` steps on the queue, then runs [`bench_splat`] (2 rounds) on the same scene
/// for the floor. Fails when a render, the trainer or a step fails.
pub fn bench_train(
    ctx: &Arc<GpuContext>,
    config: &TrainBenchConfig,
) -> Result<TrainBenchReport, TrainError> {
    let c = &config.scene;
    let scene = random_scene(c.gaussians, c.sh_degree, 0x5EED);
    let settings = RenderSettings { sh_degree: c.sh_degree, ..Default::default() };
    // Targets: another scene of the same kind, so the loss and its gradients are realistic.
    let other = GaussianBuffers::from_scene(ctx, &random_scene(c.gaussians, c.sh_degree, 0xF00D))?;
    let mut splatter = Splatter::new(ctx)?;
    let mut views = Vec::new();
    for (i, camera) in ring_cameras(c.views, c.width, c.height).into_iter().enumerate() {
        splatter.forward(&other, &camera, &settings)?;
        let target = Arc::new(splatter.read_rgba()?);
        views.push(ViewTarget { name: format!("ring{i}"), camera, target });
    }
    drop(splatter);
    let trainer = Trainer::new(ctx, &scene, &views)?;
    let targets_on_device = trainer.targets_on_device();
    let (wall_s, clock, finished) = time_steps(trainer, &views, config, &settings)?;
    // Two targets on the device: the views come round in order, so seven steps of eight upload
    // one (the view kept gets one hit a round).
    let streamed = Trainer::with_targets_on_device(ctx, &scene, &views, STREAMED_ON_DEVICE)?;
    let streamed_wall_s = time_steps(streamed, &views, config, &settings)?.0;
    let iterations = config.iterations.max(1) as f64;
    let host_ms_per_iter = (wall_s - clock.device_s) * 1e3 / iterations;
    let host_fraction = clock.host_share(wall_s);
    let passes: Vec<_> = finished
        .iter()
        .map(|f| super::splat::top_level_ms(std::slice::from_ref(&f.times)))
        .collect();
    let passes_ms = super::median_per_pass(&passes);
    let s_per_iter = wall_s / iterations;
    // A loss run is about a tenth of an iteration: four per iteration steadies the median.
    let loss_ms = [
        bench_loss(ctx, &views, 1, 4 * config.iterations)?,
        bench_loss(ctx, &views, 2, 4 * config.iterations)?,
    ];
    let splat = bench_splat(ctx, &SplatBenchConfig { rounds: 2, ..*c })?;
    Ok(TrainBenchReport {
        device: ctx.info().name.clone(),
        config: *config,
        s_per_iter,
        iters_per_s: if s_per_iter > 0.0 { 1.0 / s_per_iter } else { 0.0 },
        passes_ms,
        splat_fwd_bwd_s: splat.fwd_bwd_s,
        overhead_fraction: if s_per_iter > 0.0 { 1.0 - splat.fwd_bwd_s / s_per_iter } else { 0.0 },
        loss_ms,
        clock,
        host_ms_per_iter,
        host_fraction,
        targets_on_device,
        streamed_s_per_iter: streamed_wall_s / iterations,
    })
}

/// Targets on the device in the streamed run of [`bench_train`].
const STREAMED_ON_DEVICE: usize = 2;

/// Runs `trainer` over `views` (one warm-up round, then `config.iterations` timed steps, the
/// views in turn) and returns the timed steps' wall seconds, clock and finished steps.
fn time_steps(
    mut trainer: Trainer,
    views: &[ViewTarget],
    config: &TrainBenchConfig,
    settings: &RenderSettings,
) -> Result<(f64, ClockReading, Vec<Finished>), TrainError> {
    let ctx = trainer.context().clone();
    let mut ring = StepRing::new(&mut trainer, config.in_flight)?;
    let step = |ring: &mut StepRing, trainer: &mut Trainer, it: usize| {
        let adam = AdamParams::new(&RATES, it as u32 + 1, trainer.gaussians(), trainer.sh_degree());
        ring.step(trainer, (&BenchStage, WEIGHTS), it % views.len(), settings, &adam)
    };
    for it in 0..views.len() {
        step(&mut ring, &mut trainer, it)?;
    }
    ring.drain(&mut trainer)?;
    let (start, before) = (Instant::now(), ctx.clock());
    let mut finished = Vec::new();
    for it in views.len()..views.len() + config.iterations {
        finished.extend(step(&mut ring, &mut trainer, it)?);
    }
    finished.extend(ring.drain(&mut trainer)?);
    Ok((start.elapsed().as_secs_f64(), ctx.clock().since(&before), finished))
}

/// The channel weights of the fit's defaults.
const WEIGHTS: [f32; 4] = [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 3.0];

/// The splatting loss alone, then Adam: a fit's step without densification.
struct BenchStage;

impl StepTerms for BenchStage {}

/// Median GPU ms over `runs` of the image loss scoring `renders` renders (the next views'
/// targets, so the images are realistic) against the first view's target.
fn bench_loss(
    ctx: &Arc<GpuContext>,
    views: &[ViewTarget],
    renders: usize,
    runs: usize,
) -> Result<f64, TrainError> {
    let pixels = views[0].target.len();
    let upload = |v: &ViewTarget| GpuBuffer::from_slice(ctx, &v.name, &v.target);
    let target = upload(&views[0])?;
    let images: Vec<_> =
        (1..=renders).map(|i| upload(&views[i % views.len()])).collect::<Result<_, _>>()?;
    let sums: Vec<_> =
        images.iter().map(|_| LossTerms::sums(ctx, "terms")).collect::<Result<_, _>>()?;
    let gradients: Vec<_> = images
        .iter()
        .map(|_| GpuBuffer::<[f32; 4]>::new(ctx, "gradient", pixels))
        .collect::<Result<_, _>>()?;
    let scored: Vec<_> = (0..renders)
        .map(|i| ScoredRender {
            image: &images[i],
            channel_weights: [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 3.0],
            terms: &sums[i],
            gradient: &gradients[i],
        })
        .collect();
    let (width, height) = (views[0].camera.width, views[0].camera.height);
    let target = LossTarget { width, height, image: &target, weight: None };
    let mut loss = ImageLoss::new(ctx, renders)?;
    loss.reserve(pixels)?;
    let mut times = Vec::new();
    for _ in 0..runs.max(1) + 1 {
        let mut rec = Recorder::new(ctx)?;
        rec.begin_pass("loss");
        loss.record(&mut rec, &target, &scored)?;
        rec.end_pass();
        times.push(super::splat::top_level_ms(&[rec.submit_and_wait()?])["loss"]);
    }
    // The first run warms up (pipeline compile, first touch of the scratch).
    Ok(super::median(times[1..].to_vec()))
}
