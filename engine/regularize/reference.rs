//! f64 CPU reference of every regularizer: values and analytic gradients, written term by term
//! from the definitions in [`super`] with gradients scattered per face and per pair (the
//! kernels gather per vertex instead), so the two are independent checks of one another.

use super::{Losses, Neighbourhoods, Weights};
use glam::{DMat3, DQuat, DVec3, DVec4};

/// Parameters as stored (positions, log-scales, quaternions (w, x, y, z)) in f64.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    /// Position μ per Gaussian.
    pub positions: Vec<[f64; 3]>,
    /// Log-scale s per Gaussian.
    pub log_scales: Vec<[f64; 3]>,
    /// Quaternion q = (w, x, y, z) per Gaussian, not necessarily unit.
    pub rotations: Vec<[f64; 4]>,
}

/// Gradients shaped like [`Params`].
pub type Gradients = Params;

/// Values (unweighted) and weighted gradients of every term; `previous` enables the temporal
/// ones.
pub fn evaluate(
    nb: &Neighbourhoods,
    params: &Params,
    previous: Option<&Params>,
    weights: &Weights,
) -> (Losses<f64>, Gradients) {
    let n = params.positions.len();
    let mut grads = Params {
        positions: vec![[0.0; 3]; n],
        log_scales: vec![[0.0; 3]; n],
        rotations: vec![[0.0; 4]; n],
    };
    let mut losses = Losses::<f64>::default();
    let mut gp = vec![DVec3::ZERO; n];
    let mut gq = vec![DVec4::ZERO; n];
    losses.scale_2d = scale_2d(params, weights.scale_2d as f64, &mut grads.log_scales);
    losses.laplacian = laplacian(nb, params, weights.laplacian as f64, &mut gp);
    losses.normal = normal(nb, params, weights.normal as f64, &mut gp, &mut gq);
    if let Some(prev) = previous {
        let scale = weights.lambda_w as f64 / nb.mean_edge_length as f64;
        let huber = Huber(weights.huber as f64 * nb.mean_edge_length as f64);
        let (w_edge, w_rigid) = (weights.edge_length as f64, weights.rigidity as f64);
        losses.edge_length = edge_length(nb, params, prev, huber, w_edge, &mut gp);
        losses.rigidity = rigidity(nb, params, prev, (scale, huber), w_rigid, &mut gp, &mut gq);
        losses.rotation = rotation(nb, params, prev, scale, weights.rotation as f64, &mut gq);
    }
    for i in 0..n {
        grads.positions[i] = gp[i].to_array();
        grads.rotations[i] = normalize_backward(params.rotations[i], gq[i]).to_array();
    }
    (losses, grads)
}

/// The Huber penalty with threshold δ (scene units; 0: the absolute value).
#[derive(Clone, Copy)]
struct Huber(f64);

impl Huber {
    /// h(r) = r²/(2δ) for 0 ≤ r < δ, r − δ/2 beyond.
    fn value(self, r: f64) -> f64 {
        if r < self.0 {
            0.5 * r * r / self.0
        } else {
            r - 0.5 * self.0
        }
    }

    /// h'(r) / r: the factor that turns a residual vector of length r into h's gradient.
    fn slope_per_length(self, r: f64) -> f64 {
        1.0 / r.max(self.0)
    }
}

fn p3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

/// Unit quaternion of a stored (w, x, y, z).
fn unit(q: [f64; 4]) -> DQuat {
    DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize()
}

fn wxyz(q: DQuat) -> DVec4 {
    DVec4::new(q.w, q.x, q.y, q.z)
}

/// L_2d = Σ exp(s_z).
fn scale_2d(params: &Params, w: f64, g: &mut [[f64; 3]]) -> f64 {
    let mut loss = 0.0;
    for (i, s) in params.log_scales.iter().enumerate() {
        loss += s[2].exp();
        g[i][2] += w * s[2].exp();
    }
    loss
}

/// L_lap = (1/n) Σ ‖μᵢ − mean of its ring‖².
fn laplacian(nb: &Neighbourhoods, params: &Params, w: f64, g: &mut [DVec3]) -> f64 {
    let n = params.positions.len() as f64;
    let mut loss = 0.0;
    for i in 0..params.positions.len() {
        let ring = nb.neighbours(i);
        if ring.is_empty() {
            continue;
        }
        let m = ring.len() as f64;
        let mean = ring.iter().map(|&j| p3(params.positions[j as usize])).sum::<DVec3>() / m;
        let delta = p3(params.positions[i]) - mean;
        loss += delta.length_squared() / n;
        let gd = w * 2.0 * delta / n;
        g[i] += gd;
        ring.iter().for_each(|&j| g[j as usize] -= gd / m);
    }
    loss
}

