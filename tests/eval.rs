//! Metrics against independent oracles: scikit-image's SSIM, analytic Chamfer/EMD values on
//! meshes, hand-computed PSNR and tracking errors.

use tagsplat::eval::{chamfer_meshes, emd_meshes, psnr, ssim};

/// The integer test pattern of `ssim_reference.py` (below): values k/256 are exact in f32.
fn pattern(w: usize, h: usize, c: usize, salt: i64) -> Vec<i64> {
    let mut v = Vec::with_capacity(w * h * c);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            for ch in 0..c as i64 {
                v.push(((x * 73856093) ^ (y * 19349663) ^ ((ch + salt) * 83492791)) % 257);
            }
        }
    }
    v
}

fn pair(w: usize, h: usize, c: usize, smooth: bool) -> (Vec<f32>, Vec<f32>) {
    let a: Vec<i64> = if smooth {
        let mut v = Vec::new();
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                for ch in 0..c as i64 {
                    v.push((x * 7 + y * 3 + ch * 40) % 257);
                }
            }
        }
        v
    } else {
        pattern(w, h, c, 0)
    };
    let noise = pattern(w, h, c, 5);
    let b: Vec<i64> = a.iter().zip(&noise).map(|(a, n)| (a + n % 61 - 30).clamp(0, 256)).collect();
    let f = |v: &[i64]| v.iter().map(|&k| k as f32 / 256.0).collect::<Vec<f32>>();
    (f(&a), f(&b))
}

/// Reference values from scikit-image 0.26.0 (numpy float64 input), computed by:
/// ```python
/// import numpy as np
/// from skimage.metrics import structural_similarity
/// def img(w, h, c, salt):
///     y, x, ch = np.meshgrid(np.arange(h), np.arange(w), np.arange(c), indexing='ij')
///     return ((x * 73856093 ^ y * 19349663 ^ (ch + salt) * 83492791) % 257).astype(np.int64)
/// def pair(w, h, c, smooth):
///     if smooth:
///         y, x, ch = np.meshgrid(np.arange(h), np.arange(w), np.arange(c), indexing='ij')
///         a = (x * 7 + y * 3 + ch * 40) % 257
///     else:
///         a = img(w, h, c, 0)
///     b = np.clip(a + img(w, h, c, 5) % 61 - 30, 0, 256)
///     return a / 256.0, b / 256.0
/// a, b = pair(w, h, c, smooth)
/// structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
///     use_sample_covariance=False, data_range=1, channel_axis=-1)
/// ```
#[test]
fn ssim_equals_scikit_image() {
    let cases = [
        (32, 24, 1, false, 0.9731589923198142),
        (40, 30, 3, false, 0.9702753530185402),
        (16, 13, 1, true, 0.5047526302088802),
        (23, 19, 3, true, 0.49859593639901195),
    ];
    for (w, h, c, smooth, expect) in cases {
        let (a, b) = pair(w, h, c, smooth);
        let s = ssim(&a, &b, w, h, c).unwrap();
        assert!((s - expect).abs() < 1e-6, "{w}×{h}×{c}: {s} vs scikit-image {expect}");
        // Symmetric in its arguments.
        assert!((ssim(&b, &a, w, h, c).unwrap() - s).abs() < 1e-12);
    }
}

#[test]
fn psnr_of_the_reference_pair_is_the_hand_computed_value() {
    let (a, b) = pair(32, 24, 1, false);
    let mse = a.iter().zip(&b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len() as f64;
    assert!((psnr(&a, &b).unwrap() - 10.0 * (1.0 / mse).log10()).abs() < 1e-9);
}

/// A closed unit cube (12 triangles, CCW from outside), scaled and translated.
fn cube(scale: f32, offset: [f32; 3]) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for i in 0..8u32 {
        p.push([(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32].map(|v| v * scale));
    }
    for q in &mut p {
        for d in 0..3 {
            q[d] += offset[d];
        }
    }
    let f = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (p, f)
}

/// A flat n×n grid of unit squares in the z = `z` plane.
fn plane(n: u32, z: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let p =
        (0..(n + 1) * (n + 1)).map(|i| [(i % (n + 1)) as f32, (i / (n + 1)) as f32, z]).collect();
    let mut f = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let i = y * (n + 1) + x;
            f.push([i, i + 1, i + n + 2]);
            f.push([i, i + n + 2, i + n + 1]);
        }
    }
    (p, f)
}

