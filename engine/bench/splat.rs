//! `tagsplat bench splat`: forward and backward of the splatting renderer on a deterministic
//! scene (the issue's: 8 cameras on a ring, 256², 20 000 Gaussians in a unit ball, SH degree 3),
//! wall time per view and the GPU time of every pass, and the rasterize backward against two
//! measures of its work: the bytes it must move at the copy bandwidth of the same run, and the
//! pixel–Gaussian pairs it walks.

use super::copy::{measure_copy, CopyBandwidth};
use crate::camera::Camera;
use crate::gpu::{GpuBuffer, GpuContext, PassTimes, Recorder};
use crate::rng::SplitMix64;
use crate::splat::{
    sh_coefficients, GaussianBuffers, GaussianScene, RenderSettings, Splat, SplatError, Splatter,
    GRAD2D_STRIDE,
};
use glam::DVec3;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

/// What the benchmark renders.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct SplatBenchConfig {
    /// Gaussians of the [`random_scene`].
    pub gaussians: usize,
    /// Number of [`ring_cameras`].
    pub views: usize,
    /// Width of every view, pixels.
    pub width: u32,
    /// Height of every view, pixels.
    pub height: u32,
    /// Spherical-harmonics degree of the scene and the render.
    pub sh_degree: u32,
    /// Passes over all views; the first is a warm-up and not timed.
    pub rounds: usize,
}

impl Default for SplatBenchConfig {
    fn default() -> Self {
        Self { gaussians: 20_000, views: 8, width: 256, height: 256, sh_degree: 3, rounds: 3 }
    }
}

/// Timings of [`bench_splat`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct SplatBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// The configuration that ran.
    pub config: SplatBenchConfig,
    /// Median wall seconds per view: forward, backward, and both.
    pub fwd_s: f64,
    /// Median wall seconds per view of the backward.
    pub bwd_s: f64,
    /// Median wall seconds per view of forward + backward.
    pub fwd_bwd_s: f64,
    /// Forward + backward views per second (1 / fwd_bwd_s).
    pub fwd_bwd_per_s: f64,
    /// Median GPU ms per view of each top-level pass (project, bin, sort, rasterize,
    /// rasterize backward, project backward).
    pub passes_ms: BTreeMap<String, f64>,
    /// Mean (tile, Gaussian) intersections per view.
    pub intersections_per_view: f64,
    /// Mean pixel–Gaussian pairs per view: the Gaussians each pixel walks until its
    /// transmittance runs out, summed over pixels (the backward walks them all again).
    pub walked_pairs_per_view: f64,
    /// Copy bandwidth measured after the timed views.
    pub copy: CopyBandwidth,
    /// The bytes the rasterize backward pass moves at least, per view: each pixel's loss
    /// gradients and state (28 bytes), each intersection's id and projected Gaussian once, and
    /// per value of each Gaussian's 2D gradient row the fixed-point sum's atomic add, its
    /// resolve into the float row and the clears (60 bytes per value).
    pub backward_bytes_per_view: f64,
    /// Those bytes at the compute copy bandwidth (a copy of B bytes moves 2 B), ms.
    pub backward_bound_ms: f64,
    /// Median GPU ms of the rasterize backward over `backward_bound_ms` (0 when the bound is 0).
    pub backward_over_bound: f64,
    /// Median GPU ns of the rasterize backward per walked pair.
    pub backward_ns_per_pair: f64,
}

/// Bytes of one pixel's inputs to the rasterize backward: dL/d(colour, alpha), dL/ddepth and
/// the forward's (transmittance, walked) state.
const BACKWARD_PIXEL_BYTES: f64 = 16.0 + 4.0 + 8.0;

/// Bytes per value of a Gaussian's 2D gradient row in the rasterize backward pass: the sum's
/// 64-bit atomic add (read and write, 16), the resolve reading the sum and its dropped count
/// (16) and adding to the float (8), the float's fill (4) and the sums' clear (16).
const BACKWARD_GRADIENT_VALUE_BYTES: f64 = 16.0 + 16.0 + 8.0 + 4.0 + 16.0;

