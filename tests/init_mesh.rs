//! The initial mesh from masks, checked against ground truth: on a convex subject (an
//! ellipsoid rendered here) the mesh is a closed genus-0 manifold in one piece, near the true
//! surface (Chamfer), with about the wanted vertex count and colours near the true texture;
//! the articulated generator subject gets a looser bound (a hull cannot carve concavities);
//! noisy masks with a tolerated view; and every kind of bad input gets its error.

use glam::DVec3;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use tagsplat::camera::Camera;
use tagsplat::dataset::own::{self, OwnMeta};
use tagsplat::dataset::Dataset;
use tagsplat::eval::chamfer_meshes;
use tagsplat::geometry::SurfaceBvh;
use tagsplat::init::{init_mesh, init_mesh_from_views, HullView, InitError, InitMesh, InitOptions};
use tagsplat::io::image::{write_png, Image};
use tagsplat::mesh::TriMesh;
use tagsplat::synth::icosphere::icosphere;
use tagsplat::synth::manifold::closed_manifold_problem;
use tagsplat::synth::{generate, render, SubjectSource, SynthOptions, Texture};
use tagsplat::topology::{vertex_normals, ManifoldMesh};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-init-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The ellipsoid subject: semi-axes 1, 0.7, 0.55 about (0.3, −0.2, 0.1), 2562 vertices.
fn ellipsoid() -> TriMesh {
    let (p, faces) = icosphere(4);
    let positions = p
        .iter()
        .map(|q| [(0.3 + q[0]) as f32, (-0.2 + 0.7 * q[1]) as f32, (0.1 + 0.55 * q[2]) as f32])
        .collect();
    TriMesh { positions, faces, colors: None }
}

/// `views` cameras on a ring around `center` at 4 radii, elevations alternating ±25°.
fn ring(views: usize, resolution: u32, center: DVec3, radius: f64) -> Vec<Camera> {
    let distance = 4.0 * radius;
    let focal = 0.5 * resolution as f64 * 0.9 / (radius / distance).asin().tan();
    let half = 0.5 * resolution as f64;
    (0..views)
        .map(|k| {
            let azimuth = std::f64::consts::TAU * (k as f64 + 0.3) / views as f64;
            let elevation = if k % 2 == 0 { 25f64 } else { -25.0 }.to_radians();
            let dir = DVec3::new(
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
                elevation.cos() * azimuth.cos(),
            );
            Camera::look_at(
                resolution,
                resolution,
                focal,
                focal,
                half,
                half,
                center + distance * dir,
                center,
                DVec3::Y,
            )
            .unwrap()
        })
        .collect()
}

/// Writes `mesh` seen by `cameras` as a one-frame dataset in the own layout (images coloured
/// by the generator's texture at the mesh positions, anti-aliased masks).
fn write_dataset(dir: &Path, mesh: &TriMesh, cameras: &[Camera]) -> Texture {
    let texture = Texture::fit(&mesh.positions);
    let names: Vec<String> = (0..cameras.len()).map(|k| format!("cam{k:02}")).collect();
    for (camera, name) in cameras.iter().zip(&names) {
        for sub in ["images", "masks"] {
            std::fs::create_dir_all(dir.join(sub).join(name)).unwrap();
        }
        std::fs::create_dir_all(dir.join("cameras")).unwrap();
        camera.save_json(&own::camera_path(dir, name)).unwrap();
        let r = render(camera, &mesh.positions, &mesh.positions, &mesh.faces, &texture, 3).unwrap();
        write_png(
            &own::image_path(dir, name, 0),
            &Image { width: r.width, height: r.height, channels: 3, data: r.rgb },
        )
        .unwrap();
        write_png(
            &own::mask_path(dir, name, 0),
            &Image { width: r.width, height: r.height, channels: 1, data: r.alpha },
        )
        .unwrap();
    }
    let meta = OwnMeta {
        format: own::FORMAT_NAME.into(),
        version: 1,
        frames: 1,
        fps: 30.0,
        cameras: names,
        test_cameras: vec![],
    };
    std::fs::write(dir.join(own::META), serde_json::to_string(&meta).unwrap()).unwrap();
    texture
}

fn ellipsoid_dataset(name: &str, views: usize) -> (PathBuf, TriMesh, Texture) {
    let dir = temp(name);
    let mesh = ellipsoid();
    let texture = write_dataset(&dir, &mesh, &ring(views, 96, DVec3::new(0.3, -0.2, 0.1), 1.0));
    (dir, mesh, texture)
}

