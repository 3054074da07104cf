//! The reference renderer of the generator: a supersampled CPU z-buffer rasterizer, independent
//! of the engine's GPU code. Each pixel takes S×S samples on a regular grid
//! ((i + (a + ½)/S, j + (b + ½)/S) in the camera's pixel coordinates); a sample takes the
//! nearest front-facing triangle covering it (edges inclusive, so shared edges leave no
//! cracks), and its colour is the texture at the perspective-correctly interpolated rest-pose
//! position. A pixel's colour is the mean over its samples with a black background, its mask
//! value the covered fraction: anti-aliased edges on both.

use super::texture::Texture;
use crate::camera::Camera;
use glam::DVec3;

/// An RGB image (interleaved, values in [0, 1]) and its coverage mask in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct Render {
    /// Image width, pixels (the camera's).
    pub width: u32,
    /// Image height, pixels (the camera's).
    pub height: u32,
    /// `width × height × 3` linear RGB values, row-major, background black.
    pub rgb: Vec<f32>,
    /// `width × height` coverage values: the fraction of a pixel's samples that hit the subject.
    pub alpha: Vec<f32>,
}

/// Why a view cannot be rendered.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    /// A vertex has camera-space depth `z <= 0` (or NaN); the renderer does not clip.
    #[error("vertex {vertex} lies at or behind the camera plane (depth {depth}); the reference renderer does not clip")]
    BehindCamera {
        /// The first such vertex.
        vertex: usize,
        /// Its camera-space depth, scene units.
        depth: f64,
    },
}

/// Renders `positions`/`faces` (closed surface, counter-clockwise from outside) from `camera`
/// with `samples`² samples per pixel, colouring by `texture` at the interpolated `rest`
/// positions. Every vertex must be in front of the camera.
pub fn render(
    camera: &Camera,
    positions: &[[f32; 3]],
    rest: &[[f32; 3]],
    faces: &[[u32; 3]],
    texture: &Texture,
    samples: u32,
) -> Result<Render, RenderError> {
    let (w, h, s) = (camera.width as usize, camera.height as usize, samples.max(1) as usize);
    let (sw, sh) = (w * s, h * s);
    let mut view = Vec::with_capacity(positions.len());
    for (vertex, p) in positions.iter().enumerate() {
        let c = camera.to_camera(DVec3::from(p.map(f64::from)));
        if c.z.is_nan() || c.z <= 0.0 {
            return Err(RenderError::BehindCamera { vertex, depth: c.z });
        }
        // Position in sample units: pixel coordinate × S.
        view.push((
            c,
            [
                (camera.fx * c.x / c.z + camera.cx) * s as f64,
                (camera.fy * c.y / c.z + camera.cy) * s as f64,
            ],
        ));
    }
    let mut depth = vec![f64::INFINITY; sw * sh];
    let mut color = vec![[0.0f32; 3]; sw * sh];
    for f in faces {
        let [a, b, c] = f.map(|i| view[i as usize]);
        // Front-facing: the outward normal points back at the camera (origin of camera space).
        if (b.0 - a.0).cross(c.0 - a.0).dot(a.0) >= 0.0 {
            continue;
        }
        rasterize_triangle([a.1, b.1, c.1], (sw, sh), |sample, l| {
            let inv_z = l[0] / a.0.z + l[1] / b.0.z + l[2] / c.0.z;
            let z = 1.0 / inv_z;
            if z < depth[sample] {
                depth[sample] = z;
                let mut p = DVec3::ZERO;
                for (k, &i) in f.iter().enumerate() {
                    p += (l[k] / [a.0.z, b.0.z, c.0.z][k] * z)
                        * DVec3::from(rest[i as usize].map(f64::from));
                }
                color[sample] = texture.color(p);
            }
        });
    }
    Ok(resolve(camera, s, &depth, &color))
}

/// Calls `shade(sample index, screen barycentrics)` for every sample centre inside the
/// triangle (sample-unit coordinates; edges inclusive; degenerate triangles cover nothing).
fn rasterize_triangle(
    p: [[f64; 2]; 3],
    (sw, sh): (usize, usize),
    mut shade: impl FnMut(usize, [f64; 3]),
) {
    let edge = |a: [f64; 2], b: [f64; 2], q: [f64; 2]| {
        (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
    };
    let area = edge(p[0], p[1], p[2]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let lo = |k: usize| p.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min);
    let hi = |k: usize| p.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max);
    // Sample centres at i + 0.5: the covered index range of each axis.
    let x0 = (lo(0) - 0.5).ceil().max(0.0) as usize;
    let y0 = (lo(1) - 0.5).ceil().max(0.0) as usize;
    let x1 = ((hi(0) - 0.5).floor() + 1.0).clamp(0.0, sw as f64) as usize;
    let y1 = ((hi(1) - 0.5).floor() + 1.0).clamp(0.0, sh as f64) as usize;
    for y in y0..y1 {
        for x in x0..x1 {
            let q = [x as f64 + 0.5, y as f64 + 0.5];
            let l = [
                edge(p[1], p[2], q) / area,
                edge(p[2], p[0], q) / area,
                edge(p[0], p[1], q) / area,
            ];
            if l.iter().all(|&v| v >= 0.0) {
                shade(y * sw + x, l);
            }
        }
    }
}

