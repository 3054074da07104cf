//! Tracking against oracles: BVH queries against brute force, tracked vertices against the
//! generated trajectories, surface points against the analytic motion, pixel hits against
//! the camera projection, the CLI end to end and twice on the same input.

mod common;
mod deforming;

use deforming::{affine, bend, sequence, temp_dir};
use glam::{DMat4, DVec3};
use std::path::Path;
use tagsplat::camera::Camera;
use tagsplat::geometry::bvh::triangles;
use tagsplat::geometry::{brute, SurfaceBvh, SurfaceError};
use tagsplat::rng::SplitMix64;
use tagsplat::track::{track, Queries};

fn random_in_cube(rng: &mut SplitMix64) -> DVec3 {
    DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0
}

/// A random triangle soup: small triangles scattered in the unit cube, a tenth of them
/// degenerate (collinear or with coincident corners).
fn soup(rng: &mut SplitMix64, count: usize) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for i in 0..count {
        let a = random_in_cube(rng);
        let (b, c) = (a + random_in_cube(rng) * 0.2, a + random_in_cube(rng) * 0.2);
        let c = match i % 20 {
            0 => a + (b - a) * 0.3,
            1 => b,
            _ => c,
        };
        positions.extend([a, b, c].map(|v| v.as_vec3().to_array()));
    }
    let faces = (0..count as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    (positions, faces)
}

fn assert_relative_eq(a: f64, b: f64, tolerance: f64, what: &str) {
    assert!((a - b).abs() <= tolerance * a.abs().max(b.abs()).max(1e-300), "{what}: {a} vs {b}");
}

#[test]
fn closest_point_equals_brute_force_on_random_meshes() {
    let mut rng = SplitMix64::new(11);
    let ellipsoid = sequence(4, 1, affine);
    let meshes = [
        soup(&mut rng, 1),
        soup(&mut rng, 7),
        soup(&mut rng, 3000),
        (ellipsoid.frames[0].clone(), ellipsoid.faces.clone()),
    ];
    for (positions, faces) in meshes {
        let bvh = SurfaceBvh::build(&positions, &faces).unwrap();
        let corners = brute::corners_f64(&triangles(&positions, &faces).unwrap());
        for i in 0..1500 {
            // Mostly near the geometry, some far outside it.
            let p = random_in_cube(&mut rng) * if i % 10 == 0 { 10.0 } else { 1.2 };
            let (fast, slow) =
                (bvh.closest_point(p).unwrap(), brute::closest_point(&corners, p).unwrap());
            assert_relative_eq(fast.distance, slow.distance, 1e-6, "distance");
            // The answer is self-consistent: its barycentrics give its point on its face.
            let [a, b, c] = corners[fast.face as usize];
            let q = a * fast.barycentric[0] + b * fast.barycentric[1] + c * fast.barycentric[2];
            assert!(
                q.distance(fast.position) <= 1e-12
                    && (p.distance(q) - fast.distance).abs() <= 1e-12
            );
            assert!(
                fast.barycentric.iter().all(|&b| b >= -1e-12)
                    && (fast.barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-12
            );
        }
    }
}

#[test]
fn ray_casts_equal_brute_force_on_random_meshes() {
    let mut rng = SplitMix64::new(12);
    let ellipsoid = sequence(4, 1, affine);
    for (positions, faces) in [
        soup(&mut rng, 5),
        soup(&mut rng, 3000),
        (ellipsoid.frames[0].clone(), ellipsoid.faces.clone()),
    ] {
        let bvh = SurfaceBvh::build(&positions, &faces).unwrap();
        let corners = brute::corners_f64(&triangles(&positions, &faces).unwrap());
        let mut hits = 0;
        for i in 0..1500 {
            // Aim at a random point of a random triangle (mostly hits, some grazing edges);
            // every 7th ray is axis-parallel, where the slab test divides by zero.
            let [a, b, c] = corners[(rng.next_u32() as usize) % corners.len()];
            let (u, v) = (rng.next_f64(), rng.next_f64());
            let target = if u + v <= 1.0 {
                a + (b - a) * u + (c - a) * v
            } else {
                a + (b - a) * (1.0 - u) + (c - a) * (1.0 - v)
            };
            let (origin, dir) = match i % 7 {
                0 => (target - DVec3::X * 3.0, DVec3::X),
                1 => (target + DVec3::Y * 3.0, -DVec3::Y),
                2 => (random_in_cube(&mut rng) * 3.0, random_in_cube(&mut rng).normalize()),
                _ => {
                    let origin = random_in_cube(&mut rng) * 3.0;
                    (origin, (target - origin).normalize())
                }
            };
            match (bvh.ray_cast(origin, dir), brute::ray_cast(&corners, origin, dir)) {
                (Some(fast), Some(slow)) => {
                    hits += 1;
                    assert_relative_eq(fast.distance, slow.distance, 1e-12, "ray parameter");
                    // The hit point from barycentrics and from t agree up to the triangle's
                    // conditioning: slivers (rounded collinear corners) amplify rounding.
                    let [a, b, c] = corners[fast.face as usize];
                    let sine =
                        (b - a).cross(c - a).length() / ((b - a).length() * (c - a).length());
                    let gap = fast.position.distance(origin + dir * fast.distance);
                    assert!(
                        gap <= 1e-11 * (1.0 + fast.distance) / sine,
                        "gap {gap}, t {}, sine {sine}",
                        fast.distance
                    );
                }
                (None, None) => {}
                (fast, slow) => panic!("ray {origin} {dir}: BVH {fast:?}, brute force {slow:?}"),
            }
        }
        assert!(hits > 1000, "the test rays must mostly hit ({hits})");
    }
}

#[test]
fn unusable_meshes_are_errors_not_panics() {
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(matches!(SurfaceBvh::build(&p, &[]), Err(SurfaceError::EmptyMesh)));
    assert!(matches!(
        SurfaceBvh::build(&p, &[[0, 1, 3]]),
        Err(SurfaceError::IndexOutOfRange { face: 0, index: 3, vertices: 3 })
    ));
    let nan = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(matches!(
        SurfaceBvh::build(&nan, &[[0, 1, 2]]),
        Err(SurfaceError::NonFinitePosition { vertex: 1 })
    ));
    // A mesh made only of degenerate triangles still answers exactly.
    let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
    let hit = SurfaceBvh::build(&flat, &[[0, 1, 2]])
        .unwrap()
        .closest_point(DVec3::new(1.5, 1.0, 0.0))
        .unwrap();
    assert!(
        (hit.distance - 1.0).abs() < 1e-15
            && hit.position.distance(DVec3::new(1.5, 0.0, 0.0)) < 1e-15
    );
}

#[test]
fn tracking_the_vertices_reproduces_their_trajectories_exactly() {
    let seq = sequence(3, 12, bend);
    let points: Vec<(String, [f64; 3])> = seq.frames[0]
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("v{i}"), p.map(f64::from)))
        .collect();
    let report = track(&seq.faces, &seq.frames, &Queries::Points(points), 0.0).unwrap();
    assert!(report.unbound.is_empty());
    assert_eq!(report.points.len(), seq.frames[0].len());
    for (i, point) in report.points.iter().enumerate() {
        assert_eq!(point.binding.distance, 0.0);
        for (t, position) in point.trajectory.iter().enumerate() {
            assert_eq!(*position, seq.frames[t][i].map(f64::from), "vertex {i}, frame {t}");
        }
    }
}