/// Views of the dataset's frame 0, as the library entry reads them.
fn views(dir: &Path) -> Vec<HullView> {
    let data = Dataset::load(dir).unwrap();
    (0..data.frames[0].views.len())
        .map(|k| HullView {
            name: data.camera_names[k].clone(),
            camera: data.cameras[k],
            mask: data.mask(0, k).unwrap(),
            image: Some(data.image(0, k).unwrap()),
        })
        .collect()
}

/// Connected components of a face list (faces sharing a vertex), by flood fill.
fn components(faces: &[[u32; 3]]) -> usize {
    let n = faces.iter().flatten().max().map_or(0, |&m| m as usize + 1);
    let mut adjacent = vec![Vec::new(); n];
    for f in faces {
        for k in 0..3 {
            adjacent[f[k] as usize].push(f[(k + 1) % 3] as usize);
            adjacent[f[(k + 1) % 3] as usize].push(f[k] as usize);
        }
    }
    let mut seen = vec![false; n];
    let mut count = 0;
    for start in 0..n {
        if seen[start] || adjacent[start].is_empty() {
            continue;
        }
        count += 1;
        let mut stack = vec![start];
        seen[start] = true;
        while let Some(v) = stack.pop() {
            for &w in &adjacent[v] {
                if !seen[w] {
                    seen[w] = true;
                    stack.push(w);
                }
            }
        }
    }
    count
}

/// V − E + F.
fn euler(mesh: &TriMesh) -> i64 {
    let edges: HashSet<(u32, u32)> = mesh
        .faces
        .iter()
        .flat_map(|f| (0..3).map(move |k| (f[k].min(f[(k + 1) % 3]), f[k].max(f[(k + 1) % 3]))))
        .collect();
    mesh.positions.len() as i64 - edges.len() as i64 + mesh.faces.len() as i64
}

/// The smallest angle of each face, degrees, sorted.
fn min_angles(mesh: &TriMesh) -> Vec<f64> {
    let p = |i: u32| DVec3::from(mesh.positions[i as usize].map(f64::from));
    let mut angles: Vec<f64> = mesh
        .faces
        .iter()
        .map(|f| {
            (0..3)
                .map(|k| {
                    (p(f[(k + 1) % 3]) - p(f[k]))
                        .angle_between(p(f[(k + 2) % 3]) - p(f[k]))
                        .to_degrees()
                })
                .fold(180.0, f64::min)
        })
        .collect();
    angles.sort_by(f64::total_cmp);
    angles
}

/// Closed, manifold, one piece, and the Chamfer mean distance to `truth` as a fraction of the
/// truth's bounding-box diagonal (20 000 samples on each).
fn check_and_chamfer(built: &InitMesh, truth: &TriMesh) -> f64 {
    let m = &built.mesh;
    assert_eq!(closed_manifold_problem(m.positions.len(), &m.faces), None);
    assert_eq!(components(&m.faces), 1);
    assert_eq!(built.report.vertices, m.positions.len());
    chamfer_meshes((&m.positions, &m.faces), (&truth.positions, &truth.faces), 20_000, 7)
        .unwrap()
        .mean_fraction
}

/// Mean absolute colour error (per channel, [0, 1]) of the vertices against the texture at
/// the closest true surface point, for vertices whose normal faces some camera within 60°
/// of its view direction (the regions the views see well).
fn color_error(
    built: &InitMesh,
    truth: &TriMesh,
    texture: &Texture,
    cameras: &[Camera],
) -> (f64, f64, usize) {
    let bvh = SurfaceBvh::build(&truth.positions, &truth.faces).unwrap();
    let m = &built.mesh;
    let colors = m.colors.as_ref().unwrap();
    let normals = vertex_normals(&ManifoldMesh::new(m.positions.clone(), m.faces.clone()).unwrap());
    let (mut err, mut flat, mut n) = (0.0, 0.0, 0);
    let truths: Vec<[f32; 3]> = m
        .positions
        .iter()
        .map(|p| texture.color(bvh.closest_point(DVec3::from(p.map(f64::from))).unwrap().position))
        .collect();
    let mean: Vec<f64> = (0..3)
        .map(|c| truths.iter().map(|t| t[c] as f64).sum::<f64>() / truths.len() as f64)
        .collect();
    for (v, p) in m.positions.iter().enumerate() {
        let p = DVec3::from(p.map(f64::from));
        let normal = DVec3::from(normals[v].map(f64::from));
        if !cameras.iter().any(|c| normal.dot((c.center() - p).normalize()) > 0.5) {
            continue;
        }
        for c in 0..3 {
            err += (colors[v][c] as f64 / 255.0 - truths[v][c] as f64).abs();
            flat += (mean[c] - truths[v][c] as f64).abs();
        }
        n += 1;
    }
    (err / (3 * n) as f64, flat / (3 * n) as f64, n)
}

