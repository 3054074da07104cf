//! glTF accessors read against their buffers: every offset, stride and count from the file is
//! checked (with overflow checks) against the bytes it points into, and every materialised
//! value is charged to a [`Budget`] before it is allocated, so that a hostile count can neither
//! read past a buffer nor allocate what the file's size does not justify.

use gltf::accessor::{sparse::IndexType, DataType, Dimensions};
use std::cell::Cell;

/// The least any budget grants, bytes: small files are not held to a few kilobytes, yet one
/// edited count in a kilobyte file cannot make the reader allocate hundreds of megabytes.
const BUDGET_FLOOR: usize = 8 << 20;

/// Bytes a reader may materialise: at least `BUDGET_FLOOR` (8 MiB), else `per_byte` per byte of the
/// file (its JSON and buffers).
pub struct Budget {
    limit: usize,
    spent: Cell<usize>,
}

impl Budget {
    /// A budget of `per_byte` bytes per byte of a `file_bytes` file, at least the floor.
    pub fn new(file_bytes: usize, per_byte: usize) -> Self {
        Self { limit: file_bytes.saturating_mul(per_byte).max(BUDGET_FLOOR), spent: Cell::new(0) }
    }

    /// Charges `count` items (None: more than a usize holds) of `bytes` each, before they are
    /// allocated; returns `count`. `what` names them in the error.
    pub fn charge(
        &self,
        count: Option<usize>,
        bytes: usize,
        what: impl FnOnce() -> String,
    ) -> Result<usize, String> {
        let total = count.and_then(|n| n.checked_mul(bytes)?.checked_add(self.spent.get()));
        match (count, total) {
            (Some(count), Some(total)) if total <= self.limit => {
                self.spent.set(total);
                Ok(count)
            }
            _ => Err(format!(
                "{} would take more than the {} MiB this file's size allows",
                what(),
                self.limit >> 20
            )),
        }
    }
}

/// The file's buffers and the budget every accessor read is charged to.
pub struct Accessors<'a> {
    buffers: &'a [Vec<u8>],
    budget: Budget,
}

/// One accessor's values as f64 (exact for every component type): `count` elements of
/// `components` values, flat.
pub struct Values {
    /// The values, element after element.
    pub data: Vec<f64>,
    /// Values per element (1 for SCALAR, 3 for VEC3, 16 for MAT4).
    pub components: usize,
}

impl Values {
    /// The number of elements.
    pub fn count(&self) -> usize {
        self.data.len() / self.components.max(1)
    }
}

impl<'a> Accessors<'a> {
    /// Reads from `buffers` (indexed as the document's buffers), charging `budget`.
    pub fn new(buffers: &'a [Vec<u8>], budget: Budget) -> Self {
        Self { buffers, budget }
    }

    /// The budget, for what a reader allocates beside accessors.
    pub fn budget(&self) -> &Budget {
        &self.budget
    }

    /// Accessor `a`'s values, sparse substitutions applied and, where the accessor says
    /// `normalized`, integers mapped to [0, 1] or [−1, 1] as the glTF specification's
    /// formulas do (c / 255, max(c / 127, −1), …).
    pub fn read(&self, a: &gltf::Accessor) -> Result<Values, String> {
        let index = a.index();
        let components = components(a.dimensions(), a.data_type()).ok_or_else(|| {
            format!("accessor {index}: {:?} of {:?} is not read", a.dimensions(), a.data_type())
        })?;
        let total = self.budget.charge(a.count().checked_mul(components), 8, || {
            format!("accessor {index} ({} elements of {:?})", a.count(), a.dimensions())
        })?;
        let mut data = match a.view() {
            Some(view) => self.elements(&view, a.offset(), a.data_type(), a.count(), components)?,
            None => vec![0.0; total],
        };
        if let Some(sparse) = a.sparse() {
            let count = sparse.count();
            if count > a.count() {
                return Err(format!(
                    "accessor {index}: {count} sparse values for {} elements",
                    a.count()
                ));
            }
            let indices = sparse.indices();
            let index_type = match indices.index_type() {
                IndexType::U8 => DataType::U8,
                IndexType::U16 => DataType::U16,
                IndexType::U32 => DataType::U32,
            };
            let targets = self.elements(&indices.view(), indices.offset(), index_type, count, 1)?;
            let values = sparse.values();
            let replacements =
                self.elements(&values.view(), values.offset(), a.data_type(), count, components)?;
            for (k, &element) in targets.iter().enumerate() {
                let element = element as usize;
                if element >= a.count() {
                    return Err(format!(
                        "accessor {index}: sparse index {element} is past its {} elements",
                        a.count()
                    ));
                }
                data[element * components..(element + 1) * components]
                    .copy_from_slice(&replacements[k * components..(k + 1) * components]);
            }
        }
        if a.normalized() {
            let unit = normalisation(a.data_type());
            data.iter_mut().for_each(|c| *c = unit(*c));
        }
        Ok(Values { data, components })
    }

