//! Initial Gaussians for a fit: at given points, or sampled inside every view's mask.

use super::TrainError;
use crate::camera::{nearest_point_to_rays, Camera};
use crate::rng::SplitMix64;
use crate::splat::{sh_coefficients, GaussianScene};
use glam::DVec3;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;

/// Zeroth SH basis constant: colour = 0.5 + SH_C0 · DC.
const SH_C0: f32 = 0.282_094_8;
/// 3DGS's initial opacity.
const INITIAL_OPACITY: f32 = 0.1;

/// One isotropic Gaussian per point (3DGS's initialisation): scale the root mean square
/// distance to the three nearest other points, identity rotation, opacity 0.1, SH DC from
/// `colors` (linear [0, 1]; grey without), higher bands zero. Guarantees finite parameters for
/// finite points, duplicates included (their scale falls back to a tiny positive value).
pub fn gaussians_at_points(
    points: &[[f32; 3]],
    colors: Option<&[[f32; 3]]>,
    sh_degree: u32,
) -> GaussianScene {
    let coefficients = sh_coefficients(sh_degree);
    let mut scene = GaussianScene { sh_degree, ..Default::default() };
    if points.is_empty() {
        return scene;
    }
    let tree: ImmutableKdTree<f32, u32, 3, 32> = ImmutableKdTree::new_from_slice(points);
    let extent = (crate::mesh::bounding_diagonal(points) as f32).max(f32::MIN_POSITIVE);
    let neighbour_count =
        std::num::NonZero::new(4.min(points.len())).unwrap_or(std::num::NonZero::<usize>::MIN);
    for (i, p) in points.iter().enumerate() {
        let neighbours = tree.nearest_n::<SquaredEuclidean>(p, neighbour_count);
        let others: Vec<f32> = neighbours.iter().skip(1).map(|n| n.distance).collect();
        let mean_squared =
            if others.is_empty() { 0.0 } else { others.iter().sum::<f32>() / others.len() as f32 };
        // Coincident points would give ln 0: keep a scale far below the point spacing instead.
        let scale = mean_squared.sqrt().max(extent * 1e-6);
        scene.positions.push(*p);
        scene.log_scales.push([scale.ln(); 3]);
        scene.rotations.push([1.0, 0.0, 0.0, 0.0]);
        scene.opacity_logits.push(logit(INITIAL_OPACITY));
        let color = colors.map_or([0.5; 3], |c| c[i]);
        scene.sh.extend(color.map(|c| (c - 0.5) / SH_C0));
        scene.sh.extend(std::iter::repeat_n(0.0, 3 * (coefficients - 1)));
    }
    scene
}

#[inline]
pub(crate) fn logit(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

/// Points and their colours (linear RGB in [0, 1]).
pub type ColoredPoints = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// One view for sampling: its camera, mask (> 0.5 inside) and colour image (RGB, row-major).
pub struct MaskedView<'a> {
    /// The view's camera.
    pub camera: &'a Camera,
    /// One value per pixel, row-major; above 0.5 is inside.
    pub mask: &'a [f32],
    /// One RGB colour per pixel, row-major.
    pub rgb: &'a [[f32; 3]],
}

/// `count` points inside the visual hull of the masks, each with the mean colour of its
/// projections. Samples are drawn along the rays of random foreground pixels (a random view, a
/// random point of the pixel, a uniform depth where the ray crosses the sphere that holds the
/// cameras around the point nearest every optical axis) and kept when every view that sees
/// them has them inside its mask (and at least half the views see them). Starting inside one
/// mask makes a thin subject, a small part of that sphere, as easy to hit as a bulky one.
/// Fails, naming the cause, when the masks do not intersect in space.
pub fn points_inside_masks(
    views: &[MaskedView],
    count: usize,
    seed: u64,
) -> Result<ColoredPoints, TrainError> {
    let foreground: Vec<Vec<usize>> =
        views.iter().map(|v| (0..v.mask.len()).filter(|&i| v.mask[i] > 0.5).collect()).collect();
    let with_subject: Vec<usize> =
        (0..views.len()).filter(|&v| !foreground[v].is_empty()).collect();
    if with_subject.is_empty() {
        let problem = "no view has a non-empty mask to initialise from";
        return Err(TrainError::NoViews { frame: None, problem });
    }
    let (centre, radius) = rig_sphere(views);
    let mut rng = SplitMix64::new(seed);
    let (mut points, mut colors) = (Vec::with_capacity(count), Vec::with_capacity(count));
    let attempts = count.saturating_mul(1000).max(100_000);
    for _ in 0..attempts {
        if points.len() == count {
            break;
        }
        let v = with_subject[below(&mut rng, with_subject.len())];
        let pixel = foreground[v][below(&mut rng, foreground[v].len())];
        let p = sample_on_pixel_ray(views[v].camera, pixel, centre, radius, &mut rng);
        if let Some(color) = p.and_then(|p| color_if_inside(views, p).map(|c| (p, c))) {
            points.push(color.0.as_vec3().to_array());
            colors.push(color.1);
        }
    }
    if points.len() < count {
        return Err(TrainError::Init(format!(
            "only {} of {count} sample points fall inside every mask: do the masks intersect in space (cameras right, masks not empty)?",
            points.len()
        )));
    }
    Ok((points, colors))
}

/// The point nearest every optical axis (an inward-looking rig; else the mean camera centre)
/// and the distance from it to the farthest camera.
fn rig_sphere(views: &[MaskedView]) -> (DVec3, f64) {
    let cameras: Vec<&Camera> = views.iter().map(|v| v.camera).collect();
    let mean = cameras.iter().map(|c| c.center()).sum::<DVec3>() / cameras.len() as f64;
    let centre =
        nearest_point_to_rays(cameras.iter().map(|c| c.pixel_ray(c.cx, c.cy))).unwrap_or(mean);
    let radius = cameras.iter().map(|c| c.center().distance(centre)).fold(0.0, f64::max);
    (centre, radius)
}

