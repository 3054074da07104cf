//! `tagsplat bench topology`: one densify step and one prune step on a large torus (CPU, wall
//! time, including compaction and the remap of every Gaussian parameter), against cloning the
//! same arrays (the floor of any remap); and the regularizers' forward + backward on the GPU
//! against the compute-copy bandwidth and the f64 CPU reference, all in one run.

use super::copy::{CopyBandwidth, CopyProbe};
use crate::gpu::{GpuContext, GpuError, Recorder};
use crate::regularize::{reference, Neighbourhoods, Regularizers, Temporal, Weights};
use crate::rng::SplitMix64;
use crate::splat::{GaussianBuffers, GaussianScene};
use crate::topology::shapes::torus;
use crate::topology::{
    densify, gaussians_from_mesh, prune, DensifyConfig, DensifyReport, InitConfig, ManifoldMesh,
    PruneConfig, PruneReport,
};
use std::sync::Arc;
use std::time::Instant;

const REGULARIZE_PASS: &str = "regularize";

/// Why [`bench_topology`] failed.
#[derive(Debug, thiserror::Error)]
pub enum TopologyBenchError {
    /// The device lacks timestamp queries, or a GPU operation failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Uploading the Gaussian scene failed.
    #[error(transparent)]
    Splat(#[from] crate::splat::SplatError),
    /// Creating, uploading or recording the regularizers failed.
    #[error(transparent)]
    Regularize(#[from] crate::regularize::RegularizeError),
    /// Building the torus mesh, densifying or pruning failed.
    #[error(transparent)]
    Topology(#[from] crate::topology::TopologyError),
}

/// What the topology benchmark runs.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct TopologyBenchConfig {
    /// Torus resolution: `major × minor` vertices.
    pub major: u32,
    /// Vertices around the tube (see `major`); at least 3 are used.
    pub minor: u32,
    /// Fraction of faces split per densify step and of Gaussians picked per prune step.
    pub fraction: f64,
    /// Densify and prune steps timed (at least 1), and timed regularizer runs after one warm-up.
    pub repetitions: usize,
    /// Spherical-harmonics degree of the Gaussians.
    pub sh_degree: u32,
}

impl Default for TopologyBenchConfig {
    fn default() -> Self {
        Self { major: 500, minor: 400, fraction: 0.01, repetitions: 3, sh_degree: 3 }
    }
}

/// Timings of [`bench_topology`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct TopologyBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// The configuration that ran.
    pub config: TopologyBenchConfig,
    /// Vertices of the torus (one Gaussian each).
    pub vertices: usize,
    /// Faces of the torus.
    pub faces: usize,
    /// Median wall time of one densify step (splits, flips, compaction, scene remap), ms.
    pub densify_ms: f64,
    /// Faces split by the last densify step.
    pub densify_splits: usize,
    /// Edge flips made by the last densify step.
    pub densify_flips: usize,
    /// Median wall time of one prune step (merges, compaction, scene remap), ms.
    pub prune_ms: f64,
    /// Gaussians removed by the last prune step.
    pub pruned: usize,
    /// Gaussians the last prune step picked but kept, having no legal collapse.
    pub prune_kept_no_legal_edge: usize,
    /// Cloning the Gaussian arrays once: the floor of any remap, ms.
    pub scene_clone_ms: f64,
    /// Building the CSR 1-rings for upload, ms.
    pub neighbourhoods_ms: f64,
    /// Fastest GPU time of both regularizer passes with every term on, ms.
    pub regularize_ms: f64,
    /// Vertices per second at `regularize_ms`.
    pub regularize_vertices_per_s: f64,
    /// Bytes the passes must move at least (each buffer read or written once), and that at the
    /// compute-copy bandwidth.
    pub regularize_min_bytes: u64,
    /// `regularize_min_bytes` divided by the compute copy rate, ms.
    pub regularize_bound_ms: f64,
    /// `regularize_bound_ms / regularize_ms`.
    pub bandwidth_fraction: f64,
    /// Copy bandwidth measured between the regularizer runs of the same submission.
    pub copy: CopyBandwidth,
    /// The f64 CPU reference (one thread) on the same input, ms.
    pub reference_ms: f64,
}

/// Runs the benchmark (see the module doc).
pub fn bench_topology(
    ctx: &Arc<GpuContext>,
    config: &TopologyBenchConfig,
) -> Result<TopologyBenchReport, TopologyBenchError> {
    if ctx.limits().timestamp_period_ns.is_none() {
        return Err(GpuError::MissingFeatures {
            device: ctx.info().name.clone(),
            missing: vec!["timestamp queries on the compute queue"],
        }
        .into());
    }
    let (positions, faces) = torus(config.major.max(3), config.minor.max(3));
    let mesh = ManifoldMesh::new(positions, faces)?;
    let scene = gaussians_from_mesh(
        &mesh,
        &[],
        &InitConfig { sh_degree: config.sh_degree, ..Default::default() },
    );
    let reps = config.repetitions.max(1);
    let mut rng = SplitMix64::new(7);
    let (mut densify_ms, mut prune_ms, mut clone_ms) = (Vec::new(), Vec::new(), Vec::new());
    let (mut densified, mut pruned) = (DensifyReport::default(), PruneReport::default());
    for _ in 0..reps {
        let scores: Vec<f32> = (0..mesh.face_rows())
            .map(|_| if rng.next_f64() < config.fraction { 1.0 } else { 0.0 })
            .collect();
        let (mut m, mut s) = (mesh.clone(), scene.clone());
        let t = Instant::now();
        densified = densify(
            &mut m,
            &mut s,
            &scores,
            &DensifyConfig { threshold: 0.5, ..Default::default() },
        )?;
        densify_ms.push(ms(t));
        let (mut m, mut s) = (mesh.clone(), scene.clone());
        for (i, l) in s.opacity_logits.iter_mut().enumerate() {
            if (i as u64).wrapping_mul(0x9E37_79B9) % 1000 < (config.fraction * 1000.0) as u64 {
                *l = -10.0;
            }
        }
        let t = Instant::now();
        pruned =
            prune(&mut m, &mut s, &PruneConfig { max_scale: f32::INFINITY, ..Default::default() })?;
        prune_ms.push(ms(t));
        let t = Instant::now();
        std::hint::black_box(scene.clone());
        clone_ms.push(ms(t));
    }
    let t = Instant::now();
    let nb = Neighbourhoods::from_mesh(&mesh);
    let neighbourhoods_ms = ms(t);
    let gpu = bench_regularizers(ctx, &nb, &scene, reps)?;
    Ok(TopologyBenchReport {
        device: ctx.info().name.clone(),
        config: *config,
        vertices: mesh.vertex_count(),
        faces: mesh.face_count(),
        densify_ms: super::median(densify_ms),
        densify_splits: densified.split_faces,
        densify_flips: densified.flips,
        prune_ms: super::median(prune_ms),
        pruned: pruned.pruned,
        prune_kept_no_legal_edge: pruned.kept_no_legal_edge,
        scene_clone_ms: super::median(clone_ms),
        neighbourhoods_ms,
        regularize_ms: gpu.ms,
        regularize_vertices_per_s: nb.len() as f64 / (gpu.ms * 1e-3),
        regularize_min_bytes: gpu.min_bytes,
        regularize_bound_ms: gpu.bound_ms,
        bandwidth_fraction: gpu.bound_ms / gpu.ms,
        copy: gpu.copy,
        reference_ms: gpu.reference_ms,
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

struct GpuFigures {
    ms: f64,
    min_bytes: u64,
    bound_ms: f64,
    copy: CopyBandwidth,
    reference_ms: f64,
}

fn bench_regularizers(
    ctx: &Arc<GpuContext>,
    nb: &Neighbourhoods,
    scene: &GaussianScene,
    reps: usize,
) -> Result<GpuFigures, TopologyBenchError> {
    let mut reg = Regularizers::new(ctx)?;
    reg.upload(nb)?;
    let params = GaussianBuffers::from_scene(ctx, scene)?;
    let mut moved = scene.clone();
    moved.positions.iter_mut().for_each(|p| p[0] += 1e-3);
    let previous = GaussianBuffers::from_scene(ctx, &moved)?;
    let grads = GaussianBuffers::shaped_like(ctx, &params)?;
    let n = nb.len() as u64;
    // Per Gaussian: parameters (12 + 12 + 16), previous frame (12 + 16), ranges (8), ring
    // (4 per neighbour), scratch written and read (2 × 32), gradients read and written
    // (2 × (12 + 4 + 16)).
    let min_bytes = n * (40 + 28 + 8 + 64 + 64) + 4 * nb.ring.len() as u64;
    let probe = CopyProbe::new(ctx, min_bytes.min(64 << 20))?;
    let mut rec = Recorder::new(ctx)?;
    grads.record_zero(&mut rec);
    for _ in 0..reps + 1 {
        probe.record(&mut rec)?;
        rec.begin_pass(REGULARIZE_PASS);
        reg.record(&mut rec, &params, &grads, &Weights::default(), Some(Temporal::of(&previous)))?;
        rec.end_pass();
    }
    let times = rec.submit_and_wait()?;
    let timed: Vec<f64> =
        times.passes.iter().filter(|p| p.name == REGULARIZE_PASS).skip(1).map(|p| p.ms).collect();
    let copy = probe.bandwidth(&times);
    let gpu_ms = super::fastest(timed);
    let bound_ms = min_bytes as f64 / copy.compute_bytes_per_s * 1e3;
    let to_params = |s: &GaussianScene| reference::Params {
        positions: s.positions.iter().map(|p| p.map(f64::from)).collect(),
        log_scales: s.log_scales.iter().map(|p| p.map(f64::from)).collect(),
        rotations: s.rotations.iter().map(|p| p.map(f64::from)).collect(),
    };
    let (x, prev) = (to_params(scene), to_params(&moved));
    let t = Instant::now();
    std::hint::black_box(reference::evaluate(nb, &x, Some(&prev), &Weights::default()));
    Ok(GpuFigures { ms: gpu_ms, min_bytes, bound_ms, copy, reference_ms: ms(t) })
}
