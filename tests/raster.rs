//! The mesh rasterizer on lavapipe with validation on: triangle ids against Vulkan's own
//! rasterizer, watertightness, resolve and anti-aliasing against the f64 reference, near-plane
//! crossings and degenerate input, gradients against central finite differences, and a
//! silhouette fit.

mod common;
#[path = "raster/oracle.rs"]
mod oracle;

use glam::DVec3;
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuContext;
use tagsplat::raster::reference::{self, ReferenceMesh};
use tagsplat::raster::{
    edge_adjacency, MeshRasterizer, RasterFrame, RasterMesh, RasterSettings, NO_TRIANGLE,
};
use tagsplat::rng::SplitMix64;
use tagsplat::synth::icosphere::icosphere;

/// A mesh in f64, the form the reference and the finite differences use.
#[derive(Clone)]
struct Scene {
    positions: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    colors: Vec<[f64; 3]>,
}

impl Scene {
    fn ellipsoid(levels: u32, center: [f64; 3], radii: [f64; 3]) -> Self {
        let (unit, faces) = icosphere(levels);
        let positions =
            unit.iter().map(|p| [0, 1, 2].map(|k| center[k] + radii[k] * p[k])).collect();
        let colors =
            unit.iter().map(|p| [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1], 0.5 + 0.5 * p[2]]).collect();
        Self { positions, faces, colors }
    }

    fn jitter(mut self, rng: &mut SplitMix64, amount: f64) -> Self {
        for p in &mut self.positions {
            for c in p.iter_mut() {
                *c += amount * (rng.next_f64() - 0.5);
            }
        }
        self
    }

    /// Adds `n` random triangles of size about `size` around `center`, random colours.
    fn with_random_triangles(
        mut self,
        rng: &mut SplitMix64,
        n: usize,
        center: [f64; 3],
        spread: f64,
        size: f64,
    ) -> Self {
        for _ in 0..n {
            let c = center.map(|x| x + spread * (rng.next_f64() - 0.5));
            let base = self.positions.len() as u32;
            for _ in 0..3 {
                self.positions.push(c.map(|x| x + size * (rng.next_f64() - 0.5)));
                self.colors.push([rng.next_f64(), rng.next_f64(), rng.next_f64()]);
            }
            self.faces.push([base, base + 1, base + 2]);
        }
        self
    }

    /// Positions as the GPU gets them, and back in f64 (so both sides see the same numbers).
    fn rounded(mut self) -> Self {
        for p in &mut self.positions {
            *p = p.map(|c| c as f32 as f64);
        }
        for c in &mut self.colors {
            *c = c.map(|x| x as f32 as f64);
        }
        self
    }

    fn raster_mesh(&self) -> RasterMesh {
        let f = |v: &[[f64; 3]]| v.iter().map(|p| p.map(|c| c as f32)).collect();
        RasterMesh::new(f(&self.positions), self.faces.clone(), f(&self.colors)).unwrap()
    }

    fn reference(&self, camera: &Camera, near: f64) -> reference::ReferenceFrame {
        let adjacency = edge_adjacency(&self.faces);
        let mesh = ReferenceMesh {
            positions: &self.positions,
            faces: &self.faces,
            colors: &self.colors,
            adjacency: &adjacency,
        };
        reference::render(&mesh, camera, near)
    }

    fn camera_positions(&self, camera: &Camera) -> Vec<DVec3> {
        self.positions
            .iter()
            .map(|&p| camera.world_to_camera.transform_point3(DVec3::from(p)))
            .collect()
    }
}

fn camera(width: u32, height: u32, focal: f64, eye: [f64; 3], target: [f64; 3]) -> Camera {
    let (cx, cy) = (0.5 * width as f64 + 0.13, 0.5 * height as f64 - 0.21);
    Camera::look_at(
        width,
        height,
        focal,
        focal * 1.03,
        cx,
        cy,
        DVec3::from(eye),
        DVec3::from(target),
        DVec3::Y,
    )
    .unwrap()
}

fn settings(near: f64) -> RasterSettings {
    RasterSettings { near: near as f32, count_writes: false }
}

fn gpu_render(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    camera: &Camera,
    settings: &RasterSettings,
) -> RasterFrame {
    let rasterizer =
        MeshRasterizer::new(ctx, &scene.raster_mesh(), camera.width, camera.height).unwrap();
    rasterizer.render(camera, settings).unwrap();
    rasterizer.read_frame().unwrap()
}

/// Pixel coordinates of the part of segment (a, b) in front of the near plane, if any.
fn projected_segment(camera: &Camera, a: DVec3, b: DVec3, near: f64) -> Option<[[f64; 2]; 2]> {
    let clip = |p: DVec3, q: DVec3| {
        if p.z >= near {
            p
        } else {
            p + (q - p) * ((near - p.z) / (q.z - p.z))
        }
    };
    if a.z < near && b.z < near {
        return None;
    }
    let project = |c: DVec3| [camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy];
    Some([project(clip(a, b)), project(clip(b, a))])
}

