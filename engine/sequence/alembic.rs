//! Alembic mesh caches (the Ogawa form Maya, Houdini and Blender write): one PolyMesh's
//! time-sampled points `P` under its parent Xforms, evaluated at every sample time.
//!
//! The archive's layout on the Ogawa container ([`crate::io::ogawa`]), as the reference
//! library (AbcCoreOgawa) reads it:
//! - the root group: the file version, the library version, the top object, the archive's
//!   metadata, the table of time samplings and the indexed metadata;
//! - an object: a group of its property compound, its child objects, then a data block of the
//!   children's headers (name, metadata holding the `schema`) and 32 bytes of hashes;
//! - a compound: a group of its properties, then a data block of their headers (kind, plain
//!   type, sample count, the first and last sample that changed, time sampling, name);
//! - a property's samples: one data block each (a scalar) or a data and a dimensions block
//!   each (an array); each block is a 16-byte digest, then the values. Samples repeated at the
//!   start or the end are stored once.
//!
//! The sequence's frames are the sample times of `P` and of every ancestor Xform's values, in
//! seconds; each property is read at its sample nearest each frame (the reference library's
//! default). The world matrix composes the ancestors' xform ops, unless one says it does not
//! inherit. Alembic stores polygons clockwise; each is reversed into the counter-clockwise
//! order [`SourceSequence`] holds, so that Blender's export reads back with its own loops.

use super::source::{ReadOptions, SourceSequence};
use crate::io::ogawa::{Group, Ogawa};
use glam::{DMat4, DVec3};
use std::collections::HashSet;
use std::path::Path;

/// The schemas read as meshes: a subdivision surface is read as its control mesh.
const MESH_SCHEMAS: [&str; 2] = ["AbcGeom_PolyMesh_v1", "AbcGeom_SubD_v1"];
const XFORM_SCHEMA: &str = "AbcGeom_Xform_v3";
/// The time per cycle that marks an acyclic time sampling (the reference library's).
const ACYCLIC: f64 = f64::MAX / 32.0;

/// Plain-old-data types of property values, as the file numbers them.
const BOOL: u8 = 0;
const UINT8: u8 = 1;
const INT32: u8 = 6;
const FLOAT32: u8 = 10;
const FLOAT64: u8 = 11;
const LAST_POD: u8 = 13;

/// Reads the mesh `options.mesh` (an object path such as `/pCube1/pCubeShape1`; None: the
/// file's only mesh) at every sample time, in world space. Several meshes and no choice is an
/// error listing their paths. The topology must be one over all samples. Alembic records no up
/// axis or unit: Y-up is only a convention of the tools that write it, so `up` and
/// `meters_per_unit` stay None and the user says which with `--from-up`.
pub fn read(path: &Path, options: &ReadOptions) -> Result<SourceSequence, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
    let file = Ogawa::new(bytes)?;
    let archive = Archive::new(&file)?;
    let objects = archive.objects()?;
    let chosen = choose_mesh(&objects, options.mesh.as_deref())?;
    evaluate(&archive, &objects, chosen)
}

// ---------------------------------------------------------------------------------------------
// The archive: time samplings, indexed metadata, objects

/// When each sample index of a property falls, in seconds.
enum TimeSampling {
    /// `times` of each cycle, repeated every `period` (one time per cycle: uniform).
    Cyclic { times: Vec<f64>, period: f64 },
    /// One time per sample.
    Acyclic(Vec<f64>),
}

impl TimeSampling {
    /// The time of sample `i`, which [`Samples`] checked the sampling has.
    fn time(&self, i: u32) -> f64 {
        match self {
            TimeSampling::Cyclic { times, period } => {
                let n = times.len() as u32;
                times[(i % n) as usize] + period * (i / n) as f64
            }
            TimeSampling::Acyclic(times) => times[i as usize],
        }
    }
}

struct Archive<'a> {
    file: &'a Ogawa,
    top: Group<'a>,
    samplings: Vec<TimeSampling>,
    /// Metadata strings objects and properties refer to by index; 0 is the empty one.
    metadata: Vec<String>,
}

