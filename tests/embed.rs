//! The library as an embedding program sees it: `reconstruct_render_track` uses only what the
//! crate root re-exports (the README's library example follows it), and the test checks what it
//! returns against the data it came from. Only the fixture (a generated dataset) reaches into a
//! module.

mod common;

use common::gpu;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tagsplat::synth::{generate, SubjectSource, SynthOptions};
use tagsplat::{
    psnr, run_train, track, Dataset, GaussianBuffers, GaussianScene, GpuContext, MeshSequence,
    Queries, RenderSettings, Splatter, TrackReport, TrainConfig, TrainJob, TrainReport,
};

type Error = Box<dyn std::error::Error>;

/// What the embedding program hands back: the run's report, the sequence it wrote, the
/// held-out view's render and target (RGB rows), and the tracks of frame 0's first vertices.
struct Outcome {
    report: TrainReport,
    sequence: MeshSequence,
    render: Vec<f32>,
    target: Vec<f32>,
    tracks: TrackReport,
}

/// Reconstructs `data` into `out`, renders the last frame's Gaussians into the first held-out
/// camera and tracks frame 0's first ten vertices through the written sequence.
fn reconstruct_render_track(
    ctx: &Arc<GpuContext>,
    data: &Path,
    out: &Path,
    config: TrainConfig,
) -> Result<Outcome, Error> {
    let job = TrainJob::new(data, out, config);
    let report = run_train(ctx, &job, &mut |_| {})?;
    let sequence = MeshSequence::read(&out.join("sequence.glb"))?;

    let dataset = Dataset::load(data)?;
    let (last, camera) = (dataset.frames.len() - 1, dataset.test[0]);
    let gaussians = GaussianScene::read_ply(&out.join(format!("gaussians/{last:06}.ply")))?;
    let mut splatter = Splatter::renderer(ctx)?;
    let settings = RenderSettings { sh_degree: gaussians.sh_degree, ..Default::default() };
    let buffers = GaussianBuffers::from_scene(ctx, &gaussians)?;
    splatter.forward(&buffers, &dataset.cameras[camera], &settings)?;
    let render = splatter.read_rgba()?.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let view = dataset.frames[last].views.iter().position(|v| v.camera == camera).unwrap();
    let target = dataset.image(last, view)?.data.clone();

    let points = sequence.frames[0].iter().take(10).enumerate();
    let queries = points.map(|(i, p)| (format!("v{i}"), p.map(f64::from))).collect();
    let tracks = track(&sequence.faces, &sequence.frames, &Queries::Points(queries), 0.01)?;
    Ok(Outcome { report, sequence, render, target, tracks })
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-embed-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn an_embedding_program_reconstructs_renders_and_tracks_from_the_root_api() {
    let g = gpu();
    let dir = temp("root-api");
    let data = dir.join("data");
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 8,
        frames: 2,
        width: 96,
        height: 96,
        seed: 9,
        samples: 2,
        ..Default::default()
    };
    generate(&options, &data).unwrap();
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = 60;
    config.temporal.iterations = 60;

    let outcome = reconstruct_render_track(g.ctx(), &data, &dir.join("out"), config).unwrap();
    assert_eq!(outcome.report.frames.len(), 2);
    assert_eq!(outcome.sequence.frames.len(), 2);

    // The render explains the held-out view better than the plain background does.
    let background = vec![0.0; outcome.target.len()];
    let (ours, empty) = (
        psnr(&outcome.render, &outcome.target).unwrap(),
        psnr(&background, &outcome.target).unwrap(),
    );
    assert!(ours > empty + 6.0, "held-out PSNR {ours:.2} dB, background alone {empty:.2} dB");

    // A point bound at a vertex follows that vertex exactly.
    let tracks = &outcome.tracks;
    assert_eq!((tracks.points.len(), tracks.unbound.len()), (10, 0));
    for (i, point) in tracks.points.iter().enumerate() {
        for (t, frame) in outcome.sequence.frames.iter().enumerate() {
            let distance = (0..3)
                .map(|k| (point.trajectory[t][k] - f64::from(frame[i][k])).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(distance < 1e-5, "point {i} frame {t}: {distance} from its vertex");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