fn distance_to_segment(p: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let (d, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let len2 = d[0] * d[0] + d[1] * d[1];
    let s = if len2 > 0.0 { ((ap[0] * d[0] + ap[1] * d[1]) / len2).clamp(0.0, 1.0) } else { 0.0 };
    ((ap[0] - s * d[0]).powi(2) + (ap[1] - s * d[1]).powi(2)).sqrt()
}

/// Depth where the pixel ray meets triangle t's plane.
fn plane_depth(cam: &[DVec3], face: [u32; 3], ray: DVec3) -> f64 {
    let v = face.map(|k| cam[k as usize]);
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    n.dot(v[0]) / n.dot(ray)
}

/// Whether pixel i is an edge tie between triangle ids a and b: its centre lies within 1/64
/// pixel of an edge of either (1/256-pixel snapping moves edges by less), or both are drawn and
/// their depths there agree to 10⁻⁴.
fn is_tie(i: usize, (a, b): (u32, u32), scene: &Scene, camera: &Camera, near: f64) -> bool {
    let cam = scene.camera_positions(camera);
    let p = [(i % camera.width as usize) as f64 + 0.5, (i / camera.width as usize) as f64 + 0.5];
    let near_edge = |t: u32| {
        t != NO_TRIANGLE && {
            let v = scene.faces[t as usize].map(|k| cam[k as usize]);
            (0..3).any(|k| {
                projected_segment(camera, v[k], v[(k + 1) % 3], near)
                    .is_some_and(|s| distance_to_segment(p, s) <= 1.0 / 64.0)
            })
        }
    };
    if near_edge(a) || near_edge(b) {
        return true;
    }
    if a == NO_TRIANGLE || b == NO_TRIANGLE {
        return false;
    }
    let ray = DVec3::new((p[0] - camera.cx) / camera.fx, (p[1] - camera.cy) / camera.fy, 1.0);
    let (da, db) = (
        plane_depth(&cam, scene.faces[a as usize], ray),
        plane_depth(&cam, scene.faces[b as usize], ray),
    );
    (da - db).abs() <= 1e-4 * da.abs().max(db.abs())
}

/// At least `fraction` of the pixels have equal ids, and every differing one is a tie.
fn assert_ids_agree(
    ours: &[u32],
    theirs: &[u32],
    fraction: f64,
    scene: &Scene,
    camera: &Camera,
    near: f64,
    what: &str,
) {
    let differing: Vec<usize> = (0..ours.len()).filter(|&i| ours[i] != theirs[i]).collect();
    let agree = 1.0 - differing.len() as f64 / ours.len() as f64;
    assert!(agree >= fraction, "{what}: {} of {} pixels differ", differing.len(), ours.len());
    for &i in &differing {
        assert!(
            is_tie(i, (ours[i], theirs[i]), scene, camera, near),
            "{what}: pixel {i} has triangle {} here and {} there, not at a tie",
            ours[i],
            theirs[i]
        );
    }
    let covered = ours.iter().filter(|&&t| t != NO_TRIANGLE).count();
    assert!(covered > 0 || theirs.iter().all(|&t| t == NO_TRIANGLE), "{what}: nothing drawn");
}

/// A plane z = 1 facing a camera at the origin, as a grid whose vertices project exactly to
/// half-integer pixel coordinates (`step` pixels apart), so many edges run through pixel centres.
fn pixel_grid(step: f64, width: u32, height: u32) -> (Scene, Camera) {
    let f = width as f64;
    let camera = Camera::new(
        width,
        height,
        f,
        f,
        0.5 * width as f64,
        0.5 * height as f64,
        glam::DMat4::IDENTITY,
    )
    .unwrap();
    let (nx, ny) = (
        ((width as f64 + 10.0) / step).ceil() as u32 + 1,
        ((height as f64 + 10.0) / step).ceil() as u32 + 1,
    );
    let mut positions = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (u, v) = (-4.5 + step * i as f64, -4.5 + step * j as f64);
            positions.push([(u - camera.cx) / f, (v - camera.cy) / f, 1.0]);
        }
    }
    let mut faces = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let [a, b, c, d] = [j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i];
            // Alternate the diagonal so both directions meet pixel centres.
            if (i + j) % 2 == 0 {
                faces.extend([[a, c, b], [a, d, c]]);
            } else {
                faces.extend([[a, d, b], [b, d, c]]);
            }
        }
    }
    let colors = vec![[0.5; 3]; positions.len()];
    (Scene { positions, faces, colors }, camera)
}

