//! A glTF mesh as one vertex list: its triangle primitives merged in file order, each
//! primitive's vertices kept as the file has them (never welded, so that vertex ids are the
//! file's), with frame-0 colours, morph-target offsets and, for a skinned node, every
//! `JOINTS_n` / `WEIGHTS_n` set.
//!
//! Skin weights: glTF requires each vertex's weights to sum to 1; files with 8- or 16-bit
//! weights, or sloppy exporters, miss by a little. Each vertex's weights are divided by their
//! sum over all sets, as Blender's armature modifier does at every evaluation and three.js's
//! `SkinnedMesh.normalizeSkinWeights` does on import. A vertex whose weights sum to 0 or less,
//! or has a negative or non-finite weight, is an error.

use super::accessor::{Accessors, Values};
use crate::mesh::skinning::SkinWeights;
use crate::sequence::glb::linear_to_srgb;
use gltf::mesh::Mode;
use gltf::Semantic;

/// One `JOINTS_n` / `WEIGHTS_n` set: each vertex's four joints and weights.
type Set = Vec<([u32; 4], [f32; 4])>;

/// The merged primitives of one mesh.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Vertex positions, primitive after primitive.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices into `positions`, three per triangle.
    pub indices: Vec<u32>,
    /// `COLOR_0` as 8-bit sRGB, when every primitive has it.
    pub colors: Option<Vec<[u8; 3]>>,
    /// Each morph target's `POSITION` offsets, one per vertex (zeros where a target has none).
    pub targets: Vec<Vec<[f32; 3]>>,
    /// One layer of four influences per `JOINTS_n` / `WEIGHTS_n` set, normalised over all
    /// sets (empty when the mesh is not read as skinned).
    pub skin: Vec<SkinWeights>,
    /// How many vertices' weights were more than 1e-5 off a sum of 1 before normalisation, and
    /// the largest miss.
    pub unnormalised: (usize, f32),
}

/// Reads `mesh`; `joints` is the joint count of the node's skin (None: not skinned, joint
/// attributes ignored as glTF says).
pub fn read_mesh(
    mesh: &gltf::Mesh,
    accessors: &Accessors,
    joints: Option<usize>,
) -> Result<MeshData, String> {
    let mut out = MeshData::default();
    let mut colors = Some(Vec::new());
    let mut influences: Vec<Set> = Vec::new();
    let target_count = mesh.primitives().next().map_or(0, |p| p.morph_targets().len());
    out.targets = vec![Vec::new(); target_count];
    for primitive in mesh.primitives() {
        let p = primitive.index();
        let problem = |what: String| format!("primitive {p}: {what}");
        if primitive.mode() != Mode::Triangles {
            return Err(problem(format!(
                "its mode is {:?}; only triangles are read",
                primitive.mode()
            )));
        }
        let base = out.positions.len() as u32;
        let positions = vec3(accessors, primitive.get(&Semantic::Positions), "POSITION")
            .map_err(problem)?
            .ok_or_else(|| problem("has no POSITION".into()))?;
        let n = positions.len();
        out.indices
            .extend(triangles(accessors, &primitive, n).map_err(problem)?.iter().map(|i| i + base));
        colors = match (colors, primitive.get(&Semantic::Colors(0))) {
            (Some(mut all), Some(a)) => {
                all.extend(read_colors(accessors, &a, n).map_err(problem)?);
                Some(all)
            }
            _ => None,
        };
        if primitive.morph_targets().len() != target_count {
            return Err(problem(format!(
                "has {} morph targets, primitive 0 has {target_count} (glTF requires the same)",
                primitive.morph_targets().len()
            )));
        }
        for (k, target) in primitive.morph_targets().enumerate() {
            let offsets = vec3(accessors, target.positions(), "morph target POSITION")
                .map_err(|e| problem(format!("target {k}: {e}")))?;
            let offsets = match offsets {
                Some(o) if o.len() == n => o,
                Some(o) => {
                    return Err(problem(format!(
                        "morph target {k} has {} offsets for {n} vertices",
                        o.len()
                    )))
                }
                None => {
                    accessors
                        .budget()
                        .charge(Some(n), 12, || format!("morph target {k} without POSITION"))?;
                    vec![[0.0; 3]; n]
                }
            };
            // The first primitive's offsets are kept as read (no copy of each target).
            match out.targets[k].is_empty() {
                true => out.targets[k] = offsets,
                false => out.targets[k].extend(offsets),
            }
        }
        if let Some(joint_count) = joints {
            let sets = read_influences(accessors, &primitive, n, joint_count).map_err(problem)?;
            if sets.is_empty() {
                return Err(problem("has no JOINTS_0 / WEIGHTS_0, and its node has a skin".into()));
            }
            merge_sets(&mut influences, sets, out.positions.len());
        }
        out.positions.extend(positions);
    }
    out.colors = colors.filter(|c| c.len() == out.positions.len());
    if joints.is_some() {
        (out.skin, out.unnormalised) = normalise(&influences)?;
    }
    Ok(out)
}

