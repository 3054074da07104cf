//! glTF 2.0 (`.gltf` with its buffers beside it or in `data:` URIs, and `.glb`) read as a
//! sequence, evaluated as the specification says: one mesh node of the default scene (its
//! triangle primitives merged, vertices as the file has them), its morph targets with their
//! default and animated weights, its skin (every `JOINTS_n` / `WEIGHTS_n` set, joint matrices
//! `global(joint) · inverseBind`, the node's own transform ignored) or, unskinned, its global
//! transform; one animation sampled over the time range of its keys. Y is up and a unit is a
//! metre, as glTF defines.
//!
//! - [`load`]: the container, the JSON and the buffers; [`accessor`]: checked accessor reads.
//! - [`hierarchy`]: parents and global transforms; [`sampler`]: STEP, LINEAR, CUBICSPLINE;
//!   [`animation`]: channels and poses; [`rig`]: the evaluator `synth` shares.
//! - [`mesh`]: merged primitives; [`skin`]: joint matrices; [`frame`]: morph, then skin.
//!
//! The files `write_glb` writes (a morph target per frame, a STEP weights animation) read
//! back frame for frame: sampled at their key rate, the samples are their keys.

pub mod accessor;
pub mod animation;
mod data_uri;
pub mod frame;
pub mod hierarchy;
pub mod load;
pub mod mesh;
pub mod rig;
pub mod sampler;
pub mod skin;
#[cfg(test)]
mod tests;

use super::orient::SignedAxis;
use super::source::{ReadOptions, SourceSequence, SAMPLING_FPS};
use accessor::{Accessors, Budget};
use animation::Animation;
use hierarchy::{node_name, Hierarchy};
use mesh::read_mesh;
use rig::Rig;
use skin::Skin;
use std::path::Path;

/// Output bytes (frames × vertices) per byte of the file: a skinned animation legitimately
/// evaluates to far more than the file holds (its keys are few, its frames many), but a time
/// range made absurd by a damaged key must not allocate without bound.
const OUTPUT_PER_FILE_BYTE: usize = 1024;

/// Reads `path` as a sequence (see the module doc). `options.mesh` picks a mesh node by name,
/// `options.animation` an animation by name or index, `options.fps` the sampling rate.
pub fn read(path: &Path, options: &ReadOptions) -> Result<SourceSequence, String> {
    let loaded = load::load(path)?;
    let document = &loaded.document;
    let accessors = loaded.accessors();
    let hierarchy = Hierarchy::new(document)?;
    let node = choose_node(document, &hierarchy, options.mesh.as_deref())?;
    let mesh = node.mesh().expect("chosen for its mesh");
    let in_node = |e: String| format!("mesh node {}: {e}", node_name(&node));
    let skin = node.skin().map(|s| Skin::read(&s, &accessors)).transpose().map_err(in_node)?;
    let data = read_mesh(&mesh, &accessors, skin.as_ref().map(Skin::len)).map_err(in_node)?;
    let default_weights = default_weights(&node, data.targets.len()).map_err(in_node)?;
    let animation = choose_animation(document, &accessors, options.animation.as_deref())?;
    let output = Budget::new(loaded.file_bytes, OUTPUT_PER_FILE_BYTE);
    let charge = |frames: usize| {
        let bytes = data.positions.len() * 12 + 40;
        let what = || format!("{frames} frames of {} vertices", data.positions.len());
        output.charge(Some(frames), bytes, what).map(drop)
    };
    let (times, rate) = sample_times(animation.as_ref(), options.fps, charge)?;
    let mut notes = vec![format!(
        "mesh node {}: {} vertices{}",
        node_name(&node),
        data.positions.len(),
        match &skin {
            Some(s) => format!(", skinned by {} joints ({} weight sets)", s.len(), data.skin.len()),
            None => String::new(),
        }
    )];
    if data.unnormalised.0 > 0 {
        notes.push(format!(
            "the skin weights of {} vertices do not sum to 1 (by up to {:.3e}): each vertex's \
             are divided by their sum, as Blender and three.js do",
            data.unnormalised.0, data.unnormalised.1
        ));
    }
    notes.push(describe(document, animation.as_ref(), &times, rate));
    let rig = Rig::new(document, animation)?;
    let frames = times
        .iter()
        .map(|&t| {
            let pose = rig.pose(t);
            let globals = rig.globals(&pose);
            let weights = pose.weights[node.index()].as_deref().unwrap_or(&default_weights);
            frame::frame(&data, weights, skin.as_ref(), &globals, globals[node.index()])
        })
        .collect();
    Ok(SourceSequence {
        counts: vec![3; data.indices.len() / 3],
        indices: data.indices,
        frames,
        times,
        colors: data.colors,
        up: Some(SignedAxis { axis: 1, negative: false }),
        meters_per_unit: Some(1.0),
        notes,
    })
}

