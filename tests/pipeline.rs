//! The reconstruction pipeline end to end on a tiny generated sequence: outputs, one face list,
//! resume, and the errors a user can cause.

mod common;

use common::{file_names, gpu, without_run_specifics};
use std::path::{Path, PathBuf};
use tagsplat::ablate::copy_frame0;
use tagsplat::demo::train_and_score;
use tagsplat::eval::chamfer_meshes;
use tagsplat::io::trajectories::read_trajectories_csv;
use tagsplat::mesh::{bounding_diagonal, TriMesh};
use tagsplat::sequence::MeshSequence;
use tagsplat::synth::manifold::closed_manifold_problem;
use tagsplat::synth::{generate, SubjectSource, SynthOptions};
use tagsplat::track::queries::read_points;
use tagsplat::track::{track, Queries};
use tagsplat::train::pipeline::{run_train, Stage, TrainConfig, TrainJob, TrainReport};
use tagsplat::train::TrainError;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-pipeline-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// 8 views at 96², three frames of the procedural subject.
fn sequence(dir: &Path) {
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 8,
        frames: 3,
        width: 96,
        height: 96,
        seed: 5,
        samples: 2,
        track_vertices: 100,
        track_surface: 200,
        ..Default::default()
    };
    generate(&options, dir).unwrap();
}

fn quick_config() -> TrainConfig {
    let mut config = TrainConfig { sh_degree: 0, ..Default::default() };
    config.canonical.iterations = 80;
    config.canonical.densify_from = 20;
    config.canonical.densify_until = 60;
    config.canonical.densify_every = 20;
    config.temporal.iterations = 100;
    config.report.stats_every = 10;
    config
}

fn job(
    data: &Path,
    out: &Path,
    config: TrainConfig,
    frames: Option<std::ops::Range<usize>>,
) -> TrainJob {
    TrainJob { frames, ..TrainJob::new(data, out, config) }
}

