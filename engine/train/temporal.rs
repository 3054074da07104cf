//! The start of a temporal frame: the previous frame moved on at constant velocity.

use crate::splat::GaussianScene;
use glam::{Quat, Vec3};

/// Frame t's starting Gaussians from frames t−1 (`prev`) and t−2 (`prev2`, when there is one):
/// positions p + (p − p₂), rotations q · (q₂⁻¹ q) (the last step's rotation applied once
/// more, in the Gaussian's own frame); everything else as in `prev`. Rows must correspond (one
/// topology for the whole sequence); a `prev2` of another length is ignored.
pub fn extrapolate(prev: &GaussianScene, prev2: Option<&GaussianScene>) -> GaussianScene {
    let mut next = prev.clone();
    let Some(prev2) = prev2.filter(|p| p.len() == prev.len()) else { return next };
    for i in 0..prev.len() {
        let (p, p2) = (Vec3::from_array(prev.positions[i]), Vec3::from_array(prev2.positions[i]));
        next.positions[i] = (2.0 * p - p2).to_array();
        let (q, q2) = (quat(prev.rotations[i]), quat(prev2.rotations[i]));
        // Both signs of a quaternion are one rotation: take the short way.
        let step = (q2.conjugate() * q).normalize();
        let step = if step.w < 0.0 { -step } else { step };
        let r = (q * step).normalize();
        next.rotations[i] = [r.w, r.x, r.y, r.z];
    }
    next
}

/// A stored (w, x, y, z) quaternion, normalised (zero stays the identity).
#[inline]
fn quat([w, x, y, z]: [f32; 4]) -> Quat {
    let q = Quat::from_xyzw(x, y, z, w);
    if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        Quat::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(position: [f32; 3], rotation: Quat) -> GaussianScene {
        GaussianScene {
            positions: vec![position],
            log_scales: vec![[0.0; 3]],
            rotations: vec![[rotation.w, rotation.x, rotation.y, rotation.z]],
            opacity_logits: vec![1.0],
            sh: vec![0.1, 0.2, 0.3],
            sh_degree: 0,
        }
    }

    #[test]
    fn continues_translation_and_rotation() {
        let a = Quat::from_rotation_y(0.2) * Quat::from_rotation_x(0.5);
        let b = Quat::from_rotation_y(0.3) * a;
        let next = extrapolate(&scene([1.0, 2.0, 3.0], b), Some(&scene([0.5, 2.0, 2.0], a)));
        assert_eq!(next.positions[0], [1.5, 2.0, 4.0]);
        let [w, x, y, z] = next.rotations[0];
        let expect = b * (a.conjugate() * b);
        assert!(Quat::from_xyzw(x, y, z, w).dot(expect).abs() > 1.0 - 1e-6);
        // The rotation step is the same from the opposite sign of the older quaternion.
        let flipped = extrapolate(&scene([1.0, 2.0, 3.0], b), Some(&scene([0.5, 2.0, 2.0], -a)));
        assert!(quat(flipped.rotations[0]).dot(expect).abs() > 1.0 - 1e-6);
        assert_eq!(next.sh, vec![0.1, 0.2, 0.3]);
    }

    #[test]
    fn first_frames_and_mismatched_rows_stay_put() {
        let s = scene([1.0, 2.0, 3.0], Quat::IDENTITY);
        assert_eq!(extrapolate(&s, None), s);
        assert_eq!(extrapolate(&s, Some(&GaussianScene::default())), s);
    }
}
