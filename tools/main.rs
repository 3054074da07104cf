//! `tagsplat`: the command-line face of the engine. It parses, calls the library, prints.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use std::process::ExitCode;

// The program's `println!` and `print!`: the modules below see these instead of std's, which
// panic when the reader of stdout has gone away (`tagsplat dataset info | head`).
macro_rules! println {
    () => { $crate::print_or_exit(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::print_or_exit(format_args!("{}\n", format_args!($($arg)*))) };
}
macro_rules! print {
    ($($arg:tt)*) => { $crate::print_or_exit(format_args!($($arg)*)) };
}

mod render;
mod render_mesh;
mod track;
use std::sync::Arc;

mod bench_read;
mod bench_sequence;
mod dataset;
mod demo;
mod eval;
mod figures;
mod fit;
mod init_mesh;
mod synth;
mod topology;
mod train;
use std::cell::RefCell;
use tagsplat::bench::{
    bench_mesh, bench_render, bench_sort, bench_splat, bench_train, MeshBenchConfig,
    MeshBenchReport, RenderBenchReport, SortBenchReport, SplatBenchConfig, SplatBenchReport,
    TrainBenchConfig, TrainBenchReport,
};
use tagsplat::gpu::{
    choose_device, parse_bytes, ContextOptions, GpuContext, ValidationLog, DEVICE_ENV,
};
use tagsplat::sort::RadixVariant;

#[derive(Parser)]
#[command(
    name = "tagsplat",
    version,
    about = "Topology-consistent mesh sequences from multi-view video, on Vulkan compute"
)]
struct Cli {
    /// Vulkan device to use: an index or part of its name (see `tagsplat devices`).
    /// Overrides the TAGSPLAT_DEVICE environment variable.
    #[arg(long, global = true)]
    device: Option<String>,
    /// Turn on the Khronos validation layer (also TAGSPLAT_VALIDATION=1).
    #[arg(long, global = true)]
    validation: bool,
    /// The device memory a run may plan for (6GiB, 512MiB, bytes), when less than the device
    /// has: training targets that do not fit are streamed. Overrides TAGSPLAT_DEVICE_MEMORY.
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_size)]
    device_memory: Option<u64>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the Vulkan devices, their missing features, and which one would be chosen.
    Devices,
    /// Render one view of a 3DGS PLY scene to PNG (and depth EXR, alpha PNG).
    Render(render::RenderArgs),
    /// Render one view of a triangle mesh (PLY/OBJ) with the differentiable rasterizer.
    RenderMesh(render_mesh::RenderMeshArgs),
    /// Inspect a multi-view video dataset.
    #[command(subcommand)]
    Dataset(dataset::DatasetCommand),
    /// Generate a synthetic sequence, reconstruct it, track its ground-truth points, and score
    /// everything against the ground truth.
    Demo(demo::DemoArgs),
    /// The paper's ablations on a dataset with ground truth: one reconstruction per variant and
    /// a table of their scores.
    Ablate(demo::AblateArgs),
    /// Reconstruct a topology-consistent mesh sequence from a multi-view video dataset.
    Train(train::TrainArgs),
    /// Fit Gaussians to one frame of a multi-view dataset (plain 3DGS densification).
    Fit(fit::FitArgs),
    /// Generate a synthetic dynamic scene with ground truth.
    Synth(synth::SynthArgs),
    /// Metrics of a prediction folder against a ground-truth folder.
    Eval(eval::EvalArgs),
    /// Write the README's figures table from result files (`--json` output of the measuring
    /// commands, kept in benches/results/), or check it (`--check`).
    Figures(figures::FiguresArgs),
    /// Measure engine kernels against bounds measured in the same run.
    #[command(subcommand)]
    Bench(Bench),
    /// Track surface points through a topology-consistent mesh sequence.
    Track(Box<track::TrackArgs>),
    /// Convert a mesh sequence from any form `track` reads to a folder of frames, OBJ + PC2,
    /// OBJ + MDD, GLB or USDA.
    Convert(track::ConvertArgs),
    /// Build a frame's first mesh from its masks (visual hull), coloured from its images.
    InitMesh(init_mesh::InitMeshArgs),
}