#[test]
fn identical_meshes_give_zero() {
    let (p, f) = cube(2.0, [0.5, -1.0, 3.0]);
    let c = chamfer_meshes((&p, &f), (&p, &f), 5000, 9).unwrap();
    assert_eq!((c.squared, c.mean), (0.0, 0.0));
    assert_eq!(emd_meshes((&p, &f), (&p, &f), 300, 9).unwrap().mean, 0.0);
}

#[test]
fn plane_shifted_by_d_gives_d_squared() {
    // Same faces and areas, so the seeded samples are the same barycentric points, shifted by
    // d along the normal: every nearest neighbour and every optimal match is at distance d.
    let d = 0.25f32;
    let (a, f) = plane(6, 0.0);
    let (b, _) = plane(6, d);
    let c = chamfer_meshes((&b, &f), (&a, &f), 4000, 1).unwrap();
    let d = d as f64;
    assert!((c.squared - d * d).abs() < 1e-12, "{}", c.squared);
    assert!((c.mean - d).abs() < 1e-12);
    assert!(
        (c.mean_fraction - d / (72.0f64).sqrt()).abs() < 1e-3,
        "diagonal of the sampled points is close to the plane's"
    );
    let e = emd_meshes((&b, &f), (&a, &f), 400, 1).unwrap();
    assert!((e.mean - d).abs() < 1e-12, "{}", e.mean);
}

#[test]
fn cube_and_a_scaled_cube_are_close_to_the_analytic_distance() {
    // Concentric cubes of side 2 and 2.2: each face lies 0.1 from its counterpart. With dense
    // samples the nearest neighbour of a point is about 0.1 away (more near the edges, plus
    // the sampling gap): the mean lies in [0.1, 0.1 + a few sample spacings].
    let (a, f) = cube(2.0, [0.0; 3]);
    let (b, _) = cube(2.2, [-0.1; 3]);
    let c = chamfer_meshes((&b, &f), (&a, &f), 20_000, 4).unwrap();
    assert!(c.mean > 0.1 && c.mean < 0.125, "mean {}", c.mean);
    assert!(c.squared > 0.01 && c.squared < 0.0165, "squared {}", c.squared);
}

