//! Reading a USD mesh sequence (`.usda`, `.usdc`, `.usd` in either encoding, `.usdz`) through
//! the pure-Rust `openusd` stage, which composes the layers (sublayers, references, payloads,
//! inherits, specializes, variants, value clips, layer-offset retiming) and resolves values at
//! a time code (held or linear, quaternions by slerp), as Pixar's library does.
//!
//! One `Mesh` prim is read: its `faceVertexCounts` and `faceVertexIndices` (one connectivity
//! for the whole sequence), its `points` in world space, through its own xformOps and every
//! ancestor's (`xformOpOrder`; `!invert!` and `!resetXformStack!` honoured). The frames are the
//! union of the time codes of `points` and of every animated op on that chain; times are
//! `code / timeCodesPerSecond`. A `leftHanded` mesh, or one whose world transform mirrors it,
//! has each polygon reversed so that the result is counter-clockwise. `upAxis` (default Y) and
//! `metersPerUnit` (default 0.01) are reported, not applied.
//!
//! Refused with an error, never read in part: a layer or arc that fails to compose (a missing
//! sublayer or reference), an attribute authored as a spline (openusd 0.6 cannot evaluate
//! them), an xformOp it does not know, values of the wrong type, topology that changes over
//! time, and a layer openusd could not walk to the end (a path that never reaches the root, a
//! prim child whose name is not an identifier).

use super::orient::SignedAxis;
use super::source::{ReadOptions, SourceSequence};
use glam::{DMat4, DQuat, DVec3};
use openusd::sdf;
use openusd::usd::{AttributeQuery, Prim, PrimPredicate, Stage, TimeCode};
use std::path::Path;

/// Reads the sequence of the one `Mesh` prim of `path` (or `options.mesh`, a prim path).
///
/// openusd trusts some counts and indices of a binary (usdc) file and panics on a few damaged
/// or very old ones: such a panic is caught here and becomes an error naming the file's
/// damage, so it never reaches the caller. Every binary layer the stage opens is checked
/// first (`sequence::usdc_check`), so that what openusd allocates stays within 64 bytes per
/// byte of the layer (8 MiB at least).
pub fn read(path: &Path, options: &ReadOptions) -> Result<SourceSequence, String> {
    let read = std::panic::AssertUnwindSafe(|| read_stage(path, options));
    std::panic::catch_unwind(read).unwrap_or_else(|payload| {
        let what = crate::panic_payload::panic_text(&*payload);
        Err(format!("damaged, or a kind of USD the reader cannot read (openusd failed: {what})"))
    })
}

fn read_stage(path: &Path, options: &ReadOptions) -> Result<SourceSequence, String> {
    let stage = open(path)?;
    let mesh = choose_mesh(&stage, options.mesh.as_deref())?;
    let name = mesh.path().as_str().to_owned();
    let chain = transform_chain(&mesh)?;
    let points = AttributeQuery::new(&mesh.attribute("points"));
    let codes = frame_codes(&points, &chain).map_err(|e| format!("{name}: {e}"))?;
    let (counts, mut indices) = topology(&mesh, &codes)?;
    let mut frames = Vec::with_capacity(codes.len());
    let mut mirrored = None;
    for &code in &codes {
        let world = world_transform(&chain, code)?;
        let flip = world.determinant() < 0.0;
        if *mirrored.get_or_insert(flip) != flip {
            let at = code.map_or("the default time".into(), |c| format!("time code {c}"));
            return Err(format!("{name}: not one connectivity: the world transform mirrors the mesh from {at} on, reversing its winding"));
        }
        let local = points_at(&points, code).map_err(|e| format!("{name}.points: {e}"))?;
        frames
            .push(local.iter().map(|&p| world.transform_point3(p).as_vec3().to_array()).collect());
    }
    if orientation(&mesh)? == LEFT_HANDED || mirrored == Some(true) {
        reverse_polygons(&counts, &mut indices);
    }
    let rate = stage.time_codes_per_second();
    if !(rate.is_finite() && rate > 0.0) {
        return Err(format!("timeCodesPerSecond is {rate}"));
    }
    let times = codes.iter().map(|c| c.unwrap_or(0.0) / rate).collect();
    Ok(SourceSequence {
        counts,
        indices,
        frames,
        times,
        colors: None,
        up: Some(up_axis(&stage)?),
        meters_per_unit: Some(meters_per_unit(&stage)?),
        notes: notes(&name, &codes, rate),
    })
}

