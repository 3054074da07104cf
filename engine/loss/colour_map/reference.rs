//! f64 CPU reference of the colour-map kernels (shaders/loss/colour_map_*.comp).

use super::{ColourMap, MOMENTS};

/// The render `c` (rgba over `background`) as the camera of `map` sees it.
pub fn seen(map: &ColourMap, c: [f64; 4], background: [f64; 3]) -> [f64; 4] {
    let z = subject(c, background);
    let mut out = [0.0, 0.0, 0.0, c[3]];
    for k in 0..3 {
        out[k] =
            (0..4).map(|j| map[k][j] as f64 * z[j]).sum::<f64>() + (1.0 - c[3]) * background[k];
    }
    out
}

/// dL/dc from dL/d(seen) `g` (the map is linear in `c`).
pub fn seen_backward(map: &ColourMap, g: [f64; 4], background: [f64; 3]) -> [f64; 4] {
    let mut out = [0.0, 0.0, 0.0, g[3]];
    for k in 0..3 {
        let row = map[k].map(f64::from);
        for j in 0..3 {
            out[j] += g[k] * row[j];
        }
        let through_alpha: f64 = (0..3).map(|j| row[j] * background[j]).sum::<f64>() + row[3];
        out[3] += g[k] * (through_alpha - background[k]);
    }
    out
}

/// The subject's premultiplied colour and coverage of a render over `background`.
fn subject(c: [f64; 4], background: [f64; 3]) -> [f64; 4] {
    let a = c[3];
    [
        c[0] - (1.0 - a) * background[0],
        c[1] - (1.0 - a) * background[1],
        c[2] - (1.0 - a) * background[2],
        a,
    ]
}

/// The coverage of render and target a pixel's moments need (colour_map_forward.comp
/// `INTERIOR`).
pub const INTERIOR: f32 = 0.99;

/// The forward's moments of renders `c` against targets `t` (the kernel's order), over the
/// pixels both cover.
pub fn moments(c: &[[f64; 4]], t: &[[f64; 4]], background: [f64; 3]) -> Vec<f64> {
    let mut sums = vec![0.0; MOMENTS];
    let interior = |c: &[f64; 4], t: &[f64; 4]| c[3].min(t[3]) >= INTERIOR as f64;
    for (c, t) in c.iter().zip(t).filter(|(c, t)| interior(c, t)) {
        let z = subject(*c, background);
        let y: [f64; 3] = std::array::from_fn(|k| t[k] - (1.0 - c[3]) * background[k]);
        let mut m = 0;
        for a in 0..4 {
            for b in a..4 {
                sums[m] += z[a] * z[b];
                m += 1;
            }
        }
        for yk in y {
            for zb in z {
                sums[m] += yk * zb;
                m += 1;
            }
        }
    }
    sums
}