#[test]
fn ids_match_the_graphics_pipeline() {
    let gpu = common::gpu();
    let mut rng = common::rng(61);
    let sphere = Scene::ellipsoid(3, [0.0; 3], [1.0, 0.8, 0.9]).jitter(&mut rng, 0.02);
    let cluttered =
        sphere.clone().with_random_triangles(&mut rng, 60, [0.0; 3], 2.4, 0.8).rounded();
    let close = Scene::ellipsoid(1, [0.0; 3], [1.0; 3]).jitter(&mut rng, 0.05).rounded();
    let (grid_small, grid_camera) = pixel_grid(5.0, 64, 48);
    let (grid_large, _) = pixel_grid(29.0, 64, 48);
    // More large triangles over the centre tiles than a tile list holds (256): the fallback.
    let pile = Scene { positions: vec![], faces: vec![], colors: vec![] }
        .with_random_triangles(&mut rng, 600, [0.0; 3], 0.4, 3.0)
        .rounded();
    let cases = [
        ("sphere + random triangles", cluttered, camera(96, 72, 90.0, [0.3, 0.5, 3.2], [0.0; 3])),
        ("600 overlapping large triangles", pile, camera(64, 48, 50.0, [0.1, 0.2, 3.0], [0.0; 3])),
        ("close-up (large triangles)", close, camera(80, 64, 80.0, [0.2, 0.3, 1.6], [0.0; 3])),
        ("pixel-centre grid, small cells", grid_small, grid_camera),
        ("pixel-centre grid, large cells", grid_large, grid_camera),
    ];
    for (what, scene, cam) in cases {
        let near = 0.05;
        let (frame, _, [large, _]) = render_counting(gpu.ctx(), &scene, &cam, near);
        assert!(large > 0 || !what.contains("large"), "{what}: no triangle took the tiled path");
        let ours = frame.ids;
        let theirs = oracle::triangle_ids(&scene.camera_positions(&cam), &scene.faces, &cam, near);
        assert_ids_agree(&ours, &theirs, 0.999, &scene, &cam, near, what);
    }
}

/// Not a check of its own: the graphics-pipeline oracle's draw, in the child process that
/// `oracle::triangle_ids` starts (see tests/raster/oracle.rs for why a child).
#[test]
#[ignore = "run only by oracle::triangle_ids, in a child process"]
fn graphics_pipeline_oracle_child() {
    oracle::serve_child();
}

fn render_counting(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    camera: &Camera,
    near: f64,
) -> (RasterFrame, Vec<u32>, [u32; 2]) {
    let rasterizer =
        MeshRasterizer::new(ctx, &scene.raster_mesh(), camera.width, camera.height).unwrap();
    rasterizer.render(camera, &RasterSettings { near: near as f32, count_writes: true }).unwrap();
    (
        rasterizer.read_frame().unwrap(),
        rasterizer.read_write_counts().unwrap(),
        rasterizer.read_counters().unwrap(),
    )
}

#[test]
fn closed_meshes_and_shared_edges_are_watertight() {
    let gpu = common::gpu();
    let mut rng = common::rng(62);
    // A plane covering the whole image, edges through pixel centres: every pixel exactly once,
    // through the small-triangle path (5-pixel cells) and the tiled path (29-pixel cells).
    for step in [5.0, 29.0] {
        let (grid, cam) = pixel_grid(step, 70, 45);
        let (_, counts, [large, _]) = render_counting(gpu.ctx(), &grid, &cam, 0.05);
        assert_eq!(large > 0, step > 10.0, "cells of {step} pixels: {large} large triangles");
        let wrong: Vec<_> = counts.iter().enumerate().filter(|(_, &c)| c != 1).collect();
        assert!(
            wrong.is_empty(),
            "cells of {step} pixels: pixels not written exactly once: {:?}",
            &wrong[..wrong.len().min(10)]
        );
    }
    // A closed convex mesh: every pixel ray crosses it twice or not at all (a crack leaves 1,
    // a double write 3), and the covered set is the reference's up to edge ties.
    for (levels, eye) in [(3, [0.4, 0.2, 3.0]), (1, [0.1, 0.3, 1.9])] {
        let sphere =
            Scene::ellipsoid(levels, [0.0; 3], [1.0, 0.7, 0.9]).jitter(&mut rng, 0.01).rounded();
        let cam = camera(90, 70, 80.0, eye, [0.0; 3]);
        let (frame, counts, _) = render_counting(gpu.ctx(), &sphere, &cam, 0.05);
        let odd: Vec<_> = counts.iter().enumerate().filter(|(_, &c)| c != 0 && c != 2).collect();
        assert!(
            odd.is_empty(),
            "sphere level {levels}: write counts other than 0 or 2: {:?}",
            &odd[..odd.len().min(10)]
        );
        let reference = sphere.reference(&cam, 0.05);
        let covered = |ids: &[u32]| ids.iter().map(|&t| t != NO_TRIANGLE).collect::<Vec<_>>();
        let (ours, theirs) = (covered(&frame.ids), covered(&reference.ids));
        for i in 0..ours.len() {
            assert!(
                ours[i] == theirs[i]
                    || is_tie(i, (frame.ids[i], reference.ids[i]), &sphere, &cam, 0.05),
                "sphere level {levels}: coverage differs at pixel {i}"
            );
            assert_eq!(ours[i], counts[i] == 2, "pixel {i}: covered but not written twice");
        }
    }
}

