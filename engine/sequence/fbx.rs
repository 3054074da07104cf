//! FBX (binary and ASCII, through the `ufbx` library) read as a sequence: one mesh node, one
//! animation stack sampled over its time range, each frame the mesh as the file deforms it
//! (blend shapes, then skinning, or a point cache in place of both), in world space.
//!
//! - Vertices are the file's control points, in the file's order, so a vertex id is the one a
//!   DCC shows; polygons are the file's faces over them, counter-clockwise as FBX stores them.
//! - Coordinates stay in the file's units and axes: `ufbx` is asked for no axis or unit
//!   conversion (that would turn or scale the points before the user's `--from-up` and `--up`
//!   could); the file's up axis and unit scale are reported for [`super::orient`] to use.
//! - `options.mesh` picks a mesh node by name, `options.animation` a stack by name or index,
//!   `options.fps` the rate (default the file's frame rate, else 30).

use super::gltf::accessor::Budget;
use super::orient::SignedAxis;
use super::source::{ReadOptions, SourceSequence};
use std::path::Path;
use ufbx::{CoordinateAxis, Node, Scene};

/// Bytes the evaluated frames may take per byte of the file (see the glTF reader's
/// `OUTPUT_PER_FILE_BYTE`): an animation's keys are few and its frames many, but a damaged time
/// range must not allocate without bound.
const OUTPUT_PER_FILE_BYTE: usize = 1024;

/// Bytes `ufbx` may allocate per byte of the file, beyond [`UFBX_MEMORY_FLOOR`]: the budget every
/// reader keeps (tests/fuzz.rs holds them to it), so a damaged count cannot claim memory the file
/// does not justify. A file whose deflated arrays inflate more than about 64× is refused (out of
/// memory, named by ufbx); Blender's and Maya's exports stay far below it.
const UFBX_MEMORY_PER_FILE_BYTE: usize = 64;
const UFBX_MEMORY_FLOOR: usize = 16 << 20;

/// Reads `path` as a sequence (see the module doc).
pub fn read(path: &Path, options: &ReadOptions) -> Result<SourceSequence, String> {
    if let Some(fps) = options.fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(format!("--fps {fps} is not a positive frame rate"));
    }
    let file_bytes = std::fs::metadata(path).map_err(|e| format!("cannot read: {e}"))?.len();
    let memory_limit = memory_limit(file_bytes);
    let scene = load(path, memory_limit)?;
    let node = choose_node(&scene, options.mesh.as_deref())?;
    let mesh = node.mesh.as_ref().expect("chosen for its mesh");
    let (counts, indices) =
        polygons(mesh).map_err(|e| format!("mesh node `{}`: {e}", name(node)))?;
    let stack = choose_stack(&scene, options.animation.as_deref())?;
    let file_fps = scene.settings.frames_per_second;
    let rate = options.fps.unwrap_or(if file_fps.is_finite() && file_fps > 0.0 {
        file_fps
    } else {
        super::source::SAMPLING_FPS
    });
    let output = Budget::new(file_bytes as usize, OUTPUT_PER_FILE_BYTE);
    let vertices = mesh.num_vertices;
    let times = sample_times(stack.map(|s| (s.time_begin, s.time_end)), rate, |frames| {
        let what = || format!("{frames} frames of {vertices} vertices");
        output.charge(Some(frames), vertices * 12 + 8, what).map(drop)
    })?;
    let anim = stack.map_or(&scene.anim, |s| &s.anim);
    let frames = times
        .iter()
        .map(|&t| {
            evaluate(&scene, anim, node.element.typed_id, t, memory_limit)
                .map_err(|e| format!("mesh node `{}` at {t} s: {e}", name(node)))
        })
        .collect::<Result<_, _>>()?;
    let notes = vec![
        format!(
            "mesh node `{}`: {} vertices, {} polygons{}",
            name(node),
            vertices,
            counts.len(),
            deformers(mesh)
        ),
        match stack {
            Some(s) => format!(
                "animation stack `{}` ({} of {}): {} frames, {} to {} s, {rate:.3} frames per second",
                s.element.name,
                scene.anim_stacks.iter().position(|a| a.element.typed_id == s.element.typed_id)
                    .map_or(0, |i| i + 1),
                scene.anim_stacks.len(),
                times.len(),
                times[0],
                times[times.len() - 1]
            ),
            None => "no animation stack: one frame".into(),
        },
    ];
    Ok(SourceSequence {
        counts,
        indices,
        frames,
        times,
        colors: None,
        up: signed_axis(scene.settings.axes.up),
        meters_per_unit: Some(scene.settings.unit_meters).filter(|m| m.is_finite() && *m > 0.0),
        notes,
    })
}