/// `n` Gaussians uniformly in the unit ball: scales around the mean spacing, random rotations,
/// opacities and SH (DC broad, higher bands small). Deterministic for a seed.
pub fn random_scene(n: usize, sh_degree: u32, seed: u64) -> GaussianScene {
    let mut rng = SplitMix64::new(seed);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let spacing = (4.19 / n.max(1) as f64).cbrt();
    let coefficients = sh_coefficients(sh_degree);
    let mut scene = GaussianScene { sh_degree, ..Default::default() };
    while scene.len() < n {
        let p = DVec3::new(uniform(-1.0, 1.0), uniform(-1.0, 1.0), uniform(-1.0, 1.0));
        if p.length_squared() > 1.0 {
            continue;
        }
        scene.positions.push(p.as_vec3().to_array());
        let scale = |u: f64| (spacing * (0.3 + 0.7 * u)).ln() as f32;
        scene.log_scales.push([
            scale(uniform(0.0, 1.0)),
            scale(uniform(0.0, 1.0)),
            scale(uniform(0.0, 1.0)),
        ]);
        scene.rotations.push([
            uniform(-1.0, 1.0) as f32,
            uniform(-1.0, 1.0) as f32,
            uniform(-1.0, 1.0) as f32,
            uniform(-1.0, 1.0) as f32,
        ]);
        scene.opacity_logits.push(uniform(-1.0, 3.0) as f32);
        for k in 0..coefficients * 3 {
            let spread = if k < 3 { 1.0 } else { 0.2 };
            scene.sh.push(uniform(-spread, spread) as f32);
        }
    }
    scene
}

/// `views` cameras of `width` × `height` pixels on a horizontal ring of radius 3.5 around the
/// origin, all looking at it, with a 40° vertical field of view (the unit ball fills about 80%
/// of the frame's height) and square pixels.
pub fn ring_cameras(views: usize, width: u32, height: u32) -> Vec<Camera> {
    let f = height as f64 / 2.0 / 20f64.to_radians().tan();
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    (0..views)
        .map(|v| {
            let angle = std::f64::consts::TAU * v as f64 / views as f64;
            let eye = DVec3::new(3.5 * angle.cos(), 0.3, 3.5 * angle.sin());
            Camera::look_at(width, height, f, f, cx, cy, eye, DVec3::ZERO, DVec3::Y)
                .expect("ring cameras are valid")
        })
        .collect()
}

/// The GPU side of one benchmark view: the scene, zeroed gradient buffers and densification
/// statistics, and a loss gradient on every pixel's colour and alpha (as a training loss gives).
pub struct BenchWork {
    /// The scene's parameters.
    pub scene: GaussianBuffers,
    /// Gradients, shaped like `scene`, zeroed once at creation and accumulated by each backward.
    pub grads: GaussianBuffers,
    /// Densification statistics, one `[f32; 2]` per Gaussian, starting at zero.
    pub densify_stats: GpuBuffer<[f32; 2]>,
    /// dL/dcolour and dL/dalpha per pixel, each `1 / pixels`.
    pub grad_rgba: GpuBuffer<[f32; 4]>,
    /// dL/ddepth per pixel, zero.
    pub grad_depth: GpuBuffer<f32>,
}

impl BenchWork {
    /// Uploads `scene` and creates the buffers for views of `pixels` pixels; fails when an
    /// upload, an allocation or the zeroing submission fails.
    pub fn new(
        ctx: &Arc<GpuContext>,
        scene: &GaussianScene,
        pixels: usize,
    ) -> Result<Self, SplatError> {
        let buffers = GaussianBuffers::from_scene(ctx, scene)?;
        let grads = GaussianBuffers::shaped_like(ctx, &buffers)?;
        let work = Self {
            densify_stats: GpuBuffer::from_slice(
                ctx,
                "bench densify stats",
                &vec![[0.0f32; 2]; scene.len()],
            )?,
            grad_rgba: GpuBuffer::from_slice(
                ctx,
                "bench colour gradients",
                &vec![[1.0 / pixels as f32; 4]; pixels],
            )?,
            grad_depth: GpuBuffer::from_slice(ctx, "bench depth gradients", &vec![0.0f32; pixels])?,
            scene: buffers,
            grads,
        };
        let mut zero = Recorder::new(ctx)?;
        work.grads.record_zero(&mut zero);
        zero.submit_and_wait()?;
        Ok(work)
    }