    /// A VEC3 accessor's values as f32 triples: what [`Self::read`] gives, rounded to f32, and
    /// for a plain F32 accessor (no sparse part: what positions and morph targets are) read
    /// straight from its bytes, without the f64 copy that would double a large file's memory.
    pub fn read_vec3_f32(&self, a: &gltf::Accessor) -> Result<Vec<[f32; 3]>, String> {
        let index = a.index();
        if a.dimensions() != Dimensions::Vec3 {
            return Err(format!("accessor {index} is not VEC3"));
        }
        let plain = a.data_type() == DataType::F32 && a.sparse().is_none();
        let Some(view) = a.view().filter(|_| plain) else {
            let values = self.read(a)?;
            return Ok(values
                .data
                .chunks_exact(3)
                .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32])
                .collect());
        };
        self.budget.charge(Some(a.count()), 12, || {
            format!("accessor {index} ({} elements of VEC3)", a.count())
        })?;
        let (data, stride) = self.view_bytes(&view, a.offset(), 12, a.count())?;
        let float = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        Ok((0..a.count())
            .map(|i| &data[a.offset() + i * stride..][..12])
            .map(|b| [float(&b[0..4]), float(&b[4..8]), float(&b[8..12])])
            .collect())
    }

    /// `count` elements of `components` values of `data_type` from `view`, starting `offset`
    /// bytes into it, `view.stride()` bytes apart (tightly packed without one).
    fn elements(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        data_type: DataType,
        count: usize,
        components: usize,
    ) -> Result<Vec<f64>, String> {
        let size = data_type.size();
        let (data, stride) = self.view_bytes(view, offset, size * components, count)?;
        let mut out = Vec::with_capacity(count * components);
        for i in 0..count {
            for c in 0..components {
                let at = offset + i * stride + c * size;
                out.push(decode(data_type, &data[at..at + size]));
            }
        }
        Ok(out)
    }

    /// The bytes of `view` and its stride, checked to hold `count` elements of `element` bytes
    /// from `offset` on.
    fn view_bytes(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        element: usize,
        count: usize,
    ) -> Result<(&'a [u8], usize), String> {
        let name = view.index();
        let buffer = self
            .buffers
            .get(view.buffer().index())
            .ok_or_else(|| format!("buffer view {name} refers to a missing buffer"))?;
        let data = view
            .offset()
            .checked_add(view.length())
            .and_then(|end| buffer.get(view.offset()..end))
            .ok_or_else(|| {
                format!(
                    "buffer view {name} (bytes {} + {}) runs past its buffer of {} bytes",
                    view.offset(),
                    view.length(),
                    buffer.len()
                )
            })?;
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(format!(
                "buffer view {name} has a byte stride of {stride}, smaller than one element \
                 ({element} bytes)"
            ));
        }
        let needed = match count.checked_sub(1) {
            None => Some(0),
            Some(last) => {
                last.checked_mul(stride).and_then(|n| n.checked_add(offset)?.checked_add(element))
            }
        };
        if needed.is_none_or(|needed| needed > data.len()) {
            return Err(format!(
                "{count} elements of {element} bytes, {stride} apart from byte {offset}, do not \
                 fit buffer view {name} ({} bytes)",
                data.len()
            ));
        }
        Ok((data, stride))
    }
}

/// Values per element; None for the matrix types whose columns glTF pads (MAT2 of 1-byte,
/// MAT3 of 1- and 2-byte components), which no attribute this reader uses can be.
fn components(dimensions: Dimensions, data_type: DataType) -> Option<usize> {
    let padded = match dimensions {
        Dimensions::Mat2 => data_type.size() == 1,
        Dimensions::Mat3 => data_type.size() < 4,
        _ => false,
    };
    (!padded).then(|| dimensions.multiplicity())
}

/// One little-endian component of `data_type` from `b` (exactly its size).
fn decode(data_type: DataType, b: &[u8]) -> f64 {
    match data_type {
        DataType::I8 => b[0] as i8 as f64,
        DataType::U8 => b[0] as f64,
        DataType::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
        DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

/// The glTF specification's mapping of a normalised integer component to a real number.
fn normalisation(data_type: DataType) -> fn(f64) -> f64 {
    match data_type {
        DataType::I8 => |c| (c / 127.0).max(-1.0),
        DataType::U8 => |c| c / 255.0,
        DataType::I16 => |c| (c / 32767.0).max(-1.0),
        DataType::U16 => |c| c / 65535.0,
        DataType::U32 | DataType::F32 => |c| c,
    }
}
