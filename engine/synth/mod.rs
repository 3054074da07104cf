//! Synthetic dynamic scenes with known ground truth.
//!
//! - [`procedural`]: an articulated body (closed manifold, 5 limbs bending at joints).
//! - [`gltf`]: a rigged glTF 2.0 character (skin, joints, animation channels).
//! - linear blend skinning ([`crate::mesh::skinning`]), shared by both subjects and the glTF
//!   sequence reader.
//! - [`texture`]: the coloured procedural texture painted on the rest pose, with printed bands
//!   or without.
//! - [`raster`]: the supersampled CPU reference renderer (RGB + anti-aliased mask).
//! - [`generate`](mod@generate): cameras, renders, per-frame meshes and point trajectories on disk.

pub mod generate;
pub mod gltf;
pub mod icosphere;
pub mod manifold;
pub mod motion_stats;
pub mod procedural;
pub mod raster;
pub mod texture;

pub use crate::mesh::skinning::{skin, SkinWeights};
pub use generate::{generate, MotionPreset, SubjectSource, SynthOptions, SynthReport};
pub use raster::{render, Render, RenderError};
pub use texture::{Pattern, Texture};

use glam::DMat4;

/// A skinned subject: one rest mesh, its weights, and how its joints move.
#[derive(Clone, Debug)]
pub struct Subject {
    /// Rest-pose vertex positions, scene units.
    pub rest: Vec<[f32; 3]>,
    /// Triangles indexing `rest`, counter-clockwise from outside.
    pub faces: Vec<[u32; 3]>,
    /// Joint influences of each rest vertex.
    pub skin: SkinWeights,
    /// Where the skinning matrices of each frame come from.
    pub motion: Motion,
    /// Animation frames per captured frame (1: the animation's own speed).
    pub pace: f64,
}

/// Where the skinning matrices of a frame come from.
#[derive(Clone, Debug)]
pub enum Motion {
    /// [`procedural::procedural_pose`].
    Procedural,
    /// A glTF animation sampled at `frame / fps` seconds (wrapping at its duration); boxed, as
    /// a rig is large and the procedural body carries nothing.
    Gltf(Box<gltf::GltfRig>),
}

impl Subject {
    /// The procedural body with `subdivisions` levels of icosphere refinement.
    pub fn procedural(subdivisions: u32) -> Self {
        let (rest, faces, skin) = procedural::procedural_subject(subdivisions);
        Self { rest, faces, skin, motion: Motion::Procedural, pace: 1.0 }
    }

    /// Skinning matrices at captured frame `frame` (animation time `frame × pace`).
    pub fn joint_matrices(&self, frame: usize) -> Vec<DMat4> {
        let time = frame as f64 * self.pace;
        match &self.motion {
            Motion::Procedural => procedural::procedural_pose(time),
            Motion::Gltf(rig) => rig.joint_matrices(time),
        }
    }

    /// Vertex positions at `frame` (same vertex order and faces as the rest mesh).
    pub fn positions(&self, frame: usize) -> Vec<[f32; 3]> {
        skin(&self.rest, &self.skin, &self.joint_matrices(frame))
    }
}