/// Largest absolute difference over the components of two pixel arrays at the given pixels.
fn worst<const N: usize>(ours: &[[f32; N]], theirs: &[[f64; N]], pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .flat_map(|&i| (0..N).map(move |k| (ours[i][k] as f64 - theirs[i][k]).abs()))
        .fold(0.0, f64::max)
}

/// Resolve and anti-aliasing against the f64 reference: ids up to ties; barycentrics, colour,
/// depth and normals where the ids agree; the anti-aliased image where the whole 3x3
/// neighbourhood agrees (a pixel's blend reads its neighbours).
fn assert_matches_reference(
    ctx: &Arc<GpuContext>,
    scene: &Scene,
    cam: &Camera,
    near: f64,
    what: &str,
) {
    let frame = gpu_render(ctx, scene, cam, &settings(near));
    let reference = scene.reference(cam, near);
    assert_ids_agree(&frame.ids, &reference.ids, 0.995, scene, cam, near, what);
    let (w, h) = (cam.width as usize, cam.height as usize);
    let same: Vec<usize> = (0..w * h).filter(|&i| frame.ids[i] == reference.ids[i]).collect();
    assert!(
        worst(&frame.barycentrics, &reference.barycentrics, &same) <= 2e-4,
        "{what}: barycentrics"
    );
    assert!(worst(&frame.resolved, &reference.resolved, &same) <= 2e-4, "{what}: resolved colour");
    assert!(worst(&frame.normals, &reference.normals, &same) <= 1e-4, "{what}: normals");
    for &i in &same {
        assert!(
            (frame.depth[i] as f64 - reference.depth[i]).abs()
                <= 1e-5 * reference.depth[i].max(1.0),
            "{what}: depth at {i}"
        );
    }
    let neighbourhood_same: Vec<usize> = (0..w * h)
        .filter(|&i| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx < 0
                        || ny < 0
                        || nx >= w as i64
                        || ny >= h as i64
                        || frame.ids[ny as usize * w + nx as usize]
                            == reference.ids[ny as usize * w + nx as usize]
                })
            })
        })
        .collect();
    let aa: Vec<[f32; 4]> = (0..w * h)
        .map(|i| [frame.color[i][0], frame.color[i][1], frame.color[i][2], frame.mask[i]])
        .collect();
    let blended = neighbourhood_same.iter().filter(|&&i| aa[i] != frame.resolved[i]).count();
    assert!(
        blended > 0 || reference.ids.iter().all(|&t| t == NO_TRIANGLE),
        "{what}: anti-aliasing changed nothing"
    );
    assert!(
        worst(&aa, &reference.antialiased, &neighbourhood_same) <= 2e-4,
        "{what}: anti-aliased image"
    );
}

#[test]
fn resolve_and_antialiasing_match_the_reference() {
    let gpu = common::gpu();
    let mut rng = common::rng(63);
    let scene = Scene::ellipsoid(2, [0.0; 3], [1.0, 0.8, 0.9])
        .jitter(&mut rng, 0.03)
        .with_random_triangles(&mut rng, 40, [0.0; 3], 2.5, 0.7)
        .rounded();
    for (k, eye) in [[0.3, 0.5, 3.2], [-2.5, 1.0, 1.5], [0.0, -0.4, 2.0]].into_iter().enumerate() {
        let cam = camera(70 + 9 * k as u32, 56, 70.0, eye, [0.05, 0.0, 0.0]);
        assert_matches_reference(gpu.ctx(), &scene, &cam, 0.05, &format!("view {k}"));
    }
}

#[test]
fn meshes_crossing_the_near_plane() {
    let gpu = common::gpu();
    let mut rng = common::rng(64);
    // The camera sits inside a large sphere (every view ray hits it, triangles straddle the
    // near plane), and a ground grid runs from behind the camera to far ahead.
    let room = Scene::ellipsoid(2, [0.0; 3], [1.0; 3])
        .jitter(&mut rng, 0.02)
        .with_random_triangles(&mut rng, 20, [0.0, 0.0, 0.6], 0.6, 0.5)
        .rounded();
    let near = 0.3;
    let inside = camera(64, 48, 40.0, [0.0, 0.1, 0.05], [0.2, 0.0, 1.0]);
    let (frame, _, _) = render_counting(gpu.ctx(), &room, &inside, near);
    assert!(frame.ids.iter().all(|&t| t != NO_TRIANGLE), "a closed room must cover every pixel");
    assert_matches_reference(gpu.ctx(), &room, &inside, near, "inside a sphere");
    let theirs = oracle::triangle_ids(&room.camera_positions(&inside), &room.faces, &inside, near);
    assert_ids_agree(
        &frame.ids,
        &theirs,
        0.999,
        &room,
        &inside,
        near,
        "inside a sphere vs graphics pipeline",
    );

    let (mut ground, _) = pixel_grid(9.0, 40, 40);
    for p in &mut ground.positions {
        *p = [p[0] * 8.0, -0.5, p[1] * 8.0];
    }
    let ground = ground.rounded();
    let cam = camera(72, 54, 60.0, [0.0, 0.2, 0.0], [0.0, 0.0, 3.0]);
    let cam_positions = ground.camera_positions(&cam);
    assert!(
        cam_positions.iter().any(|p| p.z < 0.0) && cam_positions.iter().any(|p| p.z > 3.0),
        "the grid must cross the near plane"
    );
    assert_matches_reference(gpu.ctx(), &ground, &cam, 0.1, "ground plane");
    let ours = gpu_render(gpu.ctx(), &ground, &cam, &settings(0.1)).ids;
    let theirs = oracle::triangle_ids(&cam_positions, &ground.faces, &cam, 0.1);
    assert_ids_agree(
        &ours,
        &theirs,
        0.999,
        &ground,
        &cam,
        0.1,
        "ground plane vs graphics pipeline",
    );
}

