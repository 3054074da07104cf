//! Small holes in a mask: background regions enclosed by the silhouette (not touching the image
//! border) and smaller than a fraction of the silhouette's area. Real masks have such specks;
//! each one would carve a tunnel through the hull, so they are filled before carving.

use crate::io::image::four_neighbours;

/// Sets every enclosed background region (4-connected, mask ≤ 0.5) of at most
/// `max_fraction` × (foreground pixel count) pixels to 1. Returns the number of pixels filled.
pub fn fill_small_holes(mask: &mut [f32], width: usize, height: usize, max_fraction: f64) -> usize {
    let foreground = mask.iter().filter(|&&m| m > 0.5).count();
    let limit = (max_fraction * foreground as f64).floor() as usize;
    if limit == 0 {
        return 0;
    }
    let mut seen = vec![false; mask.len()];
    let (mut region, mut stack, mut filled) = (Vec::new(), Vec::new(), 0);
    for start in 0..mask.len() {
        if seen[start] || mask[start] > 0.5 {
            continue;
        }
        region.clear();
        let mut touches_border = false;
        seen[start] = true;
        stack.push(start);
        while let Some(p) = stack.pop() {
            region.push(p);
            let (x, y) = (p % width, p / width);
            touches_border |= x == 0 || y == 0 || x + 1 == width || y + 1 == height;
            for q in four_neighbours(p, width, height) {
                if !seen[q] && mask[q] <= 0.5 {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
        if !touches_border && region.len() <= limit {
            for &p in &region {
                mask[p] = 1.0;
            }
            filled += region.len();
        }
    }
    filled
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fills_enclosed_specks_only() {
        // A 10×10 square (100 px) with a 2-px hole inside, a 20-px hole, and a notch at the border.
        let (w, h) = (16, 16);
        let mut mask = vec![0.0f32; w * h];
        for y in 3..13 {
            for x in 3..13 {
                mask[y * w + x] = 1.0;
            }
        }
        mask[5 * w + 5] = 0.0;
        mask[5 * w + 6] = 0.0;
        for y in 8..12 {
            for x in 7..12 {
                mask[y * w + x] = 0.0;
            }
        }
        let before = mask.clone();
        // 78 foreground pixels; 5 % allows holes of 3 px: the speck goes, the 20-px hole stays.
        assert_eq!(fill_small_holes(&mut mask, w, h, 0.05), 2);
        assert_eq!(mask[5 * w + 5], 1.0);
        assert_eq!(mask[9 * w + 9], 0.0);
        assert_eq!(mask[0], 0.0, "the background touching the border stays");
        // Zero fraction changes nothing.
        let mut copy = before.clone();
        assert_eq!(fill_small_holes(&mut copy, w, h, 0.0), 0);
        assert_eq!(copy, before);
    }
}