#[derive(Subcommand)]
enum Bench {
    /// Train on a benchmark dataset with ground truth (gt/) and score the result: tracking
    /// RMSE, Chamfer and PSNR per frame, seconds per frame, the device and host CPU.
    Sequence(bench_sequence::BenchSequenceArgs),
    /// Densify and prune steps on a 200k-vertex torus, and the regularizer kernels.
    Topology(topology::BenchTopologyArgs),
    /// BVH build time and closest-point / ray-cast throughput against brute force.
    Track(track::BenchTrackArgs),
    /// Reading time of a 10 000-vertex, 1 000-frame sequence in every format, against OBJ + PC2.
    Read(bench_read::BenchReadArgs),
    /// GPU radix sort of random (key, u32) pairs: pairs/s, copy bandwidth, CPU sort_unstable.
    Sort {
        /// Number of pairs.
        #[arg(long, default_value_t = 1 << 22)]
        n: usize,
        /// Significant key bits (1..=64); above 32 the keys are u64.
        #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=64))]
        bits: u32,
        /// Timed repetitions (after one warm-up); the fastest sets pairs/s and the fraction.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
        repetitions: u64,
        /// Sort by the LSD passes only. CPU devices otherwise take the bucket path (one pass
        /// on the top digit, then each bucket sorted in cache) where the keys allow it.
        #[arg(long)]
        lsd_only: bool,
        /// Kernel variant: lanes, subgroups or onesweep. Default: the device's, or the
        /// TAGSPLAT_SORT environment variable's.
        #[arg(long)]
        variant: Option<RadixVariant>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Full training iterations (forward, loss, backward, Adam) on the splat bench's scene,
    /// against splatting forward + backward alone in the same run.
    Train {
        #[command(flatten)]
        scene: BenchScene,
        /// Timed iterations (after a warm-up round over the views).
        #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u64).range(1..=100000))]
        iterations: u64,
        /// Training steps on the queue at once (default: what train uses: TAGSPLAT_IN_FLIGHT,
        /// else 1 on a CPU device and 3 elsewhere).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..=8))]
        in_flight: Option<u64>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Gaussian splatting forward + backward per view on a deterministic scene (default: 8 ring
    /// cameras, 256x256, 20 000 Gaussians in a unit ball, SH degree 3).
    Splat {
        #[command(flatten)]
        scene: BenchScene,
        /// Rounds over all views; the first is a warm-up.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(2..=1000))]
        rounds: u64,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// The splatting forward alone, by a render-only splatter (no gradient buffers), on the splat
    /// bench's scene: wall time per render beside its GPU passes' time (`--gaussians 1000000
    /// --width 1920 --height 1080` for a viewer's load).
    Render {
        #[command(flatten)]
        scene: BenchScene,
        /// Rounds over all views; the first is a warm-up.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(2..=1000))]
        rounds: u64,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Mesh rasterizer forward + backward per view on a bumpy sphere (default: 100 000
    /// triangles at 1080x1080, 4 ring cameras), against the copy bandwidth of the same run.
    Mesh {
        #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(8..=20_000_000))]
        triangles: u64,
        #[arg(long, default_value_t = 1080, value_parser = clap::value_parser!(u32).range(1..=16384))]
        resolution: u32,
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=1000))]
        views: u64,
        /// Rounds over all views; the first is a warm-up.
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(2..=1000))]
        rounds: u64,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // The whole cause chain on one line; no backtrace, this is a user-facing error.
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Writes to stdout. A closed stdout ends the program with status 141 and no message, as a
/// Unix tool stopped by SIGPIPE ends (Rust ignores SIGPIPE, so the write fails instead); any
/// other failure to write is an error on stderr and status 1.
fn print_or_exit(text: std::fmt::Arguments) {
    use std::io::Write;
    if let Err(e) = std::io::stdout().write_fmt(text) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(141);
        }
        eprintln!("error: cannot write to stdout: {e}");
        std::process::exit(1);
    }
}

fn parse_size(text: &str) -> std::result::Result<u64, String> {
    parse_bytes(text).ok_or_else(|| "expected a size: 6GiB, 512MiB, 1000000 (bytes)".into())
}

fn run(cli: Cli) -> Result<()> {
    let gpu = Contexts::new(ContextOptions {
        device: cli.device.clone(),
        validation: cli.validation.then_some(true),
        device_memory: cli.device_memory,
        ..Default::default()
    });
    let outcome = run_command(cli.command, &gpu);
    outcome.and(gpu.check_validation())
}

fn run_command(command: Command, gpu: &Contexts) -> Result<()> {
    match command {
        Command::Devices => devices(gpu.options.device.as_deref()),
        Command::Figures(args) => figures::run(args),
        Command::Track(args) => track::track(*args),
        Command::Convert(args) => track::convert(args),
        Command::InitMesh(args) => init_mesh::run(args),
        Command::Bench(Bench::Track(args)) => track::bench(args),
        Command::Bench(Bench::Read(args)) => bench_read::run(args),
        Command::Bench(Bench::Sequence(args)) => bench_sequence::run(|| gpu.create(), args),
        Command::Bench(Bench::Topology(args)) => topology::bench(&gpu.create()?, &args),
        Command::Render(args) => render::render(&gpu.create()?, &args),
        Command::RenderMesh(args) => render_mesh::render_mesh(&gpu.create()?, &args),
        Command::Bench(Bench::Mesh { triangles, resolution, views, rounds, json }) => {
            let ctx = gpu.create()?;
            let config = MeshBenchConfig {
                triangles: triangles as usize,
                resolution,
                views: views as usize,
                rounds: rounds as usize,
            };
            let report = bench_mesh(&ctx, &config).context("bench mesh")?;
            show(&report, &ctx, json, print_mesh_report)
        }
        Command::Dataset(command) => dataset::run(command, &*gpu.create()?),
        Command::Synth(args) => synth::run(args),
        Command::Fit(args) => fit::fit(|| gpu.create(), args),
        Command::Train(args) => train::train(|| gpu.create(), args),
        Command::Demo(args) => demo::demo(&gpu.create()?, &args),
        Command::Ablate(args) => demo::ablate(&gpu.create()?, &args),
        Command::Eval(args) => eval::run(|| gpu.create(), args),
        Command::Bench(Bench::Sort { n, bits, repetitions, lsd_only, variant, json }) => {
            let ctx = gpu.create()?;
            let report = bench_sort(&ctx, n, bits, repetitions as usize, lsd_only, variant)
                .with_context(|| format!("bench sort --n {n} --bits {bits}"))?;
            show(&report, &ctx, json, print_sort_report)?;
            if !report.verified {
                bail!("bench sort --n {n} --bits {bits}: the GPU result is not sorted");
            }
            Ok(())
        }
        Command::Bench(Bench::Train { scene, iterations, in_flight, json }) => {
            let ctx = gpu.create()?;
            let defaults = TrainBenchConfig::for_device(&ctx);
            let config = TrainBenchConfig {
                scene: scene.config(2),
                iterations: iterations as usize,
                in_flight: in_flight.map_or(defaults.in_flight, |n| n as usize),
            };
            let report = bench_train(&ctx, &config).context("bench train")?;
            show(&report, &ctx, json, print_train_report)
        }
        Command::Bench(Bench::Splat { scene, rounds, json }) => {
            let ctx = gpu.create()?;
            let report = bench_splat(&ctx, &scene.config(rounds)).context("bench splat")?;
            show(&report, &ctx, json, print_splat_report)
        }
        Command::Bench(Bench::Render { scene, rounds, json }) => {
            let ctx = gpu.create()?;
            let report = bench_render(&ctx, &scene.config(rounds)).context("bench render")?;
            show(&report, &ctx, json, print_render_report)
        }
    }
}

/// The scene and cameras of the splatting, rendering and training benches (`SplatBenchConfig`).
#[derive(clap::Args)]
struct BenchScene {
    #[arg(long, default_value_t = 20_000)]
    gaussians: usize,
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=1000))]
    views: u64,
    #[command(flatten)]
    size: FrameSize,
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(0..=3))]
    sh_degree: u32,
}