#[test]
fn degenerate_edge_on_subpixel_and_empty_meshes() {
    let gpu = common::gpu();
    let mut rng = common::rng(65);
    let cam = camera(48, 40, 50.0, [0.0, 0.0, 3.0], [0.0; 3]);
    let eye = cam.center();
    // Edge-on: the plane through the camera centre; zero area: a repeated corner and three
    // collinear corners. None covers a pixel.
    let degenerate = Scene {
        positions: vec![
            [eye.x, eye.y + 0.7, eye.z - 3.0],
            [eye.x, eye.y - 0.5, eye.z - 2.5],
            [eye.x, eye.y + 0.2, eye.z - 4.0],
            [-0.5, -0.5, 0.0],
            [0.6, 0.4, 0.0],
            [-0.6, 0.3, 0.1],
            [0.0, 0.0, 0.1],
            [0.6, -0.3, 0.1],
        ],
        faces: vec![[0, 1, 2], [3, 4, 4], [5, 6, 7]],
        colors: vec![[1.0; 3]; 8],
    };
    let (frame, counts, _) = render_counting(gpu.ctx(), &degenerate, &cam, 0.05);
    assert!(frame.ids.iter().all(|&t| t == NO_TRIANGLE), "degenerate triangles drew pixels");
    assert!(counts.iter().all(|&c| c == 0) && frame.mask.iter().all(|&m| m == 0.0));

    // Sub-pixel triangles cover a pixel exactly when one holds a pixel centre.
    let tiny = Scene { positions: vec![], faces: vec![], colors: vec![] }
        .with_random_triangles(&mut rng, 400, [0.0; 3], 1.6, 0.05)
        .rounded();
    let ours = gpu_render(gpu.ctx(), &tiny, &cam, &settings(0.05)).ids;
    let reference = tiny.reference(&cam, 0.05);
    assert_ids_agree(&ours, &reference.ids, 0.999, &tiny, &cam, 0.05, "sub-pixel triangles");
    let drawn = ours.iter().filter(|&&t| t != NO_TRIANGLE).count();
    assert!(drawn > 5 && drawn < 400, "{drawn} pixels drawn by 400 sub-pixel triangles");

    // The empty mesh: nothing drawn, empty gradients, validation clean.
    let empty = RasterMesh::default();
    let rasterizer = MeshRasterizer::new(gpu.ctx(), &empty, cam.width, cam.height).unwrap();
    rasterizer.render(&cam, &settings(0.05)).unwrap();
    let frame = rasterizer.read_frame().unwrap();
    assert!(frame.ids.iter().all(|&t| t == NO_TRIANGLE) && frame.mask.iter().all(|&m| m == 0.0));
    let pixels = (cam.width * cam.height) as usize;
    let grads = rasterizer
        .gradients(&cam, &settings(0.05), &vec![[1.0; 3]; pixels], &vec![1.0; pixels])
        .unwrap();
    assert!(grads.positions.is_empty() && grads.colors.is_empty());
}

#[test]
fn positions_from_a_caller_buffer_render_like_written_positions() {
    let gpu = common::gpu();
    let mut rng = common::rng(67);
    let scene = Scene::ellipsoid(2, [0.0; 3], [1.0; 3]);
    let moved = scene.clone().jitter(&mut rng, 0.3).rounded();
    let cam = camera(40, 32, 40.0, [0.0, 0.3, 3.0], [0.0; 3]);
    let mut rasterizer = MeshRasterizer::new(gpu.ctx(), &scene.raster_mesh(), 40, 32).unwrap();
    let flat: Vec<f32> = moved.positions.iter().flatten().map(|&c| c as f32).collect();
    let external =
        tagsplat::gpu::GpuBuffer::from_slice(gpu.ctx(), "external positions", &flat).unwrap();
    let params = rasterizer.params(&cam, &settings(0.05)).unwrap();
    let mut rec = tagsplat::gpu::Recorder::new(gpu.ctx()).unwrap();
    rasterizer.record_forward_from(&mut rec, &params, &external).unwrap();
    rec.submit_and_wait().unwrap();
    let from_buffer = rasterizer.read_frame().unwrap();
    rasterizer.write_positions(&moved.raster_mesh().positions).unwrap();
    rasterizer.render(&cam, &settings(0.05)).unwrap();
    let written = rasterizer.read_frame().unwrap();
    assert_eq!(from_buffer.ids, written.ids);
    assert_eq!(from_buffer.color, written.color);
    assert_ne!(
        written.ids,
        gpu_render(gpu.ctx(), &scene, &cam, &settings(0.05)).ids,
        "the jitter must change the image"
    );
    let short = tagsplat::gpu::GpuBuffer::<f32>::new(gpu.ctx(), "short", 5).unwrap();
    let mut rec = tagsplat::gpu::Recorder::new(gpu.ctx()).unwrap();
    let e = rasterizer.record_forward_from(&mut rec, &params, &short).unwrap_err().to_string();
    assert!(e.contains("vertex positions"), "{e}");
}