/// Box-filters S×S sample blocks into pixels: colour over black, coverage as alpha.
fn resolve(camera: &Camera, s: usize, depth: &[f64], color: &[[f32; 3]]) -> Render {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let sw = w * s;
    let mut rgb = vec![0.0f32; w * h * 3];
    let mut alpha = vec![0.0f32; w * h];
    let norm = 1.0 / (s * s) as f32;
    for j in 0..h {
        for i in 0..w {
            let (mut sum, mut covered) = ([0.0f32; 3], 0usize);
            for b in 0..s {
                for a in 0..s {
                    let k = (j * s + b) * sw + i * s + a;
                    if depth[k].is_finite() {
                        covered += 1;
                        for c in 0..3 {
                            sum[c] += color[k][c];
                        }
                    }
                }
            }
            for c in 0..3 {
                rgb[(j * w + i) * 3 + c] = sum[c] * norm;
            }
            alpha[j * w + i] = covered as f32 * norm;
        }
    }
    Render { width: camera.width, height: camera.height, rgb, alpha }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::texture::Pattern;
    use glam::DMat4;

    fn camera(size: u32) -> Camera {
        // At the origin looking along +z.
        Camera::new(
            size,
            size,
            size as f64,
            size as f64,
            size as f64 / 2.0,
            size as f64 / 2.0,
            DMat4::IDENTITY,
        )
        .unwrap()
    }

    /// A square of side 2 at depth 4 facing the camera (CCW seen from the camera side).
    fn square() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let p = vec![[-1.0, -1.0, 4.0], [1.0, -1.0, 4.0], [1.0, 1.0, 4.0], [-1.0, 1.0, 4.0]];
        // Seen from the camera (z forward, y down), this order is the outside.
        (p, vec![[0, 2, 1], [0, 3, 2]])
    }

    #[test]
    fn coverage_equals_projected_area_and_shared_edge_has_no_crack() {
        let (p, f) = square();
        let tex = Texture { center: DVec3::ZERO, radius: 1.0, pattern: Pattern::Smooth };
        let r = render(&camera(64), &p, &p, &f, &tex, 4).unwrap();
        // Projection: f·x/z = 64·1/4 = 16 px half-side → a 32×32 px square centred in the image.
        let covered: f32 = r.alpha.iter().sum();
        assert!((covered - 32.0 * 32.0).abs() < 1e-3, "{covered}");
        assert_eq!(r.alpha[32 * 64 + 32], 1.0);
        assert!(r.alpha.iter().all(|&a| a == 0.0 || a == 1.0), "pixel-aligned edges are hard");
        // Flipped winding faces away: nothing drawn.
        let back: Vec<[u32; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert!(render(&camera(64), &p, &p, &back, &tex, 2)
            .unwrap()
            .alpha
            .iter()
            .all(|&a| a == 0.0));
    }

    #[test]
    fn partial_coverage_is_antialiased_and_colour_is_the_texture() {
        let (mut p, f) = square();
        for q in &mut p {
            q[0] += 0.5 / 16.0 * 0.5; // shift by a quarter pixel
        }
        let tex = Texture { center: DVec3::ZERO, radius: 1.0, pattern: Pattern::Smooth };
        let r = render(&camera(64), &p, &p, &f, &tex, 4).unwrap();
        let left = r.alpha[32 * 64 + 16];
        assert!((left - 0.75).abs() < 1e-6, "{left}");
        // Pixel (32, 32): the mean of the texture at its 16 samples, which lie on the square
        // at world (u − 32)/16, (v − 32)/16, 4 (rest = posed here).
        let mut expect = [0.0f32; 3];
        for b in 0..4 {
            for a in 0..4 {
                let (u, v) = (32.0 + (a as f64 + 0.5) / 4.0, 32.0 + (b as f64 + 0.5) / 4.0);
                let c = tex.color(DVec3::new((u - 32.0) / 16.0, (v - 32.0) / 16.0, 4.0));
                for k in 0..3 {
                    expect[k] += c[k] / 16.0;
                }
            }
        }
        let got = &r.rgb[(32 * 64 + 32) * 3..][..3];
        assert!(got.iter().zip(expect).all(|(g, e)| (g - e).abs() < 1e-5), "{got:?} vs {expect:?}");
    }

    #[test]
    fn vertex_behind_the_camera_is_an_error() {
        let (mut p, f) = square();
        p[1][2] = -1.0;
        let tex = Texture { center: DVec3::ZERO, radius: 1.0, pattern: Pattern::Smooth };
        assert_eq!(
            render(&camera(8), &p, &p, &f, &tex, 1).unwrap_err(),
            RenderError::BehindCamera { vertex: 1, depth: -1.0 }
        );
    }
}
