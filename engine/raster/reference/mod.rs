//! f64 CPU reference of the rasterizer: the maths of [`super`] without snapping to 1/256
//! pixel, written for clarity (brute force over each triangle's bounding box). Tests compare
//! the GPU against it and take finite differences of it.

mod antialias;
mod visibility;

pub use antialias::antialias;
pub use visibility::visibility;

use crate::camera::Camera;
use glam::{DMat3, DVec3};

/// A mesh in f64: world positions, faces, vertex colours, and [`super::edge_adjacency`].
#[derive(Clone, Copy, Debug)]
pub struct ReferenceMesh<'a> {
    /// Vertex positions, world units.
    pub positions: &'a [[f64; 3]],
    /// Triangles as vertex indices, counter-clockwise.
    pub faces: &'a [[u32; 3]],
    /// Linear RGB colour per vertex.
    pub colors: &'a [[f64; 3]],
    /// Per face and edge, the face across it or -1 ([`super::edge_adjacency`] of `faces`).
    pub adjacency: &'a [i32],
}

/// The reference's images (row-major); see [`super::RasterFrame`] for their meaning.
#[derive(Clone, Debug, Default)]
pub struct ReferenceFrame {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Triangle per pixel, [`super::NO_TRIANGLE`] where uncovered.
    pub ids: Vec<u32>,
    /// Perspective-correct barycentrics (b0, b1, b2); 0 where uncovered.
    pub barycentrics: Vec<[f64; 3]>,
    /// Resolved (rgb, mask) before anti-aliasing.
    pub resolved: Vec<[f64; 4]>,
    /// Interpolated camera-space depth z; 0 where uncovered.
    pub depth: Vec<f64>,
    /// World-space unit face normals; 0 where uncovered.
    pub normals: Vec<[f64; 3]>,
    /// Anti-aliased (rgb, mask).
    pub antialiased: Vec<[f64; 4]>,
}

/// Camera-space corners of every vertex.
pub(crate) fn to_camera(camera: &Camera, positions: &[[f64; 3]]) -> Vec<DVec3> {
    positions.iter().map(|&p| camera.world_to_camera.transform_point3(DVec3::from(p))).collect()
}

/// Pixel coordinates of a camera-space point.
#[inline]
pub(crate) fn project(camera: &Camera, c: DVec3) -> [f64; 2] {
    [camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy]
}

/// Renders `mesh` from `camera` with near plane `near`: visibility, resolve, anti-aliasing.
pub fn render(mesh: &ReferenceMesh, camera: &Camera, near: f64) -> ReferenceFrame {
    let cam = to_camera(camera, mesh.positions);
    let ids = visibility(&cam, mesh.faces, camera, near);
    let n = ids.len();
    let mut frame = ReferenceFrame {
        width: camera.width,
        height: camera.height,
        ids,
        barycentrics: vec![[0.0; 3]; n],
        resolved: vec![[0.0; 4]; n],
        depth: vec![0.0; n],
        normals: vec![[0.0; 3]; n],
        antialiased: Vec::new(),
    };
    let to_world = DMat3::from_mat4(camera.world_to_camera).transpose();
    for i in 0..n {
        let t = frame.ids[i];
        if t == super::NO_TRIANGLE {
            continue;
        }
        let f = mesh.faces[t as usize];
        let v = f.map(|k| cam[k as usize]);
        let (px, py) =
            ((i % camera.width as usize) as f64 + 0.5, (i / camera.width as usize) as f64 + 0.5);
        let d = DVec3::new((px - camera.cx) / camera.fx, (py - camera.cy) / camera.fy, 1.0);
        let s = [d.dot(v[1].cross(v[2])), d.dot(v[2].cross(v[0])), d.dot(v[0].cross(v[1]))];
        let sum = s[0] + s[1] + s[2];
        let b = if sum != 0.0 { s.map(|x| x / sum) } else { [1.0 / 3.0; 3] };
        let mut rgb = [0.0; 3];
        for k in 0..3 {
            for (c, value) in rgb.iter_mut().enumerate() {
                *value += b[k] * mesh.colors[f[k] as usize][c];
            }
        }
        let normal = (to_world * (v[1] - v[0]).cross(v[2] - v[0])).normalize_or_zero();
        frame.barycentrics[i] = b;
        frame.resolved[i] = [rgb[0], rgb[1], rgb[2], 1.0];
        frame.depth[i] = (b[0] * v[0] + b[1] * v[1] + b[2] * v[2]).z;
        frame.normals[i] = normal.to_array();
    }
    frame.antialiased = antialias(&frame, &cam, mesh, camera, near);
    frame
}