#[test]
fn a_sequence_is_reconstructed_then_resumed_with_one_face_list() {
    let g = gpu();
    let dir = temp("run");
    sequence(&dir.join("data"));
    let out = dir.join("out");
    let first =
        run_train(g.ctx(), &job(&dir.join("data"), &out, quick_config(), Some(0..2)), &mut |_| {})
            .unwrap();
    assert_eq!(first.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), vec![0, 1]);
    assert!(first.resumed_frames.is_empty());
    // The exports hold the frames done so far, at the layout's frame rate, and say what is left.
    let fps = tagsplat::Dataset::load(&dir.join("data")).unwrap().fps.unwrap();
    let partial = MeshSequence::read(&out.join("sequence.glb")).unwrap();
    assert_eq!(partial.frames.len(), 2);
    let said =
        format!("frames 0-1 of 3 at {fps} fps (the own layout's); frame 2 is not trained yet");
    assert!(first.export.starts_with(&said), "{}", first.export);
    let usd = std::fs::read_to_string(out.join("sequence.usda")).unwrap();
    assert!(usd.contains(&format!("timeCodesPerSecond = {fps}\n")), "{usd}");
    assert!(!first.frames[0].topology_steps.is_empty(), "frame 0 densifies and prunes");
    // Measured on lavapipe: Gaussian PSNR 24.9 dB and mesh PSNR 26.8 dB on frame 0.
    assert!(
        first.frames[0].psnr_gs > 20.0 && first.frames[0].psnr_mesh > 22.0,
        "{:?}",
        first.frames[0]
    );

    let mut decoded = Vec::new();
    let mut progress = |p: tagsplat::TrainProgress| {
        if p.stage == Stage::Views {
            decoded.push((p.frame, p.iteration, p.iterations));
        }
    };
    let second =
        run_train(g.ctx(), &job(&dir.join("data"), &out, quick_config(), None), &mut progress)
            .unwrap();
    assert_eq!(second.resumed_frames, vec![0, 1]);
    // Only frame 2 is decoded, and its views (held-out ones too) count up one at a time.
    let views = tagsplat::Dataset::load(&dir.join("data")).unwrap().cameras.len() as u32;
    assert_eq!(decoded, (1..=views).map(|n| (2, n, views)).collect::<Vec<_>>());
    // The report keeps the frames the first run finished, with that run's figures.
    assert_eq!(second.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), vec![0, 1, 2]);
    assert_eq!(second.frames[0].psnr_mesh, first.frames[0].psnr_mesh);
    assert_eq!(second.frames[1].wall_s, first.frames[1].wall_s);
    let meshes: Vec<TriMesh> = (0..3)
        .map(|t| TriMesh::read_ply(&out.join(format!("meshes/{t:06}.ply"))).unwrap())
        .collect();
    assert!(meshes
        .iter()
        .all(|m| m.faces == meshes[0].faces && m.positions.len() == second.vertices));
    assert_ne!(meshes[0].positions, meshes[2].positions, "the surface follows the motion");
    let glb = MeshSequence::read(&out.join("sequence.glb")).unwrap();
    assert_eq!((glb.frames.len(), glb.faces.len()), (3, second.faces));
    assert_eq!(second.export, format!("frames 0-2 of 3 at {fps} fps (the own layout's)"));
    assert_eq!(MeshSequence::read(&out.join("sequence.pc2")).unwrap().frames.len(), 3);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert!(report["total_wall_s"].as_f64().unwrap() > 0.0);
    let reported: Vec<_> =
        report["frames"].as_array().unwrap().iter().map(|f| f["frame"].as_u64()).collect();
    assert_eq!(reported, [Some(0), Some(1), Some(2)]);
    assert_eq!(report["frames"][0]["psnr_mesh"].as_f64(), Some(first.frames[0].psnr_mesh));
    // The generator's rig is Y-up: every export keeps its axes, and the report says so.
    let up = report["up_axis"].as_str().unwrap();
    assert!(up.contains("OBJ + PC2: Y up (the capture's up +Y kept); GLB: Y up"), "{up}");
    assert_eq!(report["pixel_centers"], "half-integer", "the own layout's convention");
    // run.log holds both runs, in order: each one's start, its frames, its end.
    let log = std::fs::read_to_string(out.join("run.log")).unwrap();
    let lines: Vec<&str> = log.lines().map(|l| l.split_once(' ').unwrap().1).collect();
    let at = |prefix: &str| {
        lines
            .iter()
            .position(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("{prefix}: {log}"))
    };
    assert_eq!(lines.iter().filter(|l| l.starts_with("tagsplat ")).count(), 2, "{log}");
    assert!(at("frame 0:") < at("frame 1:") && at("frame 1:") < at("resuming: frames [0, 1]"));
    // Each run exports what it has: frames 0-1 after the first, all three after the second.
    let exports: Vec<usize> =
        (0..lines.len()).filter(|&i| lines[i].starts_with("exported")).collect();
    assert!(exports.len() == 2 && exports[0] < at("resuming"), "{log}");
    assert!(at("resuming") < at("frame 2:") && at("frame 2:") < exports[1], "{log}");
    assert!(lines.iter().any(|l| l.starts_with("config | ")), "{log}");
    assert_eq!(lines.iter().filter(|l| l.starts_with("run finished: ")).count(), 2, "{log}");
    for (t, m) in meshes.iter().enumerate() {
        assert_eq!(closed_manifold_problem(m.positions.len(), &m.faces), None, "frame {t}");
    }
    beats_the_unchanged_mesh(&dir.join("data"), &meshes);

    // An uninterrupted run writes the same files as the run that was stopped after frame 1
    // and resumed, bit for bit: gradients and loss totals are order-independent sums, and the
    // temporal stage starts from the topology as written. Only timings, the output paths and
    // the list of resumed frames may differ in report.json; run.log and report.html carry
    // times.
    let whole = run_train(
        g.ctx(),
        &job(&dir.join("data"), &dir.join("whole"), quick_config(), None),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(whole.frames.iter().map(|f| f.frame).collect::<Vec<_>>(), vec![0, 1, 2]);
    assert_eq!(file_names(&dir.join("whole")), file_names(&out));
    for name in file_names(&out) {
        let read = |root: &Path| std::fs::read(root.join(&name)).unwrap();
        match name.to_str().unwrap() {
            "run.log" | "report.html" => {}
            "report.json" => {
                let json = |root: &Path| {
                    without_run_specifics(serde_json::from_slice(&read(root)).unwrap())
                };
                assert_eq!(json(&dir.join("whole")), json(&out), "report.json");
            }
            _ => assert!(
                read(&dir.join("whole")) == read(&out),
                "{} differs between the runs",
                name.display()
            ),
        }
    }

    // The demo's scoring on the finished folder: the tracked points, as CSV and, with the mesh,
    // as one USD stage whose Points prim names every tracked point.
    let (_, scores) =
        train_and_score(g.ctx(), &dir.join("data"), &out, quick_config(), &mut |_| {}).unwrap();
    let stage = std::fs::read_to_string(out.join("tracks.usda")).unwrap();
    assert!(stage.contains("def Points \"Tracks\"") && stage.contains("upAxis = \"Y\""));
    let ids = read_trajectories_csv(&out.join("trajectories.csv")).unwrap();
    assert_eq!(scores.tracked_points, 300);
    // Every frame of this call was resumed: the averages still come from all three frames'
    // figures (they were 0 when resumed frames fell out of the report).
    let mean = |f: fn(&tagsplat::train::pipeline::FrameReport) -> f64| {
        second.frames.iter().map(f).sum::<f64>() / second.frames.len() as f64
    };
    assert_eq!(scores.psnr_gs, mean(|f| f.psnr_gs));
    assert_eq!(scores.psnr_mesh, mean(|f| f.psnr_mesh));
    assert!(scores.psnr_mesh > 20.0, "{}", scores.psnr_mesh);
    assert!(ids.iter().all(|row| stage.contains(&format!("\"{}\"", row.id))));
    let _ = std::fs::remove_dir_all(&dir);
}