/// The composed stage of `path`; an error when any layer, sublayer, reference or payload
/// fails to compose.
fn open(path: &Path) -> Result<Stage, String> {
    let name = path.to_str().ok_or("the path is not valid UTF-8")?;
    let stage = Stage::builder()
        .resolver(super::usdc_check::CheckedResolver::default())
        .open(name)
        .map_err(|e| format!("cannot open the stage: {e:#}"))?;
    match stage.composition_errors().first() {
        Some(error) => Err(format!("composition failed (not read in part): {error}")),
        None => check_paths(&stage).map(|()| stage),
    }
}

/// The fields whose values are paths that composition walks up: arcs and relationship targets.
const PATH_FIELDS: [&str; 6] =
    ["references", "payload", "inheritPaths", "specializes", "targetPaths", "connectionPaths"];

/// Refuses a layer of the stage that openusd could not walk to the end: a spec path, or a path
/// in [`PATH_FIELDS`], whose chain of parents does not end (openusd 0.6 takes a path that ends
/// in `}` without being a variant selection, `/A}`, for its own parent, and composing it
/// recurses until the stack overflows), or a prim child that is no identifier. (Crate layers
/// are refused before, by their path tokens; text layers opened later, through a reference,
/// are not checked.)
fn check_paths(stage: &Stage) -> Result<(), String> {
    for id in stage.layer_identifiers() {
        let Some(layer) = stage.layer(&id) else { continue };
        let data = layer.data();
        for path in data.spec_paths() {
            let values = PATH_FIELDS.iter().filter_map(|f| data.try_field(&path, f).ok().flatten());
            let named: Vec<sdf::Path> = values.flat_map(|v| paths_in(&v)).collect();
            if let Some(path) = std::iter::once(&path).chain(&named).find(|p| !has_root(p)) {
                return Err(format!("{id}: the path {path} has no root openusd can find"));
            }
            check_children(data, &path).map_err(|e| format!("{id}: {e}"))?;
        }
    }
    Ok(())
}

/// Refuses a prim whose `primChildren` names one that is not an identifier: openusd's text
/// parser appends whatever string a prim is named to its parent's path, so that a child named
/// `""` is its parent again and traversing the stage never ends.
fn check_children(data: &dyn sdf::AbstractData, path: &sdf::Path) -> Result<(), String> {
    let children = data.try_field(path, "primChildren").ok().flatten();
    let Some(sdf::Value::TokenVec(names)) = children.as_deref() else { return Ok(()) };
    match names.iter().find(|name| !sdf::Path::is_valid_identifier(name.as_str())) {
        Some(name) => {
            Err(format!("the prim {path} has a child named {:?}, not an identifier", name.as_str()))
        }
        None => Ok(()),
    }
}

/// Whether walking up from `path`, parent after parent, ends: each step of a sound path
/// shortens it, so the walk takes at most its length.
fn has_root(path: &sdf::Path) -> bool {
    let mut ancestor = path.clone();
    for _ in 0..=path.as_str().len() {
        match ancestor.parent() {
            Some(parent) => ancestor = parent,
            None => return true,
        }
    }
    false
}

/// The paths a path-valued field holds.
fn paths_in(value: &sdf::Value) -> Vec<sdf::Path> {
    match value {
        sdf::Value::PathListOp(op) => op.iter().cloned().collect(),
        sdf::Value::PathVec(paths) => paths.clone(),
        sdf::Value::ReferenceListOp(op) => op.iter().map(|r| r.prim_path.clone()).collect(),
        sdf::Value::PayloadListOp(op) => op.iter().map(|p| p.prim_path.clone()).collect(),
        _ => Vec::new(),
    }
}

