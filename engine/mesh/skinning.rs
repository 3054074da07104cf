//! Linear blend skinning.

use glam::{DMat4, DVec3};

/// Up to four joint influences per vertex; weights sum to 1 (unused slots have weight 0).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinWeights {
    /// Joint indices of each vertex's four slots.
    pub joints: Vec<[u32; 4]>,
    /// Weight of each slot, matching `joints`.
    pub weights: Vec<[f32; 4]>,
}

/// Posed positions `p' = Σ wₖ · M[jₖ] · p` for rest positions `rest` and skinning matrices
/// `joint_matrices` (each already multiplied by its inverse bind matrix). Every joint index
/// must be below `joint_matrices.len()` (checked where the weights are built).
pub fn skin(rest: &[[f32; 3]], skin: &SkinWeights, joint_matrices: &[DMat4]) -> Vec<[f32; 3]> {
    skin_layers(rest, std::slice::from_ref(skin), joint_matrices)
}

/// [`skin`] with more than four influences per vertex: the sum runs over every layer's four
/// slots (a glTF file's `JOINTS_0`, `JOINTS_1`, …), in f64, rounded once to f32.
pub fn skin_layers(
    rest: &[[f32; 3]],
    layers: &[SkinWeights],
    joint_matrices: &[DMat4],
) -> Vec<[f32; 3]> {
    rest.iter()
        .enumerate()
        .map(|(v, p)| {
            let p = DVec3::from(p.map(f64::from));
            let mut out = DVec3::ZERO;
            for layer in layers {
                for (&j, &w) in layer.joints[v].iter().zip(&layer.weights[v]) {
                    if w != 0.0 {
                        out += w as f64 * joint_matrices[j as usize].transform_point3(p);
                    }
                }
            }
            out.as_vec3().to_array()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blends_two_transforms_linearly() {
        let rest = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        let w = SkinWeights {
            joints: vec![[0, 1, 0, 0], [1, 0, 0, 0]],
            weights: vec![[0.25, 0.75, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
        };
        let m = [DMat4::IDENTITY, DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0))];
        let out = skin(&rest, &w, &m);
        assert_eq!(out, vec![[1.0, 0.0, 3.0], [0.0, 2.0, 4.0]]);
    }

    #[test]
    fn layers_sum_every_set_of_four() {
        let rest = [[1.0, 0.0, 0.0]];
        let layer = |j: u32, w: f32| SkinWeights {
            joints: vec![[j, 0, 0, 0]],
            weights: vec![[w, 0.0, 0.0, 0.0]],
        };
        let m = [DMat4::IDENTITY, DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0))];
        let out = skin_layers(&rest, &[layer(0, 0.5), layer(1, 0.5)], &m);
        assert_eq!(out, vec![[1.0, 0.0, 2.0]]);
    }
}