#[test]
fn random_surface_points_follow_the_analytic_motion() {
    let seq = sequence(4, 10, affine);
    let mut rng = SplitMix64::new(13);
    let mut points = Vec::new();
    for i in 0..500 {
        // A uniform point of a random face of frame 0, pushed off the surface a little.
        let face = seq.faces[(rng.next_u32() as usize) % seq.faces.len()];
        let (mut u, mut v) = (rng.next_f64(), rng.next_f64());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [a, b, c] = face.map(|k| DVec3::from(seq.frames[0][k as usize].map(f64::from)));
        let normal = (b - a).cross(c - a).normalize();
        let offset = if i % 2 == 0 { 0.0 } else { 1e-4 };
        points.push((
            format!("p{i}"),
            (a * (1.0 - u - v) + b * u + c * v + normal * offset).to_array(),
        ));
    }
    let report = track(&seq.faces, &seq.frames, &Queries::Points(points.clone()), 0.001).unwrap();
    assert!(report.unbound.is_empty());
    for (point, (_, query)) in report.points.iter().zip(&points) {
        assert!(point.binding.distance <= 1.0001e-4);
        // The bound surface point moves exactly as the motion moves it.
        let surface0 = DVec3::from(point.trajectory[0]);
        for (t, position) in point.trajectory.iter().enumerate() {
            let expected = affine(t as f64, surface0);
            assert!(
                expected.distance(DVec3::from(*position)) < 1e-5,
                "{} frame {t}: {position:?} vs {expected}",
                point.id
            );
        }
        assert!(surface0.distance(DVec3::from(*query)) <= 1.0001e-4);
    }
}

#[test]
fn points_off_the_surface_are_reported_not_snapped() {
    let seq = sequence(3, 3, affine);
    let points = vec![
        ("near".to_string(), [1.001, 0.0, 0.0]),
        ("far".to_string(), [3.0, 0.0, 0.0]),
        ("inf".to_string(), [f64::INFINITY, 0.0, 0.0]),
    ];
    let report = track(&seq.faces, &seq.frames, &Queries::Points(points), 0.01).unwrap();
    assert_eq!(report.points.iter().map(|p| p.id.as_str()).collect::<Vec<_>>(), vec!["near"]);
    assert_eq!(
        report.unbound.iter().map(|p| p.id.as_str()).collect::<Vec<_>>(),
        vec!["far", "inf"]
    );
    // The ellipsoid's x radius is 1 (up to f32 rounding and the facets): 2 units away.
    let far = report.unbound[0].distance.unwrap();
    assert!((far - 2.0).abs() < 1e-3, "{far}");
    assert!(report.unbound[1].distance.is_none());
}

/// A camera at `eye` looking at the origin, OpenCV axes (x right, y down, z forward).
fn look_at_origin(eye: DVec3, size: u32) -> Camera {
    let forward = (-eye).normalize();
    let right = forward.cross(DVec3::Z).normalize();
    let down = forward.cross(right);
    let rotation = glam::DMat3::from_cols(right, down, forward).transpose();
    let world_to_camera = DMat4::from_mat3_translation(rotation, -(rotation * eye));
    Camera::new(
        size,
        size,
        size as f64,
        size as f64,
        size as f64 / 2.0,
        size as f64 / 2.0,
        world_to_camera,
    )
    .unwrap()
}

