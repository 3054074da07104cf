//! Which 16×16 tiles a projected Gaussian's footprint `σ ≤ ln(255 o)` reaches, decided
//! exactly per tile from the minimum of σ over the rectangle of the tile's pixel centres.

use super::Projected;
use crate::splat::TILE_SIZE;

/// The tiles (index `tile_y * tiles_x + tile_x`, increasing) whose pixel-centre rectangle
/// `[x0 + 0.5, x1 − 0.5] × [y0 + 0.5, y1 − 0.5]` (`x1 = min(x0 + 16, width)`) holds a point with
/// `σ ≤ ln(255 o)`. Empty for an invalid footprint (non-positive-definite or non-finite conic).
pub fn tiles_touched(p: &Projected, width: u32, height: u32) -> Vec<u32> {
    let extent = (255.0 * p.opacity).ln();
    let [q00, q01, q11] = p.conic;
    let det = q00 * q11 - q01 * q01;
    // Half-extents of the ellipse's bounding box: sqrt(2 extent Σ'_aa), Σ' = Q⁻¹.
    let half = [(2.0 * extent * q11 / det).sqrt(), (2.0 * extent * q00 / det).sqrt()];
    if !(extent >= 0.0
        && det > 0.0
        && q00 > 0.0
        && half.iter().chain(&p.mean).all(|v| v.is_finite()))
    {
        return Vec::new();
    }
    let tiles_x = width.div_ceil(TILE_SIZE);
    // Candidate tiles: the bounding box widened by a pixel, so its rounding never drops a
    // tile; the exact test below decides.
    let range = |a: usize, size: u32| {
        let tiles = f64::from(size.div_ceil(TILE_SIZE));
        let tile = f64::from(TILE_SIZE);
        let first = ((p.mean[a] - half[a] - 1.0) / tile).floor().clamp(0.0, tiles);
        let end = (((p.mean[a] + half[a] + 1.0) / tile).floor() + 1.0).clamp(0.0, tiles);
        first as u32..end as u32
    };
    let mut tiles = Vec::new();
    for ty in range(1, height) {
        for tx in range(0, width) {
            let lo = [tx * TILE_SIZE, ty * TILE_SIZE];
            let hi = [((tx + 1) * TILE_SIZE).min(width), ((ty + 1) * TILE_SIZE).min(height)];
            let lo = lo.map(|v| f64::from(v) + 0.5);
            let hi = hi.map(|v| f64::from(v) - 0.5);
            if min_sigma(p, lo, hi) <= extent {
                tiles.push(ty * tiles_x + tx);
            }
        }
    }
    tiles
}

/// The minimum of σ over the rectangle `[lo, hi]`: 0 with the mean inside, else the least
/// of its four edges, on each of which σ is a convex parabola minimised at a clamped vertex.
fn min_sigma(p: &Projected, lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let m = p.mean;
    if (lo[0]..=hi[0]).contains(&m[0]) && (lo[1]..=hi[1]).contains(&m[1]) {
        return 0.0;
    }
    let [q00, q01, q11] = p.conic;
    let mut best = f64::INFINITY;
    for x in [lo[0], hi[0]] {
        // ∂σ/∂dy = Q01 dx + Q11 dy = 0.
        let y = (m[1] - q01 * (x - m[0]) / q11).clamp(lo[1], hi[1]);
        best = best.min(p.sigma([x, y]));
    }
    for y in [lo[1], hi[1]] {
        let x = (m[0] - q01 * (y - m[1]) / q00).clamp(lo[0], hi[0]);
        best = best.min(p.sigma([x, y]));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Against dense sampling of each tile's pixel-centre rectangle: every tile with a sample
    /// inside the footprint is reported, and every reported tile has its exact minimum at or
    /// below the smallest sample (so it is no larger than the truth).
    #[test]
    fn exact_tiles_agree_with_dense_sampling() {
        let (width, height) = (67u32, 33u32);
        let mut rng = SplitMix64::new(5);
        for _ in 0..200 {
            let angle = rng.next_f64() * std::f64::consts::PI;
            let (a, b) = (0.3 + 30.0 * rng.next_f64(), 0.3 + 3.0 * rng.next_f64());
            let (c, s) = (angle.cos(), angle.sin());
            // Σ' = R diag(a², b²) Rᵀ, conic = Σ'⁻¹.
            let (s00, s01, s11) = (
                a * a * c * c + b * b * s * s,
                (a * a - b * b) * c * s,
                a * a * s * s + b * b * c * c,
            );
            let det = s00 * s11 - s01 * s01;
            let p = Projected {
                mean: [rng.next_f64() * 100.0 - 16.0, rng.next_f64() * 60.0 - 14.0],
                conic: [s11 / det, -s01 / det, s00 / det],
                opacity: 0.01 + 0.99 * rng.next_f64(),
                color: [0.0; 3],
                depth: 1.0,
            };
            let extent = (255.0 * p.opacity).ln();
            let touched = tiles_touched(&p, width, height);
            for tile in 0..5 * 3u32 {
                let (tx, ty) = (tile % 5, tile / 5);
                let lo = [tx * 16, ty * 16].map(|v| f64::from(v) + 0.5);
                let hi = [((tx + 1) * 16).min(width), ((ty + 1) * 16).min(height)]
                    .map(|v| f64::from(v) - 0.5);
                let steps = 60;
                let sampled = (0..=steps)
                    .flat_map(|i| (0..=steps).map(move |j| (i, j)))
                    .map(|(i, j)| {
                        let t = [i, j].map(|k| f64::from(k) / f64::from(steps));
                        p.sigma([lo[0] + t[0] * (hi[0] - lo[0]), lo[1] + t[1] * (hi[1] - lo[1])])
                    })
                    .fold(f64::INFINITY, f64::min);
                let exact = min_sigma(&p, lo, hi);
                assert!(exact <= sampled + 1e-12, "exact minimum {exact} above a sample {sampled}");
                if sampled <= extent {
                    assert!(
                        touched.contains(&tile),
                        "tile {tile} holds a footprint sample but is not reported"
                    );
                }
                assert_eq!(touched.contains(&tile), exact <= extent);
            }
        }
    }

    #[test]
    fn invalid_footprints_touch_nothing() {
        let p = Projected {
            mean: [5.0, 5.0],
            conic: [1.0, 0.0, 1.0],
            opacity: 0.5,
            color: [0.0; 3],
            depth: 1.0,
        };
        assert_eq!(tiles_touched(&p, 32, 32), vec![0]);
        for conic in [[1.0, 2.0, 1.0], [f64::NAN, 0.0, 1.0], [-1.0, 0.0, -1.0]] {
            assert!(tiles_touched(&Projected { conic, ..p }, 32, 32).is_empty());
        }
        assert!(tiles_touched(&Projected { opacity: 1.0 / 256.0, ..p }, 32, 32).is_empty());
        assert!(tiles_touched(&Projected { mean: [1e300, 5.0], ..p }, 32, 32).is_empty());
    }
}
