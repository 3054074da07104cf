//! glTF 2.0 binary (`.glb`) mesh sequences: the frame-0 mesh, one morph target per frame and
//! an animation that steps through them (Blender and three.js play it).
//!
//! Written layout: one node, one mesh, one triangle primitive with `POSITION` (frame 0),
//! `COLOR_0` (frame-0 colours, linear float as glTF requires) when present, `u32` indices, and
//! one `POSITION` morph target per frame holding v(t) − v(0) (frame 0's target has no buffer
//! view, which glTF defines as zeros). Target names `frame_NNNNNN` go to `mesh.extras`. The
//! animation samples the node's morph weights with `STEP` interpolation at t / fps seconds;
//! keyframe t has weight 1 on target t and 0 elsewhere, stored as a sparse accessor so the
//! file grows linearly with the frame count.
//!
//! Reading is the glTF reader's ([`super::gltf`]): sampled at their key rate, the frames of
//! such a file are its keyframes, base + target k at keyframe k.

use super::MeshSequence;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The GLB container's magic, and its JSON and BIN chunk types.
pub(super) const MAGIC: &[u8; 4] = b"glTF";
pub(super) const CHUNK_JSON: u32 = 0x4E4F_534A;
pub(super) const CHUNK_BIN: u32 = 0x004E_4942;
const UNSIGNED_INT: u32 = 5125;
const FLOAT: u32 = 5126;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const TRIANGLES: u32 = 4;
/// An error that names the GLB file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct GlbError {
    /// The GLB file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: String,
}

fn error(path: &Path, problem: impl Into<String>) -> GlbError {
    GlbError { path: path.to_path_buf(), problem: problem.into() }
}

// The part of the glTF schema this module writes.

#[derive(Serialize, Default)]
#[serde(rename_all = "camelCase")]
struct Document {
    asset: Asset,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scene: Option<usize>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    scenes: Vec<Scene>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    nodes: Vec<Node>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    meshes: Vec<Mesh>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    accessors: Vec<Accessor>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    buffer_views: Vec<BufferView>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    buffers: Vec<Buffer>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    animations: Vec<Animation>,
}

#[derive(Serialize, Default)]
struct Asset {
    version: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<String>,
}

#[derive(Serialize)]
struct Scene {
    nodes: Vec<usize>,
}

#[derive(Serialize)]
struct Node {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mesh: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
}

#[derive(Serialize)]
struct Mesh {
    primitives: Vec<Primitive>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    weights: Option<Vec<f32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    extras: Option<serde_json::Value>,
}

#[derive(Serialize)]
struct Primitive {
    attributes: BTreeMap<String, usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    indices: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mode: Option<u32>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    targets: Vec<BTreeMap<String, usize>>,
}

/// An accessor of the glTF schema (written as is by [`crate::track::pins`]).
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(crate) struct Accessor {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    buffer_view: Option<usize>,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
    component_type: u32,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    normalized: bool,
    count: usize,
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sparse: Option<Sparse>,
}