/// What `ufbx` may allocate for a file of `file_bytes`, in each of its allocators.
fn memory_limit(file_bytes: u64) -> usize {
    usize::try_from(file_bytes)
        .unwrap_or(usize::MAX)
        .saturating_mul(UFBX_MEMORY_PER_FILE_BYTE)
        .saturating_add(UFBX_MEMORY_FLOOR)
}

fn allocator(memory_limit: usize) -> ufbx::AllocatorOpts {
    ufbx::AllocatorOpts { memory_limit, ..Default::default() }
}

/// The scene as the file states it: no axis or unit conversion, external point caches loaded
/// (a missing one is an error), memory bounded by `memory_limit`.
fn load(path: &Path, memory_limit: usize) -> Result<ufbx::SceneRoot, String> {
    let name = path.to_str().ok_or("the path is not UTF-8, which the FBX library needs")?;
    let options = ufbx::LoadOpts {
        temp_allocator: allocator(memory_limit),
        result_allocator: allocator(memory_limit),
        load_external_files: true,
        evaluate_caches: true,
        ..Default::default()
    };
    ufbx::load_file(name, options).map_err(|e| describe_error(&e))
}

/// The first line of `ufbx`'s message (its description and detail), without its version prefix;
/// decoded leniently, since the detail may quote the file.
fn describe_error(error: &ufbx::Error) -> String {
    let mut buffer = [0u8; 512];
    let length = ufbx::format_error(&mut buffer, error).min(buffer.len());
    let text = String::from_utf8_lossy(&buffer[..length]);
    let line = text.lines().next().unwrap_or("").trim();
    let message = line.split_once(" error: ").map_or(line, |(_, m)| m);
    format!("not a readable FBX file: {message}")
}

/// The node's name as messages show it.
fn name(node: &Node) -> &str {
    &node.element.name
}

/// The mesh node to read: the one named `choice`, else the only one. Several and no choice, a
/// name no node has, or one several nodes have, are errors that list the mesh nodes.
fn choose_node<'a>(scene: &'a Scene, choice: Option<&str>) -> Result<&'a Node, String> {
    let candidates: Vec<&Node> =
        scene.nodes.iter().filter(|n| n.mesh.is_some()).map(|n| &**n).collect();
    let names =
        || candidates.iter().map(|n| format!("`{}`", name(n))).collect::<Vec<_>>().join(", ");
    match (choice, candidates.as_slice()) {
        (None, []) => Err("no node carries a mesh".into()),
        (None, [only]) => Ok(only),
        (None, _) => Err(format!(
            "{} mesh nodes, choose one with --mesh NAME: {}",
            candidates.len(),
            names()
        )),
        (Some(wanted), _) => match candidates.iter().filter(|n| name(n) == wanted).count() {
            0 => Err(format!("no mesh node is named `{wanted}`; the mesh nodes: {}", names())),
            1 => Ok(candidates.iter().find(|n| name(n) == wanted).expect("counted")),
            k => Err(format!("{k} mesh nodes are named `{wanted}`; the mesh nodes: {}", names())),
        },
    }
}

/// The animation stack to play: `choice` by name, else by index (from 0); the only one; None
/// in a file without stacks. Several and no choice is an error that lists them.
fn choose_stack<'a>(
    scene: &'a Scene,
    choice: Option<&str>,
) -> Result<Option<&'a ufbx::AnimStack>, String> {
    let stacks = &scene.anim_stacks;
    let list = || {
        let entry =
            |(i, s): (usize, &ufbx::Ref<ufbx::AnimStack>)| format!("{i}: {}", s.element.name);
        stacks.iter().enumerate().map(entry).collect::<Vec<_>>().join(", ")
    };
    let index = match (choice, stacks.len()) {
        (None, 0) => return Ok(None),
        (None, 1) => 0,
        (None, count) => {
            return Err(format!(
                "{count} animation stacks, choose one with --animation NAME|INDEX: {}",
                list()
            ))
        }
        (Some(c), count) => stacks
            .iter()
            .position(|s| s.element.name == c)
            .or_else(|| c.parse::<usize>().ok().filter(|&i| i < count))
            .ok_or_else(|| match count {
                0 => format!("--animation {c}: the file has no animation stack"),
                _ => format!("no animation stack `{c}`; the stacks: {}", list()),
            })?,
    };
    Ok(Some(&stacks[index]))
}

