//! Criterion benchmarks of the mesh rasterizer on the `tagsplat bench mesh` mesh at a size that
//! suits a CPU Vulkan driver (20 000 triangles, 256²): one view's forward, and forward +
//! backward with host-side image gradients (uploads, submissions and readback included).
//! Without a usable Vulkan device they are skipped, not failed.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;
use tagsplat::bench::{bumpy_sphere, ring_cameras};
use tagsplat::gpu::{ContextOptions, GpuContext};
use tagsplat::raster::{MeshRasterizer, RasterError, RasterSettings};

const TRIANGLES: usize = 20_000;
const RESOLUTION: u32 = 256;

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new(&ContextOptions::default()) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("mesh benches skipped: cannot create a Vulkan context: {e}");
            return;
        }
    };
    if let Err(e) = bench_views(c, &ctx) {
        eprintln!("mesh benches failed: {e}");
    }
}

fn bench_views(c: &mut Criterion, ctx: &Arc<GpuContext>) -> Result<(), RasterError> {
    let mesh = bumpy_sphere(TRIANGLES)?;
    let rasterizer = MeshRasterizer::new(ctx, &mesh, RESOLUTION, RESOLUTION)?;
    let camera = ring_cameras(8, RESOLUTION, RESOLUTION)[1];
    let settings = RasterSettings::scaled_to(&mesh.positions);
    let pixels = (RESOLUTION * RESOLUTION) as usize;
    let (grad_color, grad_mask) =
        (vec![[1.0 / pixels as f32; 3]; pixels], vec![1.0 / pixels as f32; pixels]);
    let mut group = c.benchmark_group("mesh_256_20k");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    group.bench_function("forward", |b| {
        b.iter(|| rasterizer.render(&camera, &settings).expect("forward"))
    });
    group.bench_function("forward_backward", |b| {
        b.iter(|| {
            rasterizer.render(&camera, &settings).expect("forward");
            black_box(
                rasterizer
                    .gradients(&camera, &settings, &grad_color, &grad_mask)
                    .expect("backward"),
            )
        })
    });
    group.finish();
    Ok(())
}

criterion_group!(mesh, benches);
criterion_main!(mesh);
