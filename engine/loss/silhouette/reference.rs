//! f64 CPU reference of the silhouette term (shaders/loss/silhouette.comp).

use super::SilhouetteView;
use glam::{DMat3, DVec2, DVec3};

/// D at index coordinates `q` (pixel centres at integers) and dD/dq, as the kernel samples it.
fn field_at(field: &[f32], width: usize, height: usize, q: DVec2) -> (f64, DVec2) {
    let inside = q.clamp(DVec2::ZERO, DVec2::new(width as f64 - 1.0, height as f64 - 1.0));
    let base = inside.floor().min(DVec2::new(width as f64 - 2.0, height as f64 - 2.0));
    let f = inside - base;
    let at = |dx: usize, dy: usize| field[(base.y as usize + dy) * width + base.x as usize + dx] as f64;
    let (d00, d10, d01, d11) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let mut value = lerp(lerp(d00, d10, f.x), lerp(d01, d11, f.x), f.y);
    let mut slope = DVec2::new(lerp(d10 - d00, d11 - d01, f.y), lerp(d01 - d00, d11 - d10, f.x));
    slope *= DVec2::new((inside.x == q.x) as u8 as f64, (inside.y == q.y) as u8 as f64);
    let out = q - inside;
    if out.length() > 0.0 {
        value += out.length();
        slope += out / out.length();
    }
    (value, slope)
}

/// The term's value and its gradient per position (the kernel's definition, weight applied).
pub fn silhouette_loss(positions: &[[f64; 3]], views: &[SilhouetteView], weight: f64, near: f64) -> (f64, Vec<[f64; 3]>) {
    let usable: Vec<_> = views.iter().filter_map(|v| v.field.as_ref().map(|f| (&v.camera, f))).collect();
    let mut grads = vec![[0.0; 3]; positions.len()];
    if usable.is_empty() || positions.is_empty() {
        return (0.0, grads);
    }
    let scale = weight / (positions.len() * usable.len()) as f64;
    let mut energy = 0.0;
    for (x, grad) in positions.iter().zip(&mut grads) {
        let mut g = DVec3::ZERO;
        for (camera, field) in &usable {
            let c = camera.to_camera(DVec3::from(*x));
            if !(c.z > near) {
                continue;
            }
            let q = DVec2::new(camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy) - 0.5;
            let (d, slope) = field_at(field, camera.width as usize, camera.height as usize, q);
            let inv = 1.0 / camera.width.max(camera.height) as f64;
            energy += scale * d * d * inv * inv;
            let dq = 2.0 * scale * d * inv * inv * slope;
            let dc = DVec3::new(dq.x * camera.fx / c.z, dq.y * camera.fy / c.z, -(dq.x * camera.fx * c.x + dq.y * camera.fy * c.y) / (c.z * c.z));
            g += DMat3::from_mat4(camera.world_to_camera).transpose() * dc;
        }
        *grad = g.to_array();
    }
    (energy, grads)
}