/// An object of the hierarchy: its path (`/a/b`; the top object's is empty), the `schema` of
/// its metadata, its group, and its parent's index.
struct Object<'a> {
    path: String,
    schema: String,
    group: Group<'a>,
    parent: Option<usize>,
}

impl<'a> Archive<'a> {
    fn new(file: &'a Ogawa) -> Result<Self, String> {
        let root = file.root()?;
        let layout = [true, true, false, true, true, true];
        if root.len() < 6 || layout.iter().enumerate().any(|(i, &data)| root.is_data(i) != data) {
            return Err("not an Alembic archive: its root group is not laid out as one".into());
        }
        let version = root.data(0)?;
        if version != [0; 4] {
            return Err(format!("Alembic Ogawa file version {version:?}; only version 0 is read"));
        }
        let mut metadata = vec![String::new()];
        let mut entries = Cursor::new(root.data(5)?, "the indexed metadata");
        while !entries.done() {
            let len = entries.u8()? as usize;
            metadata.push(String::from_utf8_lossy(entries.take(len)?).into_owned());
        }
        let samplings = time_samplings(root.data(4)?)?;
        Ok(Archive { file, top: root.group(2)?, samplings, metadata })
    }

    /// Every object, parents before children, each group visited once: a group reached twice
    /// is a cycle (or a shared object, which the format does not write).
    fn objects(&self) -> Result<Vec<Object<'a>>, String> {
        let top =
            Object { path: String::new(), schema: String::new(), group: self.top, parent: None };
        let mut objects = vec![top];
        let mut seen = HashSet::from([self.top.offset()]);
        let mut next = 0;
        while next < objects.len() {
            let parent = &objects[next];
            let mut children = Vec::new();
            for (k, (name, metadata)) in self.child_headers(parent)?.into_iter().enumerate() {
                let path = format!("{}/{name}", parent.path);
                let group = parent.group.group(k + 1).map_err(|e| format!("object {path}: {e}"))?;
                if group.offset() != 0 && !seen.insert(group.offset()) {
                    return Err(format!("object {path}: its group is reached twice (a cycle)"));
                }
                let schema = schema_of(&metadata).to_owned();
                children.push(Object { path, schema, group, parent: Some(next) });
            }
            objects.extend(children);
            next += 1;
        }
        Ok(objects)
    }

    /// The names and metadata of an object's children: the headers in its group's last data
    /// block, before 32 bytes of hashes.
    fn child_headers(&self, object: &Object) -> Result<Vec<(String, String)>, String> {
        let group = object.group;
        if group.is_empty() || !group.is_data(group.len() - 1) {
            return Ok(Vec::new());
        }
        let block = group.data(group.len() - 1)?;
        let what = format!("the child headers of object {}", shown(&object.path));
        let mut headers = Cursor::new(&block[..block.len().saturating_sub(32)], &what);
        let mut children = Vec::new();
        while !headers.done() {
            let len = headers.u32()? as usize;
            let name = String::from_utf8_lossy(headers.take(len)?).into_owned();
            if name.is_empty() || name.contains('/') {
                return Err(format!("{what}: a child is named {name:?}"));
            }
            let metadata = self.metadata_at(&mut headers, |c| Ok(c.u8()? as u32), |c| c.u32())?;
            children.push((name, metadata));
        }
        Ok(children)
    }

    /// Metadata by its index (`index` reads it) or, for index 255, inline (`len` reads its
    /// length).
    fn metadata_at(
        &self,
        at: &mut Cursor,
        index: impl Fn(&mut Cursor) -> Result<u32, String>,
        len: impl Fn(&mut Cursor) -> Result<u32, String>,
    ) -> Result<String, String> {
        match index(at)? {
            255 => {
                let n = len(at)? as usize;
                Ok(String::from_utf8_lossy(at.take(n)?).into_owned())
            }
            i => self.metadata.get(i as usize).cloned().ok_or_else(|| {
                format!("{}: metadata {i} of {} indexed", at.what, self.metadata.len())
            }),
        }
    }
}

