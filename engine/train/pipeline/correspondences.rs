//! The image correspondences of a later frame t (`crate::loss::flow` scores them): a vertex
//! that a training view sees in a source pose is followed by Lucas–Kanade from the source's
//! image to that view's image at t, searched from where the frame's starting pose projects it.
//! Two sources serve: frame t − 1 (optical flow: nearly the same shading, so a step is followed
//! precisely) and frame 0 (an anchor: the vertex's own pixel when the surface was built, so a
//! slide along the surface that earlier frames accumulated costs error and is pulled back). A
//! target is kept where the backward track returns within a pixel of the source pixel (the
//! window had texture and nothing crossed it) and lands on the subject's mask at t.

use crate::camera::Camera;
use crate::flow::{luma, GrayImage, LucasKanade};
use crate::geometry::SurfaceBvh;
use crate::loss::flow::FlowTarget;
use crate::train::ViewTarget;
use glam::DVec3;

/// Largest forward-backward round trip of a kept track, pixels.
const MAX_ROUND_TRIP_PIXELS: f32 = 1.0;

/// Relative slack of the visibility test: the faces around a vertex must not hide it.
const VISIBILITY_SLACK: f64 = 1e-3;

/// A pose of the surface and the training views it was seen in.
#[derive(Clone, Copy)]
pub struct SeenPose<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// The views of that frame.
    pub views: &'a [ViewTarget],
}

/// The targets of one source: vertex-major, one per camera of `cameras` (the views the source
/// and frame t share), and the names of shared views where no vertex could be matched.
pub struct Correspondences {
    pub targets: Vec<FlowTarget>,
    pub cameras: Vec<Camera>,
    pub unmatched_views: Vec<String>,
}

/// Where `source`'s vertices lie in the views of frame t (`now`), searched from where `guess`
/// (frame t's starting pose, the same vertices) projects them. A vertex hidden by `faces` in
/// either pose, or outside a view, has no target there; views whose sizes differ are skipped.
/// All empty when either surface cannot be built.
pub fn correspondences(
    source: SeenPose,
    guess: &[[f32; 3]],
    faces: &[[u32; 3]],
    now: &[ViewTarget],
) -> Correspondences {
    let pairs: Vec<(&ViewTarget, &ViewTarget)> = now
        .iter()
        .filter_map(|n| source.views.iter().find(|s| s.name == n.name).map(|s| (s, n)))
        .filter(|(s, n)| (s.camera.width, s.camera.height) == (n.camera.width, n.camera.height))
        .collect();
    let cameras: Vec<Camera> = pairs.iter().map(|(_, n)| n.camera).collect();
    let mut out = Correspondences {
        targets: vec![FlowTarget::default(); source.positions.len() * pairs.len()],
        cameras,
        unmatched_views: Vec::new(),
    };
    let (Ok(from), Ok(to)) = (SurfaceBvh::build(source.positions, faces), SurfaceBvh::build(guess, faces))
    else {
        return out;
    };
    let radius = std::env::var("TAGSPLAT_LK_RADIUS").ok().and_then(|r| r.parse().ok()).unwrap_or(7);
    let lk = LucasKanade { window_radius: radius, ..LucasKanade::default() };
    for (v, (before, after)) in pairs.iter().enumerate() {
        let from_pixels = visible_pixels(&from, source.positions, &before.camera);
        let to_pixels = visible_pixels(&to, guess, &after.camera);
        let (seen, (points, guesses)): (Vec<usize>, (Vec<[f32; 2]>, Vec<[f32; 2]>)) = from_pixels
            .iter()
            .zip(&to_pixels)
            .enumerate()
            .filter_map(|(i, (a, b))| Some((i, ((*a)?, (*b)?))))
            .unzip();
        let (width, height) = (before.camera.width as usize, before.camera.height as usize);
        let (gray_before, gray_after) = (luma(&before.target), luma(&after.target));
        let tracked = lk.track_consistent(
            GrayImage { pixels: &gray_before, width, height },
            GrayImage { pixels: &gray_after, width, height },
            &points,
            &guesses,
            MAX_ROUND_TRIP_PIXELS,
        );
        let mut matched = 0;
        for (&i, end) in seen.iter().zip(tracked) {
            let Some([u, w]) = end else { continue };
            let pixel =
                (w.round() as usize).min(height - 1) * width + (u.round() as usize).min(width - 1);
            if after.target[pixel][3] > 0.5 {
                out.targets[i * pairs.len() + v] = FlowTarget { u, v: w, weight: 1.0, unused: 0.0 };
                matched += 1;
            }
        }
        if matched == 0 {
            out.unmatched_views.push(after.name.clone());
        }
    }
    out
}