/// The `Mesh` prim named by `choice`, or the stage's only one.
fn choose_mesh(stage: &Stage, choice: Option<&str>) -> Result<Prim, String> {
    let mut meshes = Vec::new();
    let mut failure = None;
    stage
        .traverse(PrimPredicate::DEFAULT, |path| match stage.prim(path.clone()).type_name() {
            Ok(Some(kind)) if kind.as_str() == "Mesh" => meshes.push(path.clone()),
            Ok(_) => {}
            Err(e) => failure = Some(format!("{path}: {e:#}")),
        })
        .map_err(|e| format!("cannot traverse the stage: {e:#}"))?;
    if let Some(failure) = failure {
        return Err(failure);
    }
    let list = || meshes.iter().map(|p| p.as_str()).collect::<Vec<_>>().join(", ");
    match (choice, meshes.as_slice()) {
        (Some(choice), _) => match meshes.iter().find(|p| p.as_str() == choice) {
            Some(path) => Ok(stage.prim(path.clone())),
            None => Err(format!("no Mesh prim {choice}: the stage has {}", list())),
        },
        (None, [only]) => Ok(stage.prim(only.clone())),
        (None, []) => Err("no Mesh prim (an instanced mesh is not read)".into()),
        (None, _) => {
            Err(format!("{} Mesh prims, choose one with --mesh: {}", meshes.len(), list()))
        }
    }
}

/// One xformOp of a prim: what it does, whether it is inverted, and its attribute.
struct XformOp {
    kind: OpKind,
    inverse: bool,
    /// The op's attribute name, for errors.
    name: String,
    query: AttributeQuery,
}

#[derive(Clone, Copy, PartialEq)]
enum OpKind {
    Translate(Option<usize>),
    Scale(Option<usize>),
    /// A rotation about one axis, degrees.
    Rotate(usize),
    /// Three rotations, the axes in the order they are applied.
    RotateThree([usize; 3]),
    Orient,
    Transform,
}

/// The ops from the mesh up to the root, each prim's in `xformOpOrder`, the mesh's first: the
/// world transform is the product of the chain from its end (the root's first op) to its
/// start. An ancestor above a `!resetXformStack!` does not count.
fn transform_chain(mesh: &Prim) -> Result<Vec<XformOp>, String> {
    let mut chain = Vec::new();
    let mut path = Some(mesh.path().clone());
    while let Some(prim_path) = path.filter(|p| *p != sdf::Path::abs_root()) {
        let prim = mesh.stage().prim(prim_path.clone());
        let (ops, reset) = prim_ops(&prim)?;
        chain.extend(ops);
        if reset {
            break;
        }
        path = prim_path.parent();
    }
    Ok(chain)
}

/// A prim's ops in application order (the last listed, the most local, first), and whether it
/// resets the transform stack.
fn prim_ops(prim: &Prim) -> Result<(Vec<XformOp>, bool), String> {
    let name = prim.path().as_str();
    let order = prim.attribute("xformOpOrder");
    let order: Vec<String> = match order.get::<sdf::Value>() {
        Ok(None) => return Ok((Vec::new(), false)),
        Ok(Some(sdf::Value::TokenVec(tokens))) => {
            tokens.iter().map(|t| t.as_str().to_owned()).collect()
        }
        Ok(Some(other)) => return Err(format!("{name}.xformOpOrder is not a token[]: {other:?}")),
        Err(e) => return Err(format!("{name}.xformOpOrder: {e:#}")),
    };
    if order.iter().skip(1).any(|op| op == "!resetXformStack!") {
        return Err(format!("{name}.xformOpOrder: !resetXformStack! after the first op"));
    }
    let reset = order.first().is_some_and(|op| op == "!resetXformStack!");
    let ops = order.iter().skip(usize::from(reset)).rev().map(|op| xform_op(prim, op));
    Ok((ops.collect::<Result<_, _>>()?, reset))
}

fn xform_op(prim: &Prim, entry: &str) -> Result<XformOp, String> {
    let (inverse, attribute) = match entry.strip_prefix("!invert!") {
        Some(rest) => (true, rest),
        None => (false, entry),
    };
    let name = format!("{}.{attribute}", prim.path().as_str());
    // Never asked of openusd unless a property name: it cannot compose others (check_paths).
    let property = attribute.chars().all(|c| c.is_alphanumeric() || c == '_' || c == ':');
    let kind = attribute
        .strip_prefix("xformOp:")
        .filter(|_| property)
        .and_then(|rest| op_kind(rest.split(':').next().unwrap_or_default()))
        .ok_or_else(|| format!("{name}: not an xformOp this reader knows"))?;
    let query = AttributeQuery::new(&prim.attribute(attribute));
    Ok(XformOp { kind, inverse, name, query })
}

