//! Mesh → Gaussians: one Gaussian per vertex, lying in the surface (docs/conventions.md,
//! "Meshes"), and the per-vertex quantities the topology policies read back.

use super::geometry::{area_vector, vec};
use super::ManifoldMesh;
use crate::splat::{sh_coefficients, GaussianScene};
use glam::{DMat3, DQuat, DVec3};

/// The degree-0 SH basis constant: colour = 0.5 + SH_C0 · k_dc (engine/splat/mod.rs).
pub const SH_C0: f64 = 0.282_094_791_773_878_14;

/// How the Gaussians of a mesh start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitConfig {
    /// s_x = s_y = this × the mean distance to the 1-ring (so neighbours overlap).
    pub tangent_scale: f32,
    /// s_z = this × s_x ("small": the Gaussian starts flat in the surface).
    pub flatness: f32,
    /// Opacity after the sigmoid ("near 1").
    pub opacity: f32,
    /// Spherical-harmonics degree of the scene; the higher coefficients start at zero.
    pub sh_degree: u32,
}

impl Default for InitConfig {
    fn default() -> Self {
        Self { tangent_scale: 0.5, flatness: 0.1, opacity: 0.95, sh_degree: 3 }
    }
}

/// Unit area-weighted vertex normals (the normalised sum of the area vectors of the faces
/// around each vertex), one row per vertex row; zero for removed or degenerate fans.
pub fn vertex_normals(mesh: &ManifoldMesh) -> Vec<[f32; 3]> {
    let mut sums = vec![DVec3::ZERO; mesh.vertex_rows()];
    for f in mesh.faces() {
        let corners = mesh.face(f);
        let [a, b, c] = corners.map(|v| mesh.point(v));
        let n = area_vector(a, b, c);
        corners.iter().for_each(|&v| sums[v as usize] += n);
    }
    sums.iter().map(|n| n.normalize_or_zero().as_vec3().to_array()).collect()
}

/// One Gaussian per vertex row of a compacted mesh: position = vertex; rotation with its z
/// axis on the vertex normal and x towards the first 1-ring neighbour; s_x = s_y from the mean
/// neighbour distance, s_z small; opacity high; SH DC from `colors` (linear RGB in [0, 1], one
/// per vertex; vertices past its end get grey 0.5), higher SH coefficients zero.
pub fn gaussians_from_mesh(
    mesh: &ManifoldMesh,
    colors: &[[f32; 3]],
    config: &InitConfig,
) -> GaussianScene {
    let normals = vertex_normals(mesh);
    let n = mesh.vertex_rows();
    let coefficients = sh_coefficients(config.sh_degree);
    let mut scene = GaussianScene {
        sh_degree: config.sh_degree,
        sh: vec![0.0; n * coefficients * 3],
        ..Default::default()
    };
    let logit = (config.opacity / (1.0 - config.opacity)).ln();
    for v in 0..n as u32 {
        let ring = if mesh.is_vertex_live(v) { mesh.ring(v) } else { Vec::new() };
        let p = mesh.point(v);
        let mean = ring.iter().map(|&r| (mesh.point(r) - p).length()).sum::<f64>()
            / ring.len().max(1) as f64;
        let tangent = (config.tangent_scale as f64 * mean).max(f64::MIN_POSITIVE).ln() as f32;
        let normal = (config.flatness as f64).ln() as f32 + tangent;
        scene.positions.push(mesh.positions[v as usize]);
        scene.log_scales.push([tangent, tangent, normal]);
        scene.rotations.push(frame_quaternion(
            vec(normals[v as usize]),
            ring.first().map(|&r| mesh.point(r) - p),
        ));
        scene.opacity_logits.push(logit);
        let color = colors.get(v as usize).copied().unwrap_or([0.5; 3]);
        for (ch, c) in color.iter().enumerate() {
            scene.sh[v as usize * coefficients * 3 + ch] = ((*c as f64 - 0.5) / SH_C0) as f32;
        }
    }
    scene
}

/// (w, x, y, z) of the rotation whose z column is `normal` and whose x column is `towards`
/// made tangent (any tangent when that fails); identity for a zero normal.
fn frame_quaternion(normal: DVec3, towards: Option<DVec3>) -> [f32; 4] {
    if normal == DVec3::ZERO {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let tangent = towards.map(|t| t - normal * t.dot(normal)).and_then(|t| t.try_normalize());
    let x = tangent.unwrap_or_else(|| normal.any_orthonormal_vector());
    let q = DQuat::from_mat3(&DMat3::from_cols(x, normal.cross(x), normal)).normalize();
    [q.w as f32, q.x as f32, q.y as f32, q.z as f32]
}

/// Linear RGB of every Gaussian's SH DC term.
pub fn dc_colors(scene: &GaussianScene) -> Vec<[f32; 3]> {
    let stride = scene.coefficients() * 3;
    (0..scene.len())
        .map(|i| [0, 1, 2].map(|ch| (0.5 + SH_C0 * scene.sh[i * stride + ch] as f64) as f32))
        .collect()
}

/// The z axis (column 2 of the rotation) of a stored quaternion (w, x, y, z), normalised.
pub fn gaussian_normal(q: [f32; 4]) -> DVec3 {
    let q = DQuat::from_xyzw(q[1] as f64, q[2] as f64, q[3] as f64, q[0] as f64).normalize();
    q * DVec3::Z
}