impl BenchScene {
    fn config(&self, rounds: u64) -> SplatBenchConfig {
        let (width, height) = self.size.get();
        SplatBenchConfig {
            gaussians: self.gaussians,
            views: self.views as usize,
            width,
            height,
            sh_degree: self.sh_degree,
            rounds: rounds as usize,
        }
    }
}

/// The frame size of the splatting and training benches: `--width` and `--height` (256 each by
/// default), or `--resolution R` for R × R.
#[derive(clap::Args)]
struct FrameSize {
    /// Frame width, pixels.
    #[arg(long, value_parser = clap::value_parser!(u32).range(16..=16384))]
    width: Option<u32>,
    /// Frame height, pixels.
    #[arg(long, value_parser = clap::value_parser!(u32).range(16..=16384))]
    height: Option<u32>,
    /// Square frames of this side (instead of --width and --height).
    #[arg(long, conflicts_with_all = ["width", "height"], value_parser = clap::value_parser!(u32).range(16..=16384))]
    resolution: Option<u32>,
}

impl FrameSize {
    fn get(&self) -> (u32, u32) {
        let side = |v: Option<u32>| self.resolution.or(v).unwrap_or(256);
        (side(self.width), side(self.height))
    }
}

/// Creates the run's Vulkan contexts and keeps their validation logs: with validation on, any
/// message fails the run, so a script or test that asks for validation cannot miss one.
struct Contexts {
    options: ContextOptions,
    logs: RefCell<Vec<Arc<ValidationLog>>>,
}