fn op_kind(kind: &str) -> Option<OpKind> {
    let axis = |c: u8| b"XYZ".iter().position(|&a| a == c);
    Some(match kind {
        "translate" => OpKind::Translate(None),
        "scale" => OpKind::Scale(None),
        "orient" => OpKind::Orient,
        "transform" => OpKind::Transform,
        _ => {
            let (single, rest) = ["translate", "scale", "rotate"]
                .iter()
                .find_map(|p| kind.strip_prefix(p).map(|rest| (*p, rest.as_bytes())))?;
            match (single, rest) {
                ("translate", [a]) => OpKind::Translate(Some(axis(*a)?)),
                ("scale", [a]) => OpKind::Scale(Some(axis(*a)?)),
                ("rotate", [a]) => OpKind::Rotate(axis(*a)?),
                ("rotate", [a, b, c]) => {
                    let axes = [axis(*a)?, axis(*b)?, axis(*c)?];
                    let distinct = axes[0] != axes[1] && axes[1] != axes[2] && axes[0] != axes[2];
                    distinct.then_some(OpKind::RotateThree(axes))?
                }
                _ => return None,
            }
        }
    })
}

/// The time codes to sample: the union of those of `points` and of every animated op, in
/// increasing order; `[None]` (the default time) when nothing is animated.
fn frame_codes(points: &AttributeQuery, chain: &[XformOp]) -> Result<Vec<Option<f64>>, String> {
    let mut codes = sample_times(points, "points")?;
    for op in chain {
        codes.extend(sample_times(&op.query, &op.name)?);
    }
    codes.sort_by(f64::total_cmp);
    codes.dedup();
    Ok(if codes.is_empty() { vec![None] } else { codes.into_iter().map(Some).collect() })
}

/// An attribute's sample times, refusing a spline (which openusd cannot evaluate) and a NaN key.
fn sample_times(query: &AttributeQuery, name: &str) -> Result<Vec<f64>, String> {
    let attribute = query.attribute();
    if attribute
        .get_metadata::<sdf::Value>("spline")
        .map_err(|e| format!("{name}: {e:#}"))?
        .is_some()
    {
        return Err(format!("{name} is a spline, which this reader cannot evaluate"));
    }
    let times = query.time_sample_times().map_err(|e| format!("{name}: {e:#}"))?;
    match times.iter().find(|t| !t.is_finite()) {
        Some(t) => Err(format!("{name} has a time sample at {t}")),
        None => Ok(times),
    }
}

/// The value of `query` at `code` (the default value for None).
fn value_at(query: &AttributeQuery, code: Option<f64>) -> Result<Option<sdf::Value>, String> {
    query.get_at::<sdf::Value>(code.map(TimeCode::new)).map_err(|e| format!("{e:#}"))
}

fn points_at(points: &AttributeQuery, code: Option<f64>) -> Result<Vec<DVec3>, String> {
    let at = || code.map_or("the default time".into(), |c| format!("time code {c}"));
    match value_at(points, code)? {
        Some(sdf::Value::Vec3fVec(p)) => {
            Ok(p.iter().map(|v| DVec3::new(v.x.into(), v.y.into(), v.z.into())).collect())
        }
        Some(sdf::Value::Vec3dVec(p)) => Ok(p.iter().map(|v| DVec3::new(v.x, v.y, v.z)).collect()),
        Some(sdf::Value::Vec3hVec(p)) => {
            Ok(p.iter().map(|v| DVec3::new(v.x.to_f64(), v.y.to_f64(), v.z.to_f64())).collect())
        }
        Some(other) => Err(format!("not an array of points at {}: {}", at(), kind_of(&other))),
        None => Err(format!("no value at {}", at())),
    }
}

/// The product of the chain's op matrices at `code` (column vectors: the first op of the
/// chain, the mesh's most local, applies first).
fn world_transform(chain: &[XformOp], code: Option<f64>) -> Result<DMat4, String> {
    chain.iter().try_fold(DMat4::IDENTITY, |world, op| Ok(op_matrix(op, code)? * world))
}

