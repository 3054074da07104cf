//! A rigged glTF 2.0 character as a synthetic subject: the first node that has both a mesh and
//! a skin, its triangle primitives merged and welded by position (glTF splits vertices at UV
//! seams; the ground truth needs one connected surface), its joints driven by an animation.
//! Reading and evaluation are the sequence reader's ([`crate::sequence::gltf`]): the node
//! hierarchy, STEP / LINEAR (slerp) / CUBICSPLINE channels, skinning matrices
//! `global(joint) · inverseBind` (the skinned node's own transform ignored, as the glTF
//! specification requires).

use super::Subject;
use crate::mesh::skinning::SkinWeights;
use crate::sequence::gltf::animation::Animation;
use crate::sequence::gltf::{load::load, mesh::read_mesh, rig::Rig, skin::Skin};
use glam::DMat4;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Frames per second at which the animation is sampled.
pub const FPS: f64 = 30.0;

/// Why a glTF subject could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The file cannot be read, is not valid glTF 2.0, or lacks what a subject needs (a node
    /// with a mesh and a skin, the named animation, triangles, consistent skin data).
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The glTF file.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
}

/// The node hierarchy, one animation and the skin's joints.
#[derive(Clone, Debug)]
pub struct GltfRig {
    rig: Rig,
    skin: Skin,
    /// Name of the animation played (`#<index>` when it has none).
    pub animation: String,
    /// Length of the animation in seconds (its last key's time).
    pub duration: f64,
}

/// Loads the subject from a `.glb` (or a `.gltf` with its buffers in files beside it or in
/// `data:` URIs) and the animation named `animation` (the first one when `None`).
pub fn load_gltf(path: &Path, animation: Option<&str>) -> Result<Subject, GltfError> {
    let fail = |problem: String| GltfError::Invalid { path: path.to_owned(), problem };
    let loaded = load(path).map_err(fail)?;
    let doc = &loaded.document;
    let accessors = loaded.accessors();
    let node = doc
        .nodes()
        .find(|n| n.mesh().is_some() && n.skin().is_some())
        .ok_or_else(|| fail("has no skin: no node carries both a mesh and a skin".into()))?;
    let (mesh, skin) = (node.mesh().expect("checked"), node.skin().expect("checked"));
    let index = match animation {
        Some(name) => doc
            .animations()
            .position(|a| a.name() == Some(name))
            .ok_or_else(|| fail(format!("has no animation named `{name}`")))?,
        None if doc.animations().next().is_some() => 0,
        None => return Err(fail("has no animation".into())),
    };
    let skin = Skin::read(&skin, &accessors).map_err(fail)?;
    let data = read_mesh(&mesh, &accessors, Some(skin.len())).map_err(fail)?;
    let [weights] = data.skin.as_slice() else {
        return Err(fail(format!(
            "{} joint sets per vertex; a synthetic subject takes four influences (JOINTS_0)",
            data.skin.len()
        )));
    };
    let faces: Vec<[u32; 3]> = data.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let (rest, faces, weights) = weld(&data.positions, &faces, weights);
    if faces.is_empty() {
        return Err(fail("the skinned mesh has no triangles".into()));
    }
    let chosen = Animation::read(doc, index, &accessors).map_err(fail)?;
    let Some(&duration) = chosen.key_times().last() else {
        return Err(fail("the animation moves no node".into()));
    };
    let name = chosen.name.clone().unwrap_or_else(|| format!("#{index}"));
    let rig = GltfRig {
        rig: Rig::new(doc, Some(chosen)).map_err(fail)?,
        skin,
        animation: name,
        duration,
    };
    Ok(Subject {
        rest,
        faces,
        skin: weights,
        motion: super::Motion::Gltf(Box::new(rig)),
        pace: 1.0,
    })
}

type Welded = (Vec<[f32; 3]>, Vec<[u32; 3]>, SkinWeights);

/// Merges vertices with bit-identical positions (keeping the first one's weights) and drops the
/// faces that collapse.
fn weld(positions: &[[f32; 3]], faces: &[[u32; 3]], skin: &SkinWeights) -> Welded {
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut remap = Vec::with_capacity(positions.len());
    let (mut out, mut out_skin) =
        (Vec::new(), SkinWeights { joints: Vec::new(), weights: Vec::new() });
    for (v, p) in positions.iter().enumerate() {
        let key = p.map(|c| (c + 0.0).to_bits()); // + 0.0 folds −0 into +0
        let next = out.len() as u32;
        let id = *index.entry(key).or_insert(next);
        if id == next {
            out.push(*p);
            out_skin.joints.push(skin.joints[v]);
            out_skin.weights.push(skin.weights[v]);
        }
        remap.push(id);
    }
    let faces = faces
        .iter()
        .map(|f| f.map(|i| remap[i as usize]))
        .filter(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0])
        .collect();
    (out, faces, out_skin)
}

impl GltfRig {
    /// Skinning matrices at `frame` (time `frame / FPS` seconds, wrapped at the duration).
    pub fn joint_matrices(&self, frame: f64) -> Vec<DMat4> {
        let time = if self.duration > 0.0 { (frame / FPS) % self.duration } else { 0.0 };
        self.skin.matrices(&self.rig.globals(&self.rig.pose(time)))
    }
}
