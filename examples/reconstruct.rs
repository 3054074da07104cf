//! Embedding tagsplat as a production tool would, through the crate root's API only:
//! reconstruct a dataset with a progress display, export the sequence again as OBJ + PC2, track
//! surface points through it, and read the scores when the dataset has ground truth.
//!
//! ```sh
//! . scripts/env.sh   # lavapipe and the validation layer, as the tests use them
//! cargo run --release --example reconstruct -- DATA OUT [POINTS.csv]
//! ```
//! DATA: any dataset `tagsplat train` reads (e.g. a `tagsplat synth` folder or a benchmark).
//! POINTS.csv: `id,x,y,z` with a header (as `tagsplat track` reads it), scene units on frame 0;
//! without it the first ten vertices of frame 0 are tracked.

use std::path::{Path, PathBuf};
use tagsplat::{
    evaluate_sequence, find_ground_truth, read_points, run_train, track, ContextOptions,
    FrameFormat, GpuContext, GroundTruth, MeshSequence, Queries, SequenceEvalOptions, TrainConfig,
    TrainJob, TrainProgress,
};

type Error = Box<dyn std::error::Error>;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !(2..=3).contains(&args.len()) {
        eprintln!("usage: reconstruct DATA OUT [POINTS.csv]");
        std::process::exit(2);
    }
    let points = args.get(2).map(PathBuf::from);
    if let Err(error) = run(Path::new(&args[0]), Path::new(&args[1]), points.as_deref()) {
        eprintln!("error: {error}");
        std::process::exit(1);
    }
}

fn run(data: &Path, out: &Path, points: Option<&Path>) -> Result<(), Error> {
    let ctx = GpuContext::new(&ContextOptions::default())?;
    eprintln!("device: {}", ctx.info().name);

    // Train (or resume: frames already in OUT are kept) with a progress line per 100 steps.
    let job = TrainJob::new(data, out, TrainConfig::default());
    let report = run_train(&ctx, &job, &mut |p: TrainProgress| {
        if p.iteration.is_multiple_of(100) || p.iteration == p.iterations {
            eprintln!(
                "frame {}/{}: iteration {}/{}",
                p.frame, p.frames_end, p.iteration, p.iterations
            );
        }
    })?;
    for f in &report.frames {
        println!(
            "frame {:3}: PSNR {:.2} dB (mesh {:.2} dB), {:.1} s",
            f.frame, f.psnr_gs, f.psnr_mesh, f.wall_s
        );
    }

    // The run wrote sequence.glb / .usda / .obj + .pc2; a tool re-exports what it needs.
    let sequence = MeshSequence::read(&out.join("sequence.glb"))?;
    sequence.write(&out.join("copy.pc2"), FrameFormat::Obj, 30.0)?;

    let queries = match points {
        Some(csv) => read_points(csv)?,
        None => sequence.frames[0]
            .iter()
            .take(10)
            .enumerate()
            .map(|(i, p)| (format!("v{i}"), p.map(f64::from)))
            .collect(),
    };
    let tracks = track(&sequence.faces, &sequence.frames, &Queries::Points(queries), 0.01)?;
    for point in &tracks.points {
        let [x, y, z] = point.trajectory[point.trajectory.len() - 1];
        println!("{}: last frame at ({x:.4}, {y:.4}, {z:.4})", point.id);
    }
    for unbound in &tracks.unbound {
        println!("{}: not tracked ({})", unbound.id, unbound.reason);
    }

    if let Some(gt) = find_ground_truth(data) {
        let scores =
            evaluate_sequence(out, &GroundTruth::read(&gt)?, &SequenceEvalOptions::default())?;
        let s = &scores.summary;
        println!(
            "tracking RMSE / size: {:?}, mean Chamfer / size: {:?}",
            s.tracking_rmse_over_size, s.chamfer_mean_over_size
        );
    }
    Ok(())
}