fn op_matrix(op: &XformOp, code: Option<f64>) -> Result<DMat4, String> {
    let value = value_at(&op.query, code)
        .map_err(|e| format!("{}: {e}", op.name))?
        .ok_or_else(|| format!("{}: named in xformOpOrder but has no value", op.name))?;
    let wrong = || format!("{}: a {} value for this op", op.name, kind_of(&value));
    let matrix = match op.kind {
        OpKind::Translate(None) => DMat4::from_translation(vector(&value).ok_or_else(wrong)?),
        OpKind::Scale(None) => DMat4::from_scale(vector(&value).ok_or_else(wrong)?),
        OpKind::Translate(Some(axis)) => DMat4::from_translation(
            DVec3::ZERO.with_element(axis, scalar(&value).ok_or_else(wrong)?),
        ),
        OpKind::Scale(Some(axis)) => {
            DMat4::from_scale(DVec3::ONE.with_element(axis, scalar(&value).ok_or_else(wrong)?))
        }
        OpKind::Rotate(axis) => rotation(axis, scalar(&value).ok_or_else(wrong)?),
        OpKind::RotateThree(axes) => {
            let degrees = vector(&value).ok_or_else(wrong)?;
            axes.iter().fold(DMat4::IDENTITY, |m, &a| rotation(a, degrees[a]) * m)
        }
        OpKind::Orient => {
            let q = quaternion(&value).ok_or_else(wrong)?;
            let length = q.length();
            if !(length.is_finite() && length > 0.0) {
                return Err(format!("{}: the quaternion {q} has no direction", op.name));
            }
            DMat4::from_quat(q / length)
        }
        // USD's matrices act on row vectors: its rows are glam's columns.
        OpKind::Transform => match &value {
            sdf::Value::Matrix4d(m) => DMat4::from_cols_array(&m.0),
            _ => return Err(wrong()),
        },
    };
    if !op.inverse {
        return Ok(matrix);
    }
    let det = matrix.determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(format!("{}: !invert! of a singular matrix", op.name));
    }
    Ok(matrix.inverse())
}

trait WithElement {
    fn with_element(self, axis: usize, value: f64) -> Self;
}

impl WithElement for DVec3 {
    fn with_element(mut self, axis: usize, value: f64) -> DVec3 {
        self[axis] = value;
        self
    }
}

fn rotation(axis: usize, degrees: f64) -> DMat4 {
    let angle = degrees.to_radians();
    [DMat4::from_rotation_x, DMat4::from_rotation_y, DMat4::from_rotation_z][axis](angle)
}

fn scalar(value: &sdf::Value) -> Option<f64> {
    match value {
        sdf::Value::Double(v) => Some(*v),
        sdf::Value::Float(v) => Some(f64::from(*v)),
        sdf::Value::Half(v) => Some(v.to_f64()),
        _ => None,
    }
}

fn vector(value: &sdf::Value) -> Option<DVec3> {
    match value {
        sdf::Value::Vec3d(v) => Some(DVec3::new(v.x, v.y, v.z)),
        sdf::Value::Vec3f(v) => Some(DVec3::new(v.x.into(), v.y.into(), v.z.into())),
        sdf::Value::Vec3h(v) => Some(DVec3::new(v.x.to_f64(), v.y.to_f64(), v.z.to_f64())),
        _ => None,
    }
}

/// A USD quaternion (real part first) as glam's (imaginary part first).
fn quaternion(value: &sdf::Value) -> Option<DQuat> {
    let (w, x, y, z) = match value {
        sdf::Value::Quatd(q) => (q.w, q.x, q.y, q.z),
        sdf::Value::Quatf(q) => (q.w.into(), q.x.into(), q.y.into(), q.z.into()),
        sdf::Value::Quath(q) => (q.w.to_f64(), q.x.to_f64(), q.y.to_f64(), q.z.to_f64()),
        _ => return None,
    };
    Some(DQuat::from_xyzw(x, y, z, w))
}

/// The name of a value's type, for errors.
fn kind_of(value: &sdf::Value) -> &'static str {
    value.into()
}

