//! Signed distance to a silhouette's outline, in pixels, positive inside: the per-view term of
//! the visual-hull field. Exact Euclidean distance transform (Felzenszwalb & Huttenlocher's
//! lower envelope of parabolas) between pixel centres, refined on the outline by the mask's
//! anti-aliased coverage: a pixel covered a fraction m lies about m − ½ pixels inside.

/// Distance of a pixel centre to the silhouette outline (positive inside), one per pixel,
/// row-major, plus a continuous extension past the image border.
#[derive(Clone, Debug)]
pub struct SignedDistance {
    /// Width of the mask, in pixels.
    pub width: usize,
    /// Height of the mask, in pixels.
    pub height: usize,
    /// Signed distance of each pixel centre to the outline, in pixels (positive inside),
    /// row-major.
    pub values: Vec<f32>,
}

impl SignedDistance {
    /// From a mask in [0, 1] (> 0.5 is foreground), `width × height`, row-major. Non-finite
    /// values count as background.
    pub fn from_mask(mask: &[f32], width: usize, height: usize) -> Self {
        let mask: Vec<f32> = mask.iter().map(|&m| if m.is_finite() { m } else { 0.0 }).collect();
        let inside: Vec<bool> = mask.iter().map(|&m| m > 0.5).collect();
        let to_outside =
            nearest_feature(&inside.iter().map(|&i| !i).collect::<Vec<_>>(), width, height);
        let to_inside = nearest_feature(&inside, width, height);
        let cap = (width + height) as f64;
        // How far past its centre the outline lies from pixel q, toward the other class.
        let offset = |q: usize| (mask[q] as f64 - 0.5).clamp(-0.5, 0.5);
        let values = (0..mask.len())
            .map(|p| {
                let own = offset(p);
                let d = if own.abs() < 0.5 {
                    own // an outline pixel: its coverage says where the outline is
                } else if inside[p] {
                    to_outside[p].map_or(cap, |(d, q)| d + offset(q))
                } else {
                    to_inside[p].map_or(-cap, |(d, q)| offset(q) - d)
                };
                d as f32
            })
            .collect();
        Self { width, height, values }
    }

    /// Bilinear value at pixel coordinates (u, v) (pixel i has its centre at i + ½). Outside the
    /// image the value keeps falling by the distance to the image rectangle, so the image
    /// border acts as background and the field stays continuous.
    #[inline]
    pub fn sample(&self, u: f64, v: f64) -> f64 {
        let (w, h) = (self.width as f64, self.height as f64);
        let (cu, cv) = (u.clamp(0.0, w), v.clamp(0.0, h));
        let outside = ((u - cu).powi(2) + (v - cv).powi(2)).sqrt();
        let x = (cu - 0.5).clamp(0.0, w - 1.0);
        let y = (cv - 0.5).clamp(0.0, h - 1.0);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |i: usize, j: usize| self.values[j * self.width + i] as f64;
        let top = at(x0, y0) + fx * (at(x1, y0) - at(x0, y0));
        let bottom = at(x0, y1) + fx * (at(x1, y1) - at(x0, y1));
        let d = top + fy * (bottom - top);
        if outside > 0.0 {
            d.min(0.0) - outside
        } else {
            d
        }
    }
}

/// For every pixel centre, the Euclidean distance to the nearest pixel where `feature` is true
/// and that pixel's index (`None` when there is no feature at all).
pub fn nearest_feature(feature: &[bool], width: usize, height: usize) -> Vec<Option<(f64, usize)>> {
    let n = width.max(height);
    let mut envelope = Envelope::new(n);
    let (mut line, mut out, mut arg) = (vec![0.0; n], vec![0.0; n], vec![0usize; n]);
    // Columns: squared distance to the nearest feature in the same column, and its row.
    let mut squared: Vec<f64> = vec![f64::INFINITY; width * height];
    let mut row_of = vec![0usize; width * height];
    for x in 0..width {
        for y in 0..height {
            line[y] = if feature[y * width + x] { 0.0 } else { f64::INFINITY };
        }
        envelope.transform(&line[..height], &mut out[..height], &mut arg[..height]);
        for y in 0..height {
            squared[y * width + x] = out[y];
            row_of[y * width + x] = arg[y];
        }
    }
    // Rows: combine the column results along x.
    let mut result = vec![None; width * height];
    for y in 0..height {
        line[..width].copy_from_slice(&squared[y * width..(y + 1) * width]);
        envelope.transform(&line[..width], &mut out[..width], &mut arg[..width]);
        for x in 0..width {
            if out[x].is_finite() {
                let column = arg[x];
                result[y * width + x] =
                    Some((out[x].sqrt(), row_of[y * width + column] * width + column));
            }
        }
    }
    result
}

/// Buffers of the 1-D transform: parabola apexes and the boundaries between them.
struct Envelope {
    apex: Vec<usize>,
    bound: Vec<f64>,
}

impl Envelope {
    fn new(n: usize) -> Self {
        Self { apex: vec![0; n], bound: vec![0.0; n + 1] }
    }

