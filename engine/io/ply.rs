//! PLY, the generic way: any elements with scalar and list properties, read from ascii,
//! binary_little_endian or binary_big_endian files, written as binary little endian.
//!
//! Values are kept per property in a column of their own kind (f32, f64, or integers as i64),
//! so a 3DGS scene of f32 properties takes no more memory than the file, and integers survive
//! exactly. Typed accessors convert and name the file, element and property on any mismatch.

use std::io::Write;
use std::path::{Path, PathBuf};

/// An error that names the PLY file and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct PlyError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: String,
}

fn error(path: &Path, problem: impl Into<String>) -> PlyError {
    PlyError { path: path.to_path_buf(), problem: problem.into() }
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarType {
    /// `char` / `int8`.
    I8,
    /// `uchar` / `uint8`.
    U8,
    /// `short` / `int16`.
    I16,
    /// `ushort` / `uint16`.
    U16,
    /// `int` / `int32`.
    I32,
    /// `uint` / `uint32`.
    U32,
    /// `float` / `float32`.
    F32,
    /// `double` / `float64`.
    F64,
}

impl ScalarType {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Self::I8 => "char",
            Self::U8 => "uchar",
            Self::I16 => "short",
            Self::U16 => "ushort",
            Self::I32 => "int",
            Self::U32 => "uint",
            Self::F32 => "float",
            Self::F64 => "double",
        }
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

/// The shape of a property: one scalar per row, or a list per row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PropertyKind {
    /// One value of this type per row.
    Scalar(ScalarType),
    /// A count, then that many items, per row.
    List {
        /// Type of the count before each row (an integer type).
        count: ScalarType,
        /// Type of the items.
        item: ScalarType,
    },
}

impl PropertyKind {
    /// The fewest bytes one row of this property takes in a binary body (an empty list is its
    /// count alone).
    fn minimum_bytes(&self) -> usize {
        match self {
            Self::Scalar(ty) | Self::List { count: ty, .. } => ty.size(),
        }
    }
}

/// One property of an element, as declared in the header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Property {
    /// Name of the property.
    pub name: String,
    /// Its type.
    pub kind: PropertyKind,
}

/// Values of one property, in the kind the file stores.
#[derive(Clone, Debug)]
enum Column {
    F32(Vec<f32>),
    F64(Vec<f64>),
    Int(Vec<i64>),
}

impl Column {
    fn for_type(ty: ScalarType) -> Self {
        match ty {
            ScalarType::F32 => Self::F32(Vec::new()),
            ScalarType::F64 => Self::F64(Vec::new()),
            _ => Self::Int(Vec::new()),
        }
    }

    #[inline]
    fn push(&mut self, value: Value) {
        match (self, value) {
            (Self::F32(c), Value::Float(v)) => c.push(v as f32),
            (Self::F64(c), Value::Float(v)) => c.push(v),
            (Self::Int(c), Value::Int(v)) => c.push(v),
            _ => unreachable!("a column only receives values of its own type"),
        }
    }
}

/// One property's data: a scalar column, or list items with each row's start.
#[derive(Clone, Debug)]
struct PropertyData {
    values: Column,
    /// Lists only: row `r` holds `values[starts[r]..starts[r + 1]]`.
    starts: Option<Vec<usize>>,
}

/// One element (e.g. `vertex`, `face`) with every property's values.
#[derive(Clone, Debug)]
pub struct PlyElement {
    /// Name of the element.
    pub name: String,
    /// The properties, in header order.
    pub properties: Vec<Property>,
    len: usize,
    data: Vec<PropertyData>,
    path: PathBuf,
}

impl PlyElement {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the element has no rows.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the element declares a property named `property`.
    pub fn has(&self, property: &str) -> bool {
        self.properties.iter().any(|p| p.name == property)
    }

    fn find(&self, property: &str) -> Result<&PropertyData, PlyError> {
        let index = self.properties.iter().position(|p| p.name == property);
        index.map(|i| &self.data[i]).ok_or_else(|| {
            error(&self.path, format!("element '{}' has no property '{property}'", self.name))
        })
    }

    fn scalar(&self, property: &str) -> Result<&Column, PlyError> {
        let data = self.find(property)?;
        match data.starts {
            None => Ok(&data.values),
            Some(_) => Err(error(
                &self.path,
                format!("property '{}.{property}' is a list, a scalar was expected", self.name),
            )),
        }
    }