/// The archive's table of time samplings: per entry the most samples any property has (not
/// needed), the time per cycle, and the times of one cycle (of every sample when acyclic).
fn time_samplings(block: &[u8]) -> Result<Vec<TimeSampling>, String> {
    let mut table = Cursor::new(block, "the time samplings");
    let mut samplings = Vec::new();
    while !table.done() {
        let k = samplings.len();
        let (_, period, n) = (table.u32()?, table.f64()?, table.u32()? as usize);
        if n == 0 || n > table.left() / 8 {
            return Err(format!("time sampling {k} claims {n} times"));
        }
        let times: Vec<f64> = (0..n).map(|_| table.f64()).collect::<Result<_, _>>()?;
        let increasing = times.windows(2).all(|w| w[0] < w[1]);
        if !times.iter().all(|t| t.is_finite()) || !increasing {
            return Err(format!("time sampling {k}: its times {times:?} are not increasing"));
        }
        if period == ACYCLIC {
            samplings.push(TimeSampling::Acyclic(times));
        } else if period.is_finite() && period > 0.0 && times[n - 1] - times[0] <= period {
            samplings.push(TimeSampling::Cyclic { times, period });
        } else {
            return Err(format!("time sampling {k}: {period} s per cycle of {n} times"));
        }
    }
    Ok(samplings)
}

/// The `schema` of an object's metadata (`key=value` pairs separated by `;`).
fn schema_of(metadata: &str) -> &str {
    metadata.split(';').find_map(|pair| pair.strip_prefix("schema=")).unwrap_or("")
}

/// An object path for messages: the top object's is `/`.
fn shown(path: &str) -> &str {
    if path.is_empty() {
        "/"
    } else {
        path
    }
}

// ---------------------------------------------------------------------------------------------
// Bytes, compounds and samples

/// Reads a block front to back; errors name `what`.
struct Cursor<'b> {
    bytes: &'b [u8],
    what: String,
}

impl<'b> Cursor<'b> {
    fn new(bytes: &'b [u8], what: &str) -> Self {
        Cursor { bytes, what: what.to_owned() }
    }

    fn done(&self) -> bool {
        self.bytes.is_empty()
    }

    fn left(&self) -> usize {
        self.bytes.len()
    }