    /// One view's backward after a forward of `splatter`.
    pub fn backward(&self, splatter: &mut Splatter) -> Result<PassTimes, SplatError> {
        splatter.backward(
            &self.scene,
            &self.grad_rgba,
            &self.grad_depth,
            &self.grads,
            &self.densify_stats,
        )
    }
}

/// Renders [`random_scene`] (seed `0x5EED`) from the ring cameras forward and backward,
/// `rounds` passes over the views (at least 2, the first untimed). Fails when the splatter
/// fails.
pub fn bench_splat(
    ctx: &Arc<GpuContext>,
    config: &SplatBenchConfig,
) -> Result<SplatBenchReport, SplatError> {
    let cameras = ring_cameras(config.views, config.width, config.height);
    let pixels = config.width as usize * config.height as usize;
    let work =
        BenchWork::new(ctx, &random_scene(config.gaussians, config.sh_degree, 0x5EED), pixels)?;
    let mut splatter = Splatter::new(ctx)?;
    let settings = RenderSettings { sh_degree: config.sh_degree, ..Default::default() };
    let (mut fwd, mut bwd, mut passes, mut intersections, mut pairs) =
        (Vec::new(), Vec::new(), Vec::new(), 0usize, 0u64);
    for round in 0..config.rounds.max(2) {
        for camera in &cameras {
            let start = Instant::now();
            let forward_times = splatter.forward(&work.scene, camera, &settings)?;
            let middle = Instant::now();
            let backward_times = work.backward(&mut splatter)?;
            if round > 0 {
                fwd.push((middle - start).as_secs_f64());
                bwd.push(middle.elapsed().as_secs_f64());
                passes.push(top_level_ms(&[forward_times, backward_times]));
                intersections += splatter.intersections()?;
                pairs += splatter.walked_pairs()?;
            }
        }
    }
    let timed_views = fwd.len();
    let fwd_s = super::median(fwd.clone());
    let bwd_s = super::median(bwd.clone());
    let fwd_bwd_s = super::median(fwd.iter().zip(&bwd).map(|(f, b)| f + b).collect());
    let passes_ms = super::median_per_pass(&passes);
    let views = timed_views.max(1) as f64;
    let (intersections_per_view, walked_pairs_per_view) =
        (intersections as f64 / views, pairs as f64 / views);
    let backward_bytes_per_view = BACKWARD_PIXEL_BYTES * pixels as f64
        + (4 + size_of::<Splat>()) as f64 * intersections_per_view
        + BACKWARD_GRADIENT_VALUE_BYTES * (GRAD2D_STRIDE * config.gaussians) as f64;
    let copy = measure_copy(ctx, (backward_bytes_per_view as u64).max(1 << 20))?;
    let backward_bound_ms = backward_bytes_per_view / (2.0 * copy.compute_bytes_per_s) * 1e3;
    let backward_ms = passes_ms.get("rasterize backward").copied().unwrap_or(0.0);
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    Ok(SplatBenchReport {
        device: ctx.info().name.clone(),
        config: *config,
        fwd_s,
        bwd_s,
        fwd_bwd_s,
        fwd_bwd_per_s: ratio(1.0, fwd_bwd_s),
        passes_ms,
        intersections_per_view,
        walked_pairs_per_view,
        copy,
        backward_bytes_per_view,
        backward_bound_ms,
        backward_over_bound: ratio(backward_ms, backward_bound_ms),
        backward_ns_per_pair: ratio(backward_ms * 1e6, walked_pairs_per_view),
    })
}

/// GPU ms per top-level pass name, summed over the submissions of one view.
pub(super) fn top_level_ms(submissions: &[PassTimes]) -> BTreeMap<String, f64> {
    let mut by_name = BTreeMap::new();
    for pass in submissions.iter().flat_map(|t| &t.passes).filter(|p| p.depth == 0) {
        *by_name.entry(pass.name.clone()).or_insert(0.0) += pass.ms;
    }
    by_name
}
