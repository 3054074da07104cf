//! f64 CPU reference of the silhouette term (shaders/loss/silhouette.comp).

use super::SilhouetteView;
use glam::{DVec2, DVec3};

/// D at index coordinates `q` (pixel centres at integers) and dD/dq, as the kernel samples it.
fn field_at(field: &[f32], width: usize, height: usize, q: DVec2) -> (f64, DVec2) {
    let inside = q.clamp(DVec2::ZERO, DVec2::new(width as f64 - 1.0, height as f64 - 1.0));
    let base = inside.floor().min(DVec2::new(width as f64 - 2.0, height as f64 - 2.0));
    let f = inside - base;
    let at =
        |dx: usize, dy: usize| field[(base.y as usize + dy) * width + base.x as usize + dx] as f64;
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
pub fn silhouette_loss(
    positions: &[[f64; 3]],
    views: &[SilhouetteView],
    weight: f64,
    near: f64,
) -> (f64, Vec<[f64; 3]>) {
    let usable: Vec<_> =
        views.iter().filter_map(|v| v.field.as_ref().map(|f| (&v.camera, f))).collect();
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
            // Behind the near plane or a NaN depth: skipped.
            let in_front = c.z > near;
            if !in_front {
                continue;
            }
            let q =
                DVec2::new(camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy)
                    - 0.5;
            let (d, slope) = field_at(field, camera.width as usize, camera.height as usize, q);
            let inv = 1.0 / camera.width.max(camera.height) as f64;
            energy += scale * d * d * inv * inv;
            let dq = 2.0 * scale * d * inv * inv * slope;
            g += camera.pixel_gradient_to_world(c, dq);
        }
        *grad = g.to_array();
    }
    (energy, grads)
}

/// The coverage term (coverage_*.comp) for one view: `mask` and `coverage` per pixel
/// (row-major), uncovered where mask > 0.5 and coverage < 0.5; value and position gradients.
pub fn coverage_loss(
    positions: &[[f64; 3]],
    camera: &crate::camera::Camera,
    (mask, coverage): (&[f32], &[f32]),
    radius: i64,
    weight: f64,
    near: f64,
) -> (f64, Vec<[f64; 3]>) {
    let (w, h) = (camera.width as i64, camera.height as i64);
    let project = |x: [f64; 3]| {
        let c = camera.to_camera(DVec3::from(x));
        (c, DVec2::new(camera.fx * c.x / c.z + camera.cx, camera.fy * c.y / c.z + camera.cy))
    };
    // Each pixel keeps its lowest-id vertex.
    let mut seeds = vec![usize::MAX; (w * h) as usize];
    for (i, x) in positions.iter().enumerate().rev() {
        let (c, uv) = project(*x);
        if c.z > near && uv.x >= 0.0 && uv.y >= 0.0 && uv.x < w as f64 && uv.y < h as f64 {
            seeds[(uv.y as i64 * w + uv.x as i64) as usize] = i;
        }
    }
    let scale = weight / (w * h) as f64;
    let (mut energy, mut grads) = (0.0, vec![[0.0; 3]; positions.len()]);
    for p in 0..(w * h) {
        // A pixel inside the mask that the render does not cover (a NaN coverage counts as
        // not covering, a NaN mask as outside).
        let (inside, covered) = (mask[p as usize] > 0.5, coverage[p as usize] >= 0.5);
        if !inside || covered {
            continue;
        }
        let centre = DVec2::new((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
        let window = (-radius..=radius)
            .flat_map(|dy| (-radius..=radius).map(move |dx| (p % w + dx, p / w + dy)));
        let nearest = window
            .filter(|&(x, y)| x >= 0 && y >= 0 && x < w && y < h)
            .map(|(x, y)| seeds[(y * w + x) as usize])
            .filter(|&s| s != usize::MAX)
            .min_by(|&a, &b| {
                let d = |s: usize| (project(positions[s]).1 - centre).length_squared();
                d(a).total_cmp(&d(b)).then(a.cmp(&b))
            });
        let Some(s) = nearest else { continue };
        let (c, uv) = project(positions[s]);
        energy += scale * (uv - centre).length_squared();
        let g = 2.0 * scale * (uv - centre);
        let dx = camera.pixel_gradient_to_world(c, g);
        for a in 0..3 {
            grads[s][a] += dx[a];
        }
    }
    (energy, grads)
}
