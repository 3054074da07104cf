//! The flow term's targets for a later frame (`crate::loss::flow`): each vertex of frame t − 1
//! that a training view sees, followed by Lucas–Kanade from that view's image at t − 1 to its
//! image at t. A target is kept where the backward track returns within a pixel (so the
//! window had texture and nothing crossed it) and lands on the subject's mask at t.

use crate::flow::{luma, GrayImage, LucasKanade};
use crate::geometry::SurfaceBvh;
use crate::loss::flow::FlowTarget;
use crate::train::ViewTarget;
use glam::DVec3;

/// Largest forward-backward round trip of a kept track, pixels.
const MAX_ROUND_TRIP_PIXELS: f32 = 1.0;

/// Relative slack of the visibility test: the faces around a vertex must not hide it.
const VISIBILITY_SLACK: f64 = 1e-3;

/// Targets for `previous` (frame t − 1's vertex positions on `faces`), vertex-major, one per
/// view of `views` (each frame t − 1's and frame t's target of one camera). All empty (weight
/// 0) when the surface cannot be built; a vertex hidden from, or outside, a view has none there.
pub fn flow_targets(
    previous: &[[f32; 3]],
    faces: &[[u32; 3]],
    views: &[(&ViewTarget, &ViewTarget)],
) -> Vec<FlowTarget> {
    let mut targets = vec![FlowTarget::default(); previous.len() * views.len()];
    let Ok(bvh) = SurfaceBvh::build(previous, faces) else { return targets };
    let lk = LucasKanade::default();
    for (v, (before, now)) in views.iter().enumerate() {
        let camera = &before.camera;
        let (width, height) = (camera.width as usize, camera.height as usize);
        if now.camera.width != camera.width || now.camera.height != camera.height {
            continue;
        }
        let eye = camera.center();
        // Index coordinates (pixel centres at integers) of the visible vertices.
        let (seen, points): (Vec<usize>, Vec<[f32; 2]>) = previous
            .iter()
            .enumerate()
            .filter_map(|(i, &x)| {
                let p = DVec3::from(x.map(f64::from));
                let uv = camera.project(p)?;
                let inside =
                    uv.x >= 0.0 && uv.y >= 0.0 && uv.x < width as f64 && uv.y < height as f64;
                (inside && !bvh.hides(eye, p, VISIBILITY_SLACK))
                    .then(|| (i, [uv.x as f32 - 0.5, uv.y as f32 - 0.5]))
            })
            .unzip();
        let (gray_before, gray_now) = (luma(&before.target), luma(&now.target));
        let tracked = lk.track_consistent(
            GrayImage { pixels: &gray_before, width, height },
            GrayImage { pixels: &gray_now, width, height },
            &points,
            MAX_ROUND_TRIP_PIXELS,
        );
        for (&i, end) in seen.iter().zip(tracked) {
            let Some([u, w]) = end else { continue };
            let pixel =
                (w.round() as usize).min(height - 1) * width + (u.round() as usize).min(width - 1);
            if now.target[pixel][3] > 0.5 {
                targets[i * views.len() + v] = FlowTarget { u, v: w, weight: 1.0, unused: 0.0 };
            }
        }
    }
    targets
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    /// A grid of `n × n` vertices over the square |x|, |y| ≤ `half` at height `z`.
    fn grid(n: u32, half: f32, z: f32, first: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let at = |k: u32| -half + 2.0 * half * k as f32 / (n - 1) as f32;
        let positions = (0..n * n).map(|i| [at(i % n), at(i / n), z]).collect();
        let faces = (0..(n - 1) * (n - 1))
            .flat_map(|c| {
                let a = first + c / (n - 1) * n + c % (n - 1);
                [[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]
            })
            .collect();
        (positions, faces)
    }

    /// The unit plane z = 0, textured, moved by `shift`, seen from above (mask: the plane).
    fn view(camera: Camera, shift: [f64; 2]) -> ViewTarget {
        let texture = |x: f64, y: f64| {
            0.5 + 0.2 * (17.0 * x + 1.0).sin() * (13.0 * y).cos()
                + 0.2 * (11.0 * x - 19.0 * y).sin()
        };
        let target = (0..camera.width * camera.height)
            .map(|p| {
                let (o, d) = camera
                    .pixel_ray((p % camera.width) as f64 + 0.5, (p / camera.width) as f64 + 0.5);
                let hit = o - d * (o.z / d.z);
                let (x, y) = (hit.x - shift[0], hit.y - shift[1]);
                if x.abs() <= 1.0 && y.abs() <= 1.0 {
                    let g = texture(x, y) as f32;
                    [g, g, g, 1.0]
                } else {
                    [0.0; 4]
                }
            })
            .collect();
        ViewTarget { name: "top".into(), camera, target }
    }

    #[test]
    fn visible_vertices_follow_the_images_and_hidden_ones_get_none() {
        let eye = DVec3::new(0.2, -0.3, 3.0);
        let camera =
            Camera::look_at(64, 64, 60.0, 60.0, 32.0, 32.0, eye, DVec3::ZERO, DVec3::Y).unwrap();
        let (mut positions, mut faces) = grid(11, 1.0, 0.0, 0);
        // A smaller plane under the first: hidden from the camera.
        let (under, under_faces) = grid(3, 0.3, -0.5, positions.len() as u32);
        let hidden = positions.len()..positions.len() + under.len();
        positions.extend(under);
        faces.extend(under_faces);
        let shift = [0.1, -0.06];
        let (before, now) = (view(camera, [0.0; 2]), view(camera, shift));
        let targets = flow_targets(&positions, &faces, &[(&before, &now)]);
        assert_eq!(targets.len(), positions.len());
        assert!(hidden.clone().all(|i| targets[i].weight == 0.0), "hidden vertices have targets");
        let mut kept = 0;
        for (i, (x, t)) in positions.iter().zip(&targets).enumerate().take(hidden.start) {
            if t.weight == 0.0 {
                continue;
            }
            kept += 1;
            let moved = DVec3::new(x[0] as f64 + shift[0], x[1] as f64 + shift[1], 0.0);
            let expect = camera.project(moved).unwrap() - 0.5;
            let error = (expect - glam::DVec2::new(t.u as f64, t.v as f64)).length();
            // The plane's edge is sampled at pixel centres, not anti-aliased: it moves by
            // whole pixels, and a window holding it follows it part of the way.
            let edge = x[0].abs().max(x[1].abs()) > 0.75;
            let bound = if edge { 0.75 } else { 0.1 };
            assert!(error < bound, "vertex {i} at {x:?}: {error} pixels off");
        }
        // The border's windows reach past the plane's edge, where the image is not the
        // texture moved: most of the interior must still be kept.
        assert!(kept >= 60, "only {kept} of 121 vertices kept a target");
    }

    #[test]
    fn no_surface_or_no_views_give_no_targets() {
        let camera =
            Camera::look_at(16, 16, 20.0, 20.0, 8.0, 8.0, DVec3::Z * 3.0, DVec3::ZERO, DVec3::Y)
                .unwrap();
        let v = view(camera, [0.0; 2]);
        let points = [[0.0f32; 3]; 4];
        assert!(flow_targets(&points, &[], &[(&v, &v)]).iter().all(|t| t.weight == 0.0));
        assert!(flow_targets(&points, &[[0, 1, 2]], &[]).is_empty());
    }
}
