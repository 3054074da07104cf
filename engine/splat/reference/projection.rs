//! Projection of one Gaussian, term for term as `splat/mod.rs` states it, in f64, keeping the
//! intermediates its backward pass needs.

use super::mat::{mul, mul_vec, transpose, Mat3};
use super::sh;
use crate::camera::Camera;
use crate::splat::{sh_coefficients, GaussianScene, RenderSettings, ALPHA_MIN, DILATION};
use std::array::from_fn;

/// A Gaussian as the rasterizer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Mean in pixel coordinates.
    pub mean: [f64; 2],
    /// Inverse of the dilated 2D covariance: (Q00, Q01, Q11).
    pub conic: [f64; 3],
    /// Opacity `o = sigmoid(ℓ)` (1 in mask mode).
    pub opacity: f64,
    /// RGB `max(0, 0.5 + SH(d))` per channel ((1, 1, 1) in mask mode).
    pub color: [f64; 3],
    /// View depth `v.z`.
    pub depth: f64,
}

impl Projected {
    /// `σ(u) = ½ (Q00 dx² + Q11 dy²) + Q01 dx dy` with `d = u − m`, the exponent of the
    /// Gaussian's falloff at pixel coordinates `u`.
    #[inline]
    pub fn sigma(&self, u: [f64; 2]) -> f64 {
        let [q00, q01, q11] = self.conic;
        let (dx, dy) = (u[0] - self.mean[0], u[1] - self.mean[1]);
        0.5 * (q00 * dx * dx + q11 * dy * dy) + q01 * dx * dy
    }
}

/// The camera as the projection uses it.
pub(super) struct View {
    /// `W`, world to camera rotation.
    pub rotation: Mat3,
    /// `t`.
    pub translation: [f64; 3],
    /// Camera centre in world coordinates.
    pub center: [f64; 3],
    pub focal: [f64; 2],
    pub principal: [f64; 2],
    /// Guard band: `v.x / v.z` is clamped to `[ray_min[0], ray_max[0]]` in the Jacobian (same for y).
    pub ray_min: [f64; 2],
    pub ray_max: [f64; 2],
}

impl View {
    pub fn new(camera: &Camera) -> Self {
        let m = camera.world_to_camera;
        let size = [camera.width as f64, camera.height as f64];
        let focal = [camera.fx, camera.fy];
        let principal = [camera.cx, camera.cy];
        Self {
            rotation: from_fn(|r| from_fn(|c| m.col(c)[r])),
            translation: [m.w_axis.x, m.w_axis.y, m.w_axis.z],
            center: camera.center().to_array(),
            focal,
            principal,
            ray_min: from_fn(|a| -(principal[a] / focal[a] + 0.3 * size[a] / focal[a])),
            ray_max: from_fn(|a| (size[a] - principal[a]) / focal[a] + 0.3 * size[a] / focal[a]),
        }
    }
}

/// Everything the projection of one Gaussian computed.
pub(super) struct Forward {
    pub projected: Projected,
    /// `v = W p + t`.
    pub view_point: [f64; 3],
    /// `q / |q|` and `|q|`.
    pub unit_q: [f64; 4],
    pub q_norm: f64,
    /// `R` and `exp(s)`.
    pub rotation: Mat3,
    pub scale: [f64; 3],
    /// Guard-band-clamped `v.xy / v.z`, and whether the clamp was inactive (gradient passes).
    pub ray: [f64; 2],
    pub ray_free: [bool; 2],
    pub jacobian: [[f64; 3]; 2],
    /// `W Σ Wᵀ`.
    pub cov_view: Mat3,
    /// Colour mode only: unit `p − o_cam`, its length, the SH basis there, and per channel
    /// whether `0.5 + SH > 0` (the clamp at 0 inactive).
    pub direction: [f64; 3],
    pub distance: f64,
    pub basis: [f64; 16],
    pub color_free: [bool; 3],
}

/// Projects Gaussian `i` of `scene`; `None` when it is culled: non-finite position, log-scale,
/// rotation or opacity logit; `v.z` outside (near, far); a quaternion whose components are all
/// zero or below the smallest normal f32 (no f32 implementation can normalise it reliably);
/// `det Σ' ≤ 0`; opacity below 1/255; or any non-finite result (mean, conic, colour before
/// its clamp, which catches non-finite SH coefficients of the active degree).
pub fn project(
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
    i: usize,
) -> Option<Projected> {
    forward(scene, &View::new(camera), settings, i).map(|f| f.projected)
}

