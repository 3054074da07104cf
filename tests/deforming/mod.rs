//! Test sequences with known motion, built in the test: the subdivided sphere of
//! `tagsplat::geometry::sphere`, squashed into an ellipsoid, moved by an analytic motion.

#![allow(dead_code)] // Each test binary uses its own part.

use glam::{DMat3, DVec3};
use tagsplat::geometry::sphere::unit_sphere;
use tagsplat::sequence::MeshSequence;

/// An affine motion x ↦ A(t)·x + c(t): a rotation about a tilted axis, a pulsing anisotropic
/// scale and a translation. Affine maps commute with barycentric combinations, so every
/// surface point follows this exact formula too.
pub fn affine(t: f64, x: DVec3) -> DVec3 {
    let rotation = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.3 * t);
    let scale = DVec3::new(1.0 + 0.1 * (0.7 * t).sin(), 1.0 - 0.05 * t / (1.0 + t), 1.0 + 0.02 * t);
    rotation * (scale * x) + DVec3::new(0.1 * t, -0.05 * t * t, 0.3 * (0.5 * t).sin())
}

/// A non-affine motion (a travelling bend), the identity at t = 0: vertices follow it
/// exactly, surface points only approximately (their faces stay flat).
pub fn bend(t: f64, x: DVec3) -> DVec3 {
    x + DVec3::new(0.0, 0.2 * (2.0 * x.x + 0.8 * t).sin() * (0.5 * t).sin(), 0.1 * t * x.y * x.y)
}

/// The ellipsoid (radii 1, 0.7, 0.5) subdivided `level` times, moved by `motion` over
/// `frames` frames (frame 0 is motion(0, ·)), with per-frame vertex colours.
pub fn sequence(level: u32, frames: usize, motion: fn(f64, DVec3) -> DVec3) -> MeshSequence {
    let (sphere, faces) = unit_sphere(level);
    let rest: Vec<DVec3> = sphere
        .iter()
        .map(|p| DVec3::new(p[0] as f64, 0.7 * p[1] as f64, 0.5 * p[2] as f64))
        .collect();
    let frames_positions = (0..frames)
        .map(|t| rest.iter().map(|&x| motion(t as f64, x).as_vec3().to_array()).collect())
        .collect();
    let colors = (0..frames)
        .map(|t| {
            (0..rest.len())
                .map(|i| [(i % 256) as u8, ((i / 256 + t) % 256) as u8, (t * 37 % 256) as u8])
                .collect()
        })
        .collect();
    MeshSequence { faces, frames: frames_positions, colors: Some(colors) }
}

/// A fresh empty directory under the system temp dir, unique to this test.
pub fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("tagsplat-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
