//! One glTF animation: its channels (a node's translation, rotation, scale or morph weights,
//! each driven by a [`Sampler`]), the time range its keys span, and the pose it gives the
//! nodes at a time.

use super::accessor::Accessors;
use super::hierarchy::Local;
use super::sampler::Sampler;
use gltf::animation::Property;
use gltf::json::validation::Checked;

/// One animated property of one node.
#[derive(Clone, Debug)]
struct Channel {
    node: usize,
    property: Property,
    sampler: Sampler,
}

/// An animation's channels.
#[derive(Clone, Debug)]
pub struct Animation {
    /// Its index in the file.
    pub index: usize,
    /// Its name, when it has one.
    pub name: Option<String>,
    channels: Vec<Channel>,
}

/// What an animation sets at one time: every node's local transform and the morph weights of
/// the nodes whose weights it animates.
#[derive(Clone, Debug)]
pub struct Pose {
    /// Local transform of each node.
    pub locals: Vec<Local>,
    /// Animated morph weights of each node (None: not animated).
    pub weights: Vec<Option<Vec<f64>>>,
}

impl Animation {
    /// Reads animation `index` of `document`. Channel targets are checked here (the `gltf`
    /// crate's validation leaves them unchecked): the node exists, the path is known, a matrix
    /// node is not animated, a weights channel targets a node with morph targets and has one
    /// weight per target.
    pub fn read(
        document: &gltf::Document,
        index: usize,
        accessors: &Accessors,
    ) -> Result<Self, String> {
        let json = &document.as_json().animations[index];
        let nodes = document.nodes().len();
        let mut channels = Vec::with_capacity(json.channels.len());
        for (c, channel) in json.channels.iter().enumerate() {
            let problem = |p: String| format!("channel {c}: {p}");
            let node = channel.target.node.value();
            if node >= nodes {
                return Err(problem(format!("targets node {node} of {nodes}")));
            }
            let Checked::Valid(property) = channel.target.path else {
                return Err(problem("targets an unknown property".into()));
            };
            let node_ref = document.nodes().nth(node).expect("in range");
            if matches!(Local::of(&node_ref), Local::Matrix(_))
                && property != Property::MorphTargetWeights
            {
                return Err(problem(format!(
                    "animates node {node}, which has a matrix (glTF requires TRS for animated nodes)"
                )));
            }
            let (width, rotation) = match property {
                Property::Translation | Property::Scale => (3, false),
                Property::Rotation => (4, true),
                Property::MorphTargetWeights => (morph_targets(&node_ref), false),
            };
            if width == 0 {
                return Err(problem(format!(
                    "animates the morph weights of node {node}, whose mesh has no morph targets"
                )));
            }
            let sampler = json.samplers.get(channel.sampler.value()).ok_or_else(|| {
                problem(format!("sampler {} does not exist", channel.sampler.value()))
            })?;
            let Checked::Valid(interpolation) = sampler.interpolation else {
                return Err(problem("unknown interpolation".into()));
            };
            let accessor = |i: gltf::json::Index<gltf::json::Accessor>| {
                document
                    .accessors()
                    .nth(i.value())
                    .ok_or_else(|| problem(format!("accessor {} does not exist", i.value())))
            };
            let input = accessors.read(&accessor(sampler.input)?).map_err(problem)?;
            let output = accessors.read(&accessor(sampler.output)?).map_err(problem)?;
            if input.components != 1 {
                return Err(problem("its input is not SCALAR".into()));
            }
            if output.components != if property == Property::MorphTargetWeights { 1 } else { width }
            {
                return Err(problem(format!("its output is not of {width}-vectors")));
            }
            let sampler = Sampler::new(interpolation, input.data, output.data, width, rotation)
                .map_err(problem)?;
            channels.push(Channel { node, property, sampler });
        }
        let name = json.name.clone();
        Ok(Self { index, name, channels })
    }

    /// The animation as messages name it: `name` (#index), or #index.
    pub fn label(&self) -> String {
        match &self.name {
            Some(name) => format!("`{name}` (#{})", self.index),
            None => format!("#{}", self.index),
        }
    }

    /// Every key time of every channel, sorted, each once.
    pub fn key_times(&self) -> Vec<f64> {
        let mut times: Vec<f64> =
            self.channels.iter().flat_map(|c| c.sampler.times().iter().copied()).collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        times
    }

    /// The pose at `t` seconds: `rest` (the nodes' own transforms) with every animated
    /// property replaced by its sampled value.
    pub fn pose(&self, rest: &[Local], t: f64) -> Pose {
        let mut pose = Pose { locals: rest.to_vec(), weights: vec![None; rest.len()] };
        for channel in &self.channels {
            let v = channel.sampler.sample(t);
            let n = channel.node;
            if channel.property == Property::MorphTargetWeights {
                pose.weights[n] = Some(v);
                continue;
            }
            if let Local::Trs { t, r, s } = &mut pose.locals[n] {
                match channel.property {
                    Property::Translation => *t = [v[0], v[1], v[2]],
                    Property::Rotation => *r = [v[0], v[1], v[2], v[3]],
                    Property::Scale => *s = [v[0], v[1], v[2]],
                    Property::MorphTargetWeights => {}
                }
            }
        }
        pose
    }
}

/// The morph-target count of `node`'s mesh (that of its first primitive; glTF requires every
/// primitive to have as many), 0 without a mesh.
fn morph_targets(node: &gltf::Node) -> usize {
    let primitive = node.mesh().and_then(|m| m.primitives().next());
    primitive.map_or(0, |p| p.morph_targets().len())
}