/// What the temporal stage adds over frame 0's mesh carried unchanged through the sequence:
/// the Chamfer distance gained since frame 0 and the error of the tracked points' motion
/// (predicted minus true displacement from frame 0, so the binding offset shared by both
/// cancels) fall well below those of the unchanged mesh.
fn beats_the_unchanged_mesh(data: &Path, meshes: &[TriMesh]) {
    let truth: Vec<TriMesh> = (0..3)
        .map(|t| TriMesh::read_ply(&data.join(format!("meshes/{t:06}.ply"))).unwrap())
        .collect();
    let chamfer = |m: &TriMesh, t: usize| {
        chamfer_meshes((&m.positions, &m.faces), (&truth[t].positions, &truth[t].faces), 5000, 1)
            .unwrap()
            .mean
    };
    let base = chamfer(&meshes[0], 0);
    let moving = chamfer(&meshes[2], 2) - base;
    let still = chamfer(&meshes[0], 2) - base;
    // Measured on lavapipe: −0.0007 against 0.0127 scene units.
    assert!(
        moving < 0.5 * still,
        "Chamfer gained by frame 2: {moving} against {still} for the unchanged mesh"
    );

    let gt = read_trajectories_csv(&data.join("trajectories.csv")).unwrap();
    let queries = Queries::Points(read_points(&data.join("points.csv")).unwrap());
    let tracked = track(
        &meshes[0].faces,
        &meshes.iter().map(|m| m.positions.clone()).collect::<Vec<_>>(),
        &queries,
        0.05,
    )
    .unwrap();
    let truth_of = |id: &str, frame: u32| {
        gt.iter()
            .find(|p| p.id == id && p.frame == frame)
            .map(|p| glam::DVec3::from_array(p.position))
    };
    let (mut ours, mut unchanged, mut n) = (0.0, 0.0, 0usize);
    for point in &tracked.points {
        let (Some(g0), Some(g2)) = (truth_of(&point.id, 0), truth_of(&point.id, 2)) else {
            continue;
        };
        let predicted = glam::DVec3::from_array(point.trajectory[2])
            - glam::DVec3::from_array(point.trajectory[0]);
        ours += (predicted - (g2 - g0)).length_squared();
        unchanged += (g2 - g0).length_squared();
        n += 1;
    }
    let (ours, unchanged) = ((ours / n as f64).sqrt(), (unchanged / n as f64).sqrt());
    // Measured against 0.086 scene units over 300 points (27 November, the 32-step colour fit
    // of that afternoon): lavapipe 0.061 at subgroup size 8 and 0.058 at 4, an NVIDIA H200
    // 0.066 (size 32). Runs are bit-identical on one device, not across devices, and this
    // short run's spread is that wide.
    assert!(
        n > 200 && ours < 0.85 * unchanged,
        "motion RMSE at frame 2: {ours} against {unchanged} for the unchanged mesh ({n} points)"
    );
}