impl Contexts {
    fn new(options: ContextOptions) -> Self {
        Self { options, logs: RefCell::default() }
    }

    fn create(&self) -> Result<Arc<GpuContext>> {
        let ctx = GpuContext::new(&self.options).context("cannot create the Vulkan context")?;
        if ctx.validation_enabled() {
            self.logs.borrow_mut().push(ctx.validation().clone());
        }
        Ok(ctx)
    }

    /// Called once the command has dropped its contexts, so messages sent while they were
    /// destroyed (leaked objects) count too. The messages themselves went to stderr.
    fn check_validation(&self) -> Result<()> {
        let count: usize = self.logs.borrow().iter().map(|log| log.messages().len()).sum();
        if count > 0 {
            bail!("the Vulkan validation layer reported {count} message(s) (printed above)");
        }
        Ok(())
    }
}

fn devices(wanted: Option<&str>) -> Result<()> {
    let devices = GpuContext::list_devices().context("cannot list Vulkan devices")?;
    let env = std::env::var(DEVICE_ENV).ok();
    let chosen = choose_device(&devices, wanted.or(env.as_deref()));
    for d in &devices {
        let mark = if matches!(chosen, Ok(i) if i == d.index) { "*" } else { " " };
        let c = &d.capabilities;
        println!(
            "{mark} {}: {} ({}, {}, Vulkan {}.{}, subgroup size {})",
            d.index,
            d.name,
            d.kind_name(),
            d.driver,
            ash::vk::api_version_major(c.api_version),
            ash::vk::api_version_minor(c.api_version),
            c.subgroup_size
        );
        let missing = c.missing_features();
        if !missing.is_empty() {
            println!("      missing: {}", missing.join(", "));
        }
    }
    match chosen {
        Ok(_) => Ok(()),
        Err(e) => Err(e).context("no usable device"),
    }
}