/// `faceVertexCounts` and `faceVertexIndices`, the same at every frame.
fn topology(mesh: &Prim, codes: &[Option<f64>]) -> Result<(Vec<u32>, Vec<u32>), String> {
    let read = |attribute: &str| -> Result<Vec<u32>, String> {
        let name = format!("{}.{attribute}", mesh.path().as_str());
        let query = AttributeQuery::new(&mesh.attribute(attribute));
        // Held, never interpolated: every frame's value is one of the samples, if any.
        let samples = sample_times(&query, &name)?;
        let at: Vec<Option<f64>> = if samples.is_empty() {
            codes.to_vec()
        } else {
            samples.into_iter().map(Some).collect()
        };
        let mut first: Option<Vec<i32>> = None;
        for code in at {
            let values = match value_at(&query, code).map_err(|e| format!("{name}: {e}"))? {
                Some(sdf::Value::IntVec(values)) => values,
                Some(other) => return Err(format!("{name} is not an int[]: {}", kind_of(&other))),
                None => return Err(format!("{name} is missing")),
            };
            match &first {
                Some(first) if *first != values => {
                    let at = code.unwrap_or_default();
                    return Err(format!("not one connectivity: {name} changes at time code {at}"));
                }
                Some(_) => {}
                None => first = Some(values),
            }
        }
        let values = first.unwrap_or_default();
        match values.iter().position(|&v| v < 0) {
            Some(i) => Err(format!("{name}[{i}] is {}", values[i])),
            None => Ok(values.into_iter().map(|v| v as u32).collect()),
        }
    };
    Ok((read("faceVertexCounts")?, read("faceVertexIndices")?))
}

const LEFT_HANDED: &str = "leftHanded";

/// The mesh's `orientation` token (USD's fallback `rightHanded` when unauthored).
fn orientation(mesh: &Prim) -> Result<String, String> {
    let name = format!("{}.orientation", mesh.path().as_str());
    match mesh.attribute("orientation").get::<sdf::Value>() {
        Ok(None) => Ok("rightHanded".into()),
        Ok(Some(sdf::Value::Token(t))) if ["rightHanded", LEFT_HANDED].contains(&t.as_str()) => {
            Ok(t.as_str().to_owned())
        }
        Ok(Some(other)) => Err(format!("{name} is {other:?}, not rightHanded or leftHanded")),
        Err(e) => Err(format!("{name}: {e:#}")),
    }
}

/// Reverses each polygon's vertex order, keeping its first vertex first. A polygon that runs
/// past the indices is left for [`SourceSequence::into_sequence`] to report.
fn reverse_polygons(counts: &[u32], indices: &mut [u32]) {
    let mut start = 0usize;
    for &count in counts {
        let end = start.saturating_add(count as usize);
        let Some(polygon) = indices.get_mut(start..end) else { return };
        polygon[1..].reverse();
        start = end;
    }
}

/// The stage's `upAxis`: Y (USD's fallback) when unauthored.
fn up_axis(stage: &Stage) -> Result<SignedAxis, String> {
    match stage.stage_metadata("upAxis").map_err(|e| format!("upAxis: {e:#}"))? {
        None => Ok(SignedAxis { axis: 1, negative: false }),
        Some(sdf::Value::Token(t)) if t.as_str() == "Y" => {
            Ok(SignedAxis { axis: 1, negative: false })
        }
        Some(sdf::Value::Token(t)) if t.as_str() == "Z" => {
            Ok(SignedAxis { axis: 2, negative: false })
        }
        Some(other) => Err(format!("upAxis is {other:?}, not Y or Z")),
    }
}

/// The stage's `metersPerUnit`: 0.01 (USD's fallback) when unauthored.
fn meters_per_unit(stage: &Stage) -> Result<f64, String> {
    let value =
        stage.stage_metadata("metersPerUnit").map_err(|e| format!("metersPerUnit: {e:#}"))?;
    match value.as_ref().map(scalar) {
        None => Ok(0.01),
        Some(Some(m)) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(format!("metersPerUnit is {value:?}, not a positive number")),
    }
}

fn notes(mesh: &str, codes: &[Option<f64>], rate: f64) -> Vec<String> {
    let frames = match codes {
        [None] => "no time samples: one frame, the default values".to_owned(),
        [Some(first), .., Some(last)] => format!(
            "{} frames: time codes {first} to {last} (those of points and of the animated xformOps), {rate} per second",
            codes.len()
        ),
        _ => format!("one frame: time code {}", codes[0].unwrap_or_default()),
    };
    vec![format!("mesh {mesh}"), frames]
}