#[test]
fn folders_compare_meshes_trajectories_and_images() {
    use tagsplat::eval::{evaluate_folders, FolderOptions};
    use tagsplat::io::trajectories::{read_trajectories_csv, write_trajectories_csv};
    use tagsplat::mesh::TriMesh;
    use tagsplat::synth::{generate, SubjectSource, SynthOptions};
    let root = std::env::temp_dir().join(format!("tagsplat-eval-folders-{}", std::process::id()));
    let (gt, pred) = (root.join("gt"), root.join("pred"));
    std::fs::create_dir_all(pred.join("meshes")).unwrap();
    let o = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 2 },
        views: 2,
        frames: 2,
        width: 24,
        height: 24,
        seed: 1,
        samples: 1,
        track_vertices: 5,
        track_surface: 5,
        ..Default::default()
    };
    generate(&o, &gt).unwrap();
    let options = FolderOptions { chamfer_samples: 2000, emd_samples: 200, seed: 3 };
    let same = evaluate_folders(&gt, &gt, &options).unwrap();
    assert_eq!((same.chamfer_mean, same.emd_mean), (Some(0.0), Some(0.0)));
    assert_eq!(same.tracking.as_ref().unwrap().mse, 0.0);
    assert_eq!(same.images.as_ref().unwrap().images, 4);
    assert!((same.images.as_ref().unwrap().ssim - 1.0).abs() < 1e-12);
    // Identical images: PSNR capped at 100 dB as the trainer caps it, not infinite.
    assert_eq!(same.images.as_ref().unwrap().psnr_db, 100.0);

    // Prediction: trajectories moved by (0.03, 0.04, 0): RMSE 0.05 exactly (up to f64 text).
    let shifted: Vec<_> = read_trajectories_csv(&gt.join("trajectories.csv"))
        .unwrap()
        .into_iter()
        .map(|mut p| {
            p.position[0] += 0.03;
            p.position[1] += 0.04;
            p
        })
        .collect();
    tagsplat::io::write_atomically(&pred.join("trajectories.csv"), |w| {
        write_trajectories_csv(w, &shifted)
    })
    .unwrap();
    // Frame 0 only: frame 1 is missing and named.
    std::fs::copy(gt.join("meshes/000000.ply"), pred.join("meshes/000000.ply")).unwrap();
    let e = evaluate_folders(&pred, &gt, &options).unwrap_err().to_string();
    assert!(e.contains("000001.ply"), "{e}");
    let m = TriMesh::read_ply(&gt.join("meshes/000001.ply")).unwrap();
    m.write_ply(&pred.join("meshes/000001.ply")).unwrap();
    let r = evaluate_folders(&pred, &gt, &options).unwrap();
    let t = r.tracking.unwrap();
    assert!((t.rmse - 0.05).abs() < 1e-9 && (t.max - 0.05).abs() < 1e-9, "{t:?}");
    assert_eq!(t.pairs, 20);
    assert_eq!(r.chamfer_mean, Some(0.0));
    assert!(r.images.is_none());
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn tracker_output_on_generated_ground_truth_scores_near_zero() {
    // End to end: synth writes points.csv; the tracker follows them through the GT meshes and
    // writes its CSV; eval compares it with the GT trajectories.
    use tagsplat::eval::{evaluate_folders, FolderOptions};
    use tagsplat::mesh::TriMesh;
    use tagsplat::synth::{generate, SubjectSource, SynthOptions};
    use tagsplat::track::clock::Clock;
    use tagsplat::track::output::write_pinned_tracks_csv;
    use tagsplat::track::queries::read_points;
    use tagsplat::track::{track, Queries};
    let root = std::env::temp_dir().join(format!("tagsplat-eval-e2e-{}", std::process::id()));
    let (gt, pred) = (root.join("gt"), root.join("pred"));
    std::fs::create_dir_all(&pred).unwrap();
    let o = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 3 },
        views: 1,
        frames: 4,
        width: 16,
        height: 16,
        seed: 5,
        samples: 1,
        track_vertices: 20,
        track_surface: 40,
        ..Default::default()
    };
    let report = generate(&o, &gt).unwrap();
    let meshes: Vec<TriMesh> = (0..4)
        .map(|t| TriMesh::read_ply(&gt.join(format!("meshes/{t:06}.ply"))).unwrap())
        .collect();
    let frames: Vec<Vec<[f32; 3]>> = meshes.iter().map(|m| m.positions.clone()).collect();
    let queries = Queries::Points(read_points(&gt.join("points.csv")).unwrap());
    let tracked = track(&meshes[0].faces, &frames, &queries, 1e-4).unwrap();
    assert!(tracked.unbound.is_empty());
    // The tracker's own CSV, orientation and clock columns included, is what eval reads.
    let clock = Clock::uniform(24.0, 0.0, frames.len()).unwrap();
    write_pinned_tracks_csv(&pred.join("trajectories.csv"), &tracked.points, &clock).unwrap();
    let r = evaluate_folders(
        &pred,
        &gt,
        &FolderOptions { chamfer_samples: 10, emd_samples: 10, seed: 0 },
    )
    .unwrap();
    let t = r.tracking.unwrap();
    assert_eq!((t.points, t.frames, t.ignored), (60, 4, 0));
    // Both sides place the same barycentric point (f32 mesh, f64 arithmetic): far below the
    // subject's size.
    assert!(t.max < 1e-5 * report.radius, "max error {} (radius {})", t.max, report.radius);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn point_to_surface_chamfer_is_zero_on_itself_and_d_for_a_patch_shifted_along_its_normal() {
    use tagsplat::eval::chamfer_to_surface;
    let (p, f) = cube(2.0, [0.5, -1.0, 3.0]);
    let same = chamfer_to_surface((&p, &f), (&p, &f), 5000, 9).unwrap();
    // Each sample's closest surface point is itself, up to f64 rounding of the barycentrics.
    assert!(same.mean < 1e-14, "{}", same.mean);
    assert_eq!(same.samples, 5000);
    // Same x-y extent: every sample projects inside the other patch, at distance d.
    let d = 0.25f32;
    let (a, f) = plane(6, 0.0);
    let (b, _) = plane(6, d);
    let r = chamfer_to_surface((&b, &f), (&a, &f), 3000, 1).unwrap();
    for v in [r.pred_to_gt, r.gt_to_pred, r.mean] {
        assert!((v - d as f64).abs() < 1e-12, "{r:?}");
    }
    // Unlike sample-to-sample Chamfer, the patch against a finer copy of itself is 0 too.
    let (fine, ff) = {
        let (q, g) = plane(12, 0.0);
        (q.iter().map(|v| [v[0] * 0.5, v[1] * 0.5, v[2]]).collect::<Vec<_>>(), g)
    };
    assert!(chamfer_to_surface((&fine, &ff), (&a, &f), 3000, 2).unwrap().mean < 1e-12);
}