fn print_sort_report(r: &SortBenchReport) {
    println!("device            {}", r.device);
    println!(
        "pairs             {} ({}-bit keys, {} significant bits, {} passes, u32 values)",
        r.n,
        r.key_bytes * 8,
        r.bits,
        r.passes
    );
    println!(
        "variant, path     {}, {}",
        r.variant,
        if r.bucket_path {
            "bucket path (top-digit pass, then each bucket in cache)"
        } else {
            "LSD passes"
        }
    );
    if r.variant == "Onesweep" {
        println!(
            "look-back         {} tiles counted by a waiting tile (last sort)",
            r.lookback_fallbacks
        );
    }
    println!(
        "GPU sort          {:.3} ms  = {:.1} M pairs/s  (fastest of {}; median {:.3} ms)",
        r.sort_ms,
        r.keys_per_s * 1e-6,
        r.repetitions,
        r.sort_median_ms
    );
    for stage in &r.stage_ms {
        println!("  {:<16}{:.3} ms (median)", stage.name, stage.ms);
    }
    println!(
        "copy bandwidth    {:.2} GB/s compute kernel, {:.2} GB/s vkCmdCopyBuffer ({} MiB)",
        r.copy_gb_per_s,
        r.copy.transfer_bytes_per_s * 1e-9,
        r.copy.bytes >> 20
    );
    println!(
        "LSD bound         {:.3} ms  ({} copies x {} B/pair at compute-copy bandwidth): fraction {:.3}",
        r.lsd_bound_ms,
        r.passes,
        r.key_bytes + 4,
        r.lsd_bound_fraction
    );
    println!(
        "this path's bound {:.3} ms  ({} copies, {}): fraction {:.3}",
        r.path_bound_ms,
        r.path_copies,
        if r.bucket_path { "bucket path" } else { "LSD passes" },
        r.path_bound_fraction
    );
    println!(
        "CPU sort_unstable {:.3} ms  = {:.1} M pairs/s (one thread)",
        r.cpu_sort_ms,
        r.cpu_sort_keys_per_s * 1e-6
    );
    println!("result verified   {}", if r.verified { "sorted" } else { "NOT SORTED" });
}

/// A bench's report as one JSON object with its provenance (`--json`), else as a table.
fn show<T: serde::Serialize>(
    report: &T,
    ctx: &GpuContext,
    json: bool,
    table: fn(&T),
) -> Result<()> {
    if json {
        figures::print_result(report, Some(ctx.info()))?;
    } else {
        table(report);
    }
    Ok(())
}

/// One line per GPU pass: its median ms per `unit` (view, iteration).
fn print_passes(unit: &str, passes_ms: &std::collections::BTreeMap<String, f64>) {
    println!("GPU passes (median ms per {unit}):");
    let width = passes_ms.keys().map(|name| name.len()).max().unwrap_or(0);
    for (name, ms) in passes_ms {
        println!("  {name:<width$}  {ms:.2}");
    }
}

fn print_render_report(r: &RenderBenchReport) {
    let c = &r.config;
    println!("device              {}", r.device);
    println!(
        "scene               {} Gaussians, SH degree {}, {} views of {}x{}, render only",
        c.gaussians, c.sh_degree, c.views, c.width, c.height
    );
    println!(
        "render              {:.2} ms per view (median wall time) = {:.1} renders/s",
        r.wall_s * 1e3,
        r.renders_per_s
    );
    println!(
        "GPU passes          {:.2} ms per view = {:.1} renders/s; the rest is the host's",
        r.gpu_s * 1e3,
        r.gpu_renders_per_s
    );
    println!("intersections       {:.0} per view", r.intersections_per_view);
    print_passes("view", &r.passes_ms);
}