#[test]
fn bad_input_is_refused_with_a_clear_error() {
    let gpu = common::gpu();
    let scene = Scene::ellipsoid(1, [0.0; 3], [1.0; 3]);
    let mut rasterizer = MeshRasterizer::new(gpu.ctx(), &scene.raster_mesh(), 32, 32).unwrap();
    let mut positions: Vec<[f32; 3]> =
        scene.positions.iter().map(|p| p.map(|c| c as f32)).collect();
    positions[5][2] = f32::INFINITY;
    let e = rasterizer.write_positions(&positions).unwrap_err().to_string();
    assert!(e.contains("vertex 5") && e.contains("non-finite"), "{e}");
    let e = rasterizer.write_positions(&positions[..3]).unwrap_err().to_string();
    assert!(e.contains("positions") && e.contains('3'), "{e}");
    let wrong_size = camera(40, 32, 40.0, [0.0, 0.0, 3.0], [0.0; 3]);
    let e = rasterizer.render(&wrong_size, &settings(0.05)).unwrap_err().to_string();
    assert!(e.contains("(40, 32)") && e.contains("(32, 32)"), "{e}");
    let cam = camera(32, 32, 40.0, [0.0, 0.0, 3.0], [0.0; 3]);
    let e = rasterizer
        .render(&cam, &RasterSettings { near: -1.0, count_writes: false })
        .unwrap_err()
        .to_string();
    assert!(e.contains("near"), "{e}");
    let e = rasterizer
        .gradients(&cam, &settings(0.05), &[[0.0; 3]; 10], &[0.0; 1024])
        .unwrap_err()
        .to_string();
    assert!(e.contains("dL/dcolour"), "{e}");
}