    /// A scalar property as f32 (integers converted; f64 rounded).
    pub fn column_f32(&self, property: &str) -> Result<Vec<f32>, PlyError> {
        Ok(match self.scalar(property)? {
            Column::F32(c) => c.clone(),
            Column::F64(c) => c.iter().map(|&v| v as f32).collect(),
            Column::Int(c) => c.iter().map(|&v| v as f32).collect(),
        })
    }

    /// An integer scalar property whose values all lie in 0..=255 (e.g. vertex colours).
    pub fn column_u8(&self, property: &str) -> Result<Vec<u8>, PlyError> {
        let Column::Int(values) = self.scalar(property)? else {
            return Err(error(
                &self.path,
                format!(
                    "property '{}.{property}' is floating point, an integer was expected",
                    self.name
                ),
            ));
        };
        values
            .iter()
            .map(|&v| {
                u8::try_from(v).map_err(|_| {
                    error(
                        &self.path,
                        format!("'{}.{property}' value {v} is outside 0..=255", self.name),
                    )
                })
            })
            .collect()
    }

    /// An integer list property (e.g. `vertex_indices`) whose items are all non-negative u32.
    pub fn lists_u32(&self, property: &str) -> Result<Vec<Vec<u32>>, PlyError> {
        let data = self.find(property)?;
        let (Some(starts), Column::Int(items)) = (&data.starts, &data.values) else {
            return Err(error(
                &self.path,
                format!("property '{}.{property}' is not a list of integers", self.name),
            ));
        };
        starts
            .windows(2)
            .map(|row| {
                items[row[0]..row[1]]
                    .iter()
                    .map(|&v| {
                        u32::try_from(v).map_err(|_| {
                            error(
                                &self.path,
                                format!("'{}.{property}' item {v} is not a valid index", self.name),
                            )
                        })
                    })
                    .collect()
            })
            .collect()
    }
}

/// A parsed PLY file.
#[derive(Clone, Debug)]
pub struct Ply {
    /// The elements, in file order.
    pub elements: Vec<PlyElement>,
    /// Text of the `comment` lines, in order.
    pub comments: Vec<String>,
    /// The source, for errors (a file may have no element to name it).
    path: PathBuf,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    LittleEndian,
    BigEndian,
}

#[derive(Clone, Copy)]
enum Value {
    Float(f64),
    Int(i64),
}

impl Ply {
    /// Reads and parses `path`; every error names the file and the problem.
    pub fn read(path: &Path) -> Result<Ply, PlyError> {
        let bytes = std::fs::read(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
        Self::parse(path, &bytes)
    }

    /// Parses PLY bytes; `path` only names the source in errors.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Ply, PlyError> {
        let (format, mut elements, comments, body_start) = parse_header(path, bytes)?;
        let body = &bytes[body_start..];
        match format {
            Format::Ascii => read_ascii_body(path, body, &mut elements)?,
            _ => read_binary_body(path, body, format == Format::BigEndian, &mut elements)?,
        }
        Ok(Ply { elements, comments, path: path.to_path_buf() })
    }

    /// The first element named `name`, if any.
    pub fn element(&self, name: &str) -> Option<&PlyElement> {
        self.elements.iter().find(|e| e.name == name)
    }

    /// Like [`Ply::element`], but a missing element is an error naming the file.
    pub fn require(&self, name: &str) -> Result<&PlyElement, PlyError> {
        self.element(name).ok_or_else(|| error(&self.path, format!("no '{name}' element")))
    }
}