/// L_n = Σ ‖n_gs − n_mesh‖ with n_gs the z column of R(q) and n_mesh the normalised sum of
/// the area vectors of the faces around the vertex.
fn normal(nb: &Neighbourhoods, params: &Params, w: f64, gp: &mut [DVec3], gq: &mut [DVec4]) -> f64 {
    let p = |i: u32| p3(params.positions[i as usize]);
    let mut loss = 0.0;
    for (i, g_rot) in gq.iter_mut().enumerate() {
        let sum: DVec3 =
            nb.fan(i).map(|(b, c)| (p(b) - p(i as u32)).cross(p(c) - p(i as u32))).sum();
        let len = sum.length();
        if len == 0.0 {
            continue;
        }
        let n_mesh = sum / len;
        let rot = DMat3::from_quat(unit(params.rotations[i]));
        let r = rot.z_axis - n_mesh;
        loss += r.length();
        let Some(u) = r.try_normalize() else { continue };
        let u = w * u;
        // Through the rotation's z column.
        *g_rot +=
            rotation_backward(params.rotations[i], DMat3::from_cols(DVec3::ZERO, DVec3::ZERO, u));
        // Through n_mesh = sum / |sum| to each face's area vector A = a×b + b×c + c×a.
        let g_sum = -(u - n_mesh * n_mesh.dot(u)) / len;
        for (b, c) in nb.fan(i) {
            let (a, b, c) = (i as u32, b, c);
            gp[a as usize] += (p(b) - p(c)).cross(g_sum);
            gp[b as usize] += (p(c) - p(a)).cross(g_sum);
            gp[c as usize] += (p(a) - p(b)).cross(g_sum);
        }
    }
    loss
}

/// L_len = Σ over edges ½(sᵢ + sⱼ) h(|l_t − l_{t−1}|) (s: stiffness, h: [`Huber`]).
fn edge_length(
    nb: &Neighbourhoods,
    params: &Params,
    prev: &Params,
    huber: Huber,
    w: f64,
    g: &mut [DVec3],
) -> f64 {
    let mut loss = 0.0;
    for i in 0..params.positions.len() {
        for &j in nb.neighbours(i).iter().filter(|&&j| j as usize > i) {
            let d = p3(params.positions[i]) - p3(params.positions[j as usize]);
            let l0 = (p3(prev.positions[i]) - p3(prev.positions[j as usize])).length();
            let l = d.length();
            let s = 0.5 * (nb.stiffness[i] + nb.stiffness[j as usize]) as f64;
            let r = (l - l0).abs();
            loss += s * huber.value(r);
            if l > 0.0 && l != l0 {
                let gd = w * s * (l - l0) * huber.slope_per_length(r) * d / l;
                g[i] += gd;
                g[j as usize] -= gd;
            }
        }
    }
    loss
}

/// ω_ij = exp(−λ_w · l_{ij, t−1} / mean edge) (symmetric).
fn omega(prev: &Params, i: usize, j: usize, scale: f64) -> f64 {
    (-scale * (p3(prev.positions[i]) - p3(prev.positions[j])).length()).exp()
}

/// L_rigid = Σᵢ sᵢ Σⱼ ωᵢⱼ h(‖(μⱼ' − μᵢ') − ΔRᵢ (μⱼ − μᵢ)‖), ΔRᵢ = Rᵢ' Rᵢᵀ (primes: frame t − 1,
/// s: stiffness).
fn rigidity(
    nb: &Neighbourhoods,
    params: &Params,
    prev: &Params,
    (scale, huber): (f64, Huber),
    w: f64,
    gp: &mut [DVec3],
    gq: &mut [DVec4],
) -> f64 {
    let mut loss = 0.0;
    for i in 0..params.positions.len() {
        let (r, r_prev) = (
            DMat3::from_quat(unit(params.rotations[i])),
            DMat3::from_quat(unit(prev.rotations[i])),
        );
        let delta_r = r_prev * r.transpose();
        let mut g_rot = DMat3::ZERO;
        for &j in nb.neighbours(i) {
            let j = j as usize;
            let d = p3(params.positions[j]) - p3(params.positions[i]);
            let d_prev = p3(prev.positions[j]) - p3(prev.positions[i]);
            let weight = nb.stiffness[i] as f64 * omega(prev, i, j, scale);
            let e = d_prev - delta_r * d;
            let r = e.length();
            loss += weight * huber.value(r);
            // A NaN residual is skipped too, as the kernel does.
            if r.is_nan() || r <= 0.0 {
                continue;
            }
            let u = w * weight * huber.slope_per_length(r) * e;
            let gd = -(delta_r.transpose() * u);
            gp[j] += gd;
            gp[i] -= gd;
            // e = d' − R' Rᵀ d: dL/dR = −d (R'ᵀ u)ᵀ.
            let v = r_prev.transpose() * u;
            g_rot -= DMat3::from_cols(d * v.x, d * v.y, d * v.z);
        }
        gq[i] += rotation_backward(params.rotations[i], g_rot);
    }
    loss
}

