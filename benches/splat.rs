//! Criterion benchmarks of the splatting renderer on the `tagsplat bench splat` scene (20 000
//! Gaussians in a unit ball, SH degree 3, ring cameras at 256²): one view's forward, and its
//! forward + backward, timed on the host (both submissions, the count readback and the waits
//! included). Short by default like the sort benches; without a usable Vulkan device they are
//! skipped, not failed.

use criterion::{criterion_group, criterion_main, Criterion};
use std::sync::Arc;
use std::time::Duration;
use tagsplat::bench::{random_scene, ring_cameras};
use tagsplat::gpu::{ContextOptions, GpuBuffer, GpuContext, Recorder};
use tagsplat::splat::{GaussianBuffers, RenderSettings, SplatError, Splatter};

const GAUSSIANS: usize = 20_000;
const RESOLUTION: u32 = 256;

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new(&ContextOptions::default()) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("splat benches skipped: cannot create a Vulkan context: {e}");
            return;
        }
    };
    if let Err(e) = bench_views(c, &ctx) {
        eprintln!("splat benches failed: {e}");
    }
}

fn bench_views(c: &mut Criterion, ctx: &Arc<GpuContext>) -> Result<(), SplatError> {
    let scene = GaussianBuffers::from_scene(ctx, &random_scene(GAUSSIANS, 3, 0x5EED))?;
    let grads = GaussianBuffers::shaped_like(ctx, &scene)?;
    let pixels = (RESOLUTION * RESOLUTION) as usize;
    let stats = GpuBuffer::from_slice(ctx, "densify stats", &vec![[0.0f32; 2]; scene.len()])?;
    let grad_rgba = GpuBuffer::from_slice(ctx, "colour gradients", &vec![[1.0 / pixels as f32; 4]; pixels])?;
    let grad_depth = GpuBuffer::from_slice(ctx, "depth gradients", &vec![0.0f32; pixels])?;
    let mut zero = Recorder::new(ctx)?;
    grads.record_zero(&mut zero);
    zero.submit_and_wait()?;
    let camera = ring_cameras(8, RESOLUTION)[1];
    let settings = RenderSettings::default();
    let mut splatter = Splatter::new(ctx)?;
    let mut group = c.benchmark_group("splat_256_20k_sh3");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(5));
    group.bench_function("forward", |b| b.iter(|| splatter.forward(&scene, &camera, &settings).expect("forward")));
    group.bench_function("forward_backward", |b| {
        b.iter(|| {
            splatter.forward(&scene, &camera, &settings).expect("forward");
            splatter.backward(&scene, &grad_rgba, &grad_depth, &grads, &stats).expect("backward")
        })
    });
    group.finish();
    Ok(())
}

criterion_group!(splat, benches);
criterion_main!(splat);
