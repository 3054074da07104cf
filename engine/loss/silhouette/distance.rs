//! The distance from every pixel to a mask: the field the long-range silhouette term samples.

/// Per pixel (row-major, `width × height`), the Euclidean distance in pixels from its centre to
/// the nearest foreground pixel's centre (mask > 0.5), less half a pixel and floored at 0, so
/// foreground pixels and the half-pixel band around them, where the true outline lies, are 0.
/// `None` when the mask has no foreground pixel (or its size does not match). Exact: the
/// separable squared distance transform of Felzenszwalb and Huttenlocher, O(pixels).
pub fn mask_distance(mask: &[f32], width: usize, height: usize) -> Option<Vec<f32>> {
    if mask.len() != width * height || !mask.iter().any(|&m| m > 0.5) {
        return None;
    }
    // Larger than any squared distance inside an image, small enough to add without overflow.
    let far = ((width + height) as f64).powi(2) * 4.0;
    let mut squared: Vec<f64> = mask.iter().map(|&m| if m > 0.5 { 0.0 } else { far }).collect();
    let mut line = Vec::new();
    for x in 0..width {
        line.clear();
        line.extend((0..height).map(|y| squared[y * width + x]));
        for (y, d) in transform_1d(&line).into_iter().enumerate() {
            squared[y * width + x] = d;
        }
    }
    for row in squared.chunks_mut(width) {
        let done = transform_1d(row);
        row.copy_from_slice(&done);
    }
    Some(squared.iter().map(|&d| (d.sqrt() - 0.5).max(0.0) as f32).collect())
}

/// The lower envelope of parabolas: out(q) = min over p of (q − p)² + f(p).
fn transform_1d(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut out = vec![0.0; n];
    if n == 0 {
        return out;
    }
    let (mut vertices, mut bounds) = (vec![0usize; n], vec![0.0f64; n + 1]);
    let mut k = 0;
    bounds[0] = f64::NEG_INFINITY;
    bounds[1] = f64::INFINITY;
    let meet = |q: usize, p: usize| {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * q as f64 - 2.0 * p as f64)
    };
    for q in 1..n {
        let mut s = meet(q, vertices[k]);
        while s <= bounds[k] {
            k -= 1;
            s = meet(q, vertices[k]);
        }
        k += 1;
        vertices[k] = q;
        bounds[k] = s;
        bounds[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, value) in out.iter_mut().enumerate() {
        while bounds[k + 1] < q as f64 {
            k += 1;
        }
        let p = vertices[k];
        *value = (q as f64 - p as f64).powi(2) + f[p];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let (w, h) = (13, 9);
        let mask: Vec<f32> =
            (0..w * h).map(|i| if (i * 7919) % 23 == 0 { 1.0 } else { 0.0 }).collect();
        let field = mask_distance(&mask, w, h).unwrap();
        for y in 0..h {
            for x in 0..w {
                let nearest = (0..w * h)
                    .filter(|&j| mask[j] > 0.5)
                    .map(|j| {
                        (((j % w) as f64 - x as f64).powi(2) + ((j / w) as f64 - y as f64).powi(2))
                            .sqrt()
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    ((nearest - 0.5).max(0.0) - field[y * w + x] as f64).abs() < 1e-5,
                    "({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn empty_or_mis_sized_masks_have_no_field() {
        assert!(mask_distance(&[0.0; 12], 4, 3).is_none());
        assert!(mask_distance(&[1.0; 12], 4, 4).is_none());
        assert!(mask_distance(&[], 0, 0).is_none());
        assert_eq!(mask_distance(&[1.0; 6], 3, 2).unwrap(), vec![0.0; 6]);
    }
}
