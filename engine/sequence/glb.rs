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
//! Reading accepts any single-primitive triangle mesh whose node has a morph-weight
//! animation (or none: one frame): frame k = base + Σⱼ wₖⱼ·targetⱼ at keyframe k. Node
//! transforms are not applied (positions stay in mesh space); external buffers are refused.

use super::MeshSequence;
use serde::{Deserialize, Serialize};
use std::cell::Cell;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const FLOAT: u32 = 5126;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const TRIANGLES: u32 = 4;
/// What the reader may materialize, in bytes: at least [`BUDGET_FLOOR`], and
/// [`BUDGET_PER_FILE_BYTE`] per byte of the file. Accessors without a buffer view, morph
/// targets without POSITION and keyframes × vertices take memory no byte of the file stands
/// for, so without a budget a small file could claim gigabytes. The factor leaves room for a
/// file's own data as f64 (8 bytes per u8 component at most), for keyframes blending few
/// targets, and for the dense frames × frames weight table of the files [`write_glb`] writes
/// (1400 frames of a single triangle fit the floor; every frame of more vertices adds room).
/// The floor is small enough that one edited count in a kilobyte file cannot make the reader
/// allocate hundreds of megabytes before it finds the file inconsistent (tests/fuzz.rs).
const BUDGET_FLOOR: usize = 16 << 20;
const BUDGET_PER_FILE_BYTE: usize = 64;

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

// The part of the glTF schema this module reads and writes (unknown fields are ignored).

#[derive(Serialize, Deserialize, Default)]
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

#[derive(Serialize, Deserialize, Default)]
struct Asset {
    version: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<String>,
}

#[derive(Serialize, Deserialize)]
struct Scene {
    nodes: Vec<usize>,
}

#[derive(Serialize, Deserialize)]
struct Node {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mesh: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
}

#[derive(Serialize, Deserialize)]
struct Mesh {
    primitives: Vec<Primitive>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    weights: Option<Vec<f32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    extras: Option<serde_json::Value>,
}