fn print_splat_report(r: &SplatBenchReport) {
    let c = &r.config;
    println!("device              {}", r.device);
    println!(
        "scene               {} Gaussians, SH degree {}, {} views of {}x{}",
        c.gaussians, c.sh_degree, c.views, c.width, c.height
    );
    println!("forward             {:.2} ms per view (median wall time)", r.fwd_s * 1e3);
    println!("backward            {:.2} ms per view", r.bwd_s * 1e3);
    println!(
        "forward + backward  {:.2} ms per view = {:.2} views/s",
        r.fwd_bwd_s * 1e3,
        r.fwd_bwd_per_s
    );
    println!("intersections       {:.0} per view", r.intersections_per_view);
    println!(
        "walked pairs        {:.0} pixel-Gaussian pairs per view ({:.1} per pixel)",
        r.walked_pairs_per_view,
        r.walked_pairs_per_view / (c.width as f64 * c.height as f64)
    );
    println!("copy bandwidth      {:.2} GB/s compute kernel", r.copy.compute_bytes_per_s * 1e-9);
    println!(
        "rasterize backward  {:.2} MB per view: {:.3} ms bound at copy bandwidth; measured {:.1}x \
         the bound, {:.2} ns per walked pair",
        r.backward_bytes_per_view * 1e-6,
        r.backward_bound_ms,
        r.backward_over_bound,
        r.backward_ns_per_pair
    );
    print_passes("view", &r.passes_ms);
}

fn print_mesh_report(r: &MeshBenchReport) {
    let c = &r.config;
    println!("device              {}", r.device);
    println!(
        "mesh                {} triangles, {} views of {}x{}",
        r.triangles, c.views, c.resolution, c.resolution
    );
    println!("forward             {:.2} ms per view (median wall time) = {:.1} M triangles/s, {:.1} M pixels/s", r.forward_ms, r.tris_per_s * 1e-6, r.pixels_per_s * 1e-6);
    println!("backward            {:.2} ms per view", r.backward_ms);
    println!("large sub-triangles {:.0} per view", r.large_per_view);
    print_passes("view", &r.passes_ms);
    println!("copy bandwidth      {:.2} GB/s compute kernel", r.copy.compute_bytes_per_s * 1e-9);
    println!(
        "pixel passes        {:.2} ms bound at copy bandwidth; measured {:.1}x the bound",
        r.pixel_passes_bound_ms, r.pixel_passes_over_bound
    );
}

fn print_train_report(r: &TrainBenchReport) {
    let c = &r.config.scene;
    println!("device              {}", r.device);
    println!(
        "scene               {} Gaussians, SH degree {}, {} views of {}x{}, no densification",
        c.gaussians, c.sh_degree, c.views, c.width, c.height
    );
    println!(
        "iteration           {:.1} ms (mean of {}, {} in flight) = {:.2} it/s",
        r.s_per_iter * 1e3,
        r.config.iterations,
        r.config.in_flight,
        r.iters_per_s
    );
    println!(
        "splatting alone     {:.1} ms forward + backward per view (same run)",
        r.splat_fwd_bwd_s * 1e3
    );
    println!("loss + Adam + rest  {:.0}% of an iteration", r.overhead_fraction * 100.0);
    let share = r.host_fraction.map_or("unknown".into(), |f| format!("{:.1}%", f * 100.0));
    println!(
        "host                {:.2} ms per iteration ({share}; recording {:.2} ms, {:.1} submissions)",
        r.host_ms_per_iter,
        r.clock.recording_s * 1e3 / r.config.iterations as f64,
        r.clock.submissions as f64 / r.config.iterations as f64
    );
    println!(
        "image loss alone    {:.2} ms for one render, {:.2} ms for two against one target (same run)",
        r.loss_ms[0], r.loss_ms[1]
    );
    print_passes("iteration", &r.passes_ms);
}
