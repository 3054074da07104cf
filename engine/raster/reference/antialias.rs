//! Reference anti-aliasing at silhouettes (see [`super::super`] for the rule).

use super::{project, ReferenceFrame, ReferenceMesh};
use crate::camera::Camera;
use glam::DVec3;

struct Crossing {
    covered: usize,
    other: usize,
    t: f64,
}

fn faces_camera(cam: &[DVec3], face: [u32; 3]) -> bool {
    let v = face.map(|k| cam[k as usize]);
    (v[1] - v[0]).cross(v[2] - v[0]).dot(v[0]) < 0.0
}

fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

fn centre(i: usize, w: usize) -> [f64; 2] {
    [(i % w) as f64 + 0.5, (i / w) as f64 + 0.5]
}

/// The first outline edge of triangle t leaving pixel a towards pixel b.
fn crossing_from(
    t: u32,
    a: usize,
    b: usize,
    cam: &[DVec3],
    mesh: &ReferenceMesh,
    camera: &Camera,
    near: f64,
) -> Option<Crossing> {
    let face = mesh.faces[t as usize];
    let v = face.map(|k| cam[k as usize]);
    if v.iter().any(|c| c.z < near) {
        return None;
    }
    let s = v.map(|c| project(camera, c));
    let orientation = edge(s[0], s[1], s[2]).signum();
    let w = camera.width as usize;
    let mut found: Option<Crossing> = None;
    for k in 0..3 {
        let (e0, e1) = (s[k], s[(k + 1) % 3]);
        let ea = orientation * edge(e0, e1, centre(a, w));
        let eb = orientation * edge(e0, e1, centre(b, w));
        let across = mesh.adjacency[3 * t as usize + k];
        let outline =
            across < 0 || faces_camera(cam, mesh.faces[across as usize]) != faces_camera(cam, face);
        if ea >= 0.0 && eb < 0.0 && outline {
            let t_cross = ea / (ea - eb);
            if found.as_ref().is_none_or(|c| t_cross < c.t) {
                found = Some(Crossing { covered: a, other: b, t: t_cross });
            }
        }
    }
    found
}

/// The crossing between pixels p0 and p1, nearer pixel's triangle first.
fn pair(
    p0: usize,
    p1: usize,
    frame: &ReferenceFrame,
    cam: &[DVec3],
    mesh: &ReferenceMesh,
    camera: &Camera,
    near: f64,
) -> Option<Crossing> {
    let (t0, t1) = (frame.ids[p0], frame.ids[p1]);
    if t0 == t1 {
        return None;
    }
    let depth = |p: usize, t: u32| {
        if t == super::super::NO_TRIANGLE {
            f64::INFINITY
        } else {
            frame.depth[p]
        }
    };
    let ((np, nt), (fp, ft)) =
        if depth(p0, t0) <= depth(p1, t1) { ((p0, t0), (p1, t1)) } else { ((p1, t1), (p0, t0)) };
    let none = super::super::NO_TRIANGLE;
    let first = if nt != none { crossing_from(nt, np, fp, cam, mesh, camera, near) } else { None };
    first.or_else(|| {
        if ft != none {
            crossing_from(ft, fp, np, cam, mesh, camera, near)
        } else {
            None
        }
    })
}

/// The anti-aliased (rgb, mask) image from a resolved frame and camera-space vertices `cam`.
pub fn antialias(
    frame: &ReferenceFrame,
    cam: &[DVec3],
    mesh: &ReferenceMesh,
    camera: &Camera,
    near: f64,
) -> Vec<[f64; 4]> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut out = frame.resolved.clone();
    let mut blend = |c: Crossing| {
        let (target, source, weight) = if c.t >= 0.5 {
            (c.other, c.covered, c.t - 0.5)
        } else {
            (c.covered, c.other, 0.5 - c.t)
        };
        let (from, to) = (frame.resolved[source], frame.resolved[target]);
        for (k, value) in out[target].iter_mut().enumerate() {
            *value += weight * (from[k] - to[k]);
        }
    };
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            if x + 1 < w {
                if let Some(c) = pair(p, p + 1, frame, cam, mesh, camera, near) {
                    blend(c);
                }
            }
            if y + 1 < h {
                if let Some(c) = pair(p, p + w, frame, cam, mesh, camera, near) {
                    blend(c);
                }
            }
        }
    }
    out
}
