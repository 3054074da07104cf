//! The procedural subject: a round body with a head, two arms and two legs, one closed manifold
//! surface (an icosphere whose caps around five limb axes are mapped onto surfaces of
//! revolution), skinned to 11 joints (a root, and an upper and a lower bone per limb) that
//! swing and bend over a 48-frame cycle.
//!
//! Each limb stays inside the cone of its cap (radius over axial distance never exceeds the
//! cap's tangent), and the caps are disjoint, so the rest pose never self-intersects.

use super::icosphere::icosphere;
use crate::mesh::skinning::SkinWeights;
use glam::{DMat4, DQuat, DVec3};

/// Frames per animation cycle.
pub const CYCLE_FRAMES: f64 = 48.0;

/// One limb: its axis, cap half-angle, tube radius, tube length, bend axis and phase.
struct Limb {
    axis: DVec3,
    cap: f64,
    radius: f64,
    length: f64,
    bend_axis: DVec3,
    phase: f64,
    swing: f64,
}

fn limbs() -> [Limb; 5] {
    let z = DVec3::Z;
    let limb = |axis: DVec3, cap, radius, length, phase, swing| {
        let axis = axis.normalize();
        let bend = if axis.cross(z).length() > 1e-6 { axis.cross(z).normalize() } else { DVec3::X };
        Limb { axis, cap, radius, length, bend_axis: bend, phase, swing }
    };
    [
        limb(DVec3::new(0.0, 1.0, 0.0), 0.55, 0.42, 0.1, 0.0, 0.25),
        limb(DVec3::new(1.0, 0.2, 0.0), 0.42, 0.2, 1.1, 0.0, 0.6),
        limb(DVec3::new(-1.0, 0.2, 0.0), 0.42, 0.2, 1.1, std::f64::consts::PI, 0.6),
        limb(DVec3::new(0.55, -1.0, 0.0), 0.42, 0.23, 1.2, std::f64::consts::PI, 0.5),
        limb(DVec3::new(-0.55, -1.0, 0.0), 0.42, 0.23, 1.2, 0.0, 0.5),
    ]
}

/// Axial positions (from the body centre) of a limb's shoulder and elbow pivots.
fn pivots(limb: &Limb) -> (f64, f64) {
    let base = limb.cap.cos();
    (base + 0.2, base + 0.3 + 0.5 * limb.length)
}

/// The limb's profile from tip to base as (axial, radius) points, and the lateral area
/// accumulated along it (a surface of revolution: dA = 2π r ds).
fn profile(limb: &Limb) -> (Vec<(f64, f64)>, Vec<f64>) {
    let (base_a, base_r) = (limb.cap.cos(), limb.cap.sin());
    let shoulder_end = base_a + 0.3;
    let tube_end = shoulder_end + limb.length;
    let mut points = Vec::new();
    let n = 64;
    for i in 0..=n {
        let psi = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
        points.push((tube_end + limb.radius * psi.cos(), limb.radius * psi.sin()));
    }
    for i in 1..=n {
        points.push((tube_end - (tube_end - shoulder_end) * i as f64 / n as f64, limb.radius));
    }
    for i in 1..=n {
        let s = i as f64 / n as f64;
        let smooth = s * s * (3.0 - 2.0 * s);
        points.push((
            shoulder_end - (shoulder_end - base_a) * s,
            limb.radius + (base_r - limb.radius) * smooth,
        ));
    }
    let mut area = vec![0.0];
    for w in points.windows(2) {
        let ds = ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt();
        area.push(
            area.last().copied().unwrap_or(0.0) + std::f64::consts::PI * (w[0].1 + w[1].1) * ds,
        );
    }
    (points, area)
}

/// Maps a unit direction inside a limb's cap onto the limb, matching area fractions from the
/// tip (equal-area, so triangles keep comparable sizes).
fn map_to_limb(u: DVec3, limb: &Limb, points: &[(f64, f64)], area: &[f64]) -> DVec3 {
    let theta = u.dot(limb.axis).clamp(-1.0, 1.0).acos();
    let fraction = (1.0 - theta.cos()) / (1.0 - limb.cap.cos());
    let target = fraction.clamp(0.0, 1.0) * area[area.len() - 1];
    let i = area.partition_point(|&a| a < target).clamp(1, area.len() - 1);
    let t =
        if area[i] > area[i - 1] { (target - area[i - 1]) / (area[i] - area[i - 1]) } else { 0.0 };
    let a = points[i - 1].0 + t * (points[i].0 - points[i - 1].0);
    let r = points[i - 1].1 + t * (points[i].1 - points[i - 1].1);
    let radial = u - u.dot(limb.axis) * limb.axis;
    let radial = if radial.length() > 1e-12 { radial.normalize() } else { DVec3::ZERO };
    a * limb.axis + r * radial
}

