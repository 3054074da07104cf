//! Criterion benchmarks of the splatting renderer on the `tagsplat bench splat` scene (20 000
//! Gaussians in a unit ball, SH degree 3, ring cameras at 256²): one view's forward, and its
//! forward + backward, timed on the host (both submissions, the count readback and the waits
//! included). Short by default like the sort benches; without a usable Vulkan device they are
//! skipped, not failed.

use criterion::{criterion_group, criterion_main, Criterion};
use std::sync::Arc;
use std::time::Duration;
use tagsplat::bench::{random_scene, ring_cameras, BenchWork};
use tagsplat::gpu::{ContextOptions, GpuContext};
use tagsplat::splat::{RenderSettings, SplatError, Splatter};

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
    let work = BenchWork::new(
        ctx,
        &random_scene(GAUSSIANS, 3, 0x5EED),
        (RESOLUTION * RESOLUTION) as usize,
    )?;
    let camera = ring_cameras(8, RESOLUTION, RESOLUTION)[1];
    let settings = RenderSettings::default();
    let mut splatter = Splatter::new(ctx)?;
    let mut group = c.benchmark_group("splat_256_20k_sh3");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    group.bench_function("forward", |b| {
        b.iter(|| splatter.forward(&work.scene, &camera, &settings).expect("forward"))
    });
    group.bench_function("forward_backward", |b| {
        b.iter(|| {
            splatter.forward(&work.scene, &camera, &settings).expect("forward");
            work.backward(&mut splatter).expect("backward")
        })
    });
    group.finish();
    Ok(())
}

criterion_group!(splat, benches);
criterion_main!(splat);
