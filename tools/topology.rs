//! `tagsplat bench topology`: densify / prune steps and the regularizer kernels.

use anyhow::{Context, Result};
use clap::Args;
use std::sync::Arc;
use tagsplat::bench::{bench_topology, TopologyBenchConfig, TopologyBenchReport};
use tagsplat::gpu::GpuContext;

#[derive(Args)]
pub struct BenchTopologyArgs {
    /// Torus resolution around the axis (vertices = major × minor; default 200 000).
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u32).range(3..=100_000))]
    major: u32,
    /// Torus resolution around the tube.
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(3..=100_000))]
    minor: u32,
    /// Fraction of faces split per densify step and of Gaussians picked per prune step.
    #[arg(long, default_value_t = 0.01)]
    fraction: f64,
    /// Timed repetitions of each step.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repetitions: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn bench(ctx: &Arc<GpuContext>, args: &BenchTopologyArgs) -> Result<()> {
    if !(0.0..=1.0).contains(&args.fraction) {
        anyhow::bail!("--fraction {} is outside [0, 1]", args.fraction);
    }
    let config = TopologyBenchConfig {
        major: args.major,
        minor: args.minor,
        fraction: args.fraction,
        repetitions: args.repetitions as usize,
        ..Default::default()
    };
    let report = bench_topology(ctx, &config).context("bench topology")?;
    if args.json {
        crate::figures::print_result(&report, Some(ctx.info()))?;
    } else {
        print_report(&report);
    }
    Ok(())
}

fn print_report(r: &TopologyBenchReport) {
    println!("device              {}", r.device);
    println!(
        "mesh                torus, {} vertices, {} faces; SH degree {}",
        r.vertices, r.faces, r.config.sh_degree
    );
    println!(
        "densify step        {:.1} ms  ({} faces split, {} flips; median of {})",
        r.densify_ms, r.densify_splits, r.densify_flips, r.config.repetitions
    );
    println!(
        "prune step          {:.1} ms  ({} merged, {} kept without a legal edge)",
        r.prune_ms, r.pruned, r.prune_kept_no_legal_edge
    );
    println!(
        "scene clone         {:.1} ms  (floor of any remap of the Gaussian arrays)",
        r.scene_clone_ms
    );
    println!("1-ring upload build {:.1} ms", r.neighbourhoods_ms);
    println!(
        "regularizers        {:.2} ms GPU = {:.1} M vertices/s (forward + backward, all six terms)",
        r.regularize_ms,
        r.regularize_vertices_per_s * 1e-6
    );
    println!(
        "copy bound          {:.2} ms  ({} MB at {:.2} GB/s compute copy) -> fraction {:.3}",
        r.regularize_bound_ms,
        r.regularize_min_bytes / 1_000_000,
        r.copy.compute_bytes_per_s * 1e-9,
        r.bandwidth_fraction
    );
    println!("f64 CPU reference   {:.1} ms (one thread)", r.reference_ms);
}
