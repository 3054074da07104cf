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
use tagsplat::raster::{edge_adjacency, MeshRasterizer, RasterFrame, RasterMesh, RasterSettings, NO_TRIANGLE};
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
        let positions = unit.iter().map(|p| [0, 1, 2].map(|k| center[k] + radii[k] * p[k])).collect();
        let colors = unit.iter().map(|p| [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1], 0.5 + 0.5 * p[2]]).collect();
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
    fn with_random_triangles(mut self, rng: &mut SplitMix64, n: usize, center: [f64; 3], spread: f64, size: f64) -> Self {
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
        let mesh = ReferenceMesh { positions: &self.positions, faces: &self.faces, colors: &self.colors, adjacency: &adjacency };
        reference::render(&mesh, camera, near)
    }

    fn camera_positions(&self, camera: &Camera) -> Vec<DVec3> {
        self.positions.iter().map(|&p| camera.world_to_camera.transform_point3(DVec3::from(p))).collect()
    }
}

fn camera(width: u32, height: u32, focal: f64, eye: [f64; 3], target: [f64; 3]) -> Camera {
    let (cx, cy) = (0.5 * width as f64 + 0.13, 0.5 * height as f64 - 0.21);
    Camera::look_at(width, height, focal, focal * 1.03, cx, cy, DVec3::from(eye), DVec3::from(target), DVec3::Y).unwrap()
}

fn settings(near: f64) -> RasterSettings {
    RasterSettings { near: near as f32, count_writes: false }
}

fn gpu_render(ctx: &Arc<GpuContext>, scene: &Scene, camera: &Camera, settings: &RasterSettings) -> RasterFrame {
    let rasterizer = MeshRasterizer::new(ctx, &scene.raster_mesh(), camera.width, camera.height).unwrap();
    rasterizer.render(camera, settings).unwrap();
    rasterizer.read_frame().unwrap()
}

/// Pixel coordinates of the part of segment (a, b) in front of the near plane, if any.
fn projected_segment(camera: &Camera, a: DVec3, b: DVec3, near: f64) -> Option<[[f64; 2]; 2]> {
    let clip = |p: DVec3, q: DVec3| if p.z >= near { p } else { p + (q - p) * ((near - p.z) / (q.z - p.z)) };
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
            (0..3).any(|k| projected_segment(camera, v[k], v[(k + 1) % 3], near).is_some_and(|s| distance_to_segment(p, s) <= 1.0 / 64.0))
        }
    };
    if near_edge(a) || near_edge(b) {
        return true;
    }
    if a == NO_TRIANGLE || b == NO_TRIANGLE {
        return false;
    }
    let ray = DVec3::new((p[0] - camera.cx) / camera.fx, (p[1] - camera.cy) / camera.fy, 1.0);
    let (da, db) = (plane_depth(&cam, scene.faces[a as usize], ray), plane_depth(&cam, scene.faces[b as usize], ray));
    (da - db).abs() <= 1e-4 * da.abs().max(db.abs())
}

/// At least `fraction` of the pixels have equal ids, and every differing one is a tie.
fn assert_ids_agree(ours: &[u32], theirs: &[u32], fraction: f64, scene: &Scene, camera: &Camera, near: f64, what: &str) {
    let differing: Vec<usize> = (0..ours.len()).filter(|&i| ours[i] != theirs[i]).collect();
    let agree = 1.0 - differing.len() as f64 / ours.len() as f64;
    assert!(agree >= fraction, "{what}: {} of {} pixels differ", differing.len(), ours.len());
    for &i in &differing {
        assert!(is_tie(i, (ours[i], theirs[i]), scene, camera, near), "{what}: pixel {i} has triangle {} here and {} there, not at a tie", ours[i], theirs[i]);
    }
    let covered = ours.iter().filter(|&&t| t != NO_TRIANGLE).count();
    assert!(covered > 0 || theirs.iter().all(|&t| t == NO_TRIANGLE), "{what}: nothing drawn");
}

/// A plane z = 1 facing a camera at the origin, as a grid whose vertices project exactly to
/// half-integer pixel coordinates (`step` pixels apart), so many edges run through pixel centres.
fn pixel_grid(step: f64, width: u32, height: u32) -> (Scene, Camera) {
    let f = width as f64;
    let camera = Camera::new(width, height, f, f, 0.5 * width as f64, 0.5 * height as f64, glam::DMat4::IDENTITY).unwrap();
    let (nx, ny) = (((width as f64 + 10.0) / step).ceil() as u32 + 1, ((height as f64 + 10.0) / step).ceil() as u32 + 1);
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
    let cluttered = sphere.clone().with_random_triangles(&mut rng, 60, [0.0; 3], 2.4, 0.8).rounded();
    let close = Scene::ellipsoid(1, [0.0; 3], [1.0; 3]).jitter(&mut rng, 0.05).rounded();
    let (grid_small, grid_camera) = pixel_grid(5.0, 64, 48);
    let (grid_large, _) = pixel_grid(13.0, 64, 48);
    let cases = [
        ("sphere + random triangles", cluttered, camera(96, 72, 90.0, [0.3, 0.5, 3.2], [0.0; 3])),
        ("close-up (large triangles)", close, camera(80, 64, 80.0, [0.2, 0.3, 1.6], [0.0; 3])),
        ("pixel-centre grid, small cells", grid_small, grid_camera.clone()),
        ("pixel-centre grid, large cells", grid_large, grid_camera),
    ];
    for (what, scene, cam) in cases {
        let near = 0.05;
        let ours = gpu_render(gpu.ctx(), &scene, &cam, &settings(near)).ids;
        let theirs = oracle::triangle_ids(gpu.ctx(), &scene.camera_positions(&cam), &scene.faces, &cam, near);
        assert_ids_agree(&ours, &theirs, 0.999, &scene, &cam, near, what);
    }
}
