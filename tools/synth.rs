//! `tagsplat synth`: a synthetic dynamic scene with ground truth.

use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::synth::{generate, MotionPreset, Pattern, SubjectSource, SynthOptions};

#[derive(clap::Args)]
pub struct SynthArgs {
    /// Output folder (the project's own dataset layout plus meshes/, bindings.csv, trajectories.csv).
    #[arg(long)]
    out: PathBuf,
    /// `procedural`, or a rigged glTF 2.0 file (.glb).
    #[arg(long, default_value = "procedural")]
    subject: String,
    /// glTF animation to play (default: the first).
    #[arg(long)]
    animation: Option<String>,
    /// Icosphere subdivisions of the procedural subject (4: 2562 vertices).
    #[arg(long, default_value_t = 4)]
    subdivisions: u32,
    #[arg(long, default_value_t = 8)]
    views: usize,
    #[arg(long, default_value_t = 8)]
    frames: usize,
    /// Image width and height, pixels (--width and --height override it).
    #[arg(long, default_value_t = 256)]
    resolution: u32,
    /// Image width, pixels (default: --resolution).
    #[arg(long)]
    width: Option<u32>,
    /// Image height, pixels (default: --resolution).
    #[arg(long)]
    height: Option<u32>,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Supersampling: samples per pixel along each axis.
    #[arg(long, default_value_t = 4)]
    samples: u32,
    /// Tracked points: random vertices, then random surface points.
    #[arg(long, default_value_t = 100)]
    track_vertices: usize,
    #[arg(long, default_value_t = 200)]
    track_surface: usize,
    /// How fast the subject moves per frame: gentle (the animation's speed), walk (4×) or run
    /// (5×), as at capture frame rates.
    #[arg(long, default_value = "gentle", value_parser = MotionPreset::from_name)]
    motion: MotionPreset,
    /// What is printed on the skin: smooth (soft colour bands) or bands (high-contrast bands,
    /// at 96² 1–6 px across a row, and a speckle, as fox_walk_banded's printed cloth).
    #[arg(long, default_value = "smooth", value_parser = Pattern::from_name)]
    pattern: Pattern,
    #[arg(long)]
    json: bool,
}

pub fn run(a: SynthArgs) -> Result<()> {
    let subject = match a.subject.as_str() {
        "procedural" => SubjectSource::Procedural { subdivisions: a.subdivisions },
        path => SubjectSource::Gltf { path: path.into(), animation: a.animation.clone() },
    };
    let options = SynthOptions {
        subject,
        views: a.views,
        frames: a.frames,
        width: a.width.unwrap_or(a.resolution),
        height: a.height.unwrap_or(a.resolution),
        seed: a.seed,
        samples: a.samples,
        track_vertices: a.track_vertices,
        track_surface: a.track_surface,
        motion: a.motion,
        pattern: a.pattern,
    };
    let start = std::time::Instant::now();
    let report =
        generate(&options, &a.out).with_context(|| format!("synth --out {}", a.out.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(
                &serde_json::json!({ "report": report, "seconds": seconds })
            )?
        );
        return Ok(());
    }
    println!("wrote {}: {} views × {} frames at {} × {} px, {} vertices / {} faces, {} tracked points, subject radius {:.4} scene units, {:.2} s",
        a.out.display(), report.views, report.frames, report.width, report.height, report.vertices, report.faces, report.tracked_points, report.radius, seconds);
    let m = report.motion_per_frame;
    println!("vertex motion per frame ({:?}): mean {:.3}, 90th percentile {:.3}, max {:.3} of the subject's size", report.motion, m.mean, m.p90, m.max);
    if let Some(problem) = &report.manifold_problem {
        println!("warning: the glTF mesh is not a closed manifold ({problem})");
    }
    Ok(())
}