    fn take(&mut self, n: usize) -> Result<&'b [u8], String> {
        if n > self.bytes.len() {
            return Err(format!("{}: {n} bytes wanted, {} left", self.what, self.bytes.len()));
        }
        let (taken, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(taken)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    /// A number of 1, 2 or 4 bytes as a property header's size hint says.
    fn sized(&mut self, hint: u32) -> Result<u32, String> {
        match hint {
            0 => Ok(self.u8()? as u32),
            1 => Ok(u16::from_le_bytes(self.take(2)?.try_into().expect("2 bytes")) as u32),
            2 => self.u32(),
            _ => Err(format!("{}: size hint {hint}", self.what)),
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Compound,
    Scalar,
    Array,
}

/// A property's header.
struct Property {
    name: String,
    kind: Kind,
    pod: u8,
    extent: u8,
    /// Sample indices the property has, repeated ones included.
    samples: u32,
    /// The first and last sample that differ from their predecessor (both 0: constant).
    first: u32,
    last: u32,
    sampling: usize,
}

/// A compound property: its group (one child per property, then the headers) and headers.
struct Compound<'a> {
    /// The object path and property names, for messages.
    path: String,
    group: Group<'a>,
    properties: Vec<Property>,
}

impl<'a> Compound<'a> {
    /// An object's top compound (its group's first child).
    fn of_object(archive: &Archive, object: &Object<'a>) -> Result<Self, String> {
        let path = shown(&object.path).to_owned();
        if object.group.is_empty() {
            return Ok(Compound { path, group: object.group, properties: Vec::new() });
        }
        let group = object.group.group(0).map_err(|e| format!("object {path}: {e}"))?;
        Compound::new(archive, path, group)
    }

    fn new(archive: &Archive, path: String, group: Group<'a>) -> Result<Self, String> {
        let mut properties = Vec::new();
        if !group.is_empty() && group.is_data(group.len() - 1) {
            let what = format!("the property headers of {path}");
            let mut headers = Cursor::new(group.data(group.len() - 1)?, &what);
            while !headers.done() {
                properties.push(property_header(archive, &mut headers)?);
            }
        }
        Ok(Compound { path, group, properties })
    }

    /// The property `name`'s index and header, if the compound has it.
    fn find(&self, name: &str) -> Option<(usize, &Property)> {
        self.properties.iter().enumerate().find(|(_, p)| p.name == name)
    }

    /// The compound property `name`.
    fn compound(&self, archive: &Archive, name: &str) -> Result<Compound<'a>, String> {
        let path = format!("{}/{name}", self.path);
        match self.find(name) {
            Some((i, p)) if p.kind == Kind::Compound => {
                Compound::new(archive, path, self.group.group(i)?)
            }
            _ => Err(format!("{path} is missing")),
        }
    }

    /// The samples of property `name`, of plain type `pod` (and `extent` values per element
    /// when given); None when the compound has no such property.
    fn samples(
        &self,
        archive: &Archive,
        name: &str,
        pod: u8,
        extent: Option<u8>,
    ) -> Result<Option<Samples<'a>>, String> {
        let Some((i, p)) = self.find(name) else { return Ok(None) };
        let path = format!("{}/{name}", self.path);
        let typed = p.pod == pod && extent.is_none_or(|e| e == p.extent);
        if p.kind == Kind::Compound || !typed {
            return Err(format!("{path} has plain type {} × {}, expected {pod}", p.pod, p.extent));
        }
        if p.sampling >= archive.samplings.len() {
            return Err(format!(
                "{path} names time sampling {}, the file has {}",
                p.sampling,
                archive.samplings.len()
            ));
        }
        if let TimeSampling::Acyclic(times) = &archive.samplings[p.sampling] {
            if p.samples as usize > times.len() {
                return Err(format!("{path} has {} samples and {} times", p.samples, times.len()));
            }
        }
        let (array, samples, first, last, sampling) =
            (p.kind == Kind::Array, p.samples, p.first, p.last, p.sampling);
        let group = self.group.group(i)?;
        Ok(Some(Samples { path, group, array, samples, first, last, sampling }))
    }
}

/// One property header, as the reference library's `ReadPropertyHeaders` lays it out: an info
/// word (kind, size hint, type, which counts follow, extent, metadata index), the sample
/// count, the first and last changed samples, the time sampling, the name, inline metadata.
fn property_header(archive: &Archive, at: &mut Cursor) -> Result<Property, String> {
    let info = at.u32()?;
    let kind = match info & 3 {
        0 => Kind::Compound,
        1 => Kind::Scalar,
        _ => Kind::Array,
    };
    let hint = (info >> 2) & 3;
    let mut property = Property {
        name: String::new(),
        kind,
        pod: ((info >> 4) & 0xF) as u8,
        extent: ((info >> 12) & 0xFF) as u8,
        samples: 0,
        first: 0,
        last: 0,
        sampling: 0,
    };
    if kind != Kind::Compound {
        if property.pod > LAST_POD {
            return Err(format!("{}: plain type {}", at.what, property.pod));
        }
        property.samples = at.sized(hint)?;
        (property.first, property.last) = if info & 0x200 != 0 {
            (at.sized(hint)?, at.sized(hint)?)
        } else if info & 0x800 != 0 {
            (0, 0)
        } else {
            (1, property.samples.saturating_sub(1))
        };
        if info & 0x100 != 0 {
            property.sampling = at.sized(hint)? as usize;
        }
    }
    let len = at.sized(hint)? as usize;
    property.name = String::from_utf8_lossy(at.take(len)?).into_owned();
    let index = |_: &mut Cursor| Ok((info >> 20) & 0xFF);
    archive.metadata_at(at, index, |c| c.sized(hint))?;
    Ok(property)
}

