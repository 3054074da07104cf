//! The image correspondences of a later frame t (`crate::loss::flow` scores them), two kinds:
//! - flow: a vertex that a training view sees at frame t − 1 is followed by Lucas–Kanade from
//!   that frame's image to the view's image at t, searched from where the frame's starting
//!   pose projects it; kept where the backward track returns within a pixel of the source
//!   pixel (the window had texture and nothing crossed it) and lands on the subject's mask.
//!   It starts from the vertex's estimate at t − 1, so it stops a new slide but keeps an old one.
//! - anchors ([`VertexTracks`]): each vertex's pixel of frame 0, where the surface was built,
//!   followed through the view's frames by image tracks ([`ImageTracks`]) that never restart
//!   from an estimate, so a slide the earlier frames let in costs error and is pulled back.

use crate::camera::Camera;
use crate::flow::{luma, GrayImage, ImageTracks, LucasKanade};
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
    let (Ok(from), Ok(to)) =
        (SurfaceBvh::build(source.positions, faces), SurfaceBvh::build(guess, faces))
    else {
        return out;
    };
    let lk = LucasKanade::default();
    for (v, (before, after)) in pairs.iter().enumerate() {
        let from_pixels = visible_pixels(&from, source.positions, &before.camera);
        let to_pixels = visible_pixels(&to, guess, &after.camera);
        // (vertex, its source pixel, its guessed pixel) of every vertex both poses show.
        let shown: Vec<(usize, [f32; 2], [f32; 2])> = (from_pixels.iter().zip(&to_pixels))
            .enumerate()
            .filter_map(|(i, (a, b))| Some((i, (*a)?, (*b)?)))
            .collect();
        let points: Vec<[f32; 2]> = shown.iter().map(|s| s.1).collect();
        let guesses: Vec<[f32; 2]> = shown.iter().map(|s| s.2).collect();
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
        for (&(i, _, _), end) in shown.iter().zip(tracked) {
            let Some([u, w]) = end else { continue };
            if on_mask(after, width, [u, w]) {
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

/// Every training view's image tracks of the vertices it saw at frame 0.
pub struct VertexTracks {
    views: Vec<ViewTracks>,
    lk: LucasKanade,
}

/// One view's tracks and the images they step between.
struct ViewTracks {
    name: String,
    camera: Camera,
    /// Frame 0's luma and that of the frame the tracks are at.
    first: Vec<f32>,
    latest: Vec<f32>,
    tracks: ImageTracks,
}

impl VertexTracks {
    /// Tracks of every vertex of `frame0` that a view of it sees (not hidden by `faces`).
    /// Empty when the surface cannot be built.
    pub fn start(frame0: SeenPose, faces: &[[u32; 3]]) -> Self {
        let lk = LucasKanade { window_radius: TRACK_WINDOW_RADIUS, ..LucasKanade::default() };
        let Ok(bvh) = SurfaceBvh::build(frame0.positions, faces) else {
            return Self { views: Vec::new(), lk };
        };
        let views = frame0
            .views
            .iter()
            .map(|v| {
                let pixels = visible_pixels(&bvh, frame0.positions, &v.camera);
                let first = luma(&v.target);
                ViewTracks {
                    name: v.name.clone(),
                    camera: v.camera,
                    latest: first.clone(),
                    first,
                    tracks: ImageTracks::new(pixels),
                }
            })
            .collect();
        Self { views, lk }
    }

    /// Steps every view's tracks to its image in `next` (the following frame's training
    /// views), then revives lost tracks of vertices that `guess` (that frame's starting pose,
    /// on `faces`) shows in the view near where it projects them; a view missing in `next`, or
    /// of another size, loses its tracks.
    pub fn advance(&mut self, next: &[ViewTarget], guess: &[[f32; 3]], faces: &[[u32; 3]]) {
        let bvh = SurfaceBvh::build(guess, faces).ok();
        for view in &mut self.views {
            let size = (view.camera.width, view.camera.height);
            let Some(target) = next
                .iter()
                .find(|n| n.name == view.name && (n.camera.width, n.camera.height) == size)
            else {
                view.tracks.now.iter_mut().for_each(|p| *p = None);
                continue;
            };
            let (width, height) = (size.0 as usize, size.1 as usize);
            let image = |pixels| GrayImage { pixels, width, height };
            let now = luma(&target.target);
            view.tracks.advance(&self.lk, image(&view.first), image(&view.latest), image(&now));
            if let Some(bvh) = &bvh {
                let near = visible_pixels(bvh, guess, &view.camera);
                view.tracks.revive(&self.lk, image(&view.first), image(&now), &near);
            }
            view.latest = now;
        }
    }

    /// The anchors of frame t (`now`, the frame the tracks were last advanced to): each live
    /// track of a vertex that `guess` (frame t's starting pose) shows in that view and whose
    /// pixel lies on the view's mask.
    pub fn targets(
        &self,
        guess: &[[f32; 3]],
        faces: &[[u32; 3]],
        now: &[ViewTarget],
    ) -> Correspondences {
        let pairs: Vec<(&ViewTracks, &ViewTarget)> = self
            .views
            .iter()
            .filter_map(|v| now.iter().find(|n| n.name == v.name).map(|n| (v, n)))
            .filter(|(v, n)| v.camera.width == n.camera.width && v.camera.height == n.camera.height)
            .collect();
        let mut out = Correspondences {
            targets: vec![FlowTarget::default(); guess.len() * pairs.len()],
            cameras: pairs.iter().map(|(_, n)| n.camera).collect(),
            unmatched_views: Vec::new(),
        };
        let Ok(bvh) = SurfaceBvh::build(guess, faces) else { return out };
        for (v, (tracks, view)) in pairs.iter().enumerate() {
            let shown = visible_pixels(&bvh, guess, &view.camera);
            let width = view.camera.width as usize;
            let mut matched = 0;
            for (i, (p, shown)) in tracks.tracks.now.iter().zip(&shown).enumerate() {
                let (Some([u, w]), Some(_)) = (p, shown) else { continue };
                if i >= guess.len() || !on_mask(view, width, [*u, *w]) {
                    continue;
                }
                out.targets[i * pairs.len() + v] =
                    FlowTarget { u: *u, v: *w, weight: 1.0, unused: 0.0 };
                matched += 1;
            }
            if matched == 0 {
                out.unmatched_views.push(view.name.clone());
            }
        }
        out
    }
}

/// Half the side of the image tracks' window: 4 gives 9 × 9 pixels. Smaller than the flow's
/// 15 × 15, so a window holds less of what moves otherwise (a limb's other side, the
/// background): on fox_run_textured, stepping the true points frame by frame, 9 × 9 keeps
/// more of them within a pixel of the truth after five frames (53 % against 39 %).
const TRACK_WINDOW_RADIUS: usize = 4;

/// Whether index-coordinate pixel `p` lies on `view`'s mask (`width` its row length).
fn on_mask(view: &ViewTarget, width: usize, p: [f32; 2]) -> bool {
    let height = view.target.len() / width.max(1);
    let (x, y) = (p[0].round(), p[1].round());
    if !(x >= 0.0 && y >= 0.0 && (x as usize) < width && (y as usize) < height) {
        return false;
    }
    view.target[y as usize * width + x as usize][3] > 0.5
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
    use crate::camera::Camera;
    use glam::DVec2;
    use std::sync::Arc;

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
        ViewTarget { name: "top".into(), camera, target: Arc::new(target) }
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
    fn assert_at_moved(
        positions: &[[f32; 3]],
        hidden: std::ops::Range<usize>,
        found: &Correspondences,
        shift: [f64; 2],
    ) {
        let camera = top_camera();
        assert_eq!(found.targets.len(), positions.len());
        assert!(
            hidden.clone().all(|i| found.targets[i].weight == 0.0),
            "hidden vertices have targets"
        );
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
        let slid: Vec<[f32; 3]> =
            positions.iter().map(|x| [x[0] + 0.1 + 0.2, x[1] - 0.06 + 0.15, x[2]]).collect();
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
        assert!(correspondences(no_views, &points, &[[0, 1, 2]], std::slice::from_ref(&v))
            .targets
            .is_empty());
        // A dark view (a lost light): nothing to follow, and the view is named.
        let (positions, faces, _) = planes();
        let mut dark = view(top_camera(), [0.0; 2]);
        Arc::make_mut(&mut dark.target).iter_mut().for_each(|p| *p = [0.0, 0.0, 0.0, p[3]]);
        let source = SeenPose { positions: &positions, views: std::slice::from_ref(&dark) };
        let found = correspondences(source, &positions, &faces, std::slice::from_ref(&dark));
        assert!(found.targets.iter().all(|t| t.weight == 0.0));
        assert_eq!(found.unmatched_views, vec!["top".to_string()]);
    }
}