/// Scales the subject's colour (fully covered pixels) in every view of frame `t`, as a change
/// of light would.
fn relight(data: &Path, t: usize, factor: f32) {
    for camera in std::fs::read_dir(data.join("images")).unwrap() {
        relight_camera(data, &camera.unwrap().file_name().to_string_lossy(), t, factor);
    }
}

/// Scales the subject's pixels (mask 255) of `camera`'s image at frame `t` by `factor`,
/// clipped to 255.
fn relight_camera(data: &Path, camera: &str, t: usize, factor: f32) {
    let name = format!("{t:06}.png");
    let image_path = data.join("images").join(camera).join(&name);
    let mut image = image::open(&image_path).unwrap().to_rgb8();
    let mask = image::open(data.join("masks").join(camera).join(&name)).unwrap().to_luma8();
    for (pixel, alpha) in image.pixels_mut().zip(mask.pixels()) {
        if alpha.0[0] == 255 {
            pixel.0 = pixel.0.map(|c| (c as f32 * factor).round() as u8);
        }
    }
    image.save(&image_path).unwrap();
}

/// The names of a generated dataset's training cameras (those not held out).
fn training_cameras(data: &Path) -> Vec<String> {
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data.join("dataset.json")).unwrap()).unwrap();
    let names = |key: &str| -> Vec<String> {
        let list = meta[key].as_array().unwrap().iter();
        list.map(|c| c.as_str().unwrap().to_string()).collect()
    };
    let held_out = names("test_cameras");
    names("cameras").into_iter().filter(|c| !held_out.contains(c)).collect()
}

/// How far a frame with a dark and a saturated view may land from the clean images' frame, ×
/// the diagonal. Measured on lavapipe (Intel Xeon host, 256-bit vectors): 0.43 % with the two
/// views' colours left out and also 0.43 % with them matched (a throw-away switch), while
/// held-out mesh PSNR is 27.82 dB against 27.23 dB matched (clean 28.19): on this small subject
/// the skip shows in the colours, not in the shape.
const FLAWED_BOUND: f64 = 0.01;