#[test]
fn pixels_bind_where_their_rays_first_hit_the_surface() {
    let seq = sequence(4, 5, affine);
    let camera = look_at_origin(DVec3::new(3.0, -2.0, 1.0), 64);
    let pixels: Vec<(String, [f64; 2])> = (0..64)
        .flat_map(|j| (0..64).map(move |i| (format!("{i}_{j}"), [i as f64 + 0.5, j as f64 + 0.5])))
        .collect();
    let report =
        track(&seq.faces, &seq.frames, &Queries::Pixels { camera, pixels: pixels.clone() }, 0.0)
            .unwrap();
    assert!(
        report.points.len() > 300 && report.unbound.len() > 300,
        "{} hits, {} misses",
        report.points.len(),
        report.unbound.len()
    );
    let corners = brute::corners_f64(&triangles(&seq.frames[0], &seq.faces).unwrap());
    let by_id: std::collections::HashMap<&str, [f64; 2]> =
        pixels.iter().map(|(id, uv)| (id.as_str(), *uv)).collect();
    for point in &report.points {
        let [u, v] = by_id[point.id.as_str()];
        let hit = DVec3::from(point.trajectory[0]);
        // The hit projects back onto its pixel centre and is the nearest hit along the ray.
        let projected = camera.project(hit).unwrap();
        assert!(
            (projected.x - u).abs() < 1e-6 && (projected.y - v).abs() < 1e-6,
            "{} -> {projected}",
            point.id
        );
        let (origin, dir) = camera.pixel_ray(u, v);
        let nearest = brute::ray_cast(&corners, origin, dir).unwrap();
        assert!(nearest.position.distance(hit) < 1e-9);
    }
    for missed in &report.unbound {
        let [u, v] = by_id[missed.id.as_str()];
        let (origin, dir) = camera.pixel_ray(u, v);
        assert!(brute::ray_cast(&corners, origin, dir).is_none(), "{} should hit", missed.id);
    }
}