type Header = (Format, Vec<PlyElement>, Vec<String>, usize);

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, PlyError> {
    const END: &[u8] = b"end_header";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or_else(|| error(path, "not a PLY file: no 'end_header' line"))?;
    // The body starts after the end_header line's newline (\n or \r\n).
    let newline = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .ok_or_else(|| error(path, "header ends without a newline"))?;
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| error(path, "header is not text"))?;
    let mut lines = text.lines().map(str::trim).enumerate();
    if lines.next().map(|(_, l)| l) != Some("ply") {
        return Err(error(path, "not a PLY file: first line is not 'ply'"));
    }
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    let mut comments = Vec::new();
    for (number, line) in lines {
        let at = |problem: String| error(path, format!("header line {}: {problem}", number + 1));
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [] => {}
            ["comment", ..] | ["obj_info", ..] => {
                comments.push(line.split_once(' ').map_or("", |(_, rest)| rest).to_string())
            }
            ["format", kind, _version] => {
                format = Some(match *kind {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::LittleEndian,
                    "binary_big_endian" => Format::BigEndian,
                    other => return Err(at(format!("unknown format '{other}'"))),
                })
            }
            ["element", name, count] => {
                let len = count
                    .parse()
                    .map_err(|_| at(format!("element '{name}' has a bad count '{count}'")))?;
                elements.push(PlyElement {
                    name: name.to_string(),
                    properties: Vec::new(),
                    len,
                    data: Vec::new(),
                    path: path.to_path_buf(),
                });
            }
            ["property", ..] => {
                let element =
                    elements.last_mut().ok_or_else(|| at("property before any element".into()))?;
                let property =
                    parse_property(&words).ok_or_else(|| at(format!("cannot parse '{line}'")))?;
                if let PropertyKind::List {
                    count: count @ (ScalarType::F32 | ScalarType::F64),
                    ..
                } = property.kind
                {
                    return Err(at(format!(
                        "list property '{}' has a {} count, counts must be integers",
                        property.name,
                        count.name()
                    )));
                }
                let starts = matches!(property.kind, PropertyKind::List { .. }).then(|| vec![0]);
                let item = match property.kind {
                    PropertyKind::Scalar(t) | PropertyKind::List { item: t, .. } => t,
                };
                element.data.push(PropertyData { values: Column::for_type(item), starts });
                element.properties.push(property);
            }
            _ => return Err(at(format!("unexpected '{line}'"))),
        }
    }
    let format = format.ok_or_else(|| error(path, "header has no 'format' line"))?;
    Ok((format, elements, comments, end + newline + 1))
}

fn parse_property(words: &[&str]) -> Option<Property> {
    match words {
        ["property", "list", count, item, name] => Some(Property {
            name: name.to_string(),
            kind: PropertyKind::List {
                count: ScalarType::parse(count)?,
                item: ScalarType::parse(item)?,
            },
        }),
        ["property", ty, name] => Some(Property {
            name: name.to_string(),
            kind: PropertyKind::Scalar(ScalarType::parse(ty)?),
        }),
        _ => None,
    }
}

fn read_ascii_body(path: &Path, body: &[u8], elements: &mut [PlyElement]) -> Result<(), PlyError> {
    let text = std::str::from_utf8(body).map_err(|_| error(path, "ascii body is not text"))?;
    // Counted first, so that each element's row count is checked against the values left
    // before any of its rows is read.
    let mut left = text.split_ascii_whitespace().count();
    let mut tokens = text.split_ascii_whitespace();
    for element in elements {
        // Every property takes at least one value per row (a list its count).
        check_fits(path, element, element.properties.len(), left, "values")?;
        for row in 0..element.len {
            let mut next = |ty: ScalarType| -> Result<Value, PlyError> {
                let token = tokens.next().ok_or_else(|| {
                    error(
                        path,
                        format!(
                            "truncated: element '{}' ends at row {row} of {}",
                            element.name, element.len
                        ),
                    )
                })?;
                left -= 1;
                parse_ascii_value(token, ty).ok_or_else(|| {
                    error(
                        path,
                        format!(
                            "element '{}' row {row}: '{token}' is not a {}",
                            element.name,
                            ty.name()
                        ),
                    )
                })
            };
            read_row(&element.properties, &mut element.data, &mut next)?;
        }
    }
    Ok(())
}

fn parse_ascii_value(token: &str, ty: ScalarType) -> Option<Value> {
    match ty {
        ScalarType::F32 | ScalarType::F64 => token.parse().ok().map(Value::Float),
        _ => {
            let v: i64 = token.parse().ok()?;
            in_range(v, ty).then_some(Value::Int(v))
        }
    }
}

fn in_range(v: i64, ty: ScalarType) -> bool {
    let (lo, hi) = match ty {
        ScalarType::I8 => (i8::MIN as i64, i8::MAX as i64),
        ScalarType::U8 => (0, u8::MAX as i64),
        ScalarType::I16 => (i16::MIN as i64, i16::MAX as i64),
        ScalarType::U16 => (0, u16::MAX as i64),
        ScalarType::I32 => (i32::MIN as i64, i32::MAX as i64),
        _ => (0, u32::MAX as i64),
    };
    (lo..=hi).contains(&v)
}