/// A later frame in which one training view is dark and another saturated: their colours are
/// left out (their masks still count), the report and the run log name them, and the frame
/// lands about where the clean images put it.
#[test]
fn views_too_dark_or_saturated_to_match_leave_their_colours_out_and_say_so() {
    let g = gpu();
    let dir = temp("flawed");
    let (clean, flawed) = (dir.join("clean"), dir.join("flawed"));
    sequence(&clean);
    sequence(&flawed);
    let cameras = training_cameras(&flawed);
    relight_camera(&flawed, &cameras[0], 1, 0.0);
    relight_camera(&flawed, &cameras[1], 1, 20.0);
    let (clean_out, flawed_out) = (dir.join("clean_out"), dir.join("flawed_out"));
    let config = quick_config();
    let run = |data: &Path, out: &Path| {
        run_train(g.ctx(), &job(data, out, config.clone(), Some(0..2)), &mut |_| {}).unwrap()
    };
    let clean_report = run(&clean, &clean_out);
    copy_frame0(&clean_out, &flawed_out).unwrap();
    let report = run(&flawed, &flawed_out);

    let frame1 = report.frames.iter().find(|f| f.frame == 1).unwrap();
    let clean1 = clean_report.frames.iter().find(|f| f.frame == 1).unwrap();
    let said = &frame1.colour_left_out;
    assert_eq!(said.len(), 2, "{said:?}");
    assert!(said[0].starts_with(&format!("{}: dark", cameras[0])), "{said:?}");
    assert!(said[1].starts_with(&format!("{}: saturated", cameras[1])), "{said:?}");
    assert!(frame1.lost_views.is_empty() && frame1.iterations > 0);
    let log = std::fs::read_to_string(flawed_out.join("run.log")).unwrap();
    assert!(log.contains("warning: frame 1: colours left out"), "{log}");
    let mesh = |out: &Path| TriMesh::read_ply(&out.join("meshes/000001.ply")).unwrap();
    let (a, b) = (mesh(&clean_out), mesh(&flawed_out));
    let squares: f64 = a
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (0..3).map(|k| (p[k] as f64 - q[k] as f64).powi(2)).sum::<f64>())
        .sum();
    let moved = (squares / a.positions.len() as f64).sqrt() / bounding_diagonal(&a.positions);
    let message = format!(
        "frame 1 with a dark and a saturated view: {:.3} % of the diagonal from the clean run's, held-out PSNR {:.2} / {:.2} dB (clean {:.2} / {:.2})",
        100.0 * moved, frame1.psnr_gs, frame1.psnr_mesh, clean1.psnr_gs, clean1.psnr_mesh
    );
    eprintln!("{message}");
    assert!(moved < FLAWED_BOUND, "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_colour_fit_gives_a_frame_its_own_shading_and_leaves_its_shape() {
    let g = gpu();
    let dir = temp("colour");
    let data = dir.join("data");
    sequence(&data);
    relight(&data, 1, 0.8);
    let (fitted, frozen) = (dir.join("fitted"), dir.join("frozen"));
    let config = quick_config();
    run_train(g.ctx(), &job(&data, &fitted, config.clone(), Some(0..1)), &mut |_| {}).unwrap();
    copy_frame0(&fitted, &frozen).unwrap();
    let with =
        run_train(g.ctx(), &job(&data, &fitted, config.clone(), Some(0..2)), &mut |_| {}).unwrap();
    let fit_steps = config.temporal.colour_iterations;
    let mut off = config;
    off.temporal.colour_iterations = 0;
    let without = run_train(g.ctx(), &job(&data, &frozen, off, Some(0..2)), &mut |_| {}).unwrap();

    let frame1 = |r: &TrainReport| r.frames.iter().find(|f| f.frame == 1).unwrap().clone();
    let (a, b) = (frame1(&with), frame1(&without));
    assert_eq!((a.colour_iterations, b.colour_iterations), (fit_steps, 0));
    let mesh = |out: &Path| TriMesh::read_ply(&out.join("meshes/000001.ply")).unwrap();
    assert_eq!(mesh(&fitted).positions, mesh(&frozen).positions, "the fit moves colours only");
    let message = format!(
        "frame 1 relit: PSNR with the colour fit {:.2} dB (Gaussians) {:.2} dB (mesh), without {:.2} / {:.2} dB",
        a.psnr_gs, a.psnr_mesh, b.psnr_gs, b.psnr_mesh
    );
    eprintln!("{message}");
    // Measured on lavapipe (AMD EPYC host, the 16-step fit at 20×, a 2 % plateau, the Huber
    // strain): 27.10 / 29.52 dB with the fit, 24.62 / 27.09 without.
    assert!(a.psnr_mesh > b.psnr_mesh + 1.0 && a.psnr_gs > b.psnr_gs + 1.0, "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_non_finite_frame_stops_the_run_and_keeps_finished_frames() {
    let g = gpu();
    let dir = temp("nan");
    sequence(&dir.join("data"));
    let out = dir.join("out");
    run_train(g.ctx(), &job(&dir.join("data"), &out, quick_config(), Some(0..1)), &mut |_| {})
        .unwrap();
    let mut wild = quick_config();
    wild.learning_rates.positions = 1e30;
    wild.learning_rates.positions_final = 1e30;
    let error =
        run_train(g.ctx(), &job(&dir.join("data"), &out, wild, None), &mut |_| {}).unwrap_err();
    assert!(matches!(error, TrainError::NonFinite { frame: Some(1), .. }), "{error:?}");
    let error = error.to_string();
    assert!(error.contains("frame 1") && error.contains("non-finite"), "{error}");
    // The one policy of the shared loop (train/optimize.rs), as `fit` reports it.
    assert!(error.contains("non-finite parameters:"), "{error}");
    assert!(out.join("meshes/000000.ply").is_file() && !out.join("meshes/000001.ply").exists());
    let log = std::fs::read_to_string(out.join("run.log")).unwrap();
    let last = log.lines().last().unwrap();
    assert!(last.contains("run failed: frame 1") && last.contains("non-finite"), "{log}");
    // The deformation graph's own loop stops the same way, at its first non-finite pass.
    let mut wild_graph = quick_config();
    wild_graph.temporal.graph.translation_lr = 1e30;
    let error = run_train(g.ctx(), &job(&dir.join("data"), &out, wild_graph, None), &mut |_| {})
        .unwrap_err();
    assert!(matches!(error, TrainError::NonFinite { frame: Some(1), .. }), "{error:?}");
    let error = error.to_string();
    assert!(error.contains("graph level") && error.contains("non-finite parameters:"), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_are_named() {
    let g = gpu();
    let dir = temp("bad");
    sequence(&dir.join("data"));
    // A frame range whose predecessor is missing, one past the data: typed, and named.
    let run = |frames| {
        let job = job(&dir.join("data"), &dir.join("out"), quick_config(), Some(frames));
        run_train(g.ctx(), &job, &mut |_| {}).unwrap_err()
    };
    let error = run(1..2);
    assert!(matches!(error, TrainError::MissingFrame { frame: 1, needs: 0, .. }), "{error:?}");
    assert!(error.to_string().contains("needs frame 0"), "{error}");
    let error = run(0..9);
    assert!(matches!(error, TrainError::FrameRange { available: 3, .. }), "{error:?}");
    assert!(error.to_string().contains("0..9"), "{error}");
    // A given mesh with an edge shared by three faces.
    let bad = dir.join("fin.obj");
    std::fs::write(
        &bad,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\nf 3 4 5\n",
    )
    .unwrap();
    let with_mesh = TrainJob {
        mesh: Some(bad),
        ..job(&dir.join("data"), &dir.join("out2"), quick_config(), None)
    };
    let error = run_train(g.ctx(), &with_mesh, &mut |_| {}).unwrap_err().to_string();
    assert!(error.contains("fin.obj") && error.contains("non-manifold"), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two frames of the procedural subject at `width` × `height` with a fixed first mesh and no
/// densification, so only the pixels differ between sizes; the run's report.
fn run_at(dir: &Path, width: u32, height: u32) -> TrainReport {
    let g = gpu();
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 4,
        frames: 2,
        width,
        height,
        samples: 1,
        ..Default::default()
    };
    generate(&options, &dir.join("data")).unwrap();
    let mut config = quick_config();
    config.init.vertices = 400;
    config.canonical.iterations = 10;
    (config.canonical.densify_from, config.canonical.densify_until) = (20, 20);
    config.temporal.iterations = 5;
    config.temporal.min_iterations = 5;
    config.temporal.graph.iterations = 5;
    config.temporal.graph.min_iterations = 5;
    run_train(g.ctx(), &job(&dir.join("data"), &dir.join("out"), config, None), &mut |_| {})
        .unwrap()
}

#[test]
fn the_memory_estimate_bounds_what_the_buffers_hold() {
    let dir = temp("memory");
    let (small, large) = (run_at(&dir.join("small"), 64, 48), run_at(&dir.join("large"), 192, 144));
    for report in [&small, &large] {
        let (held, estimate) = (report.peak_device_bytes, report.memory_estimate.device_bytes);
        assert!(held > 0 && held <= estimate, "{held} bytes held, {estimate} estimated");
        assert!(report.peak_host_bytes.is_some_and(|b| b > 0) || !cfg!(target_os = "linux"));
    }
    // What grows with the pixels (nine times as many here) grows no faster than the model's
    // per-pixel parts (the fixed part of the estimate is the same for both).
    let grown = large.peak_device_bytes as i64 - small.peak_device_bytes as i64;
    let modelled =
        large.memory_estimate.device_bytes as i64 - small.memory_estimate.device_bytes as i64;
    assert!(grown > 0 && grown <= modelled, "buffers grew {grown} bytes, the model {modelled}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Later frames that lose the subject: views with an empty mask are left out and named, a
/// frame with none left keeps its extrapolated pose, and every frame is still written.
#[test]
fn frames_that_lose_the_subject_keep_going_and_say_where() {
    let g = gpu();
    let dir = temp("lost");
    let data = dir.join("data");
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 8,
        frames: 4,
        width: 96,
        height: 96,
        seed: 5,
        samples: 2,
        track_vertices: 10,
        track_surface: 10,
        ..Default::default()
    };
    generate(&options, &data).unwrap();
    let train_cameras = training_cameras(&data);
    let blank = |camera: &str, t: usize| {
        image::GrayImage::new(96, 96).save(data.join(format!("masks/{camera}/{t:06}.png"))).unwrap()
    };
    blank(&train_cameras[0], 2);
    blank(&train_cameras[2], 2);
    train_cameras.iter().for_each(|c| blank(c, 3));

    let out = dir.join("out");
    let mut config = quick_config();
    config.temporal.iterations = 60;
    config.temporal.graph.iterations = 40;
    let report = run_train(g.ctx(), &job(&data, &out, config, None), &mut |_| {}).unwrap();
    let frame = |t: usize| report.frames.iter().find(|f| f.frame == t).unwrap();
    assert!(frame(1).lost_views.is_empty());
    assert_eq!(frame(2).lost_views, vec![train_cameras[0].clone(), train_cameras[2].clone()]);
    assert!(frame(2).iterations > 0 && frame(2).graph.is_some());
    assert_eq!(frame(3).lost_views, train_cameras);
    assert_eq!(frame(3).stop_reason, tagsplat::train::pipeline::StopReason::NoViews);
    assert_eq!(frame(3).iterations, 0);
    for t in 0..4 {
        assert!(out.join(format!("meshes/{t:06}.ply")).is_file(), "frame {t} is written");
    }
    assert!(out.join("sequence.glb").is_file(), "the sequence is exported");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["frames"][3]["stop_reason"], "no_views");
    let log = std::fs::read_to_string(out.join("run.log")).unwrap();
    let warning = format!(
        "warning: frame 2: views left out, their mask is empty: {}, {}",
        train_cameras[0], train_cameras[2]
    );
    assert!(log.contains(&warning), "{log}");

    // Frame 3 is frame 2 extrapolated, with no optimisation: a range starting at 3 over a copy
    // of frames 0-2 must start from frame 2 (and 1), giving the same file byte for byte.
    let range = dir.join("range");
    for t in 0..3 {
        for kind in ["gaussians", "meshes"] {
            std::fs::create_dir_all(range.join(kind)).unwrap();
            std::fs::copy(
                out.join(format!("{kind}/{t:06}.ply")),
                range.join(format!("{kind}/{t:06}.ply")),
            )
            .unwrap();
        }
    }
    run_train(g.ctx(), &job(&data, &range, quick_config(), Some(3..4)), &mut |_| {}).unwrap();
    let frame3 = |d: &Path| std::fs::read(d.join("meshes/000003.ply")).unwrap();
    assert!(
        frame3(&range) == frame3(&out),
        "a run over frames 3..4 did not continue from frames 1 and 2"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each camera's own gain per channel: the camera's index in name order picks it.
fn camera_gain(index: usize) -> [f32; 3] {
    let g = |k: usize| 0.8 + 0.1 * ((index * 2 + k) % 5) as f32;
    [g(0), g(1), g(2)]
}

/// Multiplies every pixel by [`camera_gain`] (the images are premultiplied over black, so
/// the subject's colour, its outline included) in every view of every frame, as cameras of
/// different exposure and white balance would see it. Returns per camera its name, gain, and
/// the mean colour it then sees of the subject's fully covered pixels at frame 0.
fn expose_cameras(data: &Path) -> Vec<(String, [f32; 3], [f32; 3])> {
    let mut cameras: Vec<String> = std::fs::read_dir(data.join("images"))
        .unwrap()
        .map(|c| c.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    cameras.sort();
    let mut seen = Vec::new();
    for (index, camera) in cameras.iter().enumerate() {
        let mut frame0 = ([0.0f64; 3], 0usize);
        for frame in std::fs::read_dir(data.join("images").join(camera)).unwrap() {
            let name = frame.unwrap().file_name();
            let image_path = data.join("images").join(camera).join(&name);
            let mut image = image::open(&image_path).unwrap().to_rgb8();
            let mask = image::open(data.join("masks").join(camera).join(&name)).unwrap().to_luma8();
            for (pixel, alpha) in image.pixels_mut().zip(mask.pixels()) {
                for (c, gain) in pixel.0.iter_mut().zip(camera_gain(index)) {
                    *c = (*c as f32 * gain).round().min(255.0) as u8;
                }
                if alpha.0[0] == 255 && name.to_string_lossy().starts_with("000000.") {
                    (0..3).for_each(|k| frame0.0[k] += pixel.0[k] as f64 / 255.0);
                    frame0.1 += 1;
                }
            }
            image.save(&image_path).unwrap();
        }
        let mean = frame0.0.map(|sum| (sum / frame0.1.max(1) as f64) as f32);
        seen.push((camera.clone(), camera_gain(index), mean));
    }
    seen
}

#[test]
fn each_cameras_exposure_is_learned_on_frame_0() {
    let g = gpu();
    let dir = temp("camera-colour");
    let data = dir.join("data");
    sequence(&data);
    let applied = expose_cameras(&data);
    let mut config = quick_config();
    config.camera_colour.learn = tagsplat::train::pipeline::CaptureStep::Always;
    config.camera_colour.from_iteration = 0;
    // This subject is dark (red about 0.2), which the default ridge holds near a gain of 1;
    // its renders have no model error to absorb, so a light ridge shows the gains themselves.
    config.camera_colour.ridge = 0.01;
    config.canonical.iterations = 400;
    let (out, continued) = (dir.join("out"), dir.join("continued"));
    let report =
        run_train(g.ctx(), &job(&data, &out, config.clone(), Some(0..2)), &mut |_| {}).unwrap();
    let learned = &report.frames[0].camera_colour;
    assert!(report.frames[1].camera_colour.is_empty(), "frame 0 holds the maps");
    let train: Vec<_> = applied.iter().filter(|(name, ..)| learned.contains_key(name)).collect();
    assert!(train.len() >= 6, "one map per training camera: {learned:?}");
    // The maps' mean is the identity, so the scene's colours are the mean camera's: a colour
    // x of the subject is about mean_gain · x in the scene, and camera i must map it to
    // gain_i · x. Checked at the subject's mean colour each camera sees (a subject of few
    // colours fixes a map there, not how it splits into gain and offset).
    for k in 0..3 {
        let mean_gain = train.iter().map(|(_, gain, _)| gain[k]).sum::<f32>() / train.len() as f32;
        for (name, gain, seen) in &train {
            let map = learned[name][k];
            let scene = mean_gain * seen[k] / gain[k];
            let got = map[k] * scene + map[3];
            let message =
                format!("{name} channel {k}: sees {got:.3} of the subject, saw {:.3}", seen[k]);
            assert!((got - seen[k]).abs() < 0.03, "{message} (map {map:?})");
        }
    }
    // Frame 1 continued from a copy of frame 0 scores through the same maps.
    copy_frame0(&out, &continued).unwrap();
    run_train(g.ctx(), &job(&data, &continued, config, Some(0..2)), &mut |_| {}).unwrap();
    let mesh = |out: &Path| TriMesh::read_ply(&out.join("meshes/000001.ply")).unwrap();
    assert_eq!(mesh(&out).positions, mesh(&continued).positions);
    let _ = std::fs::remove_dir_all(&dir);
}