#[derive(Serialize, Deserialize)]
struct Primitive {
    attributes: BTreeMap<String, usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    indices: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mode: Option<u32>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    targets: Vec<BTreeMap<String, usize>>,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Accessor {
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

#[derive(Serialize, Deserialize)]
struct Sparse {
    count: usize,
    indices: SparseIndices,
    values: SparseValues,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct SparseIndices {
    buffer_view: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
    component_type: u32,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct SparseValues {
    buffer_view: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct BufferView {
    buffer: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    byte_offset: usize,
    byte_length: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    byte_stride: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    target: Option<u32>,
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Buffer {
    byte_length: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    uri: Option<String>,
}

#[derive(Serialize, Deserialize)]
struct Animation {
    channels: Vec<Channel>,
    samplers: Vec<Sampler>,
}

#[derive(Serialize, Deserialize)]
struct Channel {
    sampler: usize,
    target: ChannelTarget,
}

#[derive(Serialize, Deserialize)]
struct ChannelTarget {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    node: Option<usize>,
    path: String,
}

#[derive(Serialize, Deserialize)]
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
struct Body {
    bytes: Vec<u8>,
    views: Vec<BufferView>,
}

impl Body {
    /// Appends 4-byte values as a new buffer view; returns its index.
    fn view(&mut self, values: impl IntoIterator<Item = [u8; 4]>, target: Option<u32>) -> usize {
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

fn float_accessor(
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
fn write_container(w: &mut impl Write, json: &[u8], bin: &[u8]) -> std::io::Result<()> {
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
fn linear_to_srgb(l: f64) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.0031308 { l * 12.92 } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
    (c * 255.0).round() as u8
}

/// Reads a GLB sequence (see the module doc).
pub fn read_glb(path: &Path) -> Result<MeshSequence, GlbError> {
    let bytes = std::fs::read(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    parse_glb(path, &bytes)
}

/// Parses GLB bytes; `path` only names the source in errors. The result is checked
/// ([`MeshSequence::problem`]).
pub fn parse_glb(path: &Path, bytes: &[u8]) -> Result<MeshSequence, GlbError> {
    let (json, bin) = read_container(path, bytes)?;
    let doc: Document =
        serde_json::from_slice(json).map_err(|e| error(path, format!("invalid glTF JSON: {e}")))?;
    let budget = bytes.len().saturating_mul(BUDGET_PER_FILE_BYTE).max(BUDGET_FLOOR);
    let reader = Reader { path, doc: &doc, bin, budget, spent: Cell::new(0) };
    let sequence = reader.sequence()?;
    match sequence.problem() {
        Some(problem) => Err(error(path, problem)),
        None => Ok(sequence),
    }
}

/// The JSON and BIN chunks of a GLB container.
fn read_container<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], &'a [u8]), GlbError> {
    let word =
        |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    if bytes.len() < 12 || &bytes[..4] != MAGIC {
        return Err(error(path, "not a GLB file (no glTF header)"));
    }
    if word(4) != Some(2) {
        return Err(error(path, format!("GLB version {}, only 2 is read", word(4).unwrap_or(0))));
    }
    let declared = word(8).unwrap_or(0) as usize;
    if declared != bytes.len() {
        return Err(error(
            path,
            format!(
                "truncated or padded: the header says {declared} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let (mut json, mut bin) = (None, &[][..]);
    let mut at = 12;
    while at < bytes.len() {
        let (Some(length), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(error(path, format!("chunk header at byte {at} is cut off")));
        };
        let end = (length as usize).checked_add(at + 8);
        let data = end
            .and_then(|end| bytes.get(at + 8..end))
            .ok_or_else(|| error(path, format!("chunk at byte {at} runs past the end")))?;
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(data),
            CHUNK_BIN if bin.is_empty() => bin = data,
            _ => {}
        }
        at += 8 + data.len();
    }
    Ok((json.ok_or_else(|| error(path, "no JSON chunk"))?, bin))
}

/// Reads accessors of one document against its BIN chunk, within a memory budget.
struct Reader<'a> {
    path: &'a Path,
    doc: &'a Document,
    bin: &'a [u8],
    /// Bytes the reader may materialize (see [`BUDGET_FLOOR`]), and has so far.
    budget: usize,
    spent: Cell<usize>,
}

impl Reader<'_> {
    fn error(&self, problem: impl Into<String>) -> GlbError {
        error(self.path, problem)
    }

    /// Counts `count` items (None: more than a usize holds) of `bytes` each against the
    /// budget, before they are allocated; returns `count`.
    fn charge(
        &self,
        count: Option<usize>,
        bytes: usize,
        what: impl FnOnce() -> String,
    ) -> Result<usize, GlbError> {
        let total = count.and_then(|n| n.checked_mul(bytes)?.checked_add(self.spent.get()));
        match (count, total) {
            (Some(count), Some(total)) if total <= self.budget => {
                self.spent.set(total);
                Ok(count)
            }
            _ => Err(self.error(format!(
                "{} would take more than the {} MiB this file's size allows",
                what(),
                self.budget >> 20
            ))),
        }
    }

    /// The sequence of the animated mesh node (or the first mesh node, as one frame).
    fn sequence(&self) -> Result<MeshSequence, GlbError> {
        let doc = self.doc;
        let animated =
            doc.animations.iter().flat_map(|a| a.channels.iter().map(move |c| (a, c))).find(
                |(_, c)| {
                    c.target.path == "weights"
                        && c.target
                            .node
                            .and_then(|n| doc.nodes.get(n))
                            .is_some_and(|n| n.mesh.is_some())
                },
            );
        let node = match animated {
            Some((_, c)) => c.target.node.and_then(|n| doc.nodes.get(n)),
            None => doc.nodes.iter().find(|n| n.mesh.is_some()),
        };
        let mesh_index = node.and_then(|n| n.mesh).unwrap_or(0);
        let mesh = doc.meshes.get(mesh_index).ok_or_else(|| self.error("no mesh"))?;
        let [primitive] = mesh.primitives.as_slice() else {
            return Err(self.error(format!(
                "mesh {mesh_index} has {} primitives; one is read",
                mesh.primitives.len()
            )));
        };
        if primitive.mode.unwrap_or(TRIANGLES) != TRIANGLES {
            return Err(self.error(format!(
                "mesh {mesh_index} is not made of triangles (mode {:?})",
                primitive.mode
            )));
        }
        let position = primitive
            .attributes
            .get("POSITION")
            .ok_or_else(|| self.error("the primitive has no POSITION"))?;
        let base = self.vec3_f32(*position, "POSITION")?;
        let faces = self.faces(primitive.indices, base.len())?;
        let targets = primitive
            .targets
            .iter()
            .enumerate()
            .map(|(k, t)| match t.get("POSITION") {
                Some(&a) => self.vec3_f32(a, "morph target POSITION"),
                None => {
                    self.charge(Some(base.len()), 12, || {
                        format!("morph target {k} without POSITION")
                    })?;
                    Ok(vec![[0.0; 3]; base.len()])
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(t) = targets.iter().position(|t| t.len() != base.len()) {
            return Err(self.error(format!(
                "morph target {t} has {} positions, the mesh has {}",
                targets[t].len(),
                base.len()
            )));
        }
        let weights = match animated {
            Some((animation, channel)) => {
                self.keyframe_weights(animation, channel.sampler, targets.len())?
            }
            None => vec![mesh.weights.clone().unwrap_or_default()],
        };
        let positions = self.charge(weights.len().checked_mul(base.len()), 12, || {
            format!("{} frames of {} vertices", weights.len(), base.len())
        })?;
        let frames: Vec<Vec<[f32; 3]>> =
            weights.iter().map(|w| morph(&base, &targets, w)).collect();
        let colors = match primitive.attributes.get("COLOR_0") {
            Some(&a) => {
                let colors = self.colors(a, base.len())?;
                self.charge(Some(positions), 3, || format!("colours of {} frames", frames.len()))?;
                Some(vec![colors; frames.len()])
            }
            None => None,
        };
        Ok(MeshSequence { faces, frames, colors })
    }

    /// Morph weights at each keyframe of the sampler (the middle value for CUBICSPLINE).
    fn keyframe_weights(
        &self,
        animation: &Animation,
        sampler: usize,
        targets: usize,
    ) -> Result<Vec<Vec<f32>>, GlbError> {
        let sampler = animation
            .samplers
            .get(sampler)
            .ok_or_else(|| self.error(format!("animation sampler {sampler} does not exist")))?;
        let keyframes = self.accessor(sampler.input)?.0.len();
        let (values, _) = self.accessor(sampler.output)?;
        let per_key = if sampler.interpolation.as_deref() == Some("CUBICSPLINE") { 3 } else { 1 };
        let expected = keyframes.checked_mul(targets * per_key);
        if targets == 0 || expected != Some(values.len()) {
            return Err(self.error(format!(
                "{} morph weights for {keyframes} keyframes of {targets} targets",
                values.len()
            )));
        }
        let skip = if per_key == 3 { targets } else { 0 };
        Ok(values
            .chunks(targets * per_key)
            .map(|k| k[skip..skip + targets].iter().map(|&w| w as f32).collect())
            .collect())
    }

    /// Triangle indices (or 0, 1, 2, … for an unindexed primitive).
    fn faces(&self, indices: Option<usize>, vertices: usize) -> Result<Vec<[u32; 3]>, GlbError> {
        let flat: Vec<u32> = match indices {
            Some(a) => {
                let (values, accessor) = self.accessor(a)?;
                if accessor.kind != "SCALAR"
                    || ![UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT]
                        .contains(&accessor.component_type)
                {
                    return Err(
                        self.error(format!("indices accessor {a} is not unsigned integer scalars"))
                    );
                }
                values.iter().map(|&i| i as u32).collect()
            }
            None => (0..vertices as u32).collect(),
        };
        if !flat.len().is_multiple_of(3) {
            return Err(
                self.error(format!("{} indices is not a whole number of triangles", flat.len()))
            );
        }
        Ok(flat.chunks_exact(3).map(|f| [f[0], f[1], f[2]]).collect())
    }

    /// A VEC3 FLOAT accessor.
    fn vec3_f32(&self, index: usize, what: &str) -> Result<Vec<[f32; 3]>, GlbError> {
        let (values, accessor) = self.accessor(index)?;
        if accessor.kind != "VEC3" || accessor.component_type != FLOAT {
            return Err(self.error(format!("{what} accessor {index} is not VEC3 of FLOAT")));
        }
        Ok(values.chunks_exact(3).map(|v| [v[0] as f32, v[1] as f32, v[2] as f32]).collect())
    }

    /// COLOR_0 (VEC3 or VEC4; float, or normalized u8/u16) as 8-bit sRGB.
    fn colors(&self, index: usize, vertices: usize) -> Result<Vec<[u8; 3]>, GlbError> {
        let (values, accessor) = self.accessor(index)?;
        let components = if accessor.kind == "VEC4" { 4 } else { 3 };
        let scale = match (accessor.component_type, accessor.normalized) {
            (FLOAT, _) => 1.0,
            (UNSIGNED_BYTE, true) => 255.0,
            (UNSIGNED_SHORT, true) => 65535.0,
            _ => {
                return Err(self
                    .error(format!("COLOR_0 accessor {index} has an unsupported component type")))
            }
        };
        if !["VEC3", "VEC4"].contains(&accessor.kind.as_str()) || accessor.count != vertices {
            return Err(
                self.error(format!("COLOR_0 accessor {index} is not one VEC3/VEC4 per vertex"))
            );
        }
        Ok(values
            .chunks_exact(components)
            .map(|c| [0, 1, 2].map(|k| linear_to_srgb(c[k] / scale)))
            .collect())
    }

    /// All components of an accessor as f64 (exact for every glTF component type), sparse
    /// substitutions applied, normalization not applied.
    fn accessor(&self, index: usize) -> Result<(Vec<f64>, &Accessor), GlbError> {
        let a = self
            .doc
            .accessors
            .get(index)
            .ok_or_else(|| self.error(format!("accessor {index} does not exist")))?;
        let components = match a.kind.as_str() {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            other => {
                return Err(self.error(format!("accessor {index} has unsupported type {other}")))
            }
        };
        let total = self.charge(a.count.checked_mul(components), 8, || {
            format!("accessor {index} ({} elements of {})", a.count, a.kind)
        })?;
        let mut values = match a.buffer_view {
            Some(view) => {
                self.components(view, a.byte_offset, a.component_type, a.count, components, index)?
            }
            None => vec![0.0; total],
        };
        if let Some(sparse) = &a.sparse {
            if sparse.count > a.count {
                return Err(self.error(format!(
                    "accessor {index}: {} sparse values for {} elements",
                    sparse.count, a.count
                )));
            }
            let targets = self.components(
                sparse.indices.buffer_view,
                sparse.indices.byte_offset,
                sparse.indices.component_type,
                sparse.count,
                1,
                index,
            )?;
            let replacements = self.components(
                sparse.values.buffer_view,
                sparse.values.byte_offset,
                a.component_type,
                sparse.count,
                components,
                index,
            )?;
            for (k, &element) in targets.iter().enumerate() {
                let element = element as usize;
                if element >= a.count {
                    return Err(self.error(format!(
                        "accessor {index}: sparse index {element} is past its {} elements",
                        a.count
                    )));
                }
                values[element * components..(element + 1) * components]
                    .copy_from_slice(&replacements[k * components..(k + 1) * components]);
            }
        }
        Ok((values, a))
    }

    /// `count` elements of `components` values of `component_type` from a buffer view.
    fn components(
        &self,
        view: usize,
        offset: usize,
        component_type: u32,
        count: usize,
        components: usize,
        accessor: usize,
    ) -> Result<Vec<f64>, GlbError> {
        let err = |problem: String| self.error(format!("accessor {accessor}: {problem}"));
        let size = match component_type {
            5120 | UNSIGNED_BYTE => 1,
            5122 | UNSIGNED_SHORT => 2,
            UNSIGNED_INT | FLOAT => 4,
            other => return Err(err(format!("unknown component type {other}"))),
        };
        let v = self
            .doc
            .buffer_views
            .get(view)
            .ok_or_else(|| err(format!("buffer view {view} does not exist")))?;
        if v.buffer != 0 || self.doc.buffers.first().is_some_and(|b| b.uri.is_some()) {
            return Err(err("data outside the GLB's binary chunk is not read".into()));
        }
        let data = v
            .byte_offset
            .checked_add(v.byte_length)
            .and_then(|end| self.bin.get(v.byte_offset..end))
            .ok_or_else(|| err(format!("buffer view {view} runs past the binary chunk")))?;
        let element = size * components;
        let stride = v.byte_stride.unwrap_or(element);
        if stride < element {
            return Err(err(format!(
                "buffer view {view} has a byte stride of {stride}, smaller than one element"
            )));
        }
        // Offset, count and stride come from the file: their sum is checked, not trusted.
        let needed = match count.checked_sub(1) {
            None => Some(0),
            Some(last) => {
                last.checked_mul(stride).and_then(|n| n.checked_add(offset)?.checked_add(element))
            }
        };
        if needed.is_none_or(|needed| needed > data.len()) {
            return Err(err(format!(
                "{count} elements of {element} bytes, {stride} apart from byte {offset}, do \
                 not fit buffer view {view} ({} bytes)",
                data.len()
            )));
        }
        let mut out = Vec::with_capacity(count * components);
        for i in 0..count {
            for c in 0..components {
                let at = offset + i * stride + c * size;
                let b = &data[at..at + size];
                out.push(match component_type {
                    5120 => b[0] as i8 as f64,
                    UNSIGNED_BYTE => b[0] as f64,
                    5122 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    UNSIGNED_SHORT => u16::from_le_bytes([b[0], b[1]]) as f64,
                    UNSIGNED_INT => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                });
            }
        }
        Ok(out)
    }
}

/// base + Σⱼ wⱼ·targetⱼ in f32 (so a weight of exactly 1 on one target gives base + target).
fn morph(base: &[[f32; 3]], targets: &[Vec<[f32; 3]>], weights: &[f32]) -> Vec<[f32; 3]> {
    let mut out = base.to_vec();
    for (target, &w) in targets.iter().zip(weights).filter(|(_, &w)| w != 0.0) {
        for (o, d) in out.iter_mut().zip(target) {
            for k in 0..3 {
                o[k] += w * d[k];
            }
        }
    }
    out
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

    /// A GLB of a triangle moving over two frames, its document changed by `edit` first.
    fn edited_glb(edit: impl FnOnce(&mut Document)) -> Vec<u8> {
        let triangle = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let moved = triangle.iter().map(|p| [p[0], p[1], 1.0]).collect();
        let sequence =
            MeshSequence { faces: vec![[0, 1, 2]], frames: vec![triangle, moved], colors: None };
        let mut body = Body::default();
        let mut doc = document(&sequence, 30.0, &mut body);
        edit(&mut doc);
        let mut bytes = Vec::new();
        write_container(&mut bytes, &serde_json::to_vec(&doc).unwrap(), &body.bytes).unwrap();
        bytes
    }

    /// The base POSITION accessor of the edited document, without a buffer view: zeros.
    fn zero_positions(doc: &mut Document, count: usize) -> &mut Primitive {
        let position = doc.meshes[0].primitives[0].attributes["POSITION"];
        (doc.accessors[position].buffer_view, doc.accessors[position].count) = (None, count);
        &mut doc.meshes[0].primitives[0]
    }

    fn glb_error(edit: impl FnOnce(&mut Document)) -> String {
        let message = parse_glb(Path::new("a.glb"), &edited_glb(edit)).unwrap_err().to_string();
        assert!(message.starts_with("a.glb: "), "{message}");
        message
    }

    /// Counts no bytes of the file stand for are charged to a budget (the floor, for a file
    /// this small) before anything is allocated, cumulatively.
    #[test]
    fn counts_the_file_cannot_justify_are_refused_before_allocating() {
        assert_eq!(parse_glb(Path::new("a.glb"), &edited_glb(|_| {})).unwrap().frames.len(), 2);
        let e = glb_error(|doc| _ = zero_positions(doc, 1 << 28));
        let expected = "accessor 1 (268435456 elements of VEC3) would take more than the 16 MiB";
        assert!(e.contains(expected), "{e}");
        // 300 000 zero vertices (7.2 MB as f64) fit, and two targets without POSITION
        // (3.6 MB each), but a third does not.
        let e = glb_error(|doc| zero_positions(doc, 300_000).targets = vec![BTreeMap::new(); 9]);
        assert!(e.contains("morph target 2 without POSITION would take more than"), "{e}");
        let e = glb_error(|doc| zero_positions(doc, 300_000).targets = vec![BTreeMap::new(); 2]);
        assert!(e.contains("2 frames of 300000 vertices would take more than"), "{e}");
        let e = glb_error(|doc| _ = zero_positions(doc, usize::MAX / 2));
        assert!(e.contains("accessor 1 (9223372036854775807 elements of VEC3) would"), "{e}");
    }

    /// Offsets, strides and lengths from the file are added and multiplied with checks: an
    /// error, not an overflow.
    #[test]
    fn huge_offsets_and_strides_are_refused() {
        /// The base POSITION's buffer view, and the accessor's offset into it.
        fn view(doc: &mut Document) -> (&mut BufferView, &mut usize) {
            let position = doc.meshes[0].primitives[0].attributes["POSITION"];
            let view = doc.accessors[position].buffer_view.unwrap();
            (&mut doc.buffer_views[view], &mut doc.accessors[position].byte_offset)
        }
        let e = glb_error(|doc| view(doc).0.byte_stride = Some(usize::MAX / 2));
        assert!(e.contains("3 elements of 12 bytes, 9223372036854775807 apart from byte 0, do not fit buffer view 1 (36 bytes)"), "{e}");
        let e = glb_error(|doc| *view(doc).1 = usize::MAX);
        assert!(e.contains("do not fit buffer view 1"), "{e}");
        let e = glb_error(|doc| view(doc).0.byte_offset = usize::MAX);
        assert!(e.contains("buffer view 1 runs past the binary chunk"), "{e}");
    }

    #[test]
    fn damaged_containers_are_refused_with_the_reason() {
        let p = Path::new("a.glb");
        let mut header = b"glTF".to_vec();
        header.extend(2u32.to_le_bytes());
        header.extend(40u32.to_le_bytes());
        for (bytes, needle) in [
            (b"PK\x03\x04".to_vec(), "not a GLB file"),
            (header.clone(), "the header says 40 bytes, the file has 12"),
            (
                [&header[..], &100u32.to_le_bytes(), &CHUNK_JSON.to_le_bytes(), &[0u8; 20]]
                    .concat(),
                "chunk at byte 12 runs past the end",
            ),
            ([&header[..], &[0u8; 28]].concat(), "chunk header at byte 36 is cut off"),
        ] {
            let e = parse_glb(p, &bytes).unwrap_err().to_string();
            assert!(e.starts_with("a.glb: ") && e.contains(needle), "{e}");
        }
    }
}