/// Each vertex's pixel in `camera` (index coordinates: pixel centres at integers) where the
/// surface `bvh` does not hide it and it lies inside the image.
fn visible_pixels(
    bvh: &SurfaceBvh,
    positions: &[[f32; 3]],
    camera: &Camera,
) -> Vec<Option<[f32; 2]>> {
    let sees = |x: [f32; 3]| bvh.sees(camera, DVec3::from(x.map(f64::from)), VISIBILITY_SLACK);
    positions.iter().map(|&x| sees(x).map(|uv| [uv.x as f32 - 0.5, uv.y as f32 - 0.5])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
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

    /// An 11 × 11 plane over a hidden 3 × 3 one, its vertices, faces and the hidden range.
    fn planes() -> (Vec<[f32; 3]>, Vec<[u32; 3]>, std::ops::Range<usize>) {
        let (mut positions, mut faces) = grid(11, 1.0, 0.0, 0);
        let (under, under_faces) = grid(3, 0.3, -0.5, positions.len() as u32);
        let hidden = positions.len()..positions.len() + under.len();
        positions.extend(under);
        faces.extend(under_faces);
        (positions, faces, hidden)
    }

    fn top_camera() -> Camera {
        let eye = DVec3::new(0.2, -0.3, 3.0);
        Camera::look_at(64, 64, 60.0, 60.0, 32.0, 32.0, eye, DVec3::ZERO, DVec3::Y).unwrap()
    }

    /// Asserts that no hidden vertex has a target and that most visible ones have one where
    /// the plane's `shift` took them.
    fn assert_at_moved(positions: &[[f32; 3]], hidden: std::ops::Range<usize>, found: &Correspondences, shift: [f64; 2]) {
        let camera = top_camera();
        assert_eq!(found.targets.len(), positions.len());
        assert!(hidden.clone().all(|i| found.targets[i].weight == 0.0), "hidden vertices have targets");
        let mut kept = 0;
        for (i, (x, t)) in positions.iter().zip(&found.targets).enumerate().take(hidden.start) {
            if t.weight == 0.0 {
                continue;
            }
            kept += 1;
            let moved = DVec3::new(x[0] as f64 + shift[0], x[1] as f64 + shift[1], 0.0);
            let expect = camera.project(moved).unwrap() - 0.5;
            let error = (expect - DVec2::new(t.u as f64, t.v as f64)).length();
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
    fn visible_vertices_follow_the_images_and_hidden_ones_get_none() {
        let (positions, faces, hidden) = planes();
        let shift = [0.1, -0.06];
        let (before, now) = (view(top_camera(), [0.0; 2]), view(top_camera(), shift));
        let source = SeenPose { positions: &positions, views: std::slice::from_ref(&before) };
        // No motion known: searched from where the vertices were.
        let found = correspondences(source, &positions, &faces, std::slice::from_ref(&now));
        assert_at_moved(&positions, hidden, &found, shift);
        assert!(found.unmatched_views.is_empty());
    }

    #[test]
    fn a_slid_guess_is_matched_back_to_the_source_pixel() {
        // The anchor's case: frame t's starting pose has the plane where it is, but slid
        // along itself by a few pixels; each vertex's target is where its own source pixel
        // went, not where the slid pose puts it.
        let (positions, faces, hidden) = planes();
        let shift = [0.1, -0.06];
        let slid: Vec<[f32; 3]> = positions
            .iter()
            .map(|x| [x[0] + 0.1 + 0.2, x[1] - 0.06 + 0.15, x[2]])
            .collect();
        let (before, now) = (view(top_camera(), [0.0; 2]), view(top_camera(), shift));
        let source = SeenPose { positions: &positions, views: std::slice::from_ref(&before) };
        let found = correspondences(source, &slid, &faces, std::slice::from_ref(&now));
        assert_at_moved(&positions, hidden, &found, shift);
    }

    #[test]
    fn no_surface_no_views_or_a_flat_image_give_no_targets() {
        let camera =
            Camera::look_at(16, 16, 20.0, 20.0, 8.0, 8.0, DVec3::Z * 3.0, DVec3::ZERO, DVec3::Y)
                .unwrap();
        let v = view(camera, [0.0; 2]);
        let points = [[0.0f32; 3]; 4];
        let source = SeenPose { positions: &points, views: std::slice::from_ref(&v) };
        let none = correspondences(source, &points, &[], std::slice::from_ref(&v));
        assert!(none.targets.iter().all(|t| t.weight == 0.0));
        let no_views = SeenPose { positions: &points, views: &[] };
        assert!(correspondences(no_views, &points, &[[0, 1, 2]], std::slice::from_ref(&v)).targets.is_empty());
        // A dark view (a lost light): nothing to follow, and the view is named.
        let (positions, faces, _) = planes();
        let mut dark = view(top_camera(), [0.0; 2]);
        dark.target.iter_mut().for_each(|p| *p = [0.0, 0.0, 0.0, p[3]]);
        let source = SeenPose { positions: &positions, views: std::slice::from_ref(&dark) };
        let found = correspondences(source, &positions, &faces, std::slice::from_ref(&dark));
        assert!(found.targets.iter().all(|t| t.weight == 0.0));
        assert_eq!(found.unmatched_views, vec!["top".to_string()]);
    }
}