/// The samples of a scalar or array property.
struct Samples<'a> {
    path: String,
    group: Group<'a>,
    array: bool,
    samples: u32,
    first: u32,
    last: u32,
    sampling: usize,
}

impl<'a> Samples<'a> {
    /// Which stored sample holds sample `i`: repeats of the first are not stored, nor those
    /// after the last that changed (the reference library's `verifyIndex`).
    fn stored(&self, i: u32) -> Result<usize, String> {
        let (first, last, i) = (self.first as i64, self.last as i64, i as i64);
        let stored = if i < first || (first == 0 && last == 0) {
            0
        } else if i >= last {
            last - first + 1
        } else {
            i - first + 1
        };
        usize::try_from(stored)
            .map_err(|_| format!("{}: changed samples {first}..{last}", self.path))
    }

    /// How many samples are stored.
    fn stored_count(&self) -> Result<usize, String> {
        Ok(self.stored(self.samples.saturating_sub(1))? + 1)
    }

    /// The values of stored sample `k`, after its 16-byte digest.
    fn stored_bytes(&self, k: usize) -> Result<&'a [u8], String> {
        let child = if self.array { 2 * k } else { k };
        let block = self.group.data(child).map_err(|e| format!("{}: {e}", self.path))?;
        match block.len() {
            0 => Ok(block),
            1..16 => Err(format!("{}: a sample of {} bytes", self.path, block.len())),
            _ => Ok(&block[16..]),
        }
    }

    /// The values of sample `i`, `N` bytes each, decoded by `value`.
    fn values<const N: usize, T>(&self, i: u32, value: fn([u8; N]) -> T) -> Result<Vec<T>, String> {
        let bytes = self.stored_bytes(self.stored(i)?)?;
        if bytes.len() % N != 0 {
            return Err(format!(
                "{}: sample {i} has {} bytes, not a multiple of {N}",
                self.path,
                bytes.len()
            ));
        }
        Ok(bytes.chunks_exact(N).map(|c| value(c.try_into().expect("N bytes"))).collect())
    }

    /// The sample nearest time `t`, by bisection: sample times increase with the index.
    fn near(&self, samplings: &[TimeSampling], t: f64) -> u32 {
        let sampling = &samplings[self.sampling];
        let (mut low, mut high) = (0, self.samples.saturating_sub(1));
        while low < high {
            let middle = low + (high - low).div_ceil(2);
            if sampling.time(middle) <= t {
                low = middle;
            } else {
                high = middle - 1;
            }
        }
        let later = low + 1 < self.samples && sampling.time(low + 1) - t < t - sampling.time(low);
        low + later as u32
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes and xforms

/// The object `wanted` names, or the file's only mesh.
fn choose_mesh(objects: &[Object], wanted: Option<&str>) -> Result<usize, String> {
    let meshes: Vec<usize> = (0..objects.len())
        .filter(|&i| MESH_SCHEMAS.contains(&objects[i].schema.as_str()))
        .collect();
    let list = || meshes.iter().map(|&i| objects[i].path.as_str()).collect::<Vec<_>>().join(", ");
    match (wanted, meshes.len()) {
        (Some(wanted), _) => {
            let path = format!("/{}", wanted.trim_start_matches('/'));
            meshes
                .iter()
                .copied()
                .find(|&i| objects[i].path == path)
                .ok_or_else(|| format!("no mesh {path} in the file; its meshes: {}", list()))
        }
        (None, 1) => Ok(meshes[0]),
        (None, 0) => Err("the file holds no PolyMesh".into()),
        (None, n) => Err(format!("{n} meshes: {}; choose one with --mesh PATH", list())),
    }
}

/// A mesh's points and its one face list, reversed into counter-clockwise order.
struct Mesh<'a> {
    points: Samples<'a>,
    counts: Vec<u32>,
    indices: Vec<u32>,
}

