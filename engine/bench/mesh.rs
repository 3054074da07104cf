//! `tagsplat bench mesh`: the mesh rasterizer's forward and backward on a deterministic bumpy
//! sphere (the issue's: 100 000 triangles at 1080²) seen from ring cameras, wall time per view,
//! the GPU time of every pass, and the per-pixel passes against the copy bandwidth measured in
//! the same run.

use super::copy::{measure_copy, CopyBandwidth};
use super::splat::ring_cameras;
use crate::gpu::{GpuBuffer, GpuContext, PassTimes, Recorder};
use crate::raster::{MeshRasterizer, RasterError, RasterMesh, RasterSettings};
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;
use std::time::Instant;

/// Bytes the forward's per-pixel passes must move at least: visibility clear (8), resolve
/// (read 8, write id 4, barycentrics 16, colour 16, depth 4, normal 16), anti-aliasing (read
/// id 4, depth 4, colour 16; write rgb 12, mask 4).
const PIXEL_PASS_BYTES: f64 = 8.0 + 8.0 + 56.0 + 24.0 + 16.0;
/// Per-pixel passes of the forward, by pass name.
const PIXEL_PASSES: [&str; 3] = ["raster clear", "raster resolve", "raster antialias"];

/// What the mesh benchmark renders.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct MeshBenchConfig {
    /// Triangle count asked of [`bumpy_sphere`].
    pub triangles: usize,
    /// Width and height of every view, pixels.
    pub resolution: u32,
    /// Number of [`ring_cameras`](super::ring_cameras).
    pub views: usize,
    /// Passes over all views; the first is a warm-up and not timed.
    pub rounds: usize,
}

impl Default for MeshBenchConfig {
    fn default() -> Self {
        Self { triangles: 100_000, resolution: 1080, views: 4, rounds: 2 }
    }
}

/// Timings of [`bench_mesh`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct MeshBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// The configuration that ran.
    pub config: MeshBenchConfig,
    /// Triangles of the generated mesh (close to the configured count).
    pub triangles: usize,
    /// Median wall ms per view: forward, backward.
    pub forward_ms: f64,
    /// Median wall ms per view of the backward (recording and submission included).
    pub backward_ms: f64,
    /// Triangles and pixels rendered per second by the forward (median wall time).
    pub tris_per_s: f64,
    /// Pixels per second: `resolution²` over the median forward wall time.
    pub pixels_per_s: f64,
    /// Median GPU ms per view of each pass.
    pub passes_ms: BTreeMap<String, f64>,
    /// Sub-triangles that went to the tiled large-triangle path, per view (mean).
    pub large_per_view: f64,
    /// Copy bandwidth measured in the same run.
    pub copy: CopyBandwidth,
    /// The per-pixel forward passes at copy bandwidth, and measured time over that bound.
    pub pixel_passes_bound_ms: f64,
    /// Median GPU ms of the per-pixel forward passes over `pixel_passes_bound_ms` (1 is at the
    /// bound; 0 when the bound is 0).
    pub pixel_passes_over_bound: f64,
}

/// A latitude–longitude sphere of radius about 1 with a deterministic bump: a vertex at each
/// pole, `rows − 1` rings of `2 rows` vertices, about `triangles` triangles (4 rows²), closed,
/// counter-clockwise from outside, coloured by position.
pub fn bumpy_sphere(triangles: usize) -> Result<RasterMesh, RasterError> {
    let rows = ((triangles as f64 / 4.0).sqrt().round() as u32).max(2);
    let cols = 2 * rows;
    let point = |theta: f64, phi: f64| {
        let radius = 1.0 + 0.05 * (7.0 * phi).sin() * (5.0 * theta).sin();
        [radius * theta.sin() * phi.cos(), radius * theta.cos(), radius * theta.sin() * phi.sin()]
            .map(|x| x as f32)
    };
    let mut positions = vec![point(0.0, 0.0)];
    for r in 1..rows {
        for c in 0..cols {
            positions.push(point(PI * r as f64 / rows as f64, TAU * c as f64 / cols as f64));
        }
    }
    let south = positions.len() as u32;
    positions.push(point(PI, 0.0));
    let ring = |r: u32, c: u32| 1 + (r - 1) * cols + c % cols;
    let mut faces = Vec::new();
    for c in 0..cols {
        faces.push([0, ring(1, c + 1), ring(1, c)]);
        faces.push([south, ring(rows - 1, c), ring(rows - 1, c + 1)]);
        for r in 1..rows - 1 {
            let [a, b, d, e] = [ring(r, c), ring(r, c + 1), ring(r + 1, c), ring(r + 1, c + 1)];
            faces.extend([[a, b, e], [a, e, d]]);
        }
    }
    let colors = positions.iter().map(|p| p.map(|x| 0.5 + 0.5 * x)).collect();
    RasterMesh::new(positions, faces, colors)
}