    /// out[q] = min over p of (q − p)² + f[p] and arg[q] the minimising p: the lower envelope
    /// of parabolas rooted at the finite samples of f (all infinite: out is infinite).
    fn transform(&mut self, f: &[f64], out: &mut [f64], arg: &mut [usize]) {
        let Some(first) = f.iter().position(|v| v.is_finite()) else {
            out.fill(f64::INFINITY);
            return;
        };
        let mut k = 0;
        self.apex[0] = first;
        self.bound[0] = f64::NEG_INFINITY;
        self.bound[1] = f64::INFINITY;
        for q in first + 1..f.len() {
            if !f[q].is_finite() {
                continue;
            }
            // Pop parabolas the new one hides; bound[0] = −∞ stops the loop at k = 0.
            let mut s;
            loop {
                let p = self.apex[k];
                s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64))
                    / (2.0 * (q as f64 - p as f64));
                if s > self.bound[k] {
                    break;
                }
                k -= 1;
            }
            k += 1;
            self.apex[k] = q;
            self.bound[k] = s;
            self.bound[k + 1] = f64::INFINITY;
        }
        let mut k = 0;
        for q in 0..f.len() {
            while self.bound[k + 1] < q as f64 {
                k += 1;
            }
            let p = self.apex[k];
            out[q] = (q as f64 - p as f64).powi(2) + f[p];
            arg[q] = p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn transform_matches_brute_force() {
        let (w, h) = (23, 17);
        let mut rng = SplitMix64::new(5);
        for density in [0.02, 0.2, 0.7] {
            let feature: Vec<bool> = (0..w * h).map(|_| rng.next_f64() < density).collect();
            let nearest = nearest_feature(&feature, w, h);
            let dist = |p: usize, q: usize| {
                ((q % w) as f64 - (p % w) as f64).hypot((q / w) as f64 - (p / w) as f64)
            };
            for (p, found) in nearest.iter().enumerate() {
                let brute = (0..w * h)
                    .filter(|&q| feature[q])
                    .map(|q| dist(p, q))
                    .fold(f64::INFINITY, f64::min);
                match *found {
                    Some((d, q)) => {
                        assert!(
                            feature[q] && (d - brute).abs() < 1e-9 && (dist(p, q) - d).abs() < 1e-9,
                            "pixel {p}: {d} vs {brute}"
                        );
                    }
                    None => assert!(brute.is_infinite()),
                }
            }
        }
    }

    #[test]
    fn disk_distance_is_radius_minus_centre_distance() {
        let (n, r) = (64usize, 20.0);
        let mask: Vec<f32> = (0..n * n)
            .map(|p| {
                (((p % n) as f64 + 0.5 - 32.0).hypot((p / n) as f64 + 0.5 - 32.0) < r) as u8 as f32
            })
            .collect();
        let sd = SignedDistance::from_mask(&mask, n, n);
        // A binary mask places the outline to within half a pixel; bilinear interpolation
        // rounds off the cone's apex at the centre by about a pixel more.
        for (u, v, tolerance) in [
            (32.0, 32.0, 1.5),
            (40.3, 30.1, 0.75),
            (50.0, 32.0, 0.75),
            (52.4, 33.3, 0.75),
            (60.0, 60.0, 0.75),
            (5.5, 32.0, 0.75),
        ] {
            let exact = r - (u - 32.0f64).hypot(v - 32.0);
            assert!(
                (sd.sample(u, v) - exact).abs() < tolerance,
                "({u}, {v}): {} vs {exact}",
                sd.sample(u, v)
            );
        }
        // Past the border it keeps falling.
        assert!(sd.sample(-3.0, 32.0) < sd.sample(0.0, 32.0) - 2.9);
    }

    #[test]
    fn anti_aliased_coverage_refines_the_outline() {
        // A vertical edge at x = 10.3: pixel 10 is 30 % covered.
        let (w, h) = (20, 4);
        let mask: Vec<f32> = (0..w * h).map(|p| (10.3 - (p % w) as f32).clamp(0.0, 1.0)).collect();
        let sd = SignedDistance::from_mask(&mask, w, h);
        // Zero crossing between the centres of pixels 9 (0.5) and 10 (−0.2): at 10.3.
        let (a, b) = (sd.sample(9.5, 2.0), sd.sample(10.5, 2.0));
        let crossing = 9.5 + a / (a - b);
        assert!((crossing - 10.3).abs() < 1e-6, "{crossing}");
        // Empty and full masks: no outline, every value one sign.
        assert!(SignedDistance::from_mask(&[0.0; 16], 4, 4).values.iter().all(|&v| v < 0.0));
        assert!(SignedDistance::from_mask(&[1.0; 16], 4, 4).values.iter().all(|&v| v > 0.0));
        let mut nan = [1.0f32; 16];
        nan[5] = f32::NAN;
        nan[6] = f32::INFINITY;
        let sd = SignedDistance::from_mask(&nan, 4, 4);
        assert!(
            sd.values.iter().all(|v| v.is_finite()) && sd.values[5] < 0.0 && sd.values[6] < 0.0
        );
    }
}
