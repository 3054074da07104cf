//! Orientation frames: the rotation a locator pinned to a bound point follows.
//!
//! In each frame the bound triangle (v0, v1, v2) gives a right-handed orthonormal frame:
//! - normal n = (v1 − v0) × (v2 − v0), normalised (outward for counter-clockwise faces);
//! - tangent t = the edge v0 → v1 with its component along n removed, normalised;
//! - bitangent n × t.
//!
//! As a rotation it takes X to t, Y to n × t and Z to n. This is the frame Blender's
//! three-vertex parent gives a child (Z along the triangle's normal, X along its first edge);
//! Maya's uvPin and Houdini's rivet follow the same surface normal, with the tangent along the
//! UV direction or a chosen attribute instead of an edge, so their axis choice may differ by a
//! rotation about the normal that is fixed over time.
//!
//! A triangle without area in some frame (coincident or collinear corners) has no normal.
//! Such a frame holds the point's orientation from the nearest earlier frame whose triangle has
//! area, else from the nearest later one; a triangle without area in every frame gets the world
//! axes (n = +Z, t = +X). The frames so filled are listed, never silent, and no value is NaN.

use super::bind::Binding;
use glam::{DMat3, DQuat, DVec3};

/// A corner cross product no longer than this × the longest edge squared is no area: the
/// corners are collinear or coincide to within rounding of f64 sums of f32 positions.
const FLAT: f64 = 1e-12;

/// The orientation of a bound point in one frame: unit, orthogonal normal and tangent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceFrame {
    /// The bound triangle's unit normal.
    pub normal: [f64; 3],
    /// The unit tangent along the triangle's first edge, orthogonal to the normal.
    pub tangent: [f64; 3],
}

impl SurfaceFrame {
    /// The world axes, for a triangle that never has area: normal +Z, tangent +X.
    pub const WORLD: SurfaceFrame =
        SurfaceFrame { normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0] };

    /// The rotation taking X to the tangent, Y to normal × tangent and Z to the normal, as a
    /// unit quaternion `[x, y, z, w]` (glTF's order) with w ≥ 0.
    pub fn rotation(&self) -> [f64; 4] {
        let (n, t) = (DVec3::from(self.normal), DVec3::from(self.tangent));
        let q = DQuat::from_mat3(&DMat3::from_cols(t, n.cross(t), n)).normalize();
        let q = if q.w < 0.0 { -q } else { q };
        q.to_array()
    }
}

/// The orientation of triangle `corners` (v0, v1, v2), or None when it has no area.
pub fn triangle_orientation(corners: [DVec3; 3]) -> Option<SurfaceFrame> {
    let [v0, v1, v2] = corners;
    let (e1, e2) = (v1 - v0, v2 - v0);
    let longest = e1.length_squared().max(e2.length_squared()).max((v2 - v1).length_squared());
    let cross = e1.cross(e2);
    let area = cross.length();
    if area.is_nan() || area <= FLAT * longest {
        return None;
    }
    let normal = cross.normalize();
    let tangent = (e1 - normal * e1.dot(normal)).normalize();
    (normal.is_finite() && tangent.is_finite())
        .then(|| SurfaceFrame { normal: normal.to_array(), tangent: tangent.to_array() })
}

/// The orientation of `binding` in every frame of `frames` (vertex positions per frame, sharing
/// `faces`), and the frames whose triangle had no area (filled as the module says). None when
/// the face, or a vertex of it, is out of range.
pub fn surface_frames(
    binding: &Binding,
    faces: &[[u32; 3]],
    frames: &[Vec<[f32; 3]>],
) -> Option<(Vec<SurfaceFrame>, Vec<u32>)> {
    let face = faces.get(binding.face as usize)?;
    let per_frame = frames
        .iter()
        .map(|positions| {
            let corner = |k: usize| positions.get(face[k] as usize).map(|v| v.map(f64::from));
            Some(triangle_orientation([corner(0)?, corner(1)?, corner(2)?].map(DVec3::from)))
        })
        .collect::<Option<Vec<_>>>()?;
    Some(fill_gaps(&per_frame))
}

/// Every frame's orientation from `per_frame` (None where the triangle had no area), gaps
/// filled as the module says, and the indices of the frames so filled.
pub fn fill_gaps(per_frame: &[Option<SurfaceFrame>]) -> (Vec<SurfaceFrame>, Vec<u32>) {
    let first = per_frame.iter().flatten().next().copied().unwrap_or(SurfaceFrame::WORLD);
    let mut held = Vec::new();
    let mut last = first;
    let filled = per_frame
        .iter()
        .enumerate()
        .map(|(t, o)| match o {
            Some(o) => {
                last = *o;
                *o
            }
            None => {
                held.push(t as u32);
                last
            }
        })
        .collect();
    (filled, held)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orientation(corners: [[f64; 3]; 3]) -> Option<SurfaceFrame> {
        triangle_orientation(corners.map(DVec3::from))
    }

    #[test]
    fn a_triangle_gives_its_normal_and_first_edge() {
        let o = orientation([[1.0, 1.0, 1.0], [3.0, 1.0, 1.0], [1.0, 1.0, -4.0]]).unwrap();
        assert_eq!((o.normal, o.tangent), ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0]));
        // X -> t, Y -> n × t = -Z, Z -> n = Y: a quarter turn about X.
        let q = DQuat::from_array(o.rotation());
        assert!((q * DVec3::X - DVec3::X).length() < 1e-15);
        assert!((q * DVec3::Y + DVec3::Z).length() < 1e-15);
        assert!((q * DVec3::Z - DVec3::Y).length() < 1e-15);
    }

    #[test]
    fn triangles_without_area_have_no_orientation() {
        assert_eq!(orientation([[0.0; 3], [0.0; 3], [0.0; 3]]), None);
        assert_eq!(orientation([[0.0; 3], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]), None);
        assert_eq!(orientation([[1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 5.0, 1.0]]), None);
        assert_eq!(orientation([[f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), None);
        // Thin but not flat: still oriented.
        assert!(orientation([[0.0; 3], [1.0, 0.0, 0.0], [0.5, 1e-5, 0.0]]).is_some());
    }

    #[test]
    fn gaps_hold_the_previous_frame_else_the_next_else_the_world_axes() {
        let a = Some(SurfaceFrame { normal: [0.0, 1.0, 0.0], tangent: [0.0, 0.0, 1.0] });
        let b = Some(SurfaceFrame { normal: [1.0, 0.0, 0.0], tangent: [0.0, 1.0, 0.0] });
        let (filled, held) = fill_gaps(&[None, a, None, b, None]);
        assert_eq!(filled, [a, a, a, b, b].map(Option::unwrap));
        assert_eq!(held, [0, 2, 4]);
        assert_eq!(fill_gaps(&[None, None]), (vec![SurfaceFrame::WORLD; 2], vec![0, 1]));
    }
}