#[inline]
fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The rest mesh (positions, faces) and its skin weights; `subdivisions` refines the base
/// icosphere (4 gives 2562 vertices, 5120 faces). Units: the body has radius 1.
pub fn procedural_subject(subdivisions: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>, SkinWeights) {
    let (sphere, faces) = icosphere(subdivisions);
    let limbs = limbs();
    let profiles: Vec<_> = limbs.iter().map(profile).collect();
    let mut positions = Vec::with_capacity(sphere.len());
    let mut skin = SkinWeights { joints: Vec::new(), weights: Vec::new() };
    for p in sphere {
        let u = DVec3::from(p);
        let inside = limbs.iter().position(|l| u.dot(l.axis) > l.cap.cos());
        let (position, joints, weights) = match inside {
            None => (u, [0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            Some(k) => {
                let limb = &limbs[k];
                let q = map_to_limb(u, limb, &profiles[k].0, &profiles[k].1);
                let a = q.dot(limb.axis);
                let (shoulder, elbow) = pivots(limb);
                let (s, e) = (
                    smoothstep(shoulder - 0.12, shoulder + 0.12, a),
                    smoothstep(elbow - 0.15, elbow + 0.15, a),
                );
                let j = 1 + 2 * k as u32;
                (q, [0, j, j + 1, 0], [(1.0 - s) as f32, (s - e) as f32, e as f32, 0.0])
            }
        };
        positions.push(position.as_vec3().to_array());
        skin.joints.push(joints);
        skin.weights.push(weights);
    }
    (positions, faces, skin)
}

/// Skinning matrices of the 11 joints at animation time `time` (in cycle frames, fractional;
/// rest pose = identity matrices, so no inverse bind matrices are needed): the root turns about
/// y and bobs; each limb swings at its shoulder (left and right in opposite phase) and bends at
/// its elbow, about an axis across the limb. Time 0 is the rest pose.
pub fn procedural_pose(time: f64) -> Vec<DMat4> {
    let phi = std::f64::consts::TAU * time / CYCLE_FRAMES;
    let root = DMat4::from_translation(DVec3::new(0.0, 0.06 * (2.0 * phi).sin(), 0.0))
        * DMat4::from_rotation_y(0.3 * phi.sin());
    let mut joints = vec![root];
    let about = |pivot: DVec3, axis: DVec3, angle: f64| {
        DMat4::from_translation(pivot)
            * DMat4::from_quat(DQuat::from_axis_angle(axis, angle))
            * DMat4::from_translation(-pivot)
    };
    for limb in limbs() {
        let (shoulder, elbow) = pivots(&limb);
        let swing = limb.swing * (phi + limb.phase).sin();
        let bend = 0.9 * (0.5 - 0.5 * phi.cos());
        let upper = root * about(shoulder * limb.axis, limb.bend_axis, swing);
        let lower = upper * about(elbow * limb.axis, limb.bend_axis, bend);
        joints.push(upper);
        joints.push(lower);
    }
    joints
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::skinning::skin;
    use crate::synth::manifold::closed_manifold_problem;

    #[test]
    fn closed_manifold_weights_sum_to_one_and_rest_pose_is_identity() {
        let (p, f, w) = procedural_subject(3);
        assert_eq!(closed_manifold_problem(p.len(), &f), None);
        for ws in &w.weights {
            assert!((ws.iter().sum::<f32>() - 1.0).abs() < 1e-6 && ws.iter().all(|&x| x >= 0.0));
        }
        // Frame 0 has zero swing and zero bend, only the root transform (identity at phi = 0).
        let posed = skin(&p, &w, &procedural_pose(0.0));
        for (a, b) in p.iter().zip(&posed) {
            assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-6));
        }
        // Limbs reach out: the subject spans more than the body's diameter in x and y.
        let span = |k: usize| {
            p.iter().map(|q| q[k]).fold(f32::MIN, f32::max)
                - p.iter().map(|q| q[k]).fold(f32::MAX, f32::min)
        };
        assert!(span(0) > 3.5 && span(1) > 3.0, "{} {}", span(0), span(1));
    }

    #[test]
    fn limbs_move_and_rigid_parts_stay_rigid() {
        let (p, _, w) = procedural_subject(3);
        let posed = skin(&p, &w, &procedural_pose(12.0));
        let moved = p
            .iter()
            .zip(&posed)
            .filter(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 0.05))
            .count();
        assert!(moved > p.len() / 4);
        // Two body vertices (root weight 1) keep their distance.
        let body: Vec<usize> = (0..p.len()).filter(|&i| w.weights[i][0] == 1.0).take(2).collect();
        let d = |q: &[[f32; 3]]| {
            (0..3).map(|k| (q[body[0]][k] - q[body[1]][k]).powi(2)).sum::<f32>().sqrt()
        };
        assert!((d(&p) - d(&posed)).abs() < 1e-5);
    }
}
