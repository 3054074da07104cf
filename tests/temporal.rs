//! Tracking on fast motion: a generated run (the procedural body at the `run` preset: limbs move
//! up to about 16 % of its size between frames) continued from one shared frame 0 by the
//! temporal stage and by the stage it replaced, both scored on the generator's tracked points.

mod common;

use common::gpu;
use std::path::{Path, PathBuf};
use tagsplat::ablate::{copy_frame0, previous_temporal_stage};
use tagsplat::demo::{train_and_score, Scores};
use tagsplat::synth::{generate, MotionPreset, SubjectSource, SynthOptions};
use tagsplat::train::pipeline::{run_train, TrainConfig, TrainJob};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-temporal-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// 8 views at 96², six frames of the procedural body running.
fn fast_sequence(dir: &Path) {
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 8,
        frames: 6,
        resolution: 96,
        seed: 3,
        samples: 2,
        track_vertices: 100,
        track_surface: 200,
        motion: MotionPreset::Run,
    };
    generate(&options, dir).unwrap();
}

/// The default temporal stage after a short frame 0 (its schedule scaled to 300 iterations).
fn config() -> TrainConfig {
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = 300;
    config.canonical.densify_from = 60;
    config.canonical.densify_until = 210;
    config.canonical.densify_every = 30;
    config
}

fn per_frame(scores: &Scores) -> Vec<String> {
    scores.eval.tracking.as_ref().map_or(Vec::new(), |t| {
        t.rmse_per_frame.iter().map(|(f, e)| format!("{f}: {e:.4}")).collect()
    })
}

#[test]
fn the_temporal_stage_tracks_a_run_that_the_previous_stage_loses() {
    let g = gpu();
    let dir = temp("run");
    let data = dir.join("data");
    fast_sequence(&data);
    let (new, old) = (dir.join("new"), dir.join("previous"));
    run_train(
        g.ctx(),
        &TrainJob { frames: Some(0..1), ..TrainJob::new(&data, &new, config()) },
        &mut |_| {},
    )
    .unwrap();
    copy_frame0(&new, &old).unwrap();

    let (_, new_scores) = train_and_score(g.ctx(), &data, &new, config(), &mut |_| {}).unwrap();
    let mut previous = config();
    previous_temporal_stage(&mut previous);
    let (_, old_scores) = train_and_score(g.ctx(), &data, &old, previous, &mut |_| {}).unwrap();

    let message = format!(
        "tracking RMSE / height over frames 0-5: temporal stage {:.2} %, previous stage {:.2} %; per frame (scene units) {:?} vs {:?}",
        100.0 * new_scores.tracking_rmse_per_height,
        100.0 * old_scores.tracking_rmse_per_height,
        per_frame(&new_scores),
        per_frame(&old_scores)
    );
    eprintln!("{message}");
    // Measured on lavapipe (AMD EPYC host, 27 November, release build): 2.69 % against 4.90 %
    // with the Huber strain, 2.78 % against 4.98 % before it (the previous stage's kernel
    // divides differently by a few ULPs, which 300 steps amplify; docs/pipeline.md).
    const BOUND: f64 = 0.035;
    assert!(
        new_scores.tracking_rmse_per_height < BOUND && old_scores.tracking_rmse_per_height > BOUND,
        "{message}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