fn read_binary_body(
    path: &Path,
    body: &[u8],
    big_endian: bool,
    elements: &mut [PlyElement],
) -> Result<(), PlyError> {
    let mut at = 0usize;
    for element in elements {
        let row_bytes = element.properties.iter().map(|p| p.kind.minimum_bytes()).sum();
        check_fits(path, element, row_bytes, body.len() - at, "bytes")?;
        for row in 0..element.len {
            let mut next = |ty: ScalarType| -> Result<Value, PlyError> {
                let bytes = body.get(at..at + ty.size()).ok_or_else(|| {
                    error(
                        path,
                        format!(
                            "truncated: element '{}' ends at row {row} of {}",
                            element.name, element.len
                        ),
                    )
                })?;
                at += ty.size();
                Ok(decode(bytes, ty, big_endian))
            };
            read_row(&element.properties, &mut element.data, &mut next)?;
        }
    }
    Ok(())
}

/// Refuses an element whose rows cannot fit in the `left` units (bytes or ascii values) of the
/// body, each row taking at least `row` units, before any row is read or allocated: a header
/// could otherwise claim a trillion rows and make the reader loop or allocate for them. Rows of
/// no properties take nothing, so any count of them is refused.
fn check_fits(
    path: &Path,
    element: &PlyElement,
    row: usize,
    left: usize,
    unit: &str,
) -> Result<(), PlyError> {
    let (name, rows) = (&element.name, element.len);
    if row == 0 && rows > 0 {
        return Err(error(path, format!("element '{name}' has {rows} rows but no properties")));
    }
    if rows.checked_mul(row).is_none_or(|needed| needed > left) {
        return Err(error(
            path,
            format!(
                "truncated: element '{name}' claims {rows} rows of at least {row} {unit}, \
                 {left} {unit} are left"
            ),
        ));
    }
    Ok(())
}

fn decode(bytes: &[u8], ty: ScalarType, big_endian: bool) -> Value {
    let mut b = [0u8; 8];
    b[..bytes.len()].copy_from_slice(bytes);
    if big_endian {
        b[..bytes.len()].reverse();
    }
    match ty {
        ScalarType::I8 => Value::Int(b[0] as i8 as i64),
        ScalarType::U8 => Value::Int(b[0] as i64),
        ScalarType::I16 => Value::Int(i16::from_le_bytes([b[0], b[1]]) as i64),
        ScalarType::U16 => Value::Int(u16::from_le_bytes([b[0], b[1]]) as i64),
        ScalarType::I32 => Value::Int(i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64),
        ScalarType::U32 => Value::Int(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64),
        ScalarType::F32 => Value::Float(f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
        ScalarType::F64 => Value::Float(f64::from_le_bytes(b)),
    }
}

/// Reads one row of an element, value by value, from `next` (ascii and binary share this).
fn read_row(
    properties: &[Property],
    data: &mut [PropertyData],
    next: &mut impl FnMut(ScalarType) -> Result<Value, PlyError>,
) -> Result<(), PlyError> {
    for (property, data) in properties.iter().zip(data) {
        match property.kind {
            PropertyKind::Scalar(ty) => data.values.push(next(ty)?),
            PropertyKind::List { count, item } => {
                let Value::Int(n) = next(count)? else {
                    unreachable!("parse_header refuses list counts of a float type");
                };
                for _ in 0..n.max(0) {
                    data.values.push(next(item)?);
                }
                let starts = data.starts.as_mut().expect("list properties have row starts");
                starts.push(starts.last().copied().unwrap_or(0) + n.max(0) as usize);
            }
        }
    }
    Ok(())
}

/// Values of one property to write.
pub enum ColumnOut {
    /// Written as `float`.
    F32(Vec<f32>),
    /// Written as `uchar`.
    U8(Vec<u8>),
    /// Written as `uint`.
    U32(Vec<u32>),
    /// A list of exactly three `int` per row, with a `uchar` count (triangle `vertex_indices`).
    Triangles(Vec<[u32; 3]>),
}

impl ColumnOut {
    fn len(&self) -> usize {
        match self {
            Self::F32(c) => c.len(),
            Self::U8(c) => c.len(),
            Self::U32(c) => c.len(),
            Self::Triangles(c) => c.len(),
        }
    }

    fn header(&self) -> &'static str {
        match self {
            Self::F32(_) => "float",
            Self::U8(_) => "uchar",
            Self::U32(_) => "uint",
            Self::Triangles(_) => "list uchar int",
        }
    }

    #[inline]
    fn write_row(&self, row: usize, out: &mut Vec<u8>) {
        match self {
            Self::F32(c) => out.extend_from_slice(&c[row].to_le_bytes()),
            Self::U8(c) => out.push(c[row]),
            Self::U32(c) => out.extend_from_slice(&c[row].to_le_bytes()),
            Self::Triangles(c) => {
                out.push(3);
                for index in c[row] {
                    out.extend_from_slice(&index.to_le_bytes());
                }
            }
        }
    }
}

