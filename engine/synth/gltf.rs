//! A rigged glTF 2.0 character as a synthetic subject: the first node that has both a mesh and
//! a skin, its triangle primitives merged and welded by position (glTF splits vertices at UV
//! seams; the ground truth needs one connected surface), its joints driven by an animation's
//! translation / rotation / scale channels (STEP, LINEAR with slerp, CUBICSPLINE), skinned with
//! skinning matrices `global(joint) · inverseBind` (the skinned node's own transform is ignored,
//! as the glTF specification requires).

use super::skinning::SkinWeights;
use super::Subject;
use glam::{DMat4, DQuat, DVec3, Mat4};
use gltf::animation::{Interpolation, Property};
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

/// One animated property of one node, keyframes as 4-vectors (xyz for translation and scale,
/// xyzw for rotation); cubic splines hold (in-tangent, value, out-tangent) per key.
#[derive(Clone, Debug)]
struct Channel {
    node: usize,
    property: Property,
    interpolation: Interpolation,
    times: Vec<f32>,
    values: Vec<[f32; 4]>,
}

/// The node hierarchy, one animation and the skin's joints.
#[derive(Clone, Debug)]
pub struct GltfRig {
    parents: Vec<Option<usize>>,
    /// Rest translation, rotation (x, y, z, w), scale of every node.
    rest: Vec<([f32; 3], [f32; 4], [f32; 3])>,
    channels: Vec<Channel>,
    joints: Vec<usize>,
    inverse_bind: Vec<DMat4>,
    /// Name of the animation played (`#<index>` when it has none).
    pub animation: String,
    /// Length of the animation in seconds.
    pub duration: f64,
}

/// Loads the subject from a `.glb` (or a `.gltf` with its buffers in files beside it) and the
/// animation named `animation` (the first one when `None`).
pub fn load_gltf(path: &Path, animation: Option<&str>) -> Result<Subject, GltfError> {
    let fail = |problem: String| GltfError::Invalid { path: path.to_owned(), problem };
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let gltf = gltf::Gltf::from_slice(&bytes)
        .map_err(|e| fail(format!("not a valid glTF 2.0 file: {e}")))?;
    let buffers = load_buffers(path, &gltf).map_err(fail)?;
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(Vec::as_slice);
    let doc = &gltf.document;

    let node = doc
        .nodes()
        .find(|n| n.mesh().is_some() && n.skin().is_some())
        .ok_or_else(|| fail("has no skin: no node carries both a mesh and a skin".into()))?;
    let (mesh, skin) = (node.mesh().expect("checked"), node.skin().expect("checked"));
    let chosen = match animation {
        Some(name) => doc
            .animations()
            .find(|a| a.name() == Some(name))
            .ok_or_else(|| fail(format!("has no animation named `{name}`")))?,
        None => doc.animations().next().ok_or_else(|| fail("has no animation".into()))?,
    };

    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    let inverse_bind: Vec<DMat4> = match skin.reader(get).read_inverse_bind_matrices() {
        Some(m) => m.map(|m| Mat4::from_cols_array_2d(&m).as_dmat4()).collect(),
        None => vec![DMat4::IDENTITY; joints.len()],
    };
    if inverse_bind.len() != joints.len() {
        return Err(fail(format!(
            "skin has {} joints but {} inverse bind matrices",
            joints.len(),
            inverse_bind.len()
        )));
    }
    let (rest, faces, weights) = read_primitives(&mesh, get, joints.len()).map_err(fail)?;
    let (rest, faces, weights) = weld(&rest, &faces, &weights);
    if faces.is_empty() {
        return Err(fail("the skinned mesh has no triangles".into()));
    }

    let mut parents = vec![None; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            parents[c.index()] = Some(n.index());
        }
    }
    let channels = read_channels(&chosen, get).map_err(fail)?;
    let duration =
        channels.iter().flat_map(|c| c.times.last().copied()).fold(0.0f32, f32::max) as f64;
    let rig = GltfRig {
        parents,
        rest: doc.nodes().map(|n| n.transform().decomposed()).collect(),
        channels,
        joints,
        inverse_bind,
        animation: chosen
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("#{}", chosen.index())),
        duration,
    };
    Ok(Subject { rest, faces, skin: weights, motion: super::Motion::Gltf(rig), pace: 1.0 })
}

