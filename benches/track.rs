//! Criterion benchmarks of tracking on the subdivided unit sphere (level 7: 131 072
//! triangles): BVH build, closest-point queries and ray casts through the BVH, and the
//! brute-force closest point (every triangle) as the baseline in the same run.
//!
//! Short by default (10 samples, 1 s warm-up, 3 s measurement per benchmark); criterion's own
//! flags override that. `tagsplat bench track` reports the same figures as one table / JSON.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::DVec3;
use std::hint::black_box;
use std::time::Duration;
use tagsplat::geometry::bvh::triangles;
use tagsplat::geometry::sphere::unit_sphere;
use tagsplat::geometry::{brute, SurfaceBvh};
use tagsplat::rng::SplitMix64;

const LEVEL: u32 = 7;
const QUERIES: usize = 1000;
const BRUTE_QUERIES: usize = 10;

fn benches(c: &mut Criterion) {
    let (positions, faces) = unit_sphere(LEVEL);
    let bvh = SurfaceBvh::build(&positions, &faces).expect("the sphere is a valid mesh");
    let corners =
        brute::corners_f64(&triangles(&positions, &faces).expect("the sphere is a valid mesh"));
    let mut rng = SplitMix64::new(3);
    let mut unit =
        || DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5).normalize();
    let points: Vec<DVec3> =
        (0..QUERIES).map(|i| unit() * (0.98 + 0.04 * i as f64 / QUERIES as f64)).collect();
    let rays: Vec<(DVec3, DVec3)> = (0..QUERIES)
        .map(|_| (unit() * 3.0, unit() * 0.5))
        .map(|(o, t)| (o, (t - o).normalize()))
        .collect();

    let mut group = c.benchmark_group(format!("track_{}_triangles", faces.len()));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Elements(faces.len() as u64));
    group.bench_function("bvh_build", |b| {
        b.iter(|| SurfaceBvh::build(black_box(&positions), black_box(&faces)))
    });
    group.throughput(Throughput::Elements(QUERIES as u64));
    group.bench_function("closest_point_bvh", |b| {
        b.iter(|| {
            points.iter().for_each(|&p| {
                black_box(bvh.closest_point(black_box(p)));
            })
        })
    });
    group.bench_function("ray_cast_bvh", |b| {
        b.iter(|| {
            rays.iter().for_each(|&(o, d)| {
                black_box(bvh.ray_cast(black_box(o), black_box(d)));
            })
        })
    });
    group.throughput(Throughput::Elements(BRUTE_QUERIES as u64));
    group.bench_function("closest_point_brute_force", |b| {
        b.iter(|| {
            points[..BRUTE_QUERIES].iter().for_each(|&p| {
                black_box(brute::closest_point(black_box(&corners), black_box(p)));
            })
        })
    });
    group.finish();
}

criterion_group!(track, benches);
criterion_main!(track);