/// A uniform point of `pixel`'s footprint, then a uniform depth along its ray inside the sphere
/// (None when the ray misses it).
fn sample_on_pixel_ray(
    camera: &Camera,
    pixel: usize,
    centre: DVec3,
    radius: f64,
    rng: &mut SplitMix64,
) -> Option<DVec3> {
    let width = camera.width as usize;
    let u = (pixel % width) as f64 + rng.next_f64();
    let v = (pixel / width) as f64 + rng.next_f64();
    let (origin, dir) = camera.pixel_ray(u, v);
    // |origin + t·dir − centre| = radius, dir unit: t = b ± sqrt(b² − c).
    let to_centre = centre - origin;
    let b = dir.dot(to_centre);
    let discriminant = b * b - (to_centre.length_squared() - radius * radius);
    if discriminant.is_nan() || discriminant <= 0.0 {
        return None;
    }
    let half = discriminant.sqrt();
    let (near, far) = ((b - half).max(0.0), b + half);
    (far > near).then(|| origin + dir * (near + (far - near) * rng.next_f64()))
}

/// A uniform index below `n` (> 0).
fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.next_f64() * n as f64) as usize % n
}

/// The mean colour of `p`'s projections when it is inside the mask of every view that sees it
/// and at least half of the views see it.
fn color_if_inside(views: &[MaskedView], p: DVec3) -> Option<[f32; 3]> {
    let (mut seen, mut sum) = (0usize, [0.0f32; 3]);
    for v in views {
        let Some(px) = v.camera.project(p) else { continue };
        let (w, h) = (v.camera.width as f64, v.camera.height as f64);
        if !(px.x >= 0.0 && px.y >= 0.0 && px.x < w && px.y < h) {
            continue;
        }
        let i = px.y as usize * v.camera.width as usize + px.x as usize;
        if v.mask[i].is_nan() || v.mask[i] <= 0.5 {
            return None;
        }
        seen += 1;
        sum = [0, 1, 2].map(|k| sum[k] + v.rgb[i][k]);
    }
    (2 * seen >= views.len() && seen > 0).then(|| sum.map(|s| s / seen as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_follow_neighbour_distances_and_survive_duplicates() {
        let points =
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
        let scene = gaussians_at_points(&points, None, 1);
        scene.check().unwrap();
        assert!(
            (scene.log_scales[0][0] - 1.0f32.ln()).abs() < 1e-6,
            "three neighbours at distance 1"
        );
        assert!(scene.log_scales.iter().flatten().all(|s| s.is_finite()));
        assert_eq!(scene.sh.len(), 5 * 3 * 4);
        assert!(scene.sh[..3].iter().all(|&c| c == 0.0), "grey is DC 0");
        assert!(gaussians_at_points(&[], None, 0).is_empty());
        assert!(gaussians_at_points(&[[1.0, 2.0, 3.0]], None, 0).log_scales[0][0].is_finite());
    }

    /// 1 where the pixel-centre ray passes within `r` of the y axis for |y| ≤ 1 (a thin rod).
    fn rod_mask(camera: &Camera, r: f64) -> Vec<f32> {
        let (w, h) = (camera.width as usize, camera.height as usize);
        (0..w * h)
            .map(|i| {
                let (o, d) = camera.pixel_ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                // Closest approach of the ray to the axis: minimise over t the xz distance.
                let t = -(o.x * d.x + o.z * d.z) / (d.x * d.x + d.z * d.z);
                let p = o + d * t;
                f32::from(u8::from(p.x.hypot(p.z) <= r && p.y.abs() <= 1.0))
            })
            .collect()
    }

    #[test]
    fn a_thin_subject_far_from_its_cameras_is_sampled() {
        // A rod 0.1 wide and 2 long inside a ring of cameras at distance 10: the rod is about
        // 4e-6 of the sphere that holds the cameras.
        let cameras: Vec<Camera> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 8.0;
                let eye = DVec3::new(10.0 * a.cos(), 0.3, 10.0 * a.sin());
                Camera::look_at(64, 64, 200.0, 200.0, 32.0, 32.0, eye, DVec3::ZERO, DVec3::Y)
                    .unwrap()
            })
            .collect();
        let masks: Vec<Vec<f32>> = cameras.iter().map(|c| rod_mask(c, 0.05)).collect();
        let rgb = vec![[0.25, 0.5, 0.75]; 64 * 64];
        let views: Vec<MaskedView> = cameras
            .iter()
            .zip(&masks)
            .map(|(camera, mask)| MaskedView { camera, mask, rgb: &rgb })
            .collect();
        let (points, colors) = points_inside_masks(&views, 500, 7).unwrap();
        assert_eq!(points.len(), 500);
        // Inside the rod's visual hull: near the axis (the hull of 8 views and the pixel
        // footprint widen it a little) and within its length.
        for p in &points {
            let off_axis = f64::from(p[0]).hypot(f64::from(p[2]));
            assert!(off_axis < 0.12 && p[1].abs() < 1.1, "{p:?}");
        }
        assert!(colors.iter().all(|c| *c == [0.25, 0.5, 0.75]));
        // The same seed gives the same points.
        assert_eq!(points_inside_masks(&views, 500, 7).unwrap().0, points);
        // Masks that do not meet in space are a clear error.
        let empty = vec![0.0; 64 * 64];
        let nothing: Vec<MaskedView> =
            views.iter().map(|v| MaskedView { mask: &empty, ..*v }).collect();
        assert!(points_inside_masks(&nothing, 10, 7).is_err());
    }
}