/// The faces as polygon sizes and control-point indices. Errors: a face of fewer than 3
/// corners (a point or a line), a corner that names no control point.
fn polygons(mesh: &ufbx::Mesh) -> Result<(Vec<u32>, Vec<u32>), String> {
    if let Some(f) = mesh.faces.iter().position(|f| f.num_indices < 3) {
        return Err(format!(
            "face {f} has {} corners: points and lines are no surface",
            mesh.faces[f].num_indices
        ));
    }
    let corners = &mesh.vertex_indices;
    let counts = mesh.faces.iter().map(|f| f.num_indices).collect();
    let mut indices = Vec::with_capacity(corners.len());
    for face in mesh.faces.iter() {
        let range = face.index_begin as usize..(face.index_begin + face.num_indices) as usize;
        let corner = corners.get(range).ok_or("a face runs past the corner list")?;
        indices.extend_from_slice(corner);
    }
    if let Some(&v) = indices.iter().find(|&&v| v as usize >= mesh.num_vertices) {
        return Err(format!("a corner names control point {v}, there are {}", mesh.num_vertices));
    }
    Ok((counts, indices))
}

/// The sample times: from the stack's start to its end (a rounding's worth after it counts) at
/// `rate`; one at 0 s without a stack. `charge` is told the frame count before the times are
/// allocated.
fn sample_times(
    range: Option<(f64, f64)>,
    rate: f64,
    charge: impl Fn(usize) -> Result<(), String>,
) -> Result<Vec<f64>, String> {
    let Some((start, end)) = range else {
        charge(1)?;
        return Ok(vec![0.0]);
    };
    if !(start.is_finite() && end.is_finite() && end >= start) {
        return Err(format!("the animation stack runs from {start} to {end} s"));
    }
    let frames = ((end - start) * rate + 1e-6).floor() + 1.0;
    if frames > u32::MAX as f64 {
        return Err(format!("{} s at {rate} frames per second is too many frames", end - start));
    }
    charge(frames as usize)?;
    Ok((0..frames as usize).map(|k| start + k as f64 / rate).collect())
}

/// The control points of node `typed_id`'s mesh at `time`, world space: `ufbx` evaluates the
/// animation, blend shapes, skin and point caches; positions it leaves in the mesh's space
/// (no skin) are moved by the node's geometry-to-world transform.
fn evaluate(
    scene: &Scene,
    anim: &ufbx::Anim,
    typed_id: u32,
    time: f64,
    memory_limit: usize,
) -> Result<Vec<[f32; 3]>, String> {
    let options = ufbx::EvaluateOpts {
        temp_allocator: allocator(memory_limit),
        result_allocator: allocator(memory_limit),
        evaluate_skinning: true,
        evaluate_caches: true,
        load_external_files: true,
        ..Default::default()
    };
    let evaluated =
        ufbx::evaluate_scene(scene, anim, time, options).map_err(|e| describe_error(&e))?;
    let node = evaluated.nodes.get(typed_id as usize).ok_or("the node is gone")?;
    let mesh = node.mesh.as_ref().ok_or("the node's mesh is gone")?;
    let points = &mesh.skinned_position.values;
    if points.len() != mesh.num_vertices {
        return Err(format!("{} positions for {} control points", points.len(), mesh.num_vertices));
    }
    let to_world = |p: ufbx::Vec3| match mesh.skinned_is_local {
        true => ufbx::transform_position(&node.geometry_to_world, p),
        false => p,
    };
    Ok(points
        .iter()
        .map(|&p| {
            let w = to_world(p);
            [w.x as f32, w.y as f32, w.z as f32]
        })
        .collect())
}

/// The mesh's deformers as the note lists them, e.g. ", skinned (12 bones), 2 blend shapes".
fn deformers(mesh: &ufbx::Mesh) -> String {
    let skins =
        mesh.skin_deformers.iter().map(|s| format!(", skinned ({} bones)", s.clusters.len()));
    let shapes: usize = mesh.blend_deformers.iter().map(|b| b.channels.len()).sum();
    let mut text: String = skins.collect();
    if shapes > 0 {
        text += &format!(", {shapes} blend shapes");
    }
    if !mesh.cache_deformers.is_empty() {
        text += &format!(", {} point caches", mesh.cache_deformers.len());
    }
    text
}

/// The file's up axis; None when the file's axis system names none.
fn signed_axis(axis: CoordinateAxis) -> Option<SignedAxis> {
    let (axis, negative) = match axis {
        CoordinateAxis::PositiveX => (0, false),
        CoordinateAxis::NegativeX => (0, true),
        CoordinateAxis::PositiveY => (1, false),
        CoordinateAxis::NegativeY => (1, true),
        CoordinateAxis::PositiveZ => (2, false),
        CoordinateAxis::NegativeZ => (2, true),
        CoordinateAxis::Unknown => return None,
    };
    Some(SignedAxis { axis, negative })
}