/// `tagsplat track` on `dir`'s `frames/` and `points.csv`, writing `tracks.csv`, `.json` and
/// `.svg` into `out`, with `extra` arguments after those.
fn track_cli<'a>(
    dir: &Path,
    out: &Path,
    extra: impl IntoIterator<Item = &'a std::ffi::OsStr>,
) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"))
        .args(["track", "--sequence"])
        .arg(dir.join("frames"))
        .arg("--points")
        .arg(dir.join("points.csv"))
        .arg("--out")
        .arg(out.join("tracks.csv"))
        .arg("--json")
        .arg(out.join("tracks.json"))
        .arg("--plot")
        .arg(out.join("tracks.svg"))
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn cli_tracks_points_of_a_folder_sequence_into_csv_json_and_png() {
    let dir = temp_dir("cli-track");
    let seq = sequence(3, 6, bend);
    seq.write_folder(&dir.join("frames"), tagsplat::sequence::FrameFormat::Ply).unwrap();
    let csv: String = "id,x,y,z\n".to_string()
        + &[0usize, 17, 40]
            .iter()
            .map(|&v| {
                let p = seq.frames[0][v];
                // The f64 spelling of the f32 coordinates, so the points are the vertices exactly.
                format!("vertex{v},{},{},{}\n", p[0] as f64, p[1] as f64, p[2] as f64)
            })
            .collect::<String>();
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    let run = |extra: &[&str]| track_cli(&dir, &dir, extra.iter().map(|a| a.as_ref()));
    let out = run(&[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let tracks = std::fs::read_to_string(dir.join("tracks.csv")).unwrap();
    let mut lines = tracks.lines();
    assert_eq!(lines.next(), Some("id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame"));
    let rows: Vec<Vec<String>> =
        lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    assert_eq!(rows.len(), 3 * 6);
    for row in &rows {
        let v: usize = row[0].trim_start_matches("vertex").parse().unwrap();
        let t: usize = row[1].parse().unwrap();
        let xyz: Vec<f64> = row[2..5].iter().map(|s| s.parse().unwrap()).collect();
        assert_eq!(xyz, seq.frames[t][v].map(f64::from).to_vec(), "vertex {v} frame {t}");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("tracks.json")).unwrap()).unwrap();
    assert_eq!(json["points"].as_array().unwrap().len(), 3);
    assert_eq!(json["points"][0]["distance"], 0.0);
    assert!(json["points"][0]["face"].as_u64().unwrap() < seq.faces.len() as u64);
    let plot = std::fs::read_to_string(dir.join("tracks.svg")).unwrap();
    assert!(plot.starts_with("<svg") && plot.contains(">frame<"), "{plot}");
    // Through a camera: pixel coordinates are the camera's projection; visible is what a
    // brute-force ray cast over every triangle of the frame says.
    let eye = DVec3::new(0.3, -0.2, -6.0);
    let camera =
        Camera::look_at(80, 60, 70.0, 70.0, 40.0, 30.0, eye, DVec3::ZERO, DVec3::NEG_Y).unwrap();
    camera.save_json(&dir.join("cam.json")).unwrap();
    let by_z = |a: &&[f32; 3], b: &&[f32; 3]| a[2].total_cmp(&b[2]);
    let (near, far) =
        (seq.frames[0].iter().min_by(by_z).unwrap(), seq.frames[0].iter().max_by(by_z).unwrap());
    let vertex = |p: &[f32; 3]| seq.frames[0].iter().position(|q| q == p).unwrap();
    let row = |p: &[f32; 3]| {
        format!("vertex{},{},{},{}\n", vertex(p), p[0] as f64, p[1] as f64, p[2] as f64)
    };
    std::fs::write(dir.join("points.csv"), format!("id,x,y,z\n{}{}", row(near), row(far))).unwrap();
    let cam = dir.join("cam.json");
    assert!(run(&["--camera", cam.to_str().unwrap()]).status.success());
    let image_rows = std::fs::read_to_string(dir.join("tracks.2d.csv")).unwrap();
    let mut lines = image_rows.lines();
    assert_eq!(lines.next(), Some("id,frame,u,v,visible"));
    let (mut seen, mut hidden) = (0, 0);
    for row in lines.map(|l| l.split(',').collect::<Vec<_>>()) {
        let v: usize = row[0].trim_start_matches("vertex").parse().unwrap();
        let t: usize = row[1].parse().unwrap();
        let p = DVec3::from(seq.frames[t][v].map(f64::from));
        let uv = camera.project(p).unwrap();
        assert_eq!((row[2].parse::<f64>().unwrap(), row[3].parse::<f64>().unwrap()), (uv.x, uv.y));
        let corners = brute::corners_f64(&triangles(&seq.frames[t], &seq.faces).unwrap());
        let to = p - eye;
        let first = brute::ray_cast(&corners, eye, to.normalize()).unwrap().distance;
        let visible = first > to.length() * (1.0 - 1e-4);
        assert_eq!(row[4] == "1", visible, "vertex {v} frame {t}");
        if visible {
            seen += 1
        } else {
            hidden += 1
        }
    }
    assert!(seen > 0 && hidden > 0, "{seen} visible, {hidden} hidden: both cases covered");
    // A point far away is listed (stderr, tracks.unbound.csv, the JSON) and the others tracked;
    // --strict refuses the run instead.
    std::fs::write(dir.join("points.csv"), "id,x,y,z\nok,1,0,0\nmoon,50,0,0\n").unwrap();
    let partial = run(&[]);
    let stderr = String::from_utf8_lossy(&partial.stderr);
    assert!(partial.status.success() && stderr.contains("point moon not bound"), "{stderr}");
    assert!(stderr.contains("1 of 2 points not bound"), "{stderr}");
    assert!(String::from_utf8_lossy(&partial.stdout).contains("tracked 1 of 2 points"));
    let tracked = std::fs::read_to_string(dir.join("tracks.csv")).unwrap();
    assert!(tracked.lines().skip(1).all(|row| row.starts_with("ok,")), "{tracked}");
    let unbound = std::fs::read_to_string(dir.join("tracks.unbound.csv")).unwrap();
    let rows: Vec<Vec<&str>> = unbound.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows[0], ["id", "distance", "tolerance", "reason"]);
    let (distance, tolerance): (f64, f64) =
        (rows[1][1].parse().unwrap(), rows[1][2].parse().unwrap());
    assert!(
        rows.len() == 2 && rows[1][0] == "moon" && distance > 48.0 && tolerance < 0.1,
        "{unbound}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("tracks.json")).unwrap()).unwrap();
    assert_eq!(json["unbound"][0]["id"], "moon");
    let failed = run(&["--strict"]);
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(!failed.status.success() && stderr.contains("--strict refuses"), "{stderr}");
    // Once every point binds, the earlier list goes.
    std::fs::write(dir.join("points.csv"), "id,x,y,z\nok,1,0,0\n").unwrap();
    assert!(run(&[]).status.success() && !dir.join("tracks.unbound.csv").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two `tagsplat track` processes on the same sequence, points and camera write the same
/// files byte for byte: tracks, JSON report, image tracks, unbound list, USD and plot.
#[test]
fn track_cli_twice_on_the_same_input_writes_the_same_files() {
    let dir = temp_dir("track-rerun");
    let seq = sequence(3, 8, bend);
    seq.write_folder(&dir.join("frames"), tagsplat::sequence::FrameFormat::Ply).unwrap();
    // 300 points on random faces at random barycentrics, a little off the surface, and two
    // too far from it to bind.
    let mut rng = common::rng(21);
    let mut csv = String::from("id,x,y,z\n");
    for i in 0..300 {
        let face = seq.faces[(rng.next_f64() * seq.faces.len() as f64) as usize];
        let [a, b, c] = face.map(|v| DVec3::from(seq.frames[0][v as usize].map(f64::from)));
        let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
        let normal = (b - a).cross(c - a).normalize();
        let p = a * (1.0 - r1)
            + b * (r1 * (1.0 - r2))
            + c * (r1 * r2)
            + normal * (0.02 * rng.next_f64() - 0.01);
        csv += &format!("p{i},{},{},{}\n", p.x, p.y, p.z);
    }
    csv += "far1,5,0,0\nfar2,0,-3,1\n";
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    let eye = DVec3::new(0.3, -0.2, -6.0);
    let camera =
        Camera::look_at(80, 60, 70.0, 70.0, 40.0, 30.0, eye, DVec3::ZERO, DVec3::NEG_Y).unwrap();
    camera.save_json(&dir.join("cam.json")).unwrap();
    let run = |out: &str| {
        let out = dir.join(out);
        std::fs::create_dir_all(&out).unwrap();
        let camera = dir.join("cam.json");
        let usd = out.join("tracks.usda");
        let extra = ["--camera".as_ref(), camera.as_os_str(), "--usd".as_ref(), usd.as_os_str()];
        let output = track_cli(&dir, &out, extra);
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        assert!(stdout.contains("tracked 300 of 302 points"), "{stdout}");
        out
    };
    let (a, b) = (run("a"), run("b"));
    let names = common::file_names(&a);
    let expected = [
        "tracks.2d.csv",
        "tracks.csv",
        "tracks.json",
        "tracks.svg",
        "tracks.unbound.csv",
        "tracks.usda",
    ];
    assert_eq!(names, expected.map(std::path::PathBuf::from));
    assert_eq!(common::file_names(&b), names);
    for name in &names {
        let (x, y) = (std::fs::read(a.join(name)).unwrap(), std::fs::read(b.join(name)).unwrap());
        assert!(x == y, "{} differs between the runs", name.display());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--data DIR --camera NAME` projects into the dataset's camera of that name: the same 2D
/// tracks as its cam.json given directly; an unknown name is refused with the names there are.
#[test]
fn track_cli_takes_a_dataset_camera_by_name() {
    use tagsplat::synth::{generate, SubjectSource, SynthOptions};
    let dir = temp_dir("track-dataset-camera");
    let data = dir.join("data");
    let o = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 2 },
        views: 4,
        frames: 2,
        width: 16,
        height: 16,
        samples: 1,
        track_vertices: 4,
        track_surface: 4,
        ..Default::default()
    };
    generate(&o, &data).unwrap();
    let track = |camera: &[&std::ffi::OsStr], out: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"))
            .args(["track".as_ref(), "--sequence".as_ref(), data.join("meshes").as_os_str()])
            .args(["--points".as_ref(), data.join("points.csv").as_os_str()])
            .args(["--out".as_ref(), dir.join(out).as_os_str()])
            .args(camera)
            .output()
            .unwrap()
    };
    let cam_json = data.join("cameras/cam001.json");
    let by_file = track(&["--camera".as_ref(), cam_json.as_os_str()], "file.csv");
    let by_name = track(
        &["--data".as_ref(), data.as_os_str(), "--camera".as_ref(), "cam001".as_ref()],
        "name.csv",
    );
    for run in [&by_file, &by_name] {
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    }
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
    assert_eq!(read("file.2d.csv"), read("name.2d.csv"));
    assert!(read("name.2d.csv").len() > 100);
    let unknown = track(
        &["--data".as_ref(), data.as_os_str(), "--camera".as_ref(), "cam9".as_ref()],
        "x.csv",
    );
    let stderr = String::from_utf8_lossy(&unknown.stderr);
    assert!(!unknown.status.success() && stderr.contains("no camera named 'cam9'"), "{stderr}");
    assert!(stderr.contains("cam000, cam001, cam002, cam003"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--overlay DIR` with `--data DIR --camera NAME`: one PNG per frame, the camera's image with
/// each point drawn in its plot colour. A visible point far from the others shows its colour
/// at its pixel; a pixel far from every point keeps the footage's value.
#[test]
fn track_cli_draws_the_points_over_the_cameras_images() {
    use tagsplat::io::image::read_image;
    use tagsplat::synth::{generate, SubjectSource, SynthOptions};
    use tagsplat::track::overlay::{mark_colour, mark_radius};
    let dir = temp_dir("track-overlay");
    let data = dir.join("data");
    let o = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 2 },
        views: 4,
        frames: 3,
        width: 64,
        height: 64,
        samples: 1,
        track_vertices: 3,
        track_surface: 3,
        ..Default::default()
    };
    generate(&o, &data).unwrap();
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"))
        .args(["track".as_ref(), "--sequence".as_ref(), data.join("meshes").as_os_str()])
        .args(["--points".as_ref(), data.join("points.csv").as_os_str()])
        .args(["--out".as_ref(), dir.join("tracks.csv").as_os_str()])
        .args(["--data".as_ref(), data.as_os_str(), "--camera".as_ref(), "cam001".as_ref()])
        .args(["--overlay".as_ref(), dir.join("overlay").as_os_str()])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let rows: Vec<(usize, f64, f64, bool)> = std::fs::read_to_string(dir.join("tracks.2d.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let number = |s: &str| s.parse::<f64>().unwrap_or(f64::NAN);
            (f[1].parse().unwrap(), number(f[2]), number(f[3]), f[4] == "1")
        })
        .collect();
    let points = rows.len() / 3;
    let footage = tagsplat::dataset::Dataset::load(&data).unwrap();
    let radius = mark_radius(64, 64);
    let mut checked = 0;
    for t in 0..3 {
        let overlay = read_image(&dir.join(format!("overlay/{t:06}.png"))).unwrap();
        assert_eq!((overlay.width, overlay.height, overlay.channels), (64, 64, 3));
        let frame = &rows[t * points..(t + 1) * points];
        let near = |x: f64, y: f64, skip: usize, reach: f64| {
            frame.iter().enumerate().any(|(j, r)| j != skip && (r.1 - x).hypot(r.2 - y) <= reach)
        };
        for (i, &(f, u, v, visible)) in frame.iter().enumerate() {
            assert_eq!(f, t);
            if visible && !near(u, v, i, 2.0 * radius + 2.0) {
                let (x, y) = (u.floor() as u32, v.floor() as u32);
                let pixel = [0, 1, 2].map(|c| overlay.at(x, y, c));
                let want = mark_colour(i);
                assert!(
                    pixel.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6),
                    "frame {t} point {i}: {pixel:?} against {want:?}"
                );
                checked += 1;
            }
        }
        let view = footage.frames[t].views.iter().position(|v| v.camera == 1).unwrap();
        let image = footage.image(t, view).unwrap();
        let (x, y) = (0..64 * 64)
            .map(|p| (p % 64, p / 64))
            .find(|&(x, y)| !near(x as f64 + 0.5, y as f64 + 0.5, usize::MAX, radius + 1.0))
            .unwrap();
        for c in 0..3 {
            let source = (image.at(x, y, c).clamp(0.0, 1.0) * 255.0).round() / 255.0;
            assert!((overlay.at(x, y, c) - source).abs() < 1e-6, "footage at ({x}, {y})");
        }
    }
    assert!(checked >= 3, "only {checked} visible points lie apart from the others");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A triangle turning about a tilted axis and moving: its corners at frame t are R(t)·p + c(t).
fn turning_triangle(t: f64) -> (glam::DMat3, [DVec3; 3]) {
    let rotation = glam::DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.4 * t);
    let corners = [[0.3, -0.2, 0.1], [1.2, 0.4, -0.3], [-0.1, 0.9, 0.5]]
        .map(|p| rotation * DVec3::from(p) + DVec3::new(0.2 * t, -0.1 * t, 0.05 * t * t));
    (rotation, corners)
}

#[test]
fn orientation_frames_of_a_turning_triangle_follow_its_rotation() {
    let frames: Vec<Vec<[f32; 3]>> = (0..12)
        .map(|t| turning_triangle(t as f64).1.iter().map(|p| p.as_vec3().to_array()).collect())
        .collect();
    let given = vec![(
        "p".to_string(),
        tagsplat::track::Binding { face: 0, barycentric: [0.2, 0.3, 0.5], distance: 0.0 },
    )];
    let report = track(&[[0, 1, 2]], &frames, &Queries::Bindings(given), 0.0).unwrap();
    let point = &report.points[0];
    assert!(point.orientation_held.is_empty());
    // The analytic frame: R(t) applied to frame 0's normal and first edge, in f64 from the
    // unrounded corners; the tracked one comes from f32 corners.
    let [p0, p1, p2] = turning_triangle(0.0).1;
    let (normal0, tangent0) = ((p1 - p0).cross(p2 - p0).normalize(), (p1 - p0).normalize());
    let mut worst: f64 = 0.0;
    for t in 0..frames.len() {
        let (rotation, _) = turning_triangle(t as f64);
        let (normal, tangent) = (DVec3::from(point.normal[t]), DVec3::from(point.tangent[t]));
        worst = worst
            .max(normal.distance(rotation * normal0))
            .max(tangent.distance(rotation * tangent0));
        assert!((normal.length() - 1.0).abs() < 1e-15 && normal.dot(tangent).abs() < 1e-15);
        // The quaternion takes X, Y, Z to tangent, normal × tangent, normal.
        let q = glam::DQuat::from_array(point.surface_frame(t).unwrap().rotation());
        assert!((q * DVec3::X).distance(tangent) < 1e-14, "frame {t}");
        assert!((q * DVec3::Y).distance(normal.cross(tangent)) < 1e-14, "frame {t}");
        assert!((q * DVec3::Z).distance(normal) < 1e-14, "frame {t}");
    }
    // f32 corners of size ~1 move the normal by a few f32 epsilons.
    assert!(worst < 1e-6, "{worst}");
    eprintln!("largest orientation difference from the analytic rotation: {worst:e}");
}

#[test]
fn a_triangle_that_collapses_holds_its_last_orientation_without_nan() {
    let triangle =
        |squash: f32| vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, squash, 1.0 - squash]];
    let frames = vec![triangle(1.0), triangle(0.5), [[0.0; 3]; 3].to_vec(), triangle(1.0)];
    let given = vec![(
        "p".to_string(),
        tagsplat::track::Binding { face: 0, barycentric: [1.0, 0.0, 0.0], distance: 0.0 },
    )];
    let report = track(&[[0, 1, 2]], &frames, &Queries::Bindings(given), 0.0).unwrap();
    let point = &report.points[0];
    assert_eq!(point.orientation_held, [2]);
    assert_eq!((point.normal[2], point.tangent[2]), (point.normal[1], point.tangent[1]));
    assert!(point.normal.iter().chain(&point.tangent).flatten().all(|c| c.is_finite()));
}