#[test]
fn ellipsoid_is_closed_genus_zero_near_the_truth_and_coloured() {
    let (dir, truth, texture) = ellipsoid_dataset("ellipsoid", 8);
    let data = Dataset::load(&dir).unwrap();
    let built = init_mesh(&data, 0, &InitOptions::default()).unwrap();
    let chamfer = check_and_chamfer(&built, &truth);
    assert_eq!(euler(&built.mesh), 2, "genus 0");
    // Remeshing against the raw marching-tetrahedra mesh: far fewer thin triangles, about the
    // same distance to the truth.
    let raw = init_mesh(
        &data,
        0,
        &InitOptions { remesh_rounds: 0, colors: false, ..InitOptions::default() },
    )
    .unwrap();
    let raw_chamfer = check_and_chamfer(&raw, &truth);
    let (a, b) = (min_angles(&built.mesh), min_angles(&raw.mesh));
    let fifth = |v: &[f64]| v[v.len() / 20];
    let thin = |v: &[f64]| v.iter().filter(|&&x| x < 20.0).count() as f64 / v.len() as f64;
    eprintln!("raw: {} vertices, chamfer {raw_chamfer:.5}, 5th-percentile smallest angle {:.1}°, {:.3} of faces under 20°; remeshed {:.1}°, {:.3}", raw.mesh.positions.len(), fifth(&b), thin(&b), fifth(&a), thin(&a));
    assert!(
        fifth(&a) > 30.0 && thin(&a) < 0.01 && thin(&b) > 0.1,
        "remeshed {} / {}, raw {}",
        fifth(&a),
        thin(&a),
        thin(&b)
    );
    assert!(chamfer < raw_chamfer * 1.2);
    let (err, flat, n) = color_error(&built, &truth, &texture, &data.cameras);
    eprintln!("ellipsoid: {:?}\n  chamfer mean / diagonal {chamfer:.5}, colour error {err:.4} (flat mean colour {flat:.4}) over {n} vertices", built.report);
    // Measured 0.0049 (8 views of 96² px): the hull's own excess over a convex
    // subject plus sub-pixel extraction error; the bound keeps a factor-2 margin.
    assert!(chamfer < 0.01, "chamfer {chamfer}");
    // Measured 0.015 against 0.156 for the best flat colour.
    assert!(err < 0.04 && err < 0.25 * flat, "colour error {err}, flat {flat}");
    assert!(n * 10 > built.mesh.positions.len() * 9, "most vertices face a camera");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn vertex_count_follows_the_target() {
    let (dir, truth, _) = ellipsoid_dataset("target", 6);
    let data = Dataset::load(&dir).unwrap();
    for target in [1500, 6000] {
        let options =
            InitOptions { vertices: Some(target), colors: false, ..InitOptions::default() };
        let built = init_mesh(&data, 0, &options).unwrap();
        let chamfer = check_and_chamfer(&built, &truth);
        let ratio = built.mesh.positions.len() as f64 / target as f64;
        eprintln!(
            "target {target}: {} vertices (ratio {ratio:.3}), chamfer / diagonal {chamfer:.5}",
            built.mesh.positions.len()
        );
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "{} vertices for a target of {target}",
            built.mesh.positions.len()
        );
        assert!(chamfer < 0.015, "chamfer {chamfer}");
        assert!(built.mesh.colors.is_none());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn articulated_subject_is_closed_and_near_its_hull_bound() {
    let dir = temp("articulated");
    let options = SynthOptions {
        subject: SubjectSource::Procedural { subdivisions: 4 },
        views: 8,
        frames: 1,
        width: 96,
        height: 96,
        seed: 3,
        samples: 2,
        track_vertices: 0,
        track_surface: 0,
        ..Default::default()
    };
    generate(&options, &dir).unwrap();
    let data = Dataset::load(&dir).unwrap();
    let built = init_mesh(&data, 0, &InitOptions::default()).unwrap();
    let truth = TriMesh::read_ply(&dir.join("meshes").join("000000.ply")).unwrap();
    let chamfer = check_and_chamfer(&built, &truth);
    eprintln!("articulated: {:?}\n  chamfer mean / diagonal {chamfer:.5}", built.report);
    // Concavities between the limbs stay filled; measured 0.0059 (7 training views of 96² px),
    // the bound keeps a factor-2 margin.
    assert!(chamfer < 0.012, "chamfer {chamfer}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn noisy_masks_need_the_tolerance() {
    let (dir, truth, _) = ellipsoid_dataset("noisy", 8);
    let mut views = views(&dir);
    // View 0 loses the top-left quarter of its image (a wrong mask); view 1 gets specks.
    let (w, h) = (views[0].camera.width as usize, views[0].camera.height as usize);
    for y in 0..h {
        for x in 0..w / 2 {
            if y < h / 2 {
                views[0].mask[y * w + x] = 0.0;
            }
        }
    }
    for p in (0..w * h).step_by(97) {
        views[1].mask[p] = 0.0;
    }
    let strict = InitOptions { colors: false, ..InitOptions::default() };
    let tolerant = InitOptions { tolerance: 1, ..strict.clone() };
    let a = init_mesh_from_views(&views, &strict).unwrap();
    let b = init_mesh_from_views(&views, &tolerant).unwrap();
    let (ca, cb) = (check_and_chamfer(&a, &truth), check_and_chamfer(&b, &truth));
    eprintln!(
        "noisy masks: strict chamfer {ca:.5} ({} hole pixels filled), tolerance 1: {cb:.5}",
        a.report.mask_hole_pixels
    );
    assert!(a.report.mask_hole_pixels > 0);
    assert_eq!(euler(&a.mesh), 2, "the specks carve no tunnels");
    // Measured: strict 0.024 (the bitten view cuts the hull), tolerant 0.011.
    assert!(cb < 0.015 && ca > 1.5 * cb, "strict {ca}, tolerant {cb}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_gets_a_clear_error() {
    let (dir, _, _) = ellipsoid_dataset("bad", 4);
    let good = views(&dir);
    let options = InitOptions::default();
    let message = |r: Result<InitMesh, InitError>| r.map(|_| ()).unwrap_err().to_string();

    let mut empty = good.clone();
    empty.iter_mut().for_each(|v| v.mask.fill(0.0));
    let e = message(init_mesh_from_views(&empty, &options));
    assert!(e.contains("empty in all 4 views") && e.contains("cam00"), "{e}");

    // Cameras wrong: every camera shifted sideways by a different amount, so the cones miss
    // each other.
    let mut shifted = good.clone();
    for (k, v) in shifted.iter_mut().enumerate() {
        let offset = glam::DMat4::from_translation(DVec3::X * (1.5 * (k as f64 - 1.5)));
        v.camera.world_to_camera = offset * v.camera.world_to_camera;
    }
    let e = message(init_mesh_from_views(&shifted, &options));
    assert!(e.contains("never intersect") && e.contains("cameras or the masks are wrong"), "{e}");

    // One empty mask among good ones names the empty view.
    let mut one_empty = good.clone();
    one_empty[2].mask.fill(0.0);
    let e = message(init_mesh_from_views(&one_empty, &options));
    assert!(e.contains("never intersect") && e.contains("empty masks in [cam02]"), "{e}");
    assert!(
        init_mesh_from_views(&one_empty, &InitOptions { tolerance: 1, ..options.clone() }).is_ok()
    );

    let e = message(init_mesh_from_views(&good[..1], &options));
    assert!(e.contains("1 view(s) [cam00]") && e.contains("at least 2 cameras"), "{e}");
    let e = message(init_mesh_from_views(&[good[0].clone(), good[0].clone()], &options));
    assert!(e.contains("parallel"), "{e}");

    let mut short = good.clone();
    short[3].mask.pop();
    let e = message(init_mesh_from_views(&short, &options));
    assert!(e.contains("cam03") && e.contains("96×96"), "{e}");
    let mut small_image = good.clone();
    small_image[1].image = Some(std::sync::Arc::new(Image {
        width: 48,
        height: 96,
        channels: 3,
        data: vec![0.5; 48 * 96 * 3],
    }));
    let e = message(init_mesh_from_views(&small_image, &options));
    assert!(e.contains("cam01") && e.contains("48×96"), "{e}");

    for bad in [
        InitOptions { voxel_pixels: 0.0, ..options.clone() },
        InitOptions { voxel_pixels: f64::NAN, ..options.clone() },
        InitOptions { tolerance: 3, ..options.clone() },
        InitOptions { vertices: Some(2), ..options.clone() },
        InitOptions { mask_hole_fraction: 1.5, ..options.clone() },
        InitOptions { max_grid_bytes: 10, ..options.clone() },
    ] {
        assert!(message(init_mesh_from_views(&good, &bad)).starts_with("invalid options"));
    }

    // Through the dataset: a missing frame, and a one-camera dataset.
    let data = Dataset::load(&dir).unwrap();
    let e = message(init_mesh(&data, 5, &options));
    assert!(e.contains("frame 5 does not exist") && e.contains(&dir.display().to_string()), "{e}");
    let single = temp("single");
    write_dataset(&single, &ellipsoid(), &ring(1, 32, DVec3::ZERO, 1.0));
    let e = message(init_mesh(&Dataset::load(&single).unwrap(), 0, &options));
    assert!(e.contains("1 view(s)"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&single).unwrap();
}