/// The binary chunk of a `.glb`, or files named by relative URIs.
fn load_buffers(path: &Path, gltf: &gltf::Gltf) -> Result<Vec<Vec<u8>>, String> {
    gltf.document
        .buffers()
        .map(|b| match b.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or_else(|| "refers to a binary chunk it does not have".to_string()),
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                Err("embedded data: URIs are not supported (use .glb)".into())
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = path.parent().unwrap_or(Path::new(".")).join(uri);
                std::fs::read(&file).map_err(|e| format!("buffer {}: {e}", file.display()))
            }
        })
        .zip(gltf.document.buffers())
        .map(|(data, b)| match data {
            // Accessors are validated against the declared length; hold the data to it.
            Ok(data) if data.len() < b.length() => Err(format!(
                "buffer {} holds {} bytes, declares {}",
                b.index(),
                data.len(),
                b.length()
            )),
            other => other,
        })
        .collect()
}

type Primitives = (Vec<[f32; 3]>, Vec<[u32; 3]>, SkinWeights);

/// Triangle primitives merged into one indexed mesh with normalised weights.
fn read_primitives<'s>(
    mesh: &gltf::Mesh,
    get: impl Clone + for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
    joint_count: usize,
) -> Result<Primitives, String> {
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    let mut skin = SkinWeights { joints: Vec::new(), weights: Vec::new() };
    for (p, primitive) in mesh.primitives().enumerate() {
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            return Err(format!("primitive {p} is not made of triangles"));
        }
        let reader = primitive.reader(get.clone());
        let base = positions.len() as u32;
        let pos: Vec<[f32; 3]> =
            reader.read_positions().ok_or(format!("primitive {p} has no POSITION"))?.collect();
        let joints: Vec<[u16; 4]> = reader
            .read_joints(0)
            .ok_or(format!("primitive {p} has no JOINTS_0 (not skinned)"))?
            .into_u16()
            .collect();
        let weights: Vec<[f32; 4]> = reader
            .read_weights(0)
            .ok_or(format!("primitive {p} has no WEIGHTS_0 (not skinned)"))?
            .into_f32()
            .collect();
        if joints.len() != pos.len() || weights.len() != pos.len() {
            return Err(format!(
                "primitive {p}: {} positions, {} joint sets, {} weight sets",
                pos.len(),
                joints.len(),
                weights.len()
            ));
        }
        if let Some(v) = pos.iter().position(|q| !q.iter().all(|c| c.is_finite())) {
            return Err(format!("primitive {p}: vertex {v} has a non-finite position"));
        }
        for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
            if let Some(k) = (0..4).find(|&k| w[k] != 0.0 && j[k] as usize >= joint_count) {
                return Err(format!(
                    "primitive {p}: vertex {v} uses joint {} of a {joint_count}-joint skin",
                    j[k]
                ));
            }
            let sum: f32 = w.iter().sum();
            if !(sum > 0.0 && sum.is_finite()) {
                return Err(format!("primitive {p}: vertex {v} has weights {w:?} that do not sum to a positive number"));
            }
            skin.joints.push(j.map(u32::from));
            skin.weights.push(w.map(|x| x / sum));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..pos.len() as u32).collect(),
        };
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= pos.len()) {
            return Err(format!("primitive {p}: index {i} past its {} vertices", pos.len()));
        }
        faces.extend(indices.chunks_exact(3).map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        positions.extend(pos);
    }
    Ok((positions, faces, skin))
}