/// `tagsplat render-mesh` on malformed PLY files: a float list count (which used to panic) and
/// a trillion rows of no properties, ascii and binary (which used to spin forever) exit with
/// code 1 and an error naming the file, at once.
#[test]
fn render_mesh_cli_refuses_malformed_ply_at_once() {
    let dir = std::env::temp_dir().join(format!("tagsplat-render-mesh-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let camera_path = dir.join("cam.json");
    camera(16, 16, 20.0, [0.0, 0.0, 3.0], [0.0; 3]).save_json(&camera_path).unwrap();
    let face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n3 0 1 2\n";
    let cases = [
        ("float-count.ply", "ascii", face.replace("list uchar", "list float")),
        ("empty-rows-ascii.ply", "ascii", format!("element vertex 1000000000000\n{face}")),
        ("empty-rows.ply", "binary_little_endian", format!("element vertex 1000000000000\n{face}")),
    ];
    for (name, format, rest) in cases {
        let mesh = dir.join(name);
        std::fs::write(&mesh, format!("ply\nformat {format} 1.0\n{rest}")).unwrap();
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"))
            .arg("render-mesh")
            .args([
                "--mesh".as_ref(),
                mesh.as_os_str(),
                "--camera".as_ref(),
                camera_path.as_os_str(),
            ])
            .args(["--out".as_ref(), dir.join("never.png").as_os_str()])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() {
            if started.elapsed() > std::time::Duration::from_secs(20) {
                child.kill().unwrap();
                child.wait().unwrap();
                panic!("render-mesh on {name} still runs after 20 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let output = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{name}: {stderr}");
        assert!(
            stderr.contains(&mesh.display().to_string()) && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
    assert!(!dir.join("never.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Σ weights · (anti-aliased rgb, mask) of the reference render.
fn reference_loss(scene: &Scene, cam: &Camera, near: f64, weights: &[[f64; 4]]) -> f64 {
    let frame = scene.reference(cam, near);
    frame
        .antialiased
        .iter()
        .zip(weights)
        .map(|(o, w)| (0..4).map(|k| o[k] * w[k]).sum::<f64>())
        .sum()
}

/// Central differences of `reference_loss` in every coordinate of `values(scene)`.
fn finite_differences(
    scene: &Scene,
    cam: &Camera,
    near: f64,
    weights: &[[f64; 4]],
    eps: f64,
    colors: bool,
) -> Vec<[f64; 3]> {
    let n = scene.positions.len();
    (0..n)
        .map(|v| {
            [0, 1, 2].map(|k| {
                let mut shifted = scene.clone();
                let at = |s: &mut Scene, d: f64| {
                    if colors {
                        s.colors[v][k] += d
                    } else {
                        s.positions[v][k] += d
                    }
                };
                at(&mut shifted, eps);
                let plus = reference_loss(&shifted, cam, near, weights);
                at(&mut shifted, -2.0 * eps);
                let minus = reference_loss(&shifted, cam, near, weights);
                (plus - minus) / (2.0 * eps)
            })
        })
        .collect()
}

/// ‖a − b‖ / ‖b‖ over all components.
fn relative_error(a: &[[f32; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut diff, mut norm) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            diff += (x[k] as f64 - y[k]).powi(2);
            norm += y[k] * y[k];
        }
    }
    (diff / norm).sqrt()
}

#[test]
fn gradients_match_finite_differences() {
    let gpu = common::gpu();
    let mut rng = common::rng(66);
    let mut scene = Scene::ellipsoid(2, [0.0; 3], [1.0, 0.8, 0.9])
        .jitter(&mut rng, 0.03)
        .with_random_triangles(&mut rng, 4, [0.0, 0.0, 1.2], 1.0, 0.6);
    for c in &mut scene.colors {
        *c = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
    }
    let scene = scene.rounded();
    let cam = camera(40, 36, 38.0, [0.3, 0.4, 3.0], [0.0; 3]);
    let near = 0.05;
    let pixels = (cam.width * cam.height) as usize;
    let mut weight = || 2.0 * rng.next_f64() - 1.0;
    // Colour and mask together, then the mask alone (only the outline can move it).
    let mixed: Vec<[f64; 4]> =
        (0..pixels).map(|_| [weight(), weight(), weight(), weight()]).collect();
    let mask_only: Vec<[f64; 4]> = mixed.iter().map(|w| [0.0, 0.0, 0.0, w[3]]).collect();
    let rasterizer =
        MeshRasterizer::new(gpu.ctx(), &scene.raster_mesh(), cam.width, cam.height).unwrap();
    rasterizer.render(&cam, &settings(near)).unwrap();
    for (what, weights) in [("colour + mask", &mixed), ("mask only", &mask_only)] {
        let grad_color: Vec<[f32; 3]> =
            weights.iter().map(|w| [w[0] as f32, w[1] as f32, w[2] as f32]).collect();
        let grad_mask: Vec<f32> = weights.iter().map(|w| w[3] as f32).collect();
        let grads = rasterizer.gradients(&cam, &settings(near), &grad_color, &grad_mask).unwrap();
        let (gp, gc) = (grads.positions, grads.colors);
        // Small steps keep edges from sweeping over pixel centres (where ids change).
        let fd_positions = finite_differences(&scene, &cam, near, weights, 1e-6, false);
        let position_error = relative_error(&gp, &fd_positions);
        assert!(
            position_error <= 1e-3,
            "{what}: position gradients, relative error {position_error:.2e}"
        );
        let moved = fd_positions.iter().filter(|g| g.iter().any(|&x| x != 0.0)).count();
        assert!(moved > 20, "{what}: only {moved} vertices change the loss");
        let fd_colors = finite_differences(&scene, &cam, near, weights, 1e-3, true);
        let color_error = if what == "mask only" {
            gc.iter().flatten().map(|g| g.abs() as f64).fold(0.0, f64::max)
        } else {
            relative_error(&gc, &fd_colors)
        };
        assert!(color_error <= 1e-4, "{what}: colour gradients, error {color_error:.2e}");
    }
}

/// Vertex neighbours from the faces (for the smoothing term of the fit).
fn one_rings(vertices: usize, faces: &[[u32; 3]]) -> Vec<Vec<usize>> {
    let mut rings = vec![Vec::new(); vertices];
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            for (x, y) in [(a, b), (b, a)] {
                if !rings[x].contains(&y) {
                    rings[x].push(y);
                }
            }
        }
    }
    rings
}

/// Coverage of every view, and the mask-loss gradient of the anti-aliased mask towards `targets`.
fn mask_step(
    rasterizer: &MeshRasterizer,
    cams: &[Camera],
    targets: &[Vec<f32>],
    grad: &mut [[f64; 3]],
) -> Vec<Vec<bool>> {
    let near = settings(0.05);
    let mut coverage = Vec::new();
    for (cam, target) in cams.iter().zip(targets) {
        rasterizer.render(cam, &near).unwrap();
        let frame = rasterizer.read_frame().unwrap();
        let n = frame.mask.len() as f32;
        let grad_mask: Vec<f32> =
            frame.mask.iter().zip(target).map(|(m, t)| 2.0 * (m - t) / n).collect();
        let gp = rasterizer
            .gradients(cam, &near, &vec![[0.0; 3]; frame.mask.len()], &grad_mask)
            .unwrap()
            .positions;
        for (g, d) in grad.iter_mut().zip(&gp) {
            for k in 0..3 {
                g[k] += d[k] as f64;
            }
        }
        coverage.push(frame.ids.iter().map(|&t| t != NO_TRIANGLE).collect());
    }
    coverage
}

fn iou(a: &[Vec<bool>], b: &[Vec<bool>]) -> f64 {
    let pairs = a.iter().flatten().zip(b.iter().flatten());
    let (both, either) =
        pairs.fold((0, 0), |(i, u), (&x, &y)| (i + (x && y) as usize, u + (x || y) as usize));
    both as f64 / either as f64
}

#[test]
fn sphere_fits_ellipsoid_silhouettes() {
    let gpu = common::gpu();
    let cams: Vec<Camera> = (0..8)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 8.0;
            let elevation = if k % 2 == 0 { 0.8 } else { -0.6 };
            camera(64, 64, 60.0, [4.0 * a.cos(), elevation, 4.0 * a.sin()], [0.0; 3])
        })
        .collect();
    let target = Scene::ellipsoid(4, [0.1, 0.0, -0.1], [1.3, 0.7, 0.95]);
    let target_raster = MeshRasterizer::new(gpu.ctx(), &target.raster_mesh(), 64, 64).unwrap();
    let (mut target_masks, mut target_coverage) = (Vec::new(), Vec::new());
    for cam in &cams {
        target_raster.render(cam, &settings(0.05)).unwrap();
        let frame = target_raster.read_frame().unwrap();
        target_coverage.push(frame.ids.iter().map(|&t| t != NO_TRIANGLE).collect::<Vec<_>>());
        target_masks.push(frame.mask);
    }
    let mut scene = Scene::ellipsoid(2, [0.0; 3], [1.0; 3]);
    let rings = one_rings(scene.positions.len(), &scene.faces);
    let mut rasterizer = MeshRasterizer::new(gpu.ctx(), &scene.raster_mesh(), 64, 64).unwrap();
    let mut grad = vec![[0.0; 3]; scene.positions.len()];
    let start = iou(&mask_step(&rasterizer, &cams, &target_masks, &mut grad), &target_coverage);
    // Adam on the positions with a mild pull towards each 1-ring's mean.
    let (lr, smoothing) = (0.01, 0.05);
    let (mut m, mut v) = (vec![[0.0; 3]; grad.len()], vec![[0.0; 3]; grad.len()]);
    let mut last = start;
    for step in 1..=120 {
        for (i, ring) in rings.iter().enumerate() {
            let mean = ring.iter().fold([0.0; 3], |acc, &j| {
                [0, 1, 2].map(|k| acc[k] + scene.positions[j][k] / ring.len() as f64)
            });
            for k in 0..3 {
                let g = grad[i][k] + smoothing * (scene.positions[i][k] - mean[k]);
                m[i][k] = 0.9 * m[i][k] + 0.1 * g;
                v[i][k] = 0.999 * v[i][k] + 0.001 * g * g;
                let (mh, vh) =
                    (m[i][k] / (1.0 - 0.9f64.powi(step)), v[i][k] / (1.0 - 0.999f64.powi(step)));
                scene.positions[i][k] -= lr * mh / (vh.sqrt() + 1e-8);
            }
        }
        let positions: Vec<[f32; 3]> =
            scene.positions.iter().map(|p| p.map(|c| c as f32)).collect();
        rasterizer.write_positions(&positions).unwrap();
        grad.iter_mut().for_each(|g| *g = [0.0; 3]);
        last = iou(&mask_step(&rasterizer, &cams, &target_masks, &mut grad), &target_coverage);
    }
    eprintln!("silhouette fit: IoU {start:.3} -> {last:.3}");
    assert!(start < 0.9, "the start must be a real fit (IoU {start:.3})");
    assert!(last >= 0.95, "IoU {start:.3} -> {last:.3}");
}

#[test]
fn sub_triangles_past_the_guard_band_are_dropped_and_counted() {
    let gpu = common::gpu();
    // With a tiny near plane, a corner just in front of it projects millions of pixels away.
    let near = 1e-6;
    let cam = camera(32, 32, 40.0, [0.0, 0.0, 3.0], [0.0; 3]);
    let corner =
        cam.world_to_camera.inverse().transform_point3(DVec3::new(1.0, 0.0, 2e-6)).to_array();
    let scene = Scene {
        positions: vec![
            corner,
            [-0.5, -0.5, 0.0],
            [0.5, -0.5, 0.0],
            [-0.5, 0.5, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.6, 0.0],
        ],
        faces: vec![[0, 1, 2], [3, 4, 5]],
        colors: vec![[1.0; 3]; 6],
    }
    .rounded();
    let (frame, _, [_, dropped]) = render_counting(gpu.ctx(), &scene, &cam, near);
    assert_eq!(dropped, 1, "the far-projecting triangle is dropped, once");
    assert!(frame.ids.iter().all(|&t| t != 0), "the dropped triangle drew pixels");
    assert!(frame.ids.contains(&1), "the ordinary triangle must still be drawn");
}