impl<'a> Mesh<'a> {
    fn read(archive: &Archive, object: &Object<'a>) -> Result<Self, String> {
        let geometry = Compound::of_object(archive, object)?.compound(archive, ".geom")?;
        let required = |name, pod, extent| {
            geometry
                .samples(archive, name, pod, Some(extent))?
                .ok_or_else(|| format!("{}/{name} is missing", geometry.path))
        };
        let points = required("P", FLOAT32, 3)?;
        let counts = one_connectivity(&required(".faceCounts", INT32, 1)?)?;
        let indices = one_connectivity(&required(".faceIndices", INT32, 1)?)?;
        if counts.iter().map(|&c| c as u64).sum::<u64>() != indices.len() as u64 {
            return Err(format!(
                "{}: the face counts add up to {} indices, there are {}",
                geometry.path,
                counts.iter().map(|&c| c as u64).sum::<u64>(),
                indices.len()
            ));
        }
        let indices = reversed(&counts, &indices);
        Ok(Mesh { points, counts, indices })
    }

    /// The positions of the points' sample `i`.
    fn positions(&self, i: u32) -> Result<Vec<[f32; 3]>, String> {
        self.points.values(i, |b: [u8; 12]| {
            let c = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
            [c(0), c(4), c(8)]
        })
    }
}

/// Sample 0 of an int32 property whose every stored sample must equal it, as non-negative
/// numbers.
fn one_connectivity(samples: &Samples) -> Result<Vec<u32>, String> {
    if samples.samples == 0 {
        return Err(format!("{} has no samples", samples.path));
    }
    let first = samples.stored_bytes(0)?;
    for k in 1..samples.stored_count()? {
        if samples.stored_bytes(k)? != first {
            let sample = k as u64 + samples.first.max(1) as u64 - 1;
            return Err(format!(
                "not one connectivity: {} changes at sample {sample} (topology that changes \
                 over time cannot be tracked)",
                samples.path
            ));
        }
    }
    let values = samples.values(0, i32::from_le_bytes)?;
    values
        .iter()
        .map(|&v| u32::try_from(v))
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{} holds a negative number", samples.path))
}

/// Each polygon's indices in reverse order: counter-clockwise, and Blender's own loop order
/// for a file Blender wrote (it reverses its loops on export, starting vertex included).
fn reversed(counts: &[u32], indices: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(indices.len());
    let mut start = 0;
    for &count in counts {
        out.extend(indices[start..start + count as usize].iter().rev());
        start += count as usize;
    }
    out
}

/// An Xform's ops (the type in the high nibble, a hint in the low one), their channel values
/// over time, and whether it inherits its parent's transform.
struct Xform<'a> {
    ops: Vec<u8>,
    values: Option<Samples<'a>>,
    inherits: Option<Samples<'a>>,
}

impl<'a> Xform<'a> {
    fn read(archive: &Archive, object: &Object<'a>) -> Result<Self, String> {
        let xform = Compound::of_object(archive, object)?.compound(archive, ".xform")?;
        let ops = match xform.samples(archive, ".ops", UINT8, None)? {
            Some(ops) if ops.samples > 0 => ops.values(0, u8::from_le_bytes)?,
            _ => Vec::new(),
        };
        let values = xform.samples(archive, ".vals", FLOAT64, None)?;
        let inherits = xform.samples(archive, ".inherits", BOOL, Some(1))?;
        let needed: usize = ops.iter().map(|&op| channels(op).unwrap_or(0)).sum();
        if needed > 0 && values.as_ref().is_none_or(|v| v.samples == 0) {
            return Err(format!("{}: ops without channel values", xform.path));
        }
        Ok(Xform { ops, values, inherits })
    }