#[derive(Serialize)]
struct Sparse {
    count: usize,
    indices: SparseIndices,
    values: SparseValues,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct SparseIndices {
    buffer_view: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
    component_type: u32,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct SparseValues {
    buffer_view: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
}

/// A buffer view of the glTF schema.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(crate) struct BufferView {
    buffer: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
    byte_length: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    byte_stride: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<u32>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Buffer {
    byte_length: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    uri: Option<String>,
}

#[derive(Serialize)]
struct Animation {
    channels: Vec<Channel>,
    samplers: Vec<Sampler>,
}

#[derive(Serialize)]
struct Channel {
    sampler: usize,
    target: ChannelTarget,
}

#[derive(Serialize)]
struct ChannelTarget {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    node: Option<usize>,
    path: String,
}

#[derive(Serialize)]
struct Sampler {
    input: usize,
    output: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    interpolation: Option<String>,
}

fn is_zero(x: &usize) -> bool {
    *x == 0
}

/// The binary chunk being assembled, with its buffer views.
#[derive(Default)]
pub(crate) struct Body {
    /// The chunk's bytes so far.
    pub(crate) bytes: Vec<u8>,
    /// Its buffer views, in order of their indices.
    pub(crate) views: Vec<BufferView>,
}

impl Body {
    /// Appends 4-byte values as a new buffer view; returns its index.
    pub(crate) fn view(
        &mut self,
        values: impl IntoIterator<Item = [u8; 4]>,
        target: Option<u32>,
    ) -> usize {
        let start = self.bytes.len();
        self.bytes.extend(values.into_iter().flatten());
        self.views.push(BufferView {
            buffer: 0,
            byte_offset: start,
            byte_length: self.bytes.len() - start,
            byte_stride: None,
            target,
        });
        self.views.len() - 1
    }
}

/// A float accessor of `count` elements of `kind` (`components` each) on buffer view `view`,
/// with the exact bounds of `values`.
pub(crate) fn float_accessor(
    view: Option<usize>,
    count: usize,
    kind: &str,
    values: &[f32],
    components: usize,
) -> Accessor {
    // Bounds as the doubles equal to the f32 data, so they match it exactly (not a decimal
    // rounding of it).
    let (mut min, mut max) = (vec![f64::INFINITY; components], vec![f64::NEG_INFINITY; components]);
    for (i, &v) in values.iter().enumerate() {
        min[i % components] = min[i % components].min(v as f64);
        max[i % components] = max[i % components].max(v as f64);
    }
    if values.is_empty() {
        (min, max) = (vec![0.0; components], vec![0.0; components]);
    }
    Accessor {
        buffer_view: view,
        byte_offset: 0,
        component_type: FLOAT,
        normalized: false,
        count,
        kind: kind.into(),
        min: Some(min),
        max: Some(max),
        sparse: None,
    }
}

/// Writes `sequence` as a GLB whose animation shows frame t at t / `fps` seconds, atomically.
///
/// Errors: an unusable sequence, `fps` not positive and finite, more than 65 535 frames (the
/// keyframe weights are indexed by u32).
pub fn write_glb(path: &Path, sequence: &MeshSequence, fps: f64) -> Result<(), GlbError> {
    if sequence.frames.is_empty() {
        return Err(error(path, "cannot write: the sequence has no frames"));
    }
    if let Some(problem) = sequence.problem() {
        return Err(error(path, format!("cannot write: {problem}")));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(error(path, format!("cannot write: frame rate {fps} is not positive")));
    }
    let frames = sequence.frames.len();
    if frames > 65_535 {
        return Err(error(path, format!("cannot write: {frames} frames, at most 65535 fit")));
    }
    let mut body = Body::default();
    let doc = document(sequence, fps, &mut body);
    let json = serde_json::to_vec(&doc).map_err(|e| error(path, format!("cannot write: {e}")))?;
    crate::io::write_atomically(path, |w| write_container(w, &json, &body.bytes))
        .map_err(|e| error(path, format!("cannot write: {e}")))
}

/// The glTF document of a checked sequence, its binary data appended to `body`.
fn document(sequence: &MeshSequence, fps: f64, body: &mut Body) -> Document {
    let frames = sequence.frames.len();
    let base = &sequence.frames[0];
    let mut accessors = Vec::new();
    let mut add = |a: Accessor| {
        accessors.push(a);
        accessors.len() - 1
    };
    let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let indices: Vec<u32> = sequence.faces.iter().flatten().copied().collect();
    let view = body.view(indices.iter().map(|i| i.to_le_bytes()), Some(ELEMENT_ARRAY_BUFFER));
    let indices = add(Accessor {
        buffer_view: Some(view),
        byte_offset: 0,
        component_type: UNSIGNED_INT,
        normalized: false,
        count: indices.len(),
        kind: "SCALAR".into(),
        min: None,
        max: None,
        sparse: None,
    });
    let mut attributes = BTreeMap::new();
    let values = flat(base);
    let view = body.view(values.iter().map(|v| v.to_le_bytes()), Some(ARRAY_BUFFER));
    attributes.insert(
        "POSITION".to_string(),
        add(float_accessor(Some(view), base.len(), "VEC3", &values, 3)),
    );
    if let Some(colors) = sequence.colors.as_ref().and_then(|c| c.first()) {
        let linear: Vec<f32> = colors.iter().flatten().map(|&c| srgb_to_linear(c)).collect();
        let view = body.view(linear.iter().map(|v| v.to_le_bytes()), Some(ARRAY_BUFFER));
        attributes.insert(
            "COLOR_0".to_string(),
            add(float_accessor(Some(view), base.len(), "VEC3", &linear, 3)),
        );
    }
    let mut targets = Vec::with_capacity(frames);
    for (t, frame) in sequence.frames.iter().enumerate() {
        let delta: Vec<f32> = frame
            .iter()
            .zip(base)
            .flat_map(|(v, b)| [v[0] - b[0], v[1] - b[1], v[2] - b[2]])
            .collect();
        let view =
            (t > 0).then(|| body.view(delta.iter().map(|v| v.to_le_bytes()), Some(ARRAY_BUFFER)));
        targets.push(BTreeMap::from([(
            "POSITION".to_string(),
            add(float_accessor(view, base.len(), "VEC3", &delta, 3)),
        )]));
    }
    let times: Vec<f32> = (0..frames).map(|t| (t as f64 / fps) as f32).collect();
    let view = body.view(times.iter().map(|v| v.to_le_bytes()), None);
    let input = add(float_accessor(Some(view), frames, "SCALAR", &times, 1));
    // Keyframe k, target k: element k·frames + k of the frames × frames weight table.
    let one_hot =
        body.view((0..frames as u32).map(|k| (k * frames as u32 + k).to_le_bytes()), None);
    let ones = body.view((0..frames).map(|_| 1.0f32.to_le_bytes()), None);
    let output = add(Accessor {
        buffer_view: None,
        byte_offset: 0,
        component_type: FLOAT,
        normalized: false,
        count: frames * frames,
        kind: "SCALAR".into(),
        min: None,
        max: None,
        sparse: Some(Sparse {
            count: frames,
            indices: SparseIndices {
                buffer_view: one_hot,
                byte_offset: 0,
                component_type: UNSIGNED_INT,
            },
            values: SparseValues { buffer_view: ones, byte_offset: 0 },
        }),
    });
    let names: Vec<String> = (0..frames).map(|t| format!("frame_{t:06}")).collect();
    Document {
        asset: Asset {
            version: "2.0".into(),
            generator: Some(format!("tagsplat {}", env!("CARGO_PKG_VERSION"))),
        },
        scene: Some(0),
        scenes: vec![Scene { nodes: vec![0] }],
        nodes: vec![Node { mesh: Some(0), name: Some("sequence".into()) }],
        meshes: vec![Mesh {
            primitives: vec![Primitive {
                attributes,
                indices: Some(indices),
                mode: Some(TRIANGLES),
                targets,
            }],
            weights: None,
            extras: Some(serde_json::json!({ "targetNames": names })),
        }],
        accessors,
        buffers: vec![Buffer { byte_length: body.bytes.len(), uri: None }],
        buffer_views: std::mem::take(&mut body.views),
        animations: vec![Animation {
            channels: vec![Channel {
                sampler: 0,
                target: ChannelTarget { node: Some(0), path: "weights".into() },
            }],
            samplers: vec![Sampler { input, output, interpolation: Some("STEP".into()) }],
        }],
    }
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
pub(crate) fn write_container(w: &mut impl Write, json: &[u8], bin: &[u8]) -> std::io::Result<()> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let json_len = json.len() + pad(json.len());
    let bin_len = bin.len() + pad(bin.len());
    let total = 12 + 8 + json_len + if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = u32::try_from(total)
        .map_err(|_| std::io::Error::other("larger than the 4 GiB a GLB can hold"))?;
    w.write_all(MAGIC)?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(json_len as u32).to_le_bytes())?;
    w.write_all(&CHUNK_JSON.to_le_bytes())?;
    w.write_all(json)?;
    w.write_all(&b"   "[..pad(json.len())])?;
    if !bin.is_empty() {
        w.write_all(&(bin_len as u32).to_le_bytes())?;
        w.write_all(&CHUNK_BIN.to_le_bytes())?;
        w.write_all(bin)?;
        w.write_all(&[0u8; 3][..pad(bin.len())])?;
    }
    Ok(())
}

/// sRGB-encoded 8-bit value to linear [0, 1] (IEC 61966-2-1).
#[inline]
pub(super) fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f64 / 255.0;
    (if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }) as f32
}

/// Linear [0, 1] to the nearest sRGB-encoded 8-bit value.
#[inline]
pub(super) fn linear_to_srgb(l: f64) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.0031308 { l * 12.92 } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
    (c * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_8_bit_colour_survives_the_linear_round_trip() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(c) as f64), c);
        }
    }
}
