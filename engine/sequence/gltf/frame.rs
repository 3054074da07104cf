//! One frame of a mesh node as glTF defines it: morph targets blended first
//! (`base + Σ wᵢ · offsetᵢ`), then, for a skinned node, linear blend skinning with the joint
//! matrices (the node's own transform ignored), else the node's global transform.

use super::mesh::MeshData;
use super::skin::Skin;
use crate::mesh::skinning::skin_layers;
use glam::{DMat4, DVec3};

/// The vertex positions of `mesh` with morph `weights`, skinned by `skin` at `globals` (the
/// nodes' global transforms), or else placed by `global`, the node's own.
pub fn frame(
    mesh: &MeshData,
    weights: &[f64],
    skin: Option<&Skin>,
    globals: &[DMat4],
    global: DMat4,
) -> Vec<[f32; 3]> {
    let morphed = morph(&mesh.positions, &mesh.targets, weights);
    match skin {
        Some(skin) => skin_layers(&morphed, &mesh.skin, &skin.matrices(globals)),
        None if global == DMat4::IDENTITY => morphed,
        None => morphed
            .iter()
            .map(|p| global.transform_point3(DVec3::from(p.map(f64::from))).as_vec3().to_array())
            .collect(),
    }
}

/// `base + Σ wᵢ · targetᵢ`, summed in f64 over the non-zero weights and rounded once (so a
/// weight of exactly 1 on one target gives base + offset rounded once, as a morph-per-frame
/// file means it).
pub fn morph(base: &[[f32; 3]], targets: &[Vec<[f32; 3]>], weights: &[f64]) -> Vec<[f32; 3]> {
    let used: Vec<(&Vec<[f32; 3]>, f64)> =
        targets.iter().zip(weights.iter().copied()).filter(|&(_, w)| w != 0.0).collect();
    if used.is_empty() {
        return base.to_vec();
    }
    base.iter()
        .enumerate()
        .map(|(v, b)| {
            let mut p = b.map(f64::from);
            for (target, w) in &used {
                for k in 0..3 {
                    p[k] += w * target[v][k] as f64;
                }
            }
            p.map(|c| c as f32)
        })
        .collect()
}
