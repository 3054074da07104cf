//! Criterion benchmarks of the training step's own kernels at the `bench train` sizes: the
//! fused image loss on a 256² rgba image and one fused Adam step over 20 000 Gaussians at SH
//! degree 3, each one submission timed on the host. Skipped without a usable Vulkan device.

use criterion::{criterion_group, criterion_main, Criterion};
use std::sync::Arc;
use std::time::Duration;
use tagsplat::bench::random_scene;
use tagsplat::gpu::{ContextOptions, GpuBuffer, GpuContext, Recorder};
use tagsplat::loss::{ImageLoss, LossTarget, LossTerms, ScoredRender};
use tagsplat::optim::{Adam, AdamParams, LearningRates};
use tagsplat::rng::SplitMix64;
use tagsplat::splat::GaussianBuffers;

const RESOLUTION: u32 = 256;
const GAUSSIANS: usize = 20_000;

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new(&ContextOptions::default()) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("train benches skipped: cannot create a Vulkan context: {e}");
            return;
        }
    };
    if let Err(e) = bench_kernels(c, &ctx) {
        eprintln!("train benches failed: {e}");
    }
}

fn bench_kernels(
    c: &mut Criterion,
    ctx: &Arc<GpuContext>,
) -> Result<(), Box<dyn std::error::Error>> {
    let pixels = (RESOLUTION * RESOLUTION) as usize;
    let mut rng = SplitMix64::new(7);
    let mut image =
        || (0..pixels).map(|_| [0; 4].map(|_| rng.next_f64() as f32)).collect::<Vec<[f32; 4]>>();
    let render = GpuBuffer::from_slice(ctx, "render", &image())?;
    let target = GpuBuffer::from_slice(ctx, "target", &image())?;
    let terms = LossTerms::sums(ctx, "terms")?;
    let gradient = GpuBuffer::<[f32; 4]>::new(ctx, "gradient", pixels)?;
    let mut loss = ImageLoss::new(ctx, 1)?;
    loss.reserve(pixels)?;
    let target = LossTarget { width: RESOLUTION, height: RESOLUTION, image: &target, weight: None };
    let render = ScoredRender {
        image: &render,
        channel_weights: [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 3.0],
        terms: &terms,
        gradient: &gradient,
    };

    let scene = random_scene(GAUSSIANS, 3, 0x5EED);
    let gaussians = GaussianBuffers::from_scene(ctx, &scene)?;
    let grads = GaussianBuffers::from_scene(ctx, &random_scene(GAUSSIANS, 3, 1))?;
    let adam = Adam::new(ctx, &gaussians)?;
    let rates = LearningRates {
        positions: 1e-4,
        log_scales: 5e-3,
        rotations: 1e-3,
        opacity_logits: 0.05,
        sh_dc: 2.5e-3,
        sh_rest: 1.25e-4,
    };

    let mut group = c.benchmark_group("train_kernels");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    group.bench_function("image_loss_256", |b| {
        b.iter(|| {
            let mut rec = Recorder::new(ctx)?;
            loss.record(&mut rec, &target, &[render])?;
            rec.submit_and_wait()
        })
    });
    group.bench_function("adam_20k_sh3", |b| {
        b.iter(|| {
            let mut rec = Recorder::new(ctx)?;
            adam.record_step(
                &mut rec,
                &gaussians,
                &grads,
                &AdamParams::new(&rates, 10, GAUSSIANS, 3),
            )?;
            rec.submit_and_wait()
        })
    });
    group.finish();
    Ok(())
}

criterion_group!(train, benches);
criterion_main!(train);