/// Renders [`bumpy_sphere`] from the ring cameras forward and backward, `rounds` passes over
/// the views (at least 2, the first untimed), then measures the copy bandwidth. Fails when the
/// mesh, the rasterizer or a GPU submission fails.
pub fn bench_mesh(
    ctx: &Arc<GpuContext>,
    config: &MeshBenchConfig,
) -> Result<MeshBenchReport, RasterError> {
    let mesh = bumpy_sphere(config.triangles)?;
    let (res, pixels) =
        (config.resolution, config.resolution as usize * config.resolution as usize);
    let rasterizer = MeshRasterizer::new(ctx, &mesh, res, res)?;
    let settings = RasterSettings::scaled_to(&mesh.positions);
    let grad_color =
        GpuBuffer::from_slice(ctx, "bench dL/dcolour", &vec![1.0 / pixels as f32; 3 * pixels])?;
    let grad_mask =
        GpuBuffer::from_slice(ctx, "bench dL/dmask", &vec![1.0 / pixels as f32; pixels])?;
    let grad_positions =
        GpuBuffer::<f32>::new(ctx, "bench dL/dposition", 3 * mesh.positions.len())?;
    let grad_colors =
        GpuBuffer::<f32>::new(ctx, "bench dL/dvertex colour", 3 * mesh.positions.len())?;
    let (mut fwd, mut bwd, mut passes, mut large) = (Vec::new(), Vec::new(), Vec::new(), 0u64);
    for round in 0..config.rounds.max(2) {
        for camera in ring_cameras(config.views, res, res) {
            let params = rasterizer.params(&camera, &settings)?;
            let start = Instant::now();
            let forward_times = rasterizer.render(&camera, &settings)?;
            let middle = Instant::now();
            let mut rec = Recorder::new(ctx)?;
            rec.fill_buffer(&grad_positions, 0);
            rec.fill_buffer(&grad_colors, 0);
            rasterizer.record_backward(
                &mut rec,
                &params,
                (&grad_color, &grad_mask),
                (&grad_positions, &grad_colors),
            )?;
            let backward_times = rec.submit_and_wait()?;
            if round > 0 {
                fwd.push((middle - start).as_secs_f64());
                bwd.push(middle.elapsed().as_secs_f64());
                passes.push(pass_ms(&[forward_times, backward_times]));
                large += rasterizer.read_counters()?[0] as u64;
            }
        }
    }
    let copy = measure_copy(ctx, (pixels as u64 * 16).max(1 << 20))?;
    let passes_ms = super::median_per_pass(&passes);
    let pixel_ms: f64 = PIXEL_PASSES.iter().filter_map(|name| passes_ms.get(*name)).sum();
    // A copy of B bytes moves 2 B (read and write).
    let bound_ms = PIXEL_PASS_BYTES * pixels as f64 / (2.0 * copy.compute_bytes_per_s) * 1e3;
    let forward_s = super::median(fwd.clone());
    let per_s = |n: usize| if forward_s > 0.0 { n as f64 / forward_s } else { 0.0 };
    Ok(MeshBenchReport {
        device: ctx.info().name.clone(),
        config: *config,
        triangles: mesh.faces.len(),
        forward_ms: forward_s * 1e3,
        backward_ms: super::median(bwd) * 1e3,
        tris_per_s: per_s(mesh.faces.len()),
        pixels_per_s: per_s(pixels),
        passes_ms,
        large_per_view: large as f64 / fwd.len().max(1) as f64,
        copy,
        pixel_passes_bound_ms: bound_ms,
        pixel_passes_over_bound: if bound_ms > 0.0 { pixel_ms / bound_ms } else { 0.0 },
    })
}

/// GPU ms per pass name, summed over the submissions of one view.
fn pass_ms(submissions: &[PassTimes]) -> BTreeMap<String, f64> {
    let mut by_name = BTreeMap::new();
    for pass in submissions.iter().flat_map(|t| &t.passes) {
        *by_name.entry(pass.name.clone()).or_insert(0.0) += pass.ms;
    }
    by_name
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::manifold::closed_manifold_problem;

    #[test]
    fn bumpy_sphere_is_closed_outward_and_near_the_asked_size() {
        let mesh = bumpy_sphere(10_000).unwrap();
        assert!(
            (mesh.faces.len() as f64 / 10_000.0 - 1.0).abs() < 0.05,
            "{} triangles",
            mesh.faces.len()
        );
        assert_eq!(closed_manifold_problem(mesh.positions.len(), &mesh.faces), None);
        // Counter-clockwise from outside: the signed volume is positive (about 4π/3).
        let volume: f64 = mesh
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|k| glam::Vec3::from(mesh.positions[k as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!((volume / (4.0 * PI / 3.0) - 1.0).abs() < 0.05, "volume {volume}");
    }
}
