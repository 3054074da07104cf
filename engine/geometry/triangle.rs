//! Point–triangle and ray–triangle queries in f64, answered as barycentric coordinates.
//!
//! Both routines are the single source of truth for the BVH traversals and for the brute-force
//! references the tests and the benchmark compare against.

use glam::DVec3;

/// Barycentric coordinates (b0, b1, b2) of the point of triangle (a, b, c) closest to `p`.
///
/// Guarantees b ≥ 0 and Σb = 1 (up to rounding), so `b0·a + b1·b + b2·c` lies on the triangle.
/// Follows the Voronoi-region walk of Ericson, *Real-Time Collision Detection* §5.1.5.
/// A degenerate triangle (collinear or coincident corners) has no interior region: it is
/// answered by its closest edge, so the result stays finite.
#[inline]
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let ab = b - a;
    let ac = c - a;
    // A flat triangle has no interior, and the region tests below would divide by its
    // zero-length edges.
    if is_degenerate(ab, ac) {
        return closest_on_edges(p, a, b, c);
    }
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    // va + vb + vc = |ab × ac|² (Lagrange identity), positive after the test above.
    let area2 = va + vb + vc;
    if area2.is_nan() || area2 <= 0.0 {
        return closest_on_edges(p, a, b, c);
    }
    let v = vb / area2;
    let w = vc / area2;
    [1.0 - v - w, v, w]
}

/// Whether the triangle with edges `ab`, `ac` has no area: |ab × ac|² within its rounding
/// error (~ε·|ab|²|ac|²) of zero, which covers collinear and coincident corners.
#[inline]
fn is_degenerate(ab: DVec3, ac: DVec3) -> bool {
    let area2 = ab.cross(ac).length_squared();
    area2.is_nan() || area2 <= 8.0 * f64::EPSILON * ab.length_squared() * ac.length_squared()
}

/// The closest point on the three edges of (a, b, c), as barycentrics.
fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let (tab, tbc, tca) =
        (segment_parameter(p, a, b), segment_parameter(p, b, c), segment_parameter(p, c, a));
    let candidates = [[1.0 - tab, tab, 0.0], [0.0, 1.0 - tbc, tbc], [tca, 0.0, 1.0 - tca]];
    let mut best = candidates[0];
    let mut best_d = f64::INFINITY;
    for bary in candidates {
        let d = p.distance_squared(interpolate(bary, a, b, c));
        if d < best_d {
            best_d = d;
            best = bary;
        }
    }
    best
}

