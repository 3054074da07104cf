//! Reference visibility: near clip, projection, edge functions with the top-left rule, nearest
//! depth per pixel centre (ties to the lower triangle id).

use super::project;
use crate::camera::Camera;
use glam::DVec3;

/// Triangle per pixel (`NO_TRIANGLE` where uncovered) for camera-space vertices `cam`.
pub fn visibility(cam: &[DVec3], faces: &[[u32; 3]], camera: &Camera, near: f64) -> Vec<u32> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut best = vec![(f64::INFINITY, super::super::NO_TRIANGLE); w * h];
    for (t, face) in faces.iter().enumerate() {
        let poly = clip_near(face.map(|k| (k, cam[k as usize])), near);
        for k in 1..poly.len().saturating_sub(1) {
            let corners = [poly[0], poly[k], poly[k + 1]];
            draw(corners.map(|c| (project(camera, c), 1.0 / c.z)), t as u32, (w, h), &mut best);
        }
    }
    best.into_iter().map(|(_, t)| t).collect()
}

/// The triangle clipped to z ≥ near: 0, 3 or 4 corners (crossings from the lower vertex index).
fn clip_near(corners: [(u32, DVec3); 3], near: f64) -> Vec<DVec3> {
    let mut poly = Vec::with_capacity(4);
    if corners.iter().any(|(_, c)| !c.is_finite()) {
        return poly;
    }
    for k in 0..3 {
        let (a, b) = (corners[k], corners[(k + 1) % 3]);
        if a.1.z >= near {
            poly.push(a.1);
        }
        if (a.1.z >= near) != (b.1.z >= near) {
            let (lo, hi) = if a.0 < b.0 { (a.1, b.1) } else { (b.1, a.1) };
            let s = (near - lo.z) / (hi.z - lo.z);
            poly.push(DVec3::new(lo.x + s * (hi.x - lo.x), lo.y + s * (hi.y - lo.y), near));
        }
    }
    if poly.len() < 3 {
        Vec::new()
    } else {
        poly
    }
}

fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top-left rule in y-down pixels, for counter-clockwise (positive-area) triangles.
fn covers(e: f64, a: [f64; 2], b: [f64; 2]) -> bool {
    e > 0.0 || (e == 0.0 && (b[1] < a[1] || (b[1] == a[1] && b[0] > a[0])))
}

fn draw(mut c: [([f64; 2], f64); 3], id: u32, (w, h): (usize, usize), best: &mut [(f64, u32)]) {
    let area = edge(c[0].0, c[1].0, c[2].0);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    if area < 0.0 {
        c.swap(1, 2);
    }
    let xs = c.map(|v| v.0[0]);
    let ys = c.map(|v| v.0[1]);
    let lo = |v: [f64; 3]| (v.iter().copied().fold(f64::INFINITY, f64::min) - 0.5).ceil().max(0.0);
    let hi = |v: [f64; 3], n: usize| {
        (v.iter().copied().fold(f64::NEG_INFINITY, f64::max) - 0.5).floor().min(n as f64 - 1.0)
    };
    let (x0, x1, y0, y1) = (lo(xs), hi(xs, w), lo(ys), hi(ys, h));
    if x0 > x1 || y0 > y1 {
        return;
    }
    for y in y0 as usize..=y1 as usize {
        for x in x0 as usize..=x1 as usize {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let e = [edge(c[1].0, c[2].0, p), edge(c[2].0, c[0].0, p), edge(c[0].0, c[1].0, p)];
            if !(covers(e[0], c[1].0, c[2].0)
                && covers(e[1], c[2].0, c[0].0)
                && covers(e[2], c[0].0, c[1].0))
            {
                continue;
            }
            let sum = e[0] + e[1] + e[2];
            let depth = sum / (e[0] * c[0].1 + e[1] * c[1].1 + e[2] * c[2].1);
            let slot = &mut best[y * w + x];
            if (depth, id) < *slot {
                *slot = (depth, id);
            }
        }
    }
}
