//! `tagsplat bench read`: reading time of a large sequence in every format, against OBJ + PC2.

use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::sequence::bench::{bench_read, ripple, ReadBenchReport};

#[derive(clap::Args)]
pub struct BenchReadArgs {
    /// Grid side: the sequence has side² vertices (100: 10 000).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u64).range(2..=2000))]
    side: u64,
    /// Frames of the sequence.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    frames: u64,
    /// Reads timed per format; the fastest is reported.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    repetitions: u64,
    /// Folder for the written files (default: a new folder in the system's temporary
    /// directory, removed afterwards).
    #[arg(long)]
    scratch: Option<PathBuf>,
    /// Files of the same motion written by other tools (a .usdc, an .abc, an .fbx), timed too.
    #[arg(long)]
    extra: Vec<PathBuf>,
    /// Write the sequence into --scratch and stop (for another tool to convert it, then time
    /// its file with --extra).
    #[arg(long, requires = "scratch")]
    write_only: bool,
    /// Print one JSON object (with the run's provenance) instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: BenchReadArgs) -> Result<()> {
    let sequence = ripple(args.side as usize, args.frames as usize);
    let scratch = match &args.scratch {
        Some(dir) => dir.clone(),
        None => std::env::temp_dir().join(format!("tagsplat-bench-read-{}", std::process::id())),
    };
    std::fs::create_dir_all(&scratch)
        .with_context(|| format!("cannot create {}", scratch.display()))?;
    if args.write_only {
        sequence.write(&scratch.join("anim.pc2"), tagsplat::sequence::FrameFormat::Obj, 24.0)?;
        println!("wrote {}", scratch.join("anim.pc2").display());
        return Ok(());
    }
    let report = bench_read(&sequence, &scratch, &args.extra, args.repetitions as usize);
    if args.scratch.is_none() {
        let _ = std::fs::remove_dir_all(&scratch);
    }
    let report = report?;
    if args.json {
        crate::figures::print_result(&report, None)
    } else {
        print_table(&report);
        Ok(())
    }
}

fn print_table(r: &ReadBenchReport) {
    println!("{} vertices x {} frames, fastest of {} reads", r.vertices, r.frames, r.repetitions);
    println!(
        "{:<24} {:>10} {:>10} {:>9} {:>9} {:>9} {:>6}",
        "file", "MB", "read ms", "x OBJ+PC2", "parse ms", "parse x", "same"
    );
    for f in &r.formats {
        let mb = f.bytes as f64 / 1e6;
        println!(
            "{:<24} {mb:>10.1} {:>10.1} {:>9.2} {:>9.1} {:>9.2} {:>6}",
            f.file, f.read_ms, f.over_pc2, f.parse_ms, f.parse_over_pc2, f.same_frames
        );
    }
    println!("(parse: the same bytes read and each decimal parsed by the standard float parser, nothing built)");
}