    /// The samples whose times make frames: those of properties that change.
    fn animated(&self) -> impl Iterator<Item = &Samples<'a>> {
        [&self.values, &self.inherits].into_iter().flatten().filter(|s| s.samples > 1)
    }

    /// The local matrix (column vectors) at time `t`, and whether it inherits its parent's.
    fn at(&self, samplings: &[TimeSampling], t: f64) -> Result<(DMat4, bool), String> {
        let inherits = match &self.inherits {
            Some(s) if s.samples > 0 => s.values(s.near(samplings, t), |[b]: [u8; 1]| b != 0)?,
            _ => vec![true],
        };
        let Some(values) = self.values.as_ref().filter(|v| v.samples > 0) else {
            return Ok((DMat4::IDENTITY, inherits.first() != Some(&false)));
        };
        let i = values.near(samplings, t);
        let channels = values.values(i, f64::from_le_bytes)?;
        let matrix = compose(&self.ops, &channels)
            .map_err(|e| format!("{} sample {i}: {e}", values.path))?;
        Ok((matrix, inherits.first() != Some(&false)))
    }
}

/// How many channels an op reads: scale and translate 3, rotate 4 (axis, degrees), matrix 16,
/// rotate about X, Y or Z 1.
fn channels(op: u8) -> Option<usize> {
    match op >> 4 {
        0 | 1 => Some(3),
        2 => Some(4),
        3 => Some(16),
        4..=6 => Some(1),
        _ => None,
    }
}

/// The ops' product, the first op outermost (the reference library's `XformSample::getMatrix`,
/// in column-vector form): `channel` values are consumed in op order.
fn compose(ops: &[u8], values: &[f64]) -> Result<DMat4, String> {
    let mut matrix = DMat4::IDENTITY;
    let mut rest = values;
    for &op in ops {
        let n = channels(op).ok_or_else(|| format!("unknown xform op {op:#04x}"))?;
        if rest.len() < n {
            return Err(format!(
                "{} channel values for the ops' {}",
                values.len(),
                ops.iter().map(|&o| channels(o).unwrap_or(0)).sum::<usize>()
            ));
        }
        let (c, after) = rest.split_at(n);
        rest = after;
        if !c.iter().all(|v| v.is_finite()) {
            return Err(format!("op {op:#04x} has channel values {c:?}"));
        }
        matrix *= match op >> 4 {
            0 => DMat4::from_scale(DVec3::new(c[0], c[1], c[2])),
            1 => DMat4::from_translation(DVec3::new(c[0], c[1], c[2])),
            2 => {
                let axis = DVec3::new(c[0], c[1], c[2])
                    .try_normalize()
                    .ok_or_else(|| format!("a rotation about the axis {:?}", &c[..3]))?;
                DMat4::from_axis_angle(axis, c[3].to_radians())
            }
            // Stored row by row for row vectors: the same numbers are its transpose's columns.
            3 => DMat4::from_cols_array(c.try_into().expect("16 channels")),
            4 => DMat4::from_rotation_x(c[0].to_radians()),
            5 => DMat4::from_rotation_y(c[0].to_radians()),
            _ => DMat4::from_rotation_z(c[0].to_radians()),
        };
    }
    Ok(matrix)
}

// ---------------------------------------------------------------------------------------------
// Evaluation

/// The most frames of `n` points a file of `file` bytes may expand to: repeated samples are
/// stored once, so a small file may hold many frames, but not more than 512 output bytes per
/// file byte and 32 MiB (a static 10 000-point mesh under 1 000 animated xform samples fits).
fn frame_limit(file: usize, n: usize) -> usize {
    (512 * file + (32 << 20)) / (12 * n + 32)
}

