//! `tagsplat bench track`: BVH build time and closest-point / ray-cast throughput on a
//! ~100k-triangle mesh, against brute force measured in the same run on a subset of the same
//! queries (brute force is O(faces) per query), with every BVH answer checked against it.

use super::TrackError;
use crate::geometry::brute;
use crate::geometry::bvh::{triangles, SurfaceBvh};
use crate::geometry::sphere::unit_sphere;
use crate::geometry::SurfaceError;
use crate::rng::SplitMix64;
use glam::DVec3;
use serde::Serialize;
use std::hint::black_box;
use std::time::Instant;

/// Largest distance of a closest-point query from the unit sphere.
pub const QUERY_OFFSET: f64 = 0.02;

/// What one `bench track` run measured (one thread).
#[derive(Clone, Debug, Serialize)]
pub struct TrackBenchReport {
    /// Triangles of the benchmark mesh.
    pub triangles: usize,
    /// Vertices of the benchmark mesh.
    pub vertices: usize,
    /// Closest-point queries lie up to this far off the unit sphere.
    pub query_offset: f64,
    /// BVH build time (fastest of `repetitions`), ms.
    pub build_ms: f64,
    /// Closest-point queries per second through the BVH.
    pub queries_per_s: f64,
    /// Closest-point queries per second by testing every triangle.
    pub brute_force_queries_per_s: f64,
    /// Ray casts per second through the BVH, and by brute force.
    pub rays_per_s: f64,
    /// Ray casts per second by testing every triangle.
    pub brute_force_rays_per_s: f64,
    /// BVH queries timed, and how many of them brute force also answered (and agreed on).
    pub queries: usize,
    /// Of those, the queries brute force also answered (and agreed on).
    pub brute_force_queries: usize,
    /// Every checked BVH answer equals brute force (distance, ray parameter).
    pub verified: bool,
}

/// Runs the benchmark on the unit sphere subdivided `level` times (level 7: 131 072
/// triangles) with `queries` random queries near the surface, `repetitions` builds.
pub fn bench_track(
    level: u32,
    queries: usize,
    repetitions: usize,
) -> Result<TrackBenchReport, TrackError> {
    let (positions, faces) = unit_sphere(level);
    let mut build_ms = f64::INFINITY;
    let mut bvh = None;
    for _ in 0..repetitions.max(1) {
        let start = Instant::now();
        let built = SurfaceBvh::build(&positions, &faces)?;
        build_ms = build_ms.min(start.elapsed().as_secs_f64() * 1e3);
        bvh = Some(built);
    }
    let bvh = bvh.ok_or(SurfaceError::EmptyMesh)?;
    let mut rng = SplitMix64::new(8);
    let mut random_unit = || loop {
        let v = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
        if (0.01..=1.0).contains(&v.length_squared()) {
            break v.normalize();
        }
    };
    // Points up to QUERY_OFFSET of the radius off the surface (tracked points sit near it);
    // rays from outside towards a random point inside.
    let points: Vec<DVec3> = (0..queries)
        .map(|i| {
            random_unit() * (1.0 + QUERY_OFFSET * (2.0 * i as f64 / queries.max(1) as f64 - 1.0))
        })
        .collect();
    let rays: Vec<(DVec3, DVec3)> = (0..queries)
        .map(|_| (random_unit() * 3.0, random_unit() * 0.5))
        .map(|(o, t)| (o, (t - o).normalize()))
        .collect();
    let (bvh_points, point_s) =
        timed(|| points.iter().map(|&p| bvh.closest_point(p)).collect::<Vec<_>>());
    let (bvh_rays, ray_s) =
        timed(|| rays.iter().map(|&(o, d)| bvh.ray_cast(o, d)).collect::<Vec<_>>());
    let corners = brute::corners_f64(&triangles(&positions, &faces)?);
    let checked = (queries / 100).clamp(1, 200).min(queries);
    let (brute_points, brute_point_s) = timed(|| {
        points[..checked].iter().map(|&p| brute::closest_point(&corners, p)).collect::<Vec<_>>()
    });
    let (brute_rays, brute_ray_s) = timed(|| {
        rays[..checked].iter().map(|&(o, d)| brute::ray_cast(&corners, o, d)).collect::<Vec<_>>()
    });
    let same = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * a.abs().max(1.0),
        (None, None) => true,
        _ => false,
    };
    let verified = (0..checked).all(|i| {
        same(bvh_points[i].map(|h| h.distance), brute_points[i].map(|h| h.distance))
            && same(bvh_rays[i].map(|h| h.distance), brute_rays[i].map(|h| h.distance))
    });
    Ok(TrackBenchReport {
        triangles: faces.len(),
        vertices: positions.len(),
        query_offset: QUERY_OFFSET,
        build_ms,
        queries_per_s: queries as f64 / point_s,
        brute_force_queries_per_s: checked as f64 / brute_point_s,
        rays_per_s: queries as f64 / ray_s,
        brute_force_rays_per_s: checked as f64 / brute_ray_s,
        queries,
        brute_force_queries: checked,
        verified,
    })
}

/// The result of `f` and the seconds it took.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = black_box(f());
    (out, start.elapsed().as_secs_f64().max(1e-9))
}
