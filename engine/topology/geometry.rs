//! Small f64 triangle geometry shared by the operations' legality checks and policies.

use glam::DVec3;

#[inline]
pub fn vec(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// Unnormalised face normal (twice the area vector) of `a, b, c`.
#[inline]
pub fn area_vector(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// Twice the area over the longest squared edge below which a triangle counts as degenerate:
/// about the sine of its smallest angle, far above f32 rounding of positions (~1e-7 relative)
/// so normals stay meaningful. Scale-free.
pub const DEGENERATE_RATIO: f64 = 1e-5;

/// Whether a triangle is degenerate relative to its own size (see [`DEGENERATE_RATIO`]).
#[inline]
pub fn is_degenerate(a: DVec3, b: DVec3, c: DVec3) -> bool {
    let longest =
        (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    // NaN areas count as degenerate.
    let area = area_vector(a, b, c).length();
    area.is_nan() || area <= DEGENERATE_RATIO * longest
}

/// Whether the triangles `new` (each given by corners) are all non-degenerate and face the
/// same side as `reference` (an area vector).
pub fn faces_agree(new: &[[DVec3; 3]], reference: DVec3) -> Result<(), GeometryRefusal> {
    for &[a, b, c] in new {
        if is_degenerate(a, b, c) {
            return Err(GeometryRefusal::Degenerate);
        }
        if area_vector(a, b, c).dot(reference) <= 0.0 {
            return Err(GeometryRefusal::FoldsOver);
        }
    }
    Ok(())
}

/// Why new triangles were refused by [`faces_agree`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryRefusal {
    Degenerate,
    FoldsOver,
}

/// Smallest interior angle of a triangle, radians (0 for a degenerate one).
pub fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let angle = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        let denom = u.length() * v.length();
        if denom > 0.0 {
            (u.dot(v) / denom).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        }
    };
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}