/// The mesh `m` at every frame time, in world space.
fn evaluate(archive: &Archive, objects: &[Object], m: usize) -> Result<SourceSequence, String> {
    let object = &objects[m];
    let mesh = Mesh::read(archive, object)?;
    if mesh.points.samples == 0 {
        return Err(format!("{} has no samples", mesh.points.path));
    }
    let xforms = ancestors(objects, m)
        .filter(|o| o.schema == XFORM_SCHEMA)
        .map(|o| Xform::read(archive, o))
        .collect::<Result<Vec<_>, _>>()?;
    let n = mesh.positions(0)?.len();
    let limit = frame_limit(archive.file.len(), n);
    let animated = std::iter::once(&mesh.points).filter(|p| p.samples > 1);
    let mut times = Vec::new();
    for samples in animated.chain(xforms.iter().flat_map(Xform::animated)) {
        if samples.samples as usize > limit {
            return Err(too_many(object, limit, n, archive.file.len()));
        }
        let sampling = &archive.samplings[samples.sampling];
        times = merged(times, (0..samples.samples).map(|i| sampling.time(i)), limit)
            .map_err(|count| too_many(object, count, n, archive.file.len()))?;
    }
    if times.is_empty() {
        times.push(archive.samplings[mesh.points.sampling].time(0));
    }
    let mut frames = Vec::with_capacity(times.len());
    for &t in &times {
        frames.push(world_positions(archive, &mesh, &xforms, t)?);
    }
    let (first, last) = (times[0], times[times.len() - 1]);
    let subd = if object.schema == MESH_SCHEMAS[1] { ", a SubD read as its cage" } else { "" };
    let notes = vec![format!(
        "Alembic mesh {}{subd}: {} samples from {first} s to {last} s, through {} xform(s)",
        object.path,
        frames.len(),
        xforms.len()
    )];
    Ok(SourceSequence {
        counts: mesh.counts,
        indices: mesh.indices,
        frames,
        times,
        notes,
        ..SourceSequence::default()
    })
}

fn too_many(object: &Object, count: usize, n: usize, file: usize) -> String {
    format!(
        "{}: over {count} samples of {n} points, more than a {file}-byte file can justify",
        object.path
    )
}

/// The object's ancestors, the top one first.
fn ancestors<'o, 'a>(objects: &'o [Object<'a>], m: usize) -> impl Iterator<Item = &'o Object<'a>> {
    let mut chain = Vec::new();
    let mut at = objects[m].parent;
    while let Some(p) = at {
        chain.push(&objects[p]);
        at = objects[p].parent;
    }
    chain.into_iter().rev()
}

/// The sorted union of `times` and the increasing `more`, times within 1e-9 s merged; Err with
/// the count when it grows past `limit`.
fn merged(
    times: Vec<f64>,
    more: impl Iterator<Item = f64>,
    limit: usize,
) -> Result<Vec<f64>, usize> {
    let mut out = Vec::with_capacity(times.len());
    let mut old = times.into_iter().peekable();
    for t in more {
        while let Some(&s) = old.peek().filter(|&&s| s < t) {
            push_time(&mut out, s, limit)?;
            old.next();
        }
        push_time(&mut out, t, limit)?;
    }
    for s in old {
        push_time(&mut out, s, limit)?;
    }
    Ok(out)
}

fn push_time(times: &mut Vec<f64>, t: f64, limit: usize) -> Result<(), usize> {
    if times.last().is_none_or(|&last| t - last > 1e-9) {
        if times.len() == limit {
            return Err(limit);
        }
        times.push(t);
    }
    Ok(())
}

/// The mesh's points nearest time `t`, through the ancestors' matrices there.
fn world_positions(
    archive: &Archive,
    mesh: &Mesh,
    xforms: &[Xform],
    t: f64,
) -> Result<Vec<[f32; 3]>, String> {
    let mut world = DMat4::IDENTITY;
    for xform in xforms {
        let (local, inherits) = xform.at(&archive.samplings, t)?;
        world = if inherits { world * local } else { local };
    }
    let mut positions = mesh.positions(mesh.points.near(&archive.samplings, t))?;
    if world != DMat4::IDENTITY {
        for p in &mut positions {
            let q = world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
            *p = [q.x as f32, q.y as f32, q.z as f32];
        }
    }
    Ok(positions)
}
