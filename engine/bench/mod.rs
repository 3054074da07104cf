//! Benchmarks that report speed against a bound measured in the same run: the GPU copy
//! bandwidth (a compute copy kernel and the transfer engine) and the CPU's `sort_unstable`;
//! the splatting renderer's and the mesh rasterizer's forward and backward per view, pass by
//! pass, and the splatting forward alone at any frame size (`render`); full training iterations against splatting alone; and the topology steps (densify,
//! prune) with the regularizer kernels; and a training run on a benchmark dataset scored against
//! its ground truth (`sequence`). Each result can carry its [`Provenance`].

mod copy;
mod mesh;
mod provenance;
mod render;
mod sequence;
mod sort;
mod splat;
mod topology;
mod train;

pub use copy::{CopyBandwidth, CopyProbe};
pub use mesh::{bench_mesh, bumpy_sphere, MeshBenchConfig, MeshBenchReport};
pub use provenance::{host_cpu_model, host_description, utc_date_time, Provenance};
pub use render::{bench_render, RenderBenchReport};
pub use sequence::{bench_sequence, SequenceBenchError, SequenceBenchReport};
pub use sort::{bench_sort, SortBenchReport};
pub use splat::{
    bench_splat, random_scene, ring_cameras, BenchWork, SplatBenchConfig, SplatBenchReport,
};
use std::collections::BTreeMap;
pub use topology::{bench_topology, TopologyBenchConfig, TopologyBenchError, TopologyBenchReport};
pub use train::{bench_train, TrainBenchConfig, TrainBenchReport};

/// Median of a sample; 0 for an empty one (nothing was timed).
fn median(mut samples: Vec<f64>) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    samples.sort_by(f64::total_cmp);
    let mid = samples.len() / 2;
    if samples.len() % 2 == 1 {
        samples[mid]
    } else {
        0.5 * (samples[mid - 1] + samples[mid])
    }
}

/// Per pass name, the median of its GPU ms over `samples` (one map per view or iteration,
/// each naming the passes of the first; a pass missing from one counts 0 there).
fn median_per_pass(samples: &[BTreeMap<String, f64>]) -> BTreeMap<String, f64> {
    let names: Vec<String> =
        samples.first().map(|p| p.keys().cloned().collect()).unwrap_or_default();
    names
        .into_iter()
        .map(|name| {
            let values = samples.iter().map(|p| p.get(&name).copied().unwrap_or(0.0)).collect();
            (name, median(values))
        })
        .collect()
}

/// Smallest of a sample; 0 for an empty one.
fn fastest(samples: Vec<f64>) -> f64 {
    samples.into_iter().reduce(f64::min).unwrap_or(0.0)
}
