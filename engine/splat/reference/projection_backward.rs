//! The exact derivative of the projection: from the gradients of one Gaussian's projected
//! quantities to its stored parameters.

use super::mat::{dot, mul, mul_vec, transpose, Mat3};
use super::projection::{Forward, View};
use super::{sh, Gradients};
use crate::splat::{sh_coefficients, GaussianScene, RenderSettings};
use std::array::from_fn;

/// dL/d(each quantity a projected Gaussian hands to the rasterizer).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ProjectedGradient {
    pub mean: [f64; 2],
    /// With respect to the scalars (Q00, Q01, Q11), Q01 standing for both off-diagonal entries.
    pub conic: [f64; 3],
    pub opacity: f64,
    pub color: [f64; 3],
    pub depth: f64,
}

/// Writes Gaussian `i`'s parameter gradients into `out` (its rows are overwritten).
pub(super) fn project_backward(
    f: &Forward,
    g: &ProjectedGradient,
    view: &View,
    scene: &GaussianScene,
    settings: &RenderSettings,
    i: usize,
    out: &mut Gradients,
) {
    let d_m = dilated_covariance_gradient(f, &g.conic);
    // Σ' = J V Jᵀ + 0.3 I with V = W Σ Wᵀ.
    let d_jacobian = mul(&mul(&d_m, &f.jacobian), &f.cov_view).map(|row| row.map(|v| 2.0 * v));
    let d_cov_view = mul(&mul(&transpose(&f.jacobian), &d_m), &f.jacobian);
    let d_cov = mul(&mul(&transpose(&view.rotation), &d_cov_view), &view.rotation);

    let d_view_point = view_point_gradient(f, view, g, &d_jacobian);
    let mut d_position = mul_vec(&transpose(&view.rotation), d_view_point);
    if !settings.mask_mode {
        let d_direction = color_backward(f, g, scene, settings, i, out);
        for a in 0..3 {
            d_position[a] += d_direction[a];
        }
        let o = f.projected.opacity;
        out.opacity_logits[i] = g.opacity * o * (1.0 - o);
    }
    out.positions[i] = d_position;
    let (d_log_scale, d_quaternion) = covariance_backward(f, &d_cov);
    out.log_scales[i] = d_log_scale;
    out.rotations[i] = d_quaternion;
}

/// dL/dM as a symmetric matrix, for `Σ' = M + 0.3 I`, from dL/dQ with `Q = Σ'⁻¹`:
/// `dΣ' = −Q dQ Q` in matrix form.
fn dilated_covariance_gradient(f: &Forward, d_conic: &[f64; 3]) -> [[f64; 2]; 2] {
    let [q00, q01, q11] = f.projected.conic;
    let q = [[q00, q01], [q01, q11]];
    let d_q = [[d_conic[0], 0.5 * d_conic[1]], [0.5 * d_conic[1], d_conic[2]]];
    mul(&mul(&q, &d_q), &q).map(|row| row.map(|v| -v))
}

/// dL/dv from the mean, the depth and the Jacobian. `J02 = −fx tx / z²` with
/// `tx = z · ray_x`; `ray_x = v.x / z` unless the guard band clamps it to a constant.
fn view_point_gradient(
    f: &Forward,
    view: &View,
    g: &ProjectedGradient,
    d_jacobian: &[[f64; 3]; 2],
) -> [f64; 3] {
    let v = f.view_point;
    let z = v[2];
    let mut d_v = [0.0, 0.0, g.depth];
    for a in 0..2 {
        let focal = view.focal[a];
        // Mean: m_a = f_a v_a / z + c_a.
        d_v[a] += g.mean[a] * focal / z;
        d_v[2] -= g.mean[a] * focal * v[a] / (z * z);
        // J_aa = f_a / z.
        d_v[2] -= d_jacobian[a][a] * focal / (z * z);
        // J_a2 = −f_a ray_a / z.
        let d_edge = d_jacobian[a][2];
        d_v[2] += d_edge * focal * f.ray[a] / (z * z);
        if f.ray_free[a] {
            let d_ray = -d_edge * focal / z;
            d_v[a] += d_ray / z;
            d_v[2] -= d_ray * v[a] / (z * z);
        }
    }
    d_v
}