/// Merges vertices with bit-identical positions (keeping the first one's weights) and drops the
/// faces that collapse.
fn weld(positions: &[[f32; 3]], faces: &[[u32; 3]], skin: &SkinWeights) -> Primitives {
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

fn read_channels<'s>(
    animation: &gltf::Animation,
    get: impl Clone + for<'b> Fn(gltf::Buffer<'b>) -> Option<&'s [u8]>,
) -> Result<Vec<Channel>, String> {
    use gltf::animation::util::ReadOutputs;
    let mut channels = Vec::new();
    for (c, channel) in animation.channels().enumerate() {
        let reader = channel.reader(get.clone());
        let times: Vec<f32> = reader
            .read_inputs()
            .ok_or(format!("animation channel {c} has no input times"))?
            .collect();
        let values: Vec<[f32; 4]> =
            match reader.read_outputs().ok_or(format!("animation channel {c} has no outputs"))? {
                ReadOutputs::Translations(t) => t.map(|v| [v[0], v[1], v[2], 0.0]).collect(),
                ReadOutputs::Scales(s) => s.map(|v| [v[0], v[1], v[2], 0.0]).collect(),
                ReadOutputs::Rotations(r) => r.into_f32().collect(),
                ReadOutputs::MorphTargetWeights(_) => continue, // morph targets do not move joints
            };
        let interpolation = channel.sampler().interpolation();
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if times.is_empty() || values.len() != times.len() * per_key {
            return Err(format!(
                "animation channel {c}: {} times but {} values",
                times.len(),
                values.len()
            ));
        }
        let increasing = times.windows(2).all(|w| w[1] > w[0]);
        if !increasing || values.iter().flatten().any(|v| !v.is_finite()) {
            return Err(format!(
                "animation channel {c}: times not increasing or values not finite"
            ));
        }
        channels.push(Channel {
            node: channel.target().node().index(),
            property: channel.target().property(),
            interpolation,
            times,
            values,
        });
    }
    if channels.is_empty() {
        return Err("the animation moves no node".into());
    }
    Ok(channels)
}

impl Channel {
    /// The channel's value at `t` seconds (held constant outside the keyed range).
    fn sample(&self, t: f32) -> [f32; 4] {
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| if cubic { self.values[3 * k + 1] } else { self.values[k] };
        if n == 1 || t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let dt = self.times[k + 1] - self.times[k];
        let s = (t - self.times[k]) / dt;
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => {
                let (a, b) = (
                    DQuat::from_array(value(k).map(f64::from)),
                    DQuat::from_array(value(k + 1).map(f64::from)),
                );
                a.normalize().slerp(b.normalize(), s as f64).to_array().map(|v| v as f32)
            }
            Interpolation::Linear => {
                std::array::from_fn(|i| value(k)[i] + s * (value(k + 1)[i] - value(k)[i]))
            }
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let (v0, out0) = (self.values[3 * k + 1], self.values[3 * k + 2]);
                let (in1, v1) = (self.values[3 * (k + 1)], self.values[3 * (k + 1) + 1]);
                let mut r: [f32; 4] = std::array::from_fn(|i| {
                    (2.0 * s3 - 3.0 * s2 + 1.0) * v0[i]
                        + (s3 - 2.0 * s2 + s) * dt * out0[i]
                        + (-2.0 * s3 + 3.0 * s2) * v1[i]
                        + (s3 - s2) * dt * in1[i]
                });
                if rotation {
                    let len = r.iter().map(|x| x * x).sum::<f32>().sqrt();
                    r = r.map(|x| x / len);
                }
                r
            }
        }
    }
}

impl GltfRig {
    /// Skinning matrices at `frame` (time `frame / FPS` seconds, wrapped at the duration).
    pub fn joint_matrices(&self, frame: f64) -> Vec<DMat4> {
        let time = if self.duration > 0.0 { (frame / FPS) % self.duration } else { 0.0 } as f32;
        let mut trs = self.rest.clone();
        for c in &self.channels {
            let v = c.sample(time);
            match c.property {
                Property::Translation => trs[c.node].0 = [v[0], v[1], v[2]],
                Property::Rotation => trs[c.node].1 = v,
                Property::Scale => trs[c.node].2 = [v[0], v[1], v[2]],
                Property::MorphTargetWeights => {}
            }
        }
        let local: Vec<DMat4> = trs
            .iter()
            .map(|(t, r, s)| {
                DMat4::from_scale_rotation_translation(
                    DVec3::from(s.map(f64::from)),
                    DQuat::from_array(r.map(f64::from)).normalize(),
                    DVec3::from(t.map(f64::from)),
                )
            })
            .collect();
        self.joints
            .iter()
            .zip(&self.inverse_bind)
            .map(|(&j, ib)| self.global(j, &local) * *ib)
            .collect()
    }

    /// Product of local transforms from the root down to `node` (the hierarchy is a forest; a
    /// cycle would be invalid glTF, which the loader's validation rejects).
    fn global(&self, node: usize, local: &[DMat4]) -> DMat4 {
        let mut m = local[node];
        let mut at = self.parents[node];
        let mut guard = 0;
        while let Some(p) = at {
            m = local[p] * m;
            at = self.parents[p];
            guard += 1;
            if guard > self.parents.len() {
                break;
            }
        }
        m
    }
}
