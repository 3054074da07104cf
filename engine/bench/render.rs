//! `tagsplat bench render`: the splatting forward alone, as a viewer or a throughput benchmark
//! runs it (a render-only splatter, no gradient buffers), at any frame size: wall time per
//! render from the host (recording, submitting and waiting included) beside the GPU time of its
//! passes, so the host's share shows.

use super::splat::{random_scene, ring_cameras, top_level_ms, SplatBenchConfig};
use crate::gpu::GpuContext;
use crate::splat::{GaussianBuffers, RenderSettings, SplatError, Splatter};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

/// Timings of [`bench_render`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// The configuration that ran (the splat bench's scene and cameras).
    pub config: SplatBenchConfig,
    /// Median wall seconds per render, submission to completion seen by the host.
    pub wall_s: f64,
    /// Renders per second of wall time (1 / wall_s).
    pub renders_per_s: f64,
    /// Median GPU seconds per render: its passes' timestamps summed.
    pub gpu_s: f64,
    /// Renders per second the GPU's passes alone would allow (1 / gpu_s).
    pub gpu_renders_per_s: f64,
    /// Median GPU ms per render of each pass (project, bin, sort, rasterize).
    pub passes_ms: BTreeMap<String, f64>,
    /// Mean (tile, Gaussian) intersections per render.
    pub intersections_per_view: f64,
}

/// Renders [`random_scene`] (seed `0x5EED`, as `bench splat`) from the ring cameras,
/// `rounds` passes over the views (at least 2, the first untimed: it sizes the buffers).
/// Fails when the splatter fails, for instance when a buffer exceeds the device's limits.
pub fn bench_render(
    ctx: &Arc<GpuContext>,
    config: &SplatBenchConfig,
) -> Result<RenderBenchReport, SplatError> {
    let cameras = ring_cameras(config.views, config.width, config.height);
    let scene = GaussianBuffers::from_scene(
        ctx,
        &random_scene(config.gaussians, config.sh_degree, 0x5EED),
    )?;
    let mut splatter = Splatter::renderer(ctx)?;
    let settings = RenderSettings { sh_degree: config.sh_degree, ..Default::default() };
    let (mut wall, mut gpu, mut passes, mut intersections) =
        (Vec::new(), Vec::new(), Vec::new(), 0usize);
    for round in 0..config.rounds.max(2) {
        for camera in &cameras {
            let start = Instant::now();
            let times = splatter.forward(&scene, camera, &settings)?;
            let elapsed = start.elapsed().as_secs_f64();
            if round > 0 {
                let by_pass = top_level_ms(&[times]);
                wall.push(elapsed);
                gpu.push(by_pass.values().sum::<f64>() * 1e-3);
                passes.push(by_pass);
                intersections += splatter.intersections()?;
            }
        }
    }
    let views = wall.len().max(1) as f64;
    let passes_ms = super::median_per_pass(&passes);
    let (wall_s, gpu_s) = (super::median(wall), super::median(gpu));
    let per_s = |s: f64| if s > 0.0 { 1.0 / s } else { 0.0 };
    Ok(RenderBenchReport {
        device: ctx.info().name.clone(),
        config: *config,
        wall_s,
        renders_per_s: per_s(wall_s),
        gpu_s,
        gpu_renders_per_s: per_s(gpu_s),
        passes_ms,
        intersections_per_view: intersections as f64 / views,
    })
}