/// Parameter t in [0, 1] of the point of segment a→b closest to p (0 for a zero-length segment).
#[inline]
fn segment_parameter(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// `b0·a + b1·b + b2·c`.
#[inline]
pub fn interpolate(bary: [f64; 3], a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    a * bary[0] + b * bary[1] + c * bary[2]
}

/// First intersection of the ray `origin + t·dir`, t in [0, t_max), with triangle (a, b, c),
/// seen from either side: `(t, barycentric)`, or None for a miss or a degenerate triangle
/// (it has no surface to hit, and its rounding noise would fake hits).
///
/// Möller–Trumbore (1997). Points on an edge count as hits, so a ray through a shared edge hits
/// one of the two faces instead of slipping between them.
#[inline]
pub fn ray_triangle(
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
    a: DVec3,
    b: DVec3,
    c: DVec3,
) -> Option<(f64, [f64; 3])> {
    let e1 = b - a;
    let e2 = c - a;
    if is_degenerate(e1, e2) {
        return None;
    }
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = origin - a;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = dir.dot(qvec) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    (t >= 0.0 && t < t_max).then_some((t, [1.0 - u - v, u, v]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn random_point(rng: &mut SplitMix64) -> DVec3 {
        DVec3::new(
            rng.next_f64() * 2.0 - 1.0,
            rng.next_f64() * 2.0 - 1.0,
            rng.next_f64() * 2.0 - 1.0,
        )
    }

    /// q is the closest point of a convex set to p iff (p − q)·(x − q) ≤ 0 for every x in the
    /// set; for a triangle it is enough to check the three corners.
    fn assert_optimal(p: DVec3, tri: [DVec3; 3], bary: [f64; 3]) {
        assert!(bary.iter().all(|&b| b >= -1e-12), "{bary:?}");
        assert!((bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let q = interpolate(bary, tri[0], tri[1], tri[2]);
        let scale = (p - q).length() * tri.iter().map(|v| (*v - q).length()).fold(0.0, f64::max);
        for v in tri {
            assert!(
                (p - q).dot(v - q) <= 1e-9 * scale.max(1e-300),
                "not optimal: p {p} tri {tri:?} bary {bary:?}"
            );
        }
    }

    #[test]
    fn closest_point_satisfies_the_optimality_condition_on_random_triangles() {
        let mut rng = SplitMix64::new(1);
        for _ in 0..20_000 {
            let tri = [random_point(&mut rng), random_point(&mut rng), random_point(&mut rng)];
            let p = random_point(&mut rng) * 2.0;
            assert_optimal(p, tri, closest_on_triangle(p, tri[0], tri[1], tri[2]));
        }
    }

    #[test]
    fn closest_point_on_degenerate_triangles_is_finite_and_optimal() {
        let mut rng = SplitMix64::new(2);
        for _ in 0..5_000 {
            let a = random_point(&mut rng);
            let b = random_point(&mut rng);
            let s = rng.next_f64() * 3.0 - 1.0;
            // Collinear, two coincident corners, all coincident.
            for tri in [[a, b, a + (b - a) * s], [a, a, b], [a, a, a]] {
                let p = random_point(&mut rng);
                let bary = closest_on_triangle(p, tri[0], tri[1], tri[2]);
                assert!(bary.iter().all(|b| b.is_finite()));
                assert_optimal(p, tri, bary);
            }
        }
    }

    #[test]
    fn point_in_the_plane_inside_the_triangle_is_its_own_closest_point() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let bary = closest_on_triangle(DVec3::new(0.25, 0.5, 3.0), a, b, c);
        assert!(
            (bary[0] - 0.25).abs() < 1e-15
                && (bary[1] - 0.25).abs() < 1e-15
                && (bary[2] - 0.5).abs() < 1e-15
        );
    }

    #[test]
    fn ray_hits_at_the_analytic_distance_and_misses_outside() {
        let (a, b, c) =
            (DVec3::new(0.0, 0.0, 2.0), DVec3::new(1.0, 0.0, 2.0), DVec3::new(0.0, 1.0, 2.0));
        let (t, bary) =
            ray_triangle(DVec3::new(0.2, 0.3, 0.0), DVec3::Z, f64::INFINITY, a, b, c).unwrap();
        assert!((t - 2.0).abs() < 1e-15);
        assert!((bary[1] - 0.2).abs() < 1e-15 && (bary[2] - 0.3).abs() < 1e-15);
        // Both sides, behind the origin, beyond t_max, outside, parallel, degenerate.
        assert!(
            ray_triangle(DVec3::new(0.2, 0.3, 4.0), -DVec3::Z, f64::INFINITY, a, b, c).is_some()
        );
        assert!(ray_triangle(DVec3::new(0.2, 0.3, 4.0), DVec3::Z, f64::INFINITY, a, b, c).is_none());
        assert!(ray_triangle(DVec3::new(0.2, 0.3, 0.0), DVec3::Z, 1.5, a, b, c).is_none());
        assert!(ray_triangle(DVec3::new(0.8, 0.8, 0.0), DVec3::Z, f64::INFINITY, a, b, c).is_none());
        assert!(ray_triangle(DVec3::new(0.2, 0.3, 2.0), DVec3::X, f64::INFINITY, a, b, c).is_none());
        assert!(ray_triangle(DVec3::new(0.2, 0.0, 0.0), DVec3::Z, f64::INFINITY, a, b, b).is_none());
        let (p, q) = (
            DVec3::new(-0.7198970913887024, 0.8706438541412354, 0.3532657325267792),
            DVec3::new(-0.6692429184913635, 0.6974490880966187, 0.39339834451675415),
        );
        assert!(
            ray_triangle(DVec3::new(-3.0, 0.75, 0.38), DVec3::X, f64::INFINITY, p, q, q).is_none(),
            "coincident corners never hit"
        );
    }
}