pub(super) fn forward(
    scene: &GaussianScene,
    view: &View,
    settings: &RenderSettings,
    i: usize,
) -> Option<Forward> {
    let p = scene.positions[i].map(f64::from);
    let s = scene.log_scales[i].map(f64::from);
    let q = scene.rotations[i].map(f64::from);
    let logit = f64::from(scene.opacity_logits[i]);
    if !p.iter().chain(&s).chain(&q).chain([&logit]).all(|v| v.is_finite()) {
        return None;
    }
    let t = view.translation;
    let v: [f64; 3] = from_fn(|r| mul_vec(&view.rotation, p)[r] + t[r]);
    let z = v[2];
    if !(f64::from(settings.near) < z && z < f64::from(settings.far)) {
        return None;
    }
    let (unit_q, q_norm) = normalize_quaternion(q)?;
    let rotation = rotation_matrix(unit_q);
    let scale = s.map(f64::exp);
    let rs: Mat3 = from_fn(|r| from_fn(|c| rotation[r][c] * scale[c]));
    let cov = mul(&rs, &transpose(&rs));
    let cov_view = mul(&mul(&view.rotation, &cov), &transpose(&view.rotation));

    let [fx, fy] = view.focal;
    let raw_ray = [v[0] / z, v[1] / z];
    let ray: [f64; 2] = from_fn(|a| raw_ray[a].max(view.ray_min[a]).min(view.ray_max[a]));
    let ray_free = from_fn(|a| view.ray_min[a] <= raw_ray[a] && raw_ray[a] <= view.ray_max[a]);
    let (tx, ty) = (z * ray[0], z * ray[1]);
    let jacobian = [[fx / z, 0.0, -fx * tx / (z * z)], [0.0, fy / z, -fy * ty / (z * z)]];
    let m = mul(&mul(&jacobian, &cov_view), &transpose(&jacobian));
    let cov2d = [m[0][0] + DILATION, m[0][1], m[1][1] + DILATION];
    let det = cov2d[0] * cov2d[2] - cov2d[1] * cov2d[1];
    if !(det > 0.0 && det.is_finite()) {
        return None;
    }
    let conic = [cov2d[2] / det, -cov2d[1] / det, cov2d[0] / det];
    let mean = [fx * v[0] / z + view.principal[0], fy * v[1] / z + view.principal[1]];
    let opacity = if settings.mask_mode { 1.0 } else { 1.0 / (1.0 + (-logit).exp()) };
    if opacity < ALPHA_MIN {
        return None;
    }
    let colour =
        if settings.mask_mode { Colour::mask() } else { Colour::of(scene, settings, view, i, p) };
    let projected = Projected { mean, conic, opacity, color: colour.color, depth: z };
    let finite = mean.iter().chain(&conic).chain(&colour.sums).all(|v| v.is_finite());
    finite.then_some(Forward {
        projected,
        view_point: v,
        unit_q,
        q_norm,
        rotation,
        scale,
        ray,
        ray_free,
        jacobian,
        cov_view,
        direction: colour.direction,
        distance: colour.distance,
        basis: colour.basis,
        color_free: colour.sums.map(|sum| sum > 0.0),
    })
}

/// `q / |q|` and `|q|`, or `None` when every component is zero or subnormal as an f32.
fn normalize_quaternion(q: [f64; 4]) -> Option<([f64; 4], f64)> {
    let largest = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // q is finite here, so largest is not NaN.
    if largest < f64::from(f32::MIN_POSITIVE) {
        return None;
    }
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    Some((q.map(|v| v / norm), norm))
}

/// Rotation of a unit quaternion (w, x, y, z).
pub(super) fn rotation_matrix([w, x, y, z]: [f64; 4]) -> Mat3 {
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// The view-dependent colour and what its backward needs.
struct Colour {
    color: [f64; 3],
    /// `0.5 + SH` per channel, before the clamp at 0.
    sums: [f64; 3],
    direction: [f64; 3],
    distance: f64,
    basis: [f64; 16],
}

impl Colour {
    fn mask() -> Self {
        Self {
            color: [1.0; 3],
            sums: [1.0; 3],
            direction: [0.0; 3],
            distance: 0.0,
            basis: [0.0; 16],
        }
    }

    fn of(
        scene: &GaussianScene,
        settings: &RenderSettings,
        view: &View,
        i: usize,
        p: [f64; 3],
    ) -> Self {
        let offset: [f64; 3] = from_fn(|a| p[a] - view.center[a]);
        let distance = offset.iter().map(|v| v * v).sum::<f64>().sqrt();
        let direction = offset.map(|v| v / distance);
        let basis = sh::basis(direction);
        let stride = scene.coefficients();
        let used = sh_coefficients(settings.sh_degree.min(scene.sh_degree));
        let sums = from_fn(|ch| {
            0.5 + (0..used)
                .map(|k| basis[k] * f64::from(scene.sh[(i * stride + k) * 3 + ch]))
                .sum::<f64>()
        });
        Self { color: sums.map(|sum: f64| sum.max(0.0)), sums, direction, distance, basis }
    }
}