/// The bindings of `report`, written and read back, on a sequence of `faces` and `vertices`.
fn bindings_round_trip(
    dir: &Path,
    report: &tagsplat::track::TrackReport,
    faces: &[[u32; 3]],
    vertices: usize,
    polygon_of: Option<&[u32]>,
) -> Vec<(String, tagsplat::track::Binding)> {
    use tagsplat::track::bindings::{read_bindings, write_bindings_csv};
    let path = dir.join("bindings.csv");
    write_bindings_csv(&path, &report.points).unwrap();
    read_bindings(&path).unwrap().resolve(faces, vertices, polygon_of).unwrap()
}

#[test]
fn bindings_written_then_read_give_identical_trajectories_on_every_sequence_of_the_mesh() {
    let dir = temp_dir("bindings-round-trip");
    let (bent, moved) = (sequence(3, 8, bend), sequence(3, 5, affine));
    assert_eq!(bent.faces, moved.faces, "two sequences of one mesh");
    let mut rng = SplitMix64::new(5);
    let points: Vec<(String, [f64; 3])> =
        (0..200).map(|i| (format!("p{i}"), (random_in_cube(&mut rng) * 1.2).to_array())).collect();
    let first = track(&bent.faces, &bent.frames, &Queries::Points(points), f64::INFINITY).unwrap();
    let vertices = bent.frames[0].len();
    let given = bindings_round_trip(&dir, &first, &bent.faces, vertices, None);
    let again = track(&bent.faces, &bent.frames, &Queries::Bindings(given.clone()), 0.0).unwrap();
    for (a, b) in first.points.iter().zip(&again.points) {
        assert_eq!(
            (&a.id, a.binding.face, a.binding.barycentric),
            (&b.id, b.binding.face, b.binding.barycentric)
        );
        assert_eq!((&a.trajectory, &a.normal, &a.tangent), (&b.trajectory, &b.normal, &b.tangent));
    }
    // On the other sequence, every frame's position is Σ bₖ·vₖ(t), summed here in f64.
    let other = track(&moved.faces, &moved.frames, &Queries::Bindings(given), 0.0).unwrap();
    for point in &other.points {
        let face = moved.faces[point.binding.face as usize];
        for (t, frame) in moved.frames.iter().enumerate() {
            let mut expected = [0.0; 3];
            for (k, &v) in face.iter().enumerate() {
                for (e, &c) in expected.iter_mut().zip(&frame[v as usize]) {
                    *e += point.binding.barycentric[k] * f64::from(c);
                }
            }
            let got = point.trajectory[t];
            assert!(
                (0..3).all(|c| (got[c] - expected[c]).abs() <= 1e-15),
                "{} frame {t}",
                point.id
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_vertex_binding_tracks_that_vertex_exactly() {
    let dir = temp_dir("vertex-bindings");
    let seq = sequence(2, 6, bend);
    let vertices = seq.frames[0].len();
    let rows: String = (0..vertices).map(|v| format!("v{v},{v}\n")).collect();
    std::fs::write(dir.join("vertices.csv"), format!("id,vertex\n{rows}")).unwrap();
    let file = tagsplat::track::bindings::read_bindings(&dir.join("vertices.csv")).unwrap();
    let given = file.resolve(&seq.faces, vertices, None).unwrap();
    let report = track(&seq.faces, &seq.frames, &Queries::Bindings(given), 0.0).unwrap();
    assert_eq!(report.points.len(), vertices);
    for (v, point) in report.points.iter().enumerate() {
        for (t, frame) in seq.frames.iter().enumerate() {
            assert_eq!(point.trajectory[t], frame[v].map(f64::from), "vertex {v} frame {t}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bindings_on_a_polygon_mesh_name_their_polygon_and_refuse_another_fanning() {
    use tagsplat::sequence::SourceSequence;
    let dir = temp_dir("polygon-bindings");
    // Three quads in a row (a 4 × 2 grid of vertices), each fanned into two triangles.
    let grid: Vec<[f32; 3]> = (0..8).map(|i| [(i % 4) as f32, (i / 4) as f32, 0.0]).collect();
    let source = SourceSequence {
        counts: vec![4, 4, 4],
        indices: vec![0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6],
        frames: vec![grid.clone(), grid.iter().map(|p| [p[0], p[1], p[0] * p[1]]).collect()],
        times: vec![0.0, 0.5],
        ..SourceSequence::default()
    };
    let (seq, info) = source.into_sequence().unwrap();
    let polygon_of = info.polygon_of.unwrap();
    assert_eq!(polygon_of, [0, 0, 1, 1, 2, 2]);
    // A point inside each quad, on either of its triangles.
    let points = (0..3).map(|q| (format!("quad{q}"), [q as f64 + 0.7, 0.4, 0.0])).collect();
    let report = track(&seq.faces, &seq.frames, &Queries::Points(points), 0.0)
        .unwrap()
        .in_polygons(&polygon_of)
        .unwrap();
    assert_eq!(report.points.iter().map(|p| p.polygon).collect::<Vec<_>>(), [0, 1, 2]);
    let given = bindings_round_trip(&dir, &report, &seq.faces, 8, Some(&polygon_of));
    assert_eq!(given.len(), 3);
    // Read as if the triangles were the file's faces, the polygon column disagrees.
    let file = tagsplat::track::bindings::read_bindings(&dir.join("bindings.csv")).unwrap();
    let error = file.resolve(&seq.faces, 8, None).unwrap_err().to_string();
    assert!(
        error.contains("bindings.csv: line 3: ") && error.contains("not in polygon 1"),
        "{error}"
    );
    assert!(report.in_polygons(&[0, 0]).is_err(), "a map of the wrong length");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The JSON chunk of a GLB and the floats of its accessor `index` (tightly packed).
fn glb_floats(bytes: &[u8], index: usize) -> (serde_json::Value, Vec<f32>) {
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let json_length = word(12);
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
    let bin = &bytes[20 + json_length + 8..];
    let accessor = &json["accessors"][index];
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let length = view["byteLength"].as_u64().unwrap() as usize;
    let floats = bin[start..start + length]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (json, floats)
}

#[test]
fn cli_writes_oriented_tracks_a_valid_pins_glb_and_bindings_that_track_the_same() {
    let dir = temp_dir("cli-pins");
    let seq = sequence(3, 6, bend);
    seq.write_folder(&dir.join("frames"), tagsplat::sequence::FrameFormat::Ply).unwrap();
    std::fs::write(
        dir.join("points.csv"),
        "id,x,y,z\nside,1,0,0\nmid,0.3769,0.3769,0.3769\nfront,0,0,0.5\n",
    )
    .unwrap();
    let (glb, bindings) = (dir.join("pins.glb"), dir.join("bindings.csv"));
    let out = track_cli(
        &dir,
        &dir,
        ["--glb".as_ref(), glb.as_os_str(), "--bindings-out".as_ref(), bindings.as_os_str()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("tracks.json")).unwrap()).unwrap();
    assert_eq!((json["fps"].as_f64(), json["start_frame"].as_f64()), (Some(24.0), Some(0.0)));
    let tracks = std::fs::read_to_string(dir.join("tracks.csv")).unwrap();
    let mut lines = tracks.lines();
    assert_eq!(lines.next(), Some("id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 3 * 6);
    for row in &rows {
        let point = json["points"].as_array().unwrap().iter().find(|p| p["id"] == row[0]).unwrap();
        let t: usize = row[1].parse().unwrap();
        let number = |k: usize| row[k].parse::<f64>().unwrap();
        for (column, field) in [(2, "trajectory"), (5, "normal"), (8, "tangent")] {
            let expected: Vec<f64> = (0..3).map(|c| point[field][t][c].as_f64().unwrap()).collect();
            assert_eq!((column..column + 3).map(number).collect::<Vec<_>>(), expected);
        }
        assert_eq!((number(11), number(12), number(13)), (t as f64 / 24.0, 24.0, 0.0));
        assert_eq!(point["polygon"], point["face"], "a triangle mesh's polygons are its faces");
    }
    // The GLB: valid, one node per point named by its id, keyed at every frame's time with the
    // CSV's positions (as f32) and rotations that take Y (glTF's up) to the normal.
    common::validate_gltf(&glb);
    let bytes = std::fs::read(&glb).unwrap();
    let (gltf, times) = glb_floats(&bytes, 0);
    assert_eq!(times, (0..6).map(|t| (t as f64 / 24.0) as f32).collect::<Vec<_>>());
    let names: Vec<&str> =
        gltf["nodes"].as_array().unwrap().iter().map(|n| n["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["side", "mid", "front"]);
    for (n, point) in json["points"].as_array().unwrap().iter().enumerate() {
        let (_, translations) = glb_floats(&bytes, 1 + 2 * n);
        let (_, rotations) = glb_floats(&bytes, 2 + 2 * n);
        for t in 0..6 {
            let position: Vec<f32> =
                (0..3).map(|c| point["trajectory"][t][c].as_f64().unwrap() as f32).collect();
            assert_eq!(translations[3 * t..3 * t + 3], position[..]);
            let q = glam::Quat::from_slice(&rotations[4 * t..4 * t + 4]).as_dquat();
            let normal = DVec3::new(
                point["normal"][t][0].as_f64().unwrap(),
                point["normal"][t][1].as_f64().unwrap(),
                point["normal"][t][2].as_f64().unwrap(),
            );
            assert!((q * DVec3::Y).distance(normal) < 1e-6, "{} frame {t}", point["id"]);
        }
    }
    // The bindings written back track the same: the same CSV byte for byte.
    let track_bindings = || {
        std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"))
            .args(["track", "--sequence"])
            .arg(dir.join("frames"))
            .arg("--bindings")
            .arg(&bindings)
            .arg("--out")
            .arg(dir.join("again.csv"))
            .output()
            .unwrap()
    };
    let again = track_bindings();
    assert!(again.status.success(), "{}", String::from_utf8_lossy(&again.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("again.csv")).unwrap(), tracks);
    // A binding off the mesh names the file, the line and the problem.
    std::fs::write(&bindings, "id,face,u,v,w\nok,0,1,0,0\nfar,99999,1,0,0\n").unwrap();
    let bad = track_bindings();
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success()
            && stderr.contains("bindings.csv: line 3: face 99999 is out of range"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