/// A benchmark ground-truth folder (gt/ layout) under `root`: a 4×4 patch sliding along x by
/// 0.1 per frame, `frames` frames, points on vertices and inside faces, `size` 5.
fn write_gt(root: &std::path::Path, frames: usize) -> Vec<tagsplat::mesh::TriMesh> {
    use tagsplat::mesh::TriMesh;
    let gt = root.join("gt");
    std::fs::create_dir_all(gt.join("meshes")).unwrap();
    let (p, f) = plane(4, 0.0);
    let meshes: Vec<TriMesh> = (0..frames)
        .map(|t| TriMesh {
            positions: p.iter().map(|v| [v[0] + 0.1 * t as f32, v[1], v[2]]).collect(),
            faces: f.clone(),
            colors: None,
        })
        .collect();
    for (t, m) in meshes.iter().enumerate() {
        m.write_ply(&gt.join(format!("meshes/{t:06}.ply"))).unwrap();
    }
    let points: Vec<[f64; 3]> =
        vec![[0.0, 0.0, 0.0], [2.0, 3.0, 0.0], [1.25, 0.5, 0.0], [3.5, 3.75, 0.0], [0.3, 2.6, 0.0]];
    let mut csv = String::from("id,x,y,z\n");
    let mut tracks = String::from("id,frame,x,y,z\n");
    for (i, q) in points.iter().enumerate() {
        csv += &format!("p{i},{},{},{}\n", q[0], q[1], q[2]);
        for t in 0..frames {
            tracks += &format!("p{i},{t},{},{},{}\n", q[0] + 0.1 * t as f64, q[1], q[2]);
        }
    }
    std::fs::write(gt.join("points.csv"), csv).unwrap();
    std::fs::write(gt.join("tracks.csv"), tracks).unwrap();
    std::fs::write(gt.join("info.json"), r#"{"frames": 4, "size": 5.0, "height": 1.0}"#).unwrap();
    meshes
}

fn temp(name: &str) -> std::path::PathBuf {
    let root = std::env::temp_dir().join(format!("tagsplat-eval-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    root
}

#[test]
fn benchmark_ground_truth_scores_a_perfect_and_an_offset_prediction() {
    use tagsplat::score::{
        evaluate_sequence, find_ground_truth, write_sequence_eval, GroundTruth, SequenceEvalOptions,
    };
    let root = temp("sequence");
    let meshes = write_gt(&root, 4);
    let gt = GroundTruth::read(&find_ground_truth(&root).unwrap()).unwrap();
    assert_eq!(find_ground_truth(&root.join("gt")), Some(root.join("gt")));
    assert_eq!((gt.size, gt.frames, gt.points.len(), gt.tracks.len()), (5.0, 4, 5, 20));
    let options = SequenceEvalOptions { chamfer_samples: 2000, ..Default::default() };

    // The ground truth as its own prediction: every score 0.
    let same = evaluate_sequence(&root.join("gt"), &gt, &options).unwrap();
    assert_eq!(same.summary.frames, [0, 1, 2, 3]);
    assert!(
        same.summary.tracking_rmse_over_size.unwrap() < 1e-7
            && same.summary.chamfer_mean_over_size.unwrap() < 1e-12,
        "{:?}",
        same.summary
    );

    // Frames 1.. moved by d along the patch's normal, frame 2 missing, a training report with
    // some fields: tracking and Chamfer are d / size on the moved frames.
    let pred = root.join("pred");
    std::fs::create_dir_all(pred.join("meshes")).unwrap();
    let d = 0.3;
    for (t, m) in meshes.iter().enumerate().filter(|(t, _)| *t != 2) {
        let mut m = m.clone();
        m.positions.iter_mut().filter(|_| t > 0).for_each(|v| v[2] += d as f32);
        m.write_ply(&pred.join(format!("meshes/{t:06}.ply"))).unwrap();
    }
    std::fs::write(pred.join("report.json"), r#"{"frames": [{"frame": 0, "psnr_gs": 30.5, "iterations": 50, "wall_s": 2.0}, {"frame": 3, "psnr_mesh": 21.0, "stop_reason": "plateau", "extra": 1}]}"#).unwrap();
    let e = evaluate_sequence(&pred, &gt, &options).unwrap();
    let s = &e.summary;
    assert_eq!(
        (s.frames.as_slice(), s.missing_frames.as_slice()),
        ([0, 1, 3].as_slice(), [2].as_slice())
    );
    let expect = d / 5.0;
    for f in &e.frames {
        let want = if f.frame == 0 { 0.0 } else { expect };
        assert!(
            (f.tracking_rmse_over_size.unwrap() - want).abs() < 1e-6
                && (f.tracking_max_over_size.unwrap() - want).abs() < 1e-6,
            "{f:?}"
        );
        assert!((f.chamfer_over_size - want).abs() < 1e-6, "{f:?}");
        // Lifted off the surface, not slid on it: all of the error is off the surface.
        assert!(
            (f.tracking_off_surface_over_size.unwrap() - want).abs() < 1e-6
                && f.tracking_along_surface_over_size.unwrap() < 1e-6,
            "{f:?}"
        );
    }
    // Over 5 points × 3 frames, two of them off by d.
    assert!(
        (s.tracking_rmse_over_size.unwrap() - expect * (2.0f64 / 3.0).sqrt()).abs() < 1e-6,
        "{s:?}"
    );
    let (off, along) =
        (s.tracking_off_surface_over_size.unwrap(), s.tracking_along_surface_over_size.unwrap());
    assert!((off - s.tracking_rmse_over_size.unwrap()).abs() < 1e-6 && along < 1e-6, "{s:?}");
    assert_eq!(
        (s.psnr_gs_first_db, s.psnr_gs_last_db, s.psnr_mesh_last_db),
        (Some(30.5), None, Some(21.0))
    );
    assert_eq!(
        (e.frames[0].train.iterations, e.frames[2].train.stop_reason.as_deref()),
        (Some(50), Some("plateau"))
    );
    assert_eq!(e.frames[1].train, Default::default(), "frame 1 is not in the report: all absent");

    let files = write_sequence_eval(&root.join("scores"), &e).unwrap();
    let csv = std::fs::read_to_string(&files[0]).unwrap();
    assert_eq!(csv.lines().count(), 4);
    assert!(csv.lines().nth(3).unwrap().ends_with(",,21,,,plateau"), "{csv}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn bad_benchmark_input_names_the_file() {
    use tagsplat::score::{evaluate_sequence, GroundTruth, SequenceEvalOptions};
    let root = temp("bad");
    write_gt(&root, 2);
    let gt_dir = root.join("gt");
    let read_error = |file: &str, text: &str| {
        let saved = std::fs::read_to_string(gt_dir.join(file)).unwrap();
        std::fs::write(gt_dir.join(file), text).unwrap();
        let e = GroundTruth::read(&gt_dir).unwrap_err().to_string();
        std::fs::write(gt_dir.join(file), saved).unwrap();
        e
    };
    let e = read_error("info.json", r#"{"height": 1.0}"#);
    assert!(e.contains("info.json") && e.contains("size"), "{e}");
    let e = read_error("info.json", r#"{"size": -2}"#);
    assert!(e.contains("info.json") && e.contains("positive"), "{e}");
    let e = read_error("tracks.csv", "id,frame,x,y,z\np0,0,0,0,0\np1,1,NaN,0,0\n");
    assert!(e.contains("tracks.csv") && e.contains("line 3"), "{e}");
    let e = read_error("tracks.csv", "id,frame,x,y,z\nnose,0,0,0,0\n");
    assert!(e.contains("tracks.csv") && e.contains("`nose`"), "{e}");
    let e = read_error("points.csv", "id,x,y,z\np0,0,0\n");
    assert!(e.contains("points.csv") && e.contains("line 2"), "{e}");

    let gt = GroundTruth::read(&gt_dir).unwrap();
    let pred = root.join("pred");
    std::fs::create_dir_all(pred.join("meshes")).unwrap();
    let options = SequenceEvalOptions { chamfer_samples: 100, ..Default::default() };
    let e = evaluate_sequence(&pred, &gt, &options).unwrap_err().to_string();
    assert!(e.contains("000000.ply") && e.contains("missing"), "{e}");
    // Frame 1 with another face list.
    std::fs::copy(gt_dir.join("meshes/000000.ply"), pred.join("meshes/000000.ply")).unwrap();
    let mut m = tagsplat::mesh::TriMesh::read_ply(&gt_dir.join("meshes/000001.ply")).unwrap();
    m.faces.swap(0, 1);
    m.write_ply(&pred.join("meshes/000001.ply")).unwrap();
    let e = evaluate_sequence(&pred, &gt, &options).unwrap_err().to_string();
    assert!(e.contains("000001.ply") && e.contains("face 0"), "{e}");
    std::fs::write(pred.join("report.json"), "{\"frames\": 3").unwrap();
    std::fs::remove_file(pred.join("meshes/000001.ply")).unwrap();
    let e = evaluate_sequence(&pred, &gt, &options).unwrap_err().to_string();
    assert!(e.contains("report.json") && e.contains("not JSON"), "{e}");
    let e = evaluate_sequence(&pred, &gt, &SequenceEvalOptions { frames: Some(0..5), ..options })
        .unwrap_err()
        .to_string();
    assert!(e.contains("0..5") && e.contains("0..2"), "{e}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// The 64² camera (focal length 40 px, y up) at `eye` looking at `at`, as [`write_rig`] writes it.
fn rig_camera((eye, at): ([f64; 3], [f64; 3])) -> tagsplat::camera::Camera {
    let (eye, at) = (glam::DVec3::from(eye), glam::DVec3::from(at));
    tagsplat::camera::Camera::look_at(64, 64, 40.0, 40.0, 32.0, 32.0, eye, at, glam::DVec3::Y)
        .unwrap()
}

/// A Panoptic-layout `train_meta.json` in `root` for `frames` frames: one [`rig_camera`] per
/// (eye, point looked at) of `rig` (image files are not read).
fn write_rig(root: &std::path::Path, frames: usize, rig: &[([f64; 3], [f64; 3])]) {
    let w2c: Vec<[[f64; 4]; 4]> = rig
        .iter()
        .map(|&view| {
            let m = rig_camera(view).world_to_camera;
            std::array::from_fn(|r| std::array::from_fn(|c| m.col(c)[r]))
        })
        .collect();
    let k = [[40.0, 0.0, 31.5], [0.0, 40.0, 31.5], [0.0, 0.0, 1.0]];
    let per_frame = |f: &dyn Fn(usize, usize) -> serde_json::Value| -> Vec<Vec<serde_json::Value>> {
        (0..frames).map(|t| (0..rig.len()).map(|c| f(t, c)).collect()).collect()
    };
    let meta = serde_json::json!({
        "w": 64, "h": 64,
        "k": per_frame(&|_, _| serde_json::json!(k)),
        "w2c": per_frame(&|_, c| serde_json::json!(w2c[c])),
        "fn": per_frame(&|t, c| serde_json::json!(format!("c{c:02}/{t:06}.png"))),
        "cam_id": per_frame(&|_, c| serde_json::json!(c)),
    });
    std::fs::write(root.join("train_meta.json"), meta.to_string()).unwrap();
}

#[test]
fn the_tracking_error_splits_by_how_many_training_cameras_see_the_points() {
    use tagsplat::score::{evaluate_sequence, find_ground_truth, GroundTruth, SequenceEvalOptions};
    let root = temp("sight");
    let meshes = write_gt(&root, 3);
    let gt = GroundTruth::read(&find_ground_truth(&root).unwrap()).unwrap();
    let options = SequenceEvalOptions { chamfer_samples: 500, ..Default::default() };
    // A prediction slid along the patch by 0.2 on frames 1 and 2.
    let pred = root.join("pred");
    std::fs::create_dir_all(pred.join("meshes")).unwrap();
    for (t, m) in meshes.iter().enumerate() {
        let mut m = m.clone();
        m.positions.iter_mut().filter(|_| t > 0).for_each(|v| v[1] += 0.2);
        m.write_ply(&pred.join(format!("meshes/{t:06}.ply"))).unwrap();
    }
    // No dataset around gt/: no cameras, no split, no pixels.
    let alone = evaluate_sequence(&pred, &gt, &options).unwrap().summary;
    assert_eq!(alone.sight, Default::default());
    assert_eq!(alone.tracking_rmse_px, None);
    // Three cameras above the patch see every point in every frame: all of the error is seen.
    let patch = [2.0, 2.0, 0.0];
    let rig = [([2.0, 2.0, 6.0], patch), ([0.5, 1.0, 6.0], patch), ([3.5, 3.0, 6.0], patch)];
    write_rig(&root, 3, &rig);
    let above = evaluate_sequence(&pred, &gt, &options).unwrap().summary;
    let rmse = above.tracking_rmse_over_size.unwrap();
    assert_eq!(above.sight.seen_share, Some(1.0), "{above:?}");
    assert!((above.sight.tracking_seen_over_size.unwrap() - rmse).abs() < 1e-9, "{above:?}");
    assert_eq!(above.sight.tracking_unseen_over_size, None);
    // In pixels: each pair's slide of 0.2 along y through the pinhole of each camera (focal
    // length 40 px), the median of the three, RMS over every pair (frame 0's slide is 0).
    let slid_px = |g: glam::DVec3, view: ([f64; 3], [f64; 3])| {
        let camera = rig_camera(view);
        let [a, b] = [g + glam::DVec3::new(0.0, 0.2, 0.0), g].map(|p| camera.to_camera(p));
        40.0 * ((a.x / a.z - b.x / b.z).powi(2) + (a.y / a.z - b.y / b.z).powi(2)).sqrt()
    };
    let squares: Vec<f64> = gt
        .tracks
        .iter()
        .map(|row| match row.frame {
            0 => 0.0,
            _ => {
                let mut px = rig.map(|c| slid_px(row.position.into(), c));
                px.sort_by(f64::total_cmp);
                px[1] * px[1]
            }
        })
        .collect();
    let want = (squares.iter().sum::<f64>() / squares.len() as f64).sqrt();
    let px = above.tracking_rmse_px.unwrap();
    assert!(want > 0.5 && (px - want).abs() < 1e-3 * want, "{px} px, {want} px by hand");
    assert_eq!(above.tracking_px_unmeasured, 0);
    // Two of them, and one that looks away: no point has three cameras.
    let away = [rig[0], rig[1], ([2.0, 2.0, 6.0], [2.0, 2.0, 12.0])];
    write_rig(&root, 3, &away);
    let below = evaluate_sequence(&pred, &gt, &options).unwrap().summary;
    assert_eq!(below.sight.seen_share, Some(0.0), "{below:?}");
    // Two cameras still see every point: the pixel error is the median (mean) of theirs.
    assert_eq!(below.tracking_px_unmeasured, 0);
    assert!(below.tracking_rmse_px.unwrap() > 0.5, "{below:?}");
    assert!((below.sight.tracking_unseen_over_size.unwrap() - rmse).abs() < 1e-9, "{below:?}");
    std::fs::remove_dir_all(&root).unwrap();
}