/// The mesh node to read: the one named `choice`, else the only mesh node of the default
/// scene (the first scene; every node when there is none). Several and no choice is an error
/// that lists them.
fn choose_node<'a>(
    document: &'a gltf::Document,
    hierarchy: &Hierarchy,
    choice: Option<&str>,
) -> Result<gltf::Node<'a>, String> {
    let scene = document.default_scene().or_else(|| document.scenes().next());
    let in_scene = |node: &gltf::Node| {
        let mut root = node.index();
        while let Some(p) = hierarchy.parent(root) {
            root = p;
        }
        scene.as_ref().is_none_or(|s| s.nodes().any(|n| n.index() == root))
    };
    let candidates: Vec<gltf::Node> =
        document.nodes().filter(|n| n.mesh().is_some() && in_scene(n)).collect();
    let names = || candidates.iter().map(node_name).collect::<Vec<_>>().join(", ");
    match (choice, candidates.as_slice()) {
        (None, []) => Err("no node of the scene carries a mesh".into()),
        (None, [only]) => Ok(only.clone()),
        (None, _) => Err(format!(
            "{} mesh nodes, choose one with --mesh NAME: {}",
            candidates.len(),
            names()
        )),
        (Some(name), _) => candidates
            .iter()
            .find(|n| n.name() == Some(name) || format!("#{}", n.index()) == name)
            .cloned()
            .ok_or_else(|| format!("no mesh node is named `{name}`; the mesh nodes: {}", names())),
    }
}

/// The node's morph weights when no animation sets them: the node's `weights`, else its
/// mesh's, else zeros; one per morph target.
fn default_weights(node: &gltf::Node, targets: usize) -> Result<Vec<f64>, String> {
    let mesh = node.mesh().expect("a mesh node");
    match node.weights().or(mesh.weights()) {
        None => Ok(vec![0.0; targets]),
        Some(w) if w.len() == targets => Ok(w.iter().map(|&w| w as f64).collect()),
        Some(w) => Err(format!("{} default morph weights for {targets} morph targets", w.len())),
    }
}

/// The animation to play: `choice` by name, else by index; the only one; none in a file
/// without animations. Several and no choice is an error that lists them.
fn choose_animation(
    document: &gltf::Document,
    accessors: &Accessors,
    choice: Option<&str>,
) -> Result<Option<Animation>, String> {
    let count = document.animations().len();
    let list = || {
        document
            .animations()
            .map(|a| format!("{}: {}", a.index(), a.name().unwrap_or("(no name)")))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let index = match choice {
        None if count == 0 => return Ok(None),
        None if count == 1 => 0,
        None => {
            return Err(format!(
                "{count} animations, choose one with --animation NAME|INDEX: {}",
                list()
            ))
        }
        Some(c) => document
            .animations()
            .position(|a| a.name() == Some(c))
            .or_else(|| c.parse::<usize>().ok().filter(|&i| i < count))
            .ok_or_else(|| match count {
                0 => format!("--animation {c}: the file has no animation"),
                _ => format!("no animation `{c}`; the animations: {}", list()),
            })?,
    };
    let animation = Animation::read(document, index, accessors);
    let name = document.animations().nth(index).and_then(|a| a.name().map(str::to_owned));
    let label = name.map_or(format!("#{index}"), |n| format!("`{n}` (#{index})"));
    animation.map(Some).map_err(|e| format!("animation {label}: {e}"))
}

/// The sample times (seconds, from the first key to the last) and the rate: `fps` when given;
/// else the keys themselves when they are evenly spaced (their rate), else [`SAMPLING_FPS`].
/// No animation, or one key: one sample, at 0 s or at the key. `charge` is told the frame
/// count before the times are allocated.
fn sample_times(
    animation: Option<&Animation>,
    fps: Option<f64>,
    charge: impl Fn(usize) -> Result<(), String>,
) -> Result<(Vec<f64>, Option<f64>), String> {
    if let Some(fps) = fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(format!("--fps {fps} is not a positive frame rate"));
    }
    let Some(keys) = animation.map(Animation::key_times).filter(|k| !k.is_empty()) else {
        charge(1)?;
        return Ok((vec![0.0], None));
    };
    let (start, end) = (keys[0], keys[keys.len() - 1]);
    if keys.len() == 1 {
        charge(1)?;
        return Ok((vec![start], None));
    }
    let step = (end - start) / (keys.len() - 1) as f64;
    let even = keys.windows(2).all(|w| ((w[1] - w[0]) - step).abs() <= 1e-3 * step);
    let rate = match fps {
        None if even => {
            charge(keys.len())?;
            return Ok((keys, Some(1.0 / step)));
        }
        None => SAMPLING_FPS,
        Some(fps) => fps,
    };
    // Every sample up to the last key, compared as the sampler does, at f32 precision: a
    // sample a rounding after the key is the key.
    let mut frames = ((end - start) * rate).floor() + 1.0;
    if frames > u32::MAX as f64 {
        return Err(format!("{} s at {rate} frames per second is too many frames", end - start));
    }
    if (start + frames / rate) as f32 <= end as f32 {
        frames += 1.0;
    }
    charge(frames as usize)?;
    Ok(((0..frames as usize).map(|k| start + k as f64 / rate).collect(), Some(rate)))
}

/// The note on what was played: the animation, which of how many, the frames and the rate.
fn describe(
    document: &gltf::Document,
    animation: Option<&Animation>,
    times: &[f64],
    rate: Option<f64>,
) -> String {
    let Some(animation) = animation else { return "no animation: one frame".into() };
    let count = document.animations().len();
    let span = format!("{} to {} s", times[0], times[times.len() - 1]);
    let rate = match rate {
        Some(r) => format!("{r:.3} frames per second"),
        None => "one key".into(),
    };
    format!(
        "animation {} ({} of {count}): {} frames, {span}, {rate}",
        animation.label(),
        animation.index + 1,
        times.len()
    )
}