/// L_rot = Σᵢ Σⱼ ωᵢⱼ ‖qⱼ ⊗ qⱼ'⁻¹ − qᵢ ⊗ qᵢ'⁻¹‖ with unit quaternions.
fn rotation(
    nb: &Neighbourhoods,
    params: &Params,
    prev: &Params,
    scale: f64,
    w: f64,
    gq: &mut [DVec4],
) -> f64 {
    let relative = |i: usize| unit(params.rotations[i]) * unit(prev.rotations[i]).conjugate();
    let mut loss = 0.0;
    for i in 0..params.positions.len() {
        for &j in nb.neighbours(i) {
            let j = j as usize;
            let diff = wxyz(relative(j)) - wxyz(relative(i));
            let weight = omega(prev, i, j, scale);
            loss += weight * diff.length();
            let Some(u) = diff.try_normalize() else { continue };
            let u = w * weight * u;
            // p = q ⊗ c is linear in q; its transpose is right-multiplication by c̄ = q'.
            let back = |g: DVec4, k: usize| {
                wxyz(DQuat::from_xyzw(g.y, g.z, g.w, g.x) * unit(prev.rotations[k]))
            };
            gq[j] += back(u, j);
            gq[i] -= back(u, i);
        }
    }
    loss
}

/// Gradient of the unit quaternion (w, x, y, z) from the gradient `g` of its rotation matrix
/// (`g.col(c)[r]` = `dL/dR[r][c]`).
pub fn rotation_backward(q: [f64; 4], g: DMat3) -> DVec4 {
    let u = unit(q);
    let (w, x, y, z) = (u.w, u.x, u.y, u.z);
    let e = |r: usize, c: usize| g.col(c)[r];
    DVec4::new(
        2.0 * (-z * e(0, 1) + y * e(0, 2) + z * e(1, 0) - x * e(1, 2) - y * e(2, 0) + x * e(2, 1)),
        2.0 * (y * e(0, 1) + z * e(0, 2) + y * e(1, 0) - 2.0 * x * e(1, 1) - w * e(1, 2)
            + z * e(2, 0)
            + w * e(2, 1)
            - 2.0 * x * e(2, 2)),
        2.0 * (-2.0 * y * e(0, 0) + x * e(0, 1) + w * e(0, 2) + x * e(1, 0) + z * e(1, 2)
            - w * e(2, 0)
            + z * e(2, 1)
            - 2.0 * y * e(2, 2)),
        2.0 * (-2.0 * z * e(0, 0) - w * e(0, 1) + x * e(0, 2) + w * e(1, 0) - 2.0 * z * e(1, 1)
            + y * e(1, 2)
            + x * e(2, 0)
            + y * e(2, 1)),
    )
}

/// From dL/d(q/|q|) to dL/dq for the stored (w, x, y, z).
pub fn normalize_backward(q: [f64; 4], g: DVec4) -> DVec4 {
    let q = DVec4::from_array(q);
    let len = q.length();
    if len == 0.0 {
        return DVec4::ZERO;
    }
    let u = q / len;
    (g - u * u.dot(g)) / len
}

#[cfg(test)]
mod tests {
    use super::Huber;

    #[test]
    fn huber_is_quadratic_below_delta_linear_beyond_and_the_absolute_value_at_zero() {
        let h = Huber(0.5);
        assert_eq!(h.value(0.25), 0.0625);
        assert_eq!(h.value(2.0), 1.75);
        // Value and slope meet at δ.
        assert!((h.value(0.5 - 1e-9) - h.value(0.5 + 1e-9)).abs() < 1e-8);
        assert!((h.slope_per_length(0.5 - 1e-9) * (0.5 - 1e-9) - 1.0).abs() < 1e-8);
        assert_eq!(h.slope_per_length(2.0) * 2.0, 1.0);
        let abs = Huber(0.0);
        assert_eq!((abs.value(0.3), abs.slope_per_length(0.3) * 0.3), (0.3, 1.0));
    }
}