/// One element to write: its name and its properties' columns, all of the same length.
pub struct ElementOut {
    /// Name of the element.
    pub name: String,
    /// Name and values of each property, in header order.
    pub properties: Vec<(String, ColumnOut)>,
}

impl ElementOut {
    /// An element named `name` with no properties yet.
    pub fn new(name: &str) -> Self {
        Self { name: name.into(), properties: Vec::new() }
    }

    /// Adds the property `property` with its values, after those added before.
    pub fn with(mut self, property: &str, column: ColumnOut) -> Self {
        self.properties.push((property.into(), column));
        self
    }

    fn len(&self) -> usize {
        self.properties.first().map_or(0, |(_, c)| c.len())
    }
}

/// Writes a binary little-endian PLY, atomically. Every column of an element must have the
/// same length (an error otherwise, naming the element and property).
pub fn write_ply(path: &Path, comments: &[&str], elements: &[ElementOut]) -> Result<(), PlyError> {
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    for comment in comments {
        header += &format!("comment {}\n", comment.replace('\n', " "));
    }
    for element in elements {
        header += &format!("element {} {}\n", element.name, element.len());
        for (name, column) in &element.properties {
            if column.len() != element.len() {
                return Err(error(
                    path,
                    format!(
                        "cannot write '{}.{name}': {} values for {} rows",
                        element.name,
                        column.len(),
                        element.len()
                    ),
                ));
            }
            header += &format!("property {} {name}\n", column.header());
        }
    }
    header += "end_header\n";
    crate::io::write_atomically(path, |w| {
        w.write_all(header.as_bytes())?;
        let mut row_bytes = Vec::new();
        for element in elements {
            for row in 0..element.len() {
                row_bytes.clear();
                for (_, column) in &element.properties {
                    column.write_row(row, &mut row_bytes);
                }
                w.write_all(&row_bytes)?;
            }
        }
        Ok(())
    })
    .map_err(|e| error(path, format!("cannot write: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty uchar red\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n0.5 255\n-1 0\n2e3 7\n3 0 1 2\n";

    #[test]
    fn ascii_columns_and_lists() {
        let ply = Ply::parse(Path::new("a.ply"), ASCII.as_bytes()).unwrap();
        let vertex = ply.element("vertex").unwrap();
        assert_eq!(vertex.column_f32("x").unwrap(), vec![0.5, -1.0, 2000.0]);
        assert_eq!(vertex.column_u8("red").unwrap(), vec![255, 0, 7]);
        assert_eq!(
            ply.element("face").unwrap().lists_u32("vertex_indices").unwrap(),
            vec![vec![0, 1, 2]]
        );
        assert_eq!(ply.comments, vec!["made by hand"]);
    }

    #[test]
    fn big_endian_binary() {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement v 2\nproperty double d\nproperty short s\nend_header\n".to_vec();
        for (d, s) in [(1.25f64, -3i16), (-7.5, 300)] {
            bytes.extend_from_slice(&d.to_be_bytes());
            bytes.extend_from_slice(&s.to_be_bytes());
        }
        let ply = Ply::parse(Path::new("b.ply"), &bytes).unwrap();
        let v = ply.element("v").unwrap();
        assert_eq!(v.column_f32("d").unwrap(), vec![1.25, -7.5]);
        assert_eq!(v.column_f32("s").unwrap(), vec![-3.0, 300.0]);
    }

    #[test]
    fn write_then_read() {
        let path = std::env::temp_dir().join(format!("tagsplat-ply-{}.ply", std::process::id()));
        let vertex = ElementOut::new("vertex")
            .with("x", ColumnOut::F32(vec![1.0, f32::MIN_POSITIVE, -0.0]))
            .with("id", ColumnOut::U32(vec![0, u32::MAX, 5]));
        let face = ElementOut::new("face")
            .with("vertex_indices", ColumnOut::Triangles(vec![[0, 1, 2], [2, 1, 0]]));
        write_ply(&path, &["round trip"], &[vertex, face]).unwrap();
        let ply = Ply::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let v = ply.element("vertex").unwrap();
        assert_eq!(v.column_f32("x").unwrap(), vec![1.0, f32::MIN_POSITIVE, -0.0]);
        assert_eq!(
            ply.element("face").unwrap().lists_u32("vertex_indices").unwrap(),
            vec![vec![0, 1, 2], vec![2, 1, 0]]
        );
        let Column::Int(ids) = v.scalar("id").unwrap() else { panic!("uint is an integer column") };
        assert_eq!(ids, &vec![0, u32::MAX as i64, 5]);
    }

    #[test]
    fn list_counts_must_be_integers() {
        let bytes = b"ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n3 0 1 2\n";
        let message = Ply::parse(Path::new("m.ply"), bytes).unwrap_err().to_string();
        assert!(
            message.starts_with("m.ply: header line 4: ")
                && message.contains("'vertex_indices'")
                && message.contains("float"),
            "{message}"
        );
    }

    /// Counts the body cannot hold are refused before any row is read: neither a spin over
    /// rows of nothing nor a loop over rows of a short file.
    #[test]
    fn row_counts_the_file_cannot_hold_are_refused_at_once() {
        let empty_rows = "element vertex 1000000000000\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        for format in ["ascii", "binary_little_endian"] {
            let bytes = format!("ply\nformat {format} 1.0\n{empty_rows}3 0 1 2\n");
            let message = Ply::parse(Path::new("m.ply"), bytes.as_bytes()).unwrap_err().to_string();
            assert!(
                message.starts_with("m.ply: ")
                    && message.contains("'vertex' has 1000000000000 rows but no properties"),
                "{message}"
            );
        }
        let doubles =
            b"ply\nformat binary_big_endian 1.0\nelement v 3\nproperty double d\nend_header\n";
        let message = Ply::parse(Path::new("d.ply"), &[&doubles[..], &[0; 20]].concat())
            .unwrap_err()
            .to_string();
        let expected =
            "truncated: element 'v' claims 3 rows of at least 8 bytes, 20 bytes are left";
        assert!(message == format!("d.ply: {expected}"), "{message}");
        // A list row takes at least its count; the face follows 3 vertex rows of 4 bytes.
        let faces = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nelement face 5\nproperty list ushort int vertex_indices\nend_header\n";
        let message = Ply::parse(Path::new("f.ply"), &[&faces[..], &[0; 12 + 9]].concat())
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("'face' claims 5 rows of at least 2 bytes, 9 bytes are left"),
            "{message}"
        );
        // An ascii row takes at least one value per property.
        let ascii = b"ply\nformat ascii 1.0\nelement v 4\nproperty float x\nproperty float y\nend_header\n1 2\n";
        let message = Ply::parse(Path::new("a.ply"), ascii).unwrap_err().to_string();
        assert!(
            message.contains("'v' claims 4 rows of at least 2 values, 2 values are left"),
            "{message}"
        );
    }

    #[test]
    fn bad_files_name_the_problem() {
        let cases: [(&[u8], &str); 6] = [
            (b"not a ply", "end_header"),
            (b"ply\nelement vertex 1\nproperty float x\nend_header\n1\n", "no 'format'"),
            (b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n", "truncated"),
            (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty uchar x\nend_header\n300\n", "not a uchar"),
            (b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n", "truncated"),
            (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"),
        ];
        for (bytes, expected) in cases {
            let message = Ply::parse(Path::new("bad.ply"), bytes).unwrap_err().to_string();
            assert!(message.starts_with("bad.ply: ") && message.contains(expected), "{message}");
        }
        let ply = Ply::parse(Path::new("a.ply"), ASCII.as_bytes()).unwrap();
        let missing = ply.element("vertex").unwrap().column_f32("nx").unwrap_err().to_string();
        assert!(missing.contains("no property 'nx'"), "{missing}");
        assert!(ply.element("vertex").unwrap().lists_u32("x").is_err());
        assert!(ply.element("face").unwrap().column_f32("vertex_indices").is_err());
    }
}
