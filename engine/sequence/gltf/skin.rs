//! A glTF skin: its joints and inverse bind matrices, and the joint matrices of a pose,
//! `global(joint) · inverseBind` as the specification defines them. The skinned node's own
//! transform takes no part (glTF requires it to be ignored).

use super::accessor::Accessors;
use glam::DMat4;

/// The joints (node indices) of a skin and their inverse bind matrices.
#[derive(Clone, Debug)]
pub struct Skin {
    joints: Vec<usize>,
    inverse_bind: Vec<DMat4>,
}

impl Skin {
    /// Reads `skin`: identity inverse bind matrices when it has none, as glTF says.
    pub fn read(skin: &gltf::Skin, accessors: &Accessors) -> Result<Self, String> {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(a) => {
                let values = accessors.read(&a)?;
                if values.components != 16 {
                    return Err(format!(
                        "skin {}: inverse bind matrices are not MAT4",
                        skin.index()
                    ));
                }
                values.data.chunks_exact(16).map(|m| DMat4::from_cols_slice(m)).collect()
            }
            None => vec![DMat4::IDENTITY; joints.len()],
        };
        if inverse_bind.len() != joints.len() {
            return Err(format!(
                "skin {} has {} joints but {} inverse bind matrices",
                skin.index(),
                joints.len(),
                inverse_bind.len()
            ));
        }
        Ok(Self { joints, inverse_bind })
    }

    /// The number of joints.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether the skin has no joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Joint matrices `global(joint) · inverseBind` for the nodes' global transforms.
    pub fn matrices(&self, globals: &[DMat4]) -> Vec<DMat4> {
        self.joints.iter().zip(&self.inverse_bind).map(|(&j, ib)| globals[j] * *ib).collect()
    }
}