/// A VEC3 accessor as f32 triples (None when absent).
fn vec3(
    accessors: &Accessors,
    accessor: Option<gltf::Accessor>,
    what: &str,
) -> Result<Option<Vec<[f32; 3]>>, String> {
    let Some(a) = accessor else { return Ok(None) };
    accessors.read_vec3_f32(&a).map(Some).map_err(|e| format!("{what}: {e}"))
}

/// The primitive's triangle indices (0, 1, 2, … without an index accessor), each below `n`.
fn triangles(
    accessors: &Accessors,
    primitive: &gltf::Primitive,
    n: usize,
) -> Result<Vec<u32>, String> {
    let indices: Vec<u32> = match primitive.indices() {
        Some(a) => {
            let values = accessors.read(&a)?;
            if values.components != 1 {
                return Err(format!("index accessor {} is not SCALAR", a.index()));
            }
            values.data.iter().map(|&i| i as u32).collect()
        }
        None => (0..n as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(format!("{} indices is not a whole number of triangles", indices.len()));
    }
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {i} is past its {n} vertices"));
    }
    Ok(indices)
}

/// `COLOR_0` (VEC3 or VEC4; float, or normalised 8- or 16-bit) as 8-bit sRGB, one per vertex.
fn read_colors(
    accessors: &Accessors,
    a: &gltf::Accessor,
    n: usize,
) -> Result<Vec<[u8; 3]>, String> {
    let Values { data, components } = accessors.read(a)?;
    if !(components == 3 || components == 4) || data.len() != n * components {
        return Err(format!("COLOR_0 accessor {} is not one VEC3/VEC4 per vertex", a.index()));
    }
    Ok(data.chunks_exact(components).map(|c| [0, 1, 2].map(|k| linear_to_srgb(c[k]))).collect())
}

/// Each vertex's joints and weights of every `JOINTS_n` / `WEIGHTS_n` set, set after set.
fn read_influences(
    accessors: &Accessors,
    primitive: &gltf::Primitive,
    n: usize,
    joint_count: usize,
) -> Result<Vec<Set>, String> {
    let mut sets = Vec::new();
    for set in 0.. {
        let (joints, weights) =
            match (primitive.get(&Semantic::Joints(set)), primitive.get(&Semantic::Weights(set))) {
                (None, None) => break,
                (Some(j), Some(w)) => (accessors.read(&j)?, accessors.read(&w)?),
                _ => return Err(format!("has only one of JOINTS_{set} and WEIGHTS_{set}")),
            };
        if joints.components != 4
            || weights.components != 4
            || joints.count() != n
            || weights.count() != n
        {
            return Err(format!("JOINTS_{set} / WEIGHTS_{set} are not one VEC4 per vertex ({n})"));
        }
        let mut influences = Vec::with_capacity(n);
        for (v, (j, w)) in joints.data.chunks_exact(4).zip(weights.data.chunks_exact(4)).enumerate()
        {
            let (j, w) = ([0, 1, 2, 3].map(|k| j[k] as u32), [0, 1, 2, 3].map(|k| w[k] as f32));
            if let Some(k) = (0..4).find(|&k| !(w[k].is_finite() && w[k] >= 0.0)) {
                return Err(format!("vertex {v} has weight {} in WEIGHTS_{set}", w[k]));
            }
            if let Some(k) = (0..4).find(|&k| w[k] != 0.0 && j[k] as usize >= joint_count) {
                return Err(format!(
                    "vertex {v} uses joint {} of a {joint_count}-joint skin (JOINTS_{set})",
                    j[k]
                ));
            }
            influences.push((j, w));
        }
        sets.push(influences);
    }
    Ok(sets)
}

/// Appends one primitive's sets to the mesh's (`before` vertices so far), a set that only
/// some primitives have filled with zero weights elsewhere.
fn merge_sets(all: &mut Vec<Set>, sets: Vec<Set>, before: usize) {
    let n = sets[0].len();
    while all.len() < sets.len() {
        all.push(vec![([0; 4], [0.0; 4]); before]);
    }
    for (s, layer) in all.iter_mut().enumerate() {
        match sets.get(s) {
            Some(set) => layer.extend_from_slice(set),
            None => layer.extend(std::iter::repeat_n(([0; 4], [0.0; 4]), n)),
        }
    }
}

/// The sets as skin layers, each vertex's weights divided by their sum over all sets (in f32,
/// in set and slot order), and the count and largest size of the misses from 1.
fn normalise(sets: &[Set]) -> Result<(Vec<SkinWeights>, (usize, f32)), String> {
    let n = sets.first().map_or(0, Vec::len);
    let mut layers: Vec<SkinWeights> = sets
        .iter()
        .map(|_| SkinWeights { joints: Vec::with_capacity(n), weights: Vec::with_capacity(n) })
        .collect();
    let mut missed = (0, 0.0f32);
    for v in 0..n {
        let sum: f32 = sets.iter().flat_map(|s| s[v].1).sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(format!("vertex {v}'s skin weights sum to {sum}, not a positive number"));
        }
        if (sum - 1.0).abs() > 1e-5 {
            missed = (missed.0 + 1, missed.1.max((sum - 1.0).abs()));
        }
        for (layer, set) in layers.iter_mut().zip(sets) {
            layer.joints.push(set[v].0);
            layer.weights.push(set[v].1.map(|w| w / sum));
        }
    }
    Ok((layers, missed))
}
