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
use crate::flow::{luma, GrayImage, ImageTracks, LucasKanade, Warp, IDENTITY};
use crate::geometry::SurfaceBvh;
use crate::loss::flow::FlowTarget;
use crate::train::ViewTarget;
use glam::{DMat2, DVec2, DVec3};

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
    /// Frame 0's vertex positions, from which each frame's window warps are measured.
    start: Vec<[f32; 3]>,
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
            return Self { views: Vec::new(), start: Vec::new(), lk };
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
        Self { views, start: frame0.positions.to_vec(), lk }
    }

    /// Steps every view's tracks to its image in `next` (the following frame's training
    /// views), then revives lost tracks of vertices that `guess` (that frame's starting pose,
    /// on `faces`) shows in the view near where it projects them; a view missing in `next`, or
    /// of another size, loses its tracks. Frame 0's windows are matched through the warps the
    /// surface went through from frame 0 to `guess` ([`surface_warps`]), so a part that turned
    /// or stretched since is matched as it now looks.
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
            let warps = surface_warps(&self.start, guess, faces, &view.camera);
            let frames = [image(&view.first), image(&view.latest), image(&now)];
            view.tracks.advance(&self.lk, frames, &warps);
            if let Some(bvh) = &bvh {
                let near = visible_pixels(bvh, guess, &view.camera);
                view.tracks.revive(&self.lk, [frames[0], frames[2]], &near, &warps);
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

/// Each vertex's window warp in `camera` from pose `from` to pose `to` (the same vertices on
/// `faces`): the 2×2 map that best carries, in least squares, the pixel offsets to its faces'
/// other corners under `from` onto those under `to`. [`IDENTITY`] where the offsets do not fix
/// one (fewer than two independent ones, a corner behind the camera) or it turns the window
/// inside out or scales its area past [`MAX_WARP_AREA`]: there the window is matched unwarped.
fn surface_warps(
    from: &[[f32; 3]],
    to: &[[f32; 3]],
    faces: &[[u32; 3]],
    camera: &Camera,
) -> Vec<Warp> {
    let pixels = |pose: &[[f32; 3]]| -> Vec<Option<DVec2>> {
        pose.iter().map(|x| camera.project(DVec3::from(x.map(f64::from)))).collect()
    };
    let (before, after) = (pixels(from), pixels(to));
    // Per vertex: Σ d dᵀ of its offsets before, and Σ d' dᵀ of after against before.
    let mut sums = vec![(DMat2::ZERO, DMat2::ZERO); from.len().min(to.len())];
    let offset = |p: &[Option<DVec2>], a: usize, b: usize| Some((*p.get(b)?)? - (*p.get(a)?)?);
    for face in faces {
        for k in 0..3 {
            let [a, b, c] = [0, 1, 2].map(|j| face[(k + j) % 3] as usize);
            for other in [b, c] {
                let (Some(d), Some(e)) = (offset(&before, a, other), offset(&after, a, other))
                else {
                    continue;
                };
                if let Some(sum) = sums.get_mut(a) {
                    sum.0 += DMat2::from_cols(d * d.x, d * d.y);
                    sum.1 += DMat2::from_cols(e * d.x, e * d.y);
                }
            }
        }
    }
    sums.iter().map(|&(spread, carried)| warp_of(spread, carried)).collect()
}

/// Smallest ratio of the short to the long axis of a vertex's offsets that fixes a warp.
const MIN_SPREAD_RATIO: f64 = 0.01;

/// Largest factor by which a kept warp may scale a window's area, or shrink it.
const MAX_WARP_AREA: f64 = 4.0;

/// The least-squares map `carried · spread⁻¹` as a [`Warp`], [`IDENTITY`] where `spread` is
/// near singular or the map is not a plausible surface motion (see [`surface_warps`]).
fn warp_of(spread: DMat2, carried: DMat2) -> Warp {
    // Offsets along one line only (or none) leave the other direction unknown.
    // det / trace² is about the ratio of the spread's two axes when one is small.
    let trace = spread.x_axis.x + spread.y_axis.y;
    if spread.determinant() <= MIN_SPREAD_RATIO * trace * trace {
        return IDENTITY;
    }
    let map = carried * spread.inverse();
    let area = map.determinant();
    if !(area.is_finite() && (1.0 / MAX_WARP_AREA..=MAX_WARP_AREA).contains(&area)) {
        return IDENTITY;
    }
    [map.x_axis.x, map.y_axis.x, map.x_axis.y, map.y_axis.y].map(|m| m as f32)
}

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

    #[test]
    fn a_turned_plane_warps_its_windows_by_the_turn() {
        // On the plane's axis, so the image of the plane is a similarity of it.
        let eye = DVec3::new(0.0, 0.0, 3.0);
        let camera =
            Camera::look_at(64, 64, 60.0, 60.0, 32.0, 32.0, eye, DVec3::ZERO, DVec3::Y).unwrap();
        let (from, faces) = grid(11, 1.0, 0.0, 0);
        // Turned 20 degrees about the view axis and pushed a third closer: the image turns by
        // as much (either way round: the image's y axis points down) and grows by 3 / 2.
        let (c, s) = (20f32.to_radians().cos(), 20f32.to_radians().sin());
        let turned: Vec<[f32; 3]> =
            from.iter().map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1], 1.0]).collect();
        let warps = surface_warps(&from, &turned, &faces, &camera);
        let scale = 3.0 / 2.0;
        for (i, w) in warps.iter().enumerate() {
            let turn = [c, s.copysign(w[1]), -s.copysign(w[1]), c].map(|m| m * scale);
            let off = (w.iter().zip(turn)).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            assert!(off < 1e-4, "vertex {i}: {w:?} against {turn:?}");
        }
        // A pose behind the camera, a mirrored one and a collapsed one are not warped.
        let behind: Vec<[f32; 3]> = from.iter().map(|p| [p[0], p[1], 5.0]).collect();
        let mirrored: Vec<[f32; 3]> = from.iter().map(|p| [-p[0], p[1], 0.0]).collect();
        let collapsed: Vec<[f32; 3]> = from.iter().map(|p| [p[0], 0.0, 0.0]).collect();
        for pose in [&behind, &mirrored, &collapsed] {
            assert!(surface_warps(&from, pose, &faces, &camera).iter().all(|&w| w == IDENTITY));
        }
        // Vertices of no face, or faces past the poses, leave the rest as they are.
        let short = surface_warps(&from[..5], &turned, &faces, &camera);
        assert_eq!(short.len(), 5);
    }
}
