//! f64 CPU reference of the flow term (shaders/loss/flow.comp).

use super::FlowTarget;
use crate::camera::Camera;
use glam::{DVec2, DVec3};

/// The term's value and its gradient per position (the kernel's definition, weight applied):
/// `targets` vertex-major, `cameras.len()` per vertex; `tau` the Cauchy scale in pixels.
pub fn flow_loss(
    positions: &[[f64; 3]],
    cameras: &[Camera],
    targets: &[FlowTarget],
    (weight, tau, near): (f64, f64, f64),
) -> (f64, Vec<[f64; 3]>) {
    let mut grads = vec![[0.0; 3]; positions.len()];
    let pairs = targets.iter().filter(|t| t.weight > 0.0).count();
    if pairs == 0 || cameras.is_empty() {
        return (0.0, grads);
    }
    let (scale, tau2) = (weight / pairs as f64, tau * tau);
    let mut energy = 0.0;
    for (i, (x, grad)) in positions.iter().zip(&mut grads).enumerate() {
        let mut g = DVec3::ZERO;
        for (v, camera) in cameras.iter().enumerate() {
            let target = targets[i * cameras.len() + v];
            let c = camera.to_camera(DVec3::from(*x));
            // A NaN weight or depth is skipped too.
            let usable = target.weight > 0.0 && c.z > near;
            if !usable {
                continue;
            }
            let q =
                DVec2::new(camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy)
                    - 0.5;
            let r = q - DVec2::new(target.u as f64, target.v as f64);
            let inv = 1.0 / camera.width.max(camera.height) as f64;
            let s = scale * target.weight as f64 * inv * inv;
            energy += s * tau2 * (1.0 + r.length_squared() / tau2).ln();
            let dq = 2.0 * s * r / (1.0 + r.length_squared() / tau2);
            g += camera.pixel_gradient_to_world(c, dq);
        }
        *grad = g.to_array();
    }
    (energy, grads)
}
