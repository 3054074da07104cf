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
    pub camera: &'a Camera,
    pub mask: &'a [f32],
    pub rgb: &'a [[f32; 3]],
}

/// `count` points inside the visual hull of the masks, each with the mean colour of its
/// projections: uniform samples in a box around the point nearest to every optical axis, kept
/// when every view that sees them has them inside its mask (and at least half the views see
/// them). Fails, naming the cause, when the masks do not intersect in space.
pub fn points_inside_masks(
    views: &[MaskedView],
    count: usize,
    seed: u64,
) -> Result<ColoredPoints, TrainError> {
    if views.is_empty() {
        return Err(TrainError::Input("no views with masks to initialise from".into()));
    }
    let cameras: Vec<&Camera> = views.iter().map(|v| v.camera).collect();
    // Where the optical axes meet (an inward-looking rig), else the mean camera centre.
    let mean = cameras.iter().map(|c| c.center()).sum::<DVec3>() / cameras.len() as f64;
    let centre =
        nearest_point_to_rays(cameras.iter().map(|c| c.pixel_ray(c.cx, c.cy))).unwrap_or(mean);
    let radius = cameras.iter().map(|c| c.center().distance(centre)).fold(0.0, f64::max);
    let mut rng = SplitMix64::new(seed);
    let (mut points, mut colors) = (Vec::with_capacity(count), Vec::with_capacity(count));
    let attempts = count.saturating_mul(2000).max(100_000);
    for _ in 0..attempts {
        if points.len() == count {
            break;
        }
        let p = centre
            + radius
                * DVec3::new(
                    rng.next_f64() * 2.0 - 1.0,
                    rng.next_f64() * 2.0 - 1.0,
                    rng.next_f64() * 2.0 - 1.0,
                );
        if let Some(color) = color_if_inside(views, p) {
            points.push(p.as_vec3().to_array());
            colors.push(color);
        }
    }
    if points.len() < count {
        return Err(TrainError::Input(format!(
            "only {} of {count} sample points fall inside every mask: do the masks intersect in space (cameras right, masks not empty)?",
            points.len()
        )));
    }
    Ok((points, colors))
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
        if !(v.mask[i] > 0.5) {
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
}
