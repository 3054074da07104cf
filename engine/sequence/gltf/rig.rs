//! The evaluator the sequence reader and the synthetic subjects share: a file's node
//! hierarchy, its nodes' own transforms and (optionally) one animation, giving the nodes'
//! global transforms and animated morph weights at any time.

use super::animation::{Animation, Pose};
use super::hierarchy::{Hierarchy, Local};
use glam::DMat4;

/// A file's nodes and the animation that moves them.
#[derive(Clone, Debug)]
pub struct Rig {
    hierarchy: Hierarchy,
    rest: Vec<Local>,
    animation: Option<Animation>,
}

impl Rig {
    /// The nodes of `document` (checked to form a forest), moved by `animation`.
    pub fn new(document: &gltf::Document, animation: Option<Animation>) -> Result<Self, String> {
        let hierarchy = Hierarchy::new(document)?;
        let rest = document.nodes().map(|n| Local::of(&n)).collect();
        Ok(Self { hierarchy, rest, animation })
    }

    /// The pose at `t` seconds (the nodes' own transforms without an animation).
    pub fn pose(&self, t: f64) -> Pose {
        match &self.animation {
            Some(a) => a.pose(&self.rest, t),
            None => Pose { locals: self.rest.clone(), weights: vec![None; self.rest.len()] },
        }
    }

    /// Every node's global transform in `pose`.
    pub fn globals(&self, pose: &Pose) -> Vec<DMat4> {
        self.hierarchy.globals(&pose.locals)
    }
}