/// dL/d(log-scale) and dL/dq from dL/dΣ, with `Σ = (R S)(R S)ᵀ`, through `q / |q|`.
fn covariance_backward(f: &Forward, d_cov: &Mat3) -> ([f64; 3], [f64; 4]) {
    let rs: Mat3 = from_fn(|r| from_fn(|c| f.rotation[r][c] * f.scale[c]));
    let d_cov_sym: Mat3 = from_fn(|r| from_fn(|c| d_cov[r][c] + d_cov[c][r]));
    let d_rs = mul(&d_cov_sym, &rs);
    let d_rotation: Mat3 = from_fn(|r| from_fn(|c| d_rs[r][c] * f.scale[c]));
    let d_log_scale =
        from_fn(|c| (0..3).map(|r| f.rotation[r][c] * d_rs[r][c]).sum::<f64>() * f.scale[c]);
    let d_unit = rotation_backward(f.unit_q, &d_rotation);
    let along = dot(f.unit_q, d_unit);
    (d_log_scale, from_fn(|k| (d_unit[k] - f.unit_q[k] * along) / f.q_norm))
}

/// dL/d(w, x, y, z) of a unit quaternion from dL/dR, R as in [`super::projection::rotation_matrix`].
fn rotation_backward([w, x, y, z]: [f64; 4], g: &Mat3) -> [f64; 4] {
    [
        2.0 * (-z * g[0][1] + y * g[0][2] + z * g[1][0] - x * g[1][2] - y * g[2][0] + x * g[2][1]),
        2.0 * (y * g[0][1] + z * g[0][2] + y * g[1][0] - 2.0 * x * g[1][1] - w * g[1][2]
            + z * g[2][0]
            + w * g[2][1]
            - 2.0 * x * g[2][2]),
        2.0 * (-2.0 * y * g[0][0] + x * g[0][1] + w * g[0][2] + x * g[1][0] + z * g[1][2]
            - w * g[2][0]
            + z * g[2][1]
            - 2.0 * y * g[2][2]),
        2.0 * (-2.0 * z * g[0][0] - w * g[0][1] + x * g[0][2] + w * g[1][0] - 2.0 * z * g[1][1]
            + y * g[1][2]
            + x * g[2][0]
            + y * g[2][1]),
    ]
}

/// Writes the SH coefficient gradients of Gaussian `i` and returns dL/dposition through the
/// view direction. A channel clamped at 0 passes nothing.
fn color_backward(
    f: &Forward,
    g: &ProjectedGradient,
    scene: &GaussianScene,
    settings: &RenderSettings,
    i: usize,
    out: &mut Gradients,
) -> [f64; 3] {
    let d_sum: [f64; 3] = from_fn(|ch| if f.color_free[ch] { g.color[ch] } else { 0.0 });
    let stride = scene.coefficients();
    let used = sh_coefficients(settings.sh_degree.min(scene.sh_degree));
    let basis_gradient = sh::basis_gradient(f.direction);
    let mut d_direction = [0.0; 3];
    for (k, basis_gradient) in basis_gradient.iter().enumerate().take(used) {
        for (ch, d_sum) in d_sum.iter().enumerate() {
            let at = (i * stride + k) * 3 + ch;
            out.sh[at] = d_sum * f.basis[k];
            let weight = d_sum * f64::from(scene.sh[at]);
            for (d, b) in d_direction.iter_mut().zip(basis_gradient) {
                *d += weight * b;
            }
        }
    }
    // direction = offset / |offset|.
    let along = dot(f.direction, d_direction);
    from_fn(|a| (d_direction[a] - f.direction[a] * along) / f.distance)
}
