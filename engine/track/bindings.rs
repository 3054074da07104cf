//! Bindings given directly and written back: `bindings.csv`, so that one binding serves every
//! sequence of the same mesh.
//!
//! A row is `id,face,u,v,w` (barycentric (u, v, w) on triangle `face` of the sequence, the
//! position `u·v0 + v·v1 + w·v2`) or `id,vertex` (that vertex exactly: the first triangle that
//! has it, with weight 1 on its corner). A header may have both forms' columns; a row then
//! fills one of them and leaves the other's fields empty. An optional `polygon` column names
//! the file polygon the triangle was fanned from, and is checked against the sequence read.
//! Other columns are ignored. The CSV rules are the query files' ([`super::queries`]).
//! The same anchors given as arrays (a front's) resolve alike ([`resolve_anchors`]).
//!
//! Written files have `id,face,u,v,w,polygon`, floats as shortest round-trip decimals, so a
//! written binding reads back bit for bit.

use super::bind::Binding;
use super::output::TrackedPoint;
use super::queries::{Row, Table};
use super::TrackError;
use crate::io::write_atomically;
use std::io::Write;
use std::path::{Path, PathBuf};

/// How far a barycentric coordinate may fall below 0, or their sum stray from 1.
pub const BARYCENTRIC_TOLERANCE: f64 = 1e-6;

const EXPECTED: &str = "id,face,u,v,w or id,vertex";

/// Where a row of a bindings file puts its point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Anchor {
    /// Barycentric coordinates on a triangle of the sequence.
    Surface {
        /// The triangle's index.
        face: u32,
        /// Weights of its three corners.
        barycentric: [f64; 3],
    },
    /// A vertex of the sequence.
    Vertex(u32),
}

/// One row of a bindings file.
#[derive(Clone, Debug, PartialEq)]
pub struct BindingRow {
    /// The point's id.
    pub id: String,
    /// The row's line in the file, from 1.
    pub line: usize,
    /// Where the point is.
    pub anchor: Anchor,
    /// The file polygon the row says its triangle belongs to, when it says.
    pub polygon: Option<u32>,
}

/// A bindings file as read, not yet checked against a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct BindingsFile {
    /// The file, named in errors.
    pub path: PathBuf,
    /// Its rows, in file order.
    pub rows: Vec<BindingRow>,
}

/// Reads a bindings file. Errors name the file and the line: no header or neither form's
/// columns, a row filling neither or both forms, a bad number, a duplicate id, no rows.
pub fn read_bindings(path: &Path) -> Result<BindingsFile, TrackError> {
    let text = std::fs::read_to_string(path)
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })?;
    parse_bindings(&text, path)
}

/// Parses the text of a bindings file; `path` names it in errors (see [`read_bindings`]).
pub fn parse_bindings(text: &str, path: &Path) -> Result<BindingsFile, TrackError> {
    let table = Table::parse(text, path, EXPECTED)?;
    let surface = match ["face", "u", "v", "w"].map(|c| table.column(c)) {
        [Some(f), Some(u), Some(v), Some(w)] => Some((f, [u, v, w])),
        [None, None, None, None] => None,
        _ => {
            return Err(table.header_error(format!(
                "the columns face, u, v, w come together; expected `{EXPECTED}`"
            )))
        }
    };
    let vertex = table.column("vertex");
    if surface.is_none() && vertex.is_none() {
        return Err(table.header_error(format!("no column face or vertex; expected `{EXPECTED}`")));
    }
    let polygon = table.column("polygon");
    let rows = table
        .rows()?
        .into_iter()
        .map(|row| {
            let anchor = anchor(&row, surface, vertex)?;
            let polygon = match polygon.filter(|&c| !row.field(c).is_empty()) {
                Some(c) => Some(row.index(c, "polygon")?),
                None => None,
            };
            Ok(BindingRow { id: row.id.to_owned(), line: row.line, anchor, polygon })
        })
        .collect::<Result<_, TrackError>>()?;
    Ok(BindingsFile { path: path.to_owned(), rows })
}

/// The anchor a row fills: the surface columns or the vertex column, exactly one of them.
fn anchor(
    row: &Row,
    surface: Option<(usize, [usize; 3])>,
    vertex: Option<usize>,
) -> Result<Anchor, TrackError> {
    let filled = |c: usize| !row.field(c).is_empty();
    let on_surface = surface.filter(|(f, _)| filled(*f));
    match (on_surface, vertex.filter(|&c| filled(c))) {
        (Some((f, [u, v, w])), None) => Ok(Anchor::Surface {
            face: row.index(f, "face")?,
            barycentric: [row.number(u, "u")?, row.number(v, "v")?, row.number(w, "w")?],
        }),
        (None, Some(c)) => Ok(Anchor::Vertex(row.index(c, "vertex")?)),
        (Some(_), Some(_)) => Err(row.error("both a face and a vertex: give one".into())),
        (None, None) => Err(row.error("neither a face nor a vertex".into())),
    }
}

impl BindingsFile {
    /// The bindings on a sequence with `faces` and `vertices` vertices per frame, whose
    /// triangles come from the file polygons `polygon_of` (None: the triangles are the file's
    /// faces). Errors name the file and the line: a face or vertex out of range, a vertex no
    /// triangle has, barycentric coordinates that are negative or do not sum to 1 (beyond
    /// [`BARYCENTRIC_TOLERANCE`]), a polygon other than the sequence's.
    pub fn resolve(
        &self,
        faces: &[[u32; 3]],
        vertices: usize,
        polygon_of: Option<&[u32]>,
    ) -> Result<Vec<(String, Binding)>, TrackError> {
        let first_face = first_face_of_each_vertex(faces, vertices);
        let fail = |row: &BindingRow, message: String| TrackError::Csv {
            path: self.path.clone(),
            line: row.line,
            message,
        };
        self.rows
            .iter()
            .map(|row| {
                let binding = anchor_binding(row.anchor, faces.len(), &first_face)
                    .map_err(|m| fail(row, m))?;
                let polygon = polygon_of_face(binding.face, polygon_of);
                match row.polygon {
                    Some(p) if p != polygon => Err(fail(row, format!("face {} is in polygon {polygon} of the sequence, not in polygon {p}: the file was made on another mesh", binding.face))),
                    _ => Ok((row.id.clone(), binding)),
                }
            })
            .collect()
    }
}

/// The bindings of anchors given directly, (id, anchor) per point (a front's arrays), on a
/// sequence with `faces` and `vertices` vertices per frame, as [`BindingsFile::resolve`] finds
/// them. Errors name the point: a face or vertex out of range, a vertex no triangle has,
/// barycentric coordinates that are negative or do not sum to 1.
pub fn resolve_anchors(
    anchors: &[(String, Anchor)],
    faces: &[[u32; 3]],
    vertices: usize,
) -> Result<Vec<(String, Binding)>, TrackError> {
    let first_face = first_face_of_each_vertex(faces, vertices);
    anchors
        .iter()
        .map(|(id, anchor)| match anchor_binding(*anchor, faces.len(), &first_face) {
            Ok(binding) => Ok((id.clone(), binding)),
            Err(problem) => Err(TrackError::Binding { id: id.clone(), problem }),
        })
        .collect()
}

/// The binding `anchor` names on a sequence of `faces` triangles whose vertices' first
/// triangles are `first_face` ([`first_face_of_each_vertex`]), checked ([`check_binding`]).
fn anchor_binding(
    anchor: Anchor,
    faces: usize,
    first_face: &[Option<(u32, usize)>],
) -> Result<Binding, String> {
    let binding = match anchor {
        Anchor::Surface { face, barycentric } => Binding { face, barycentric, distance: 0.0 },
        Anchor::Vertex(v) => {
            let vertices = first_face.len();
            let slot = first_face.get(v as usize).ok_or_else(|| {
                format!("vertex {v} is out of range: the sequence has {vertices} vertices")
            })?;
            let (face, corner) =
                (*slot).ok_or_else(|| format!("vertex {v} is in no triangle of the sequence"))?;
            let mut barycentric = [0.0; 3];
            barycentric[corner] = 1.0;
            Binding { face, barycentric, distance: 0.0 }
        }
    };
    check_binding(&binding, faces)?;
    Ok(binding)
}

/// Per vertex, the first triangle that has it and its corner there.
fn first_face_of_each_vertex(faces: &[[u32; 3]], vertices: usize) -> Vec<Option<(u32, usize)>> {
    let mut first = vec![None; vertices];
    for (f, face) in faces.iter().enumerate().rev() {
        for (corner, &v) in face.iter().enumerate().rev() {
            if let Some(slot) = first.get_mut(v as usize) {
                *slot = Some((f as u32, corner));
            }
        }
    }
    first
}

/// The file polygon of triangle `face`: `polygon_of[face]`, or the face itself when the
/// triangles are the file's faces (or `polygon_of` is too short to say).
pub fn polygon_of_face(face: u32, polygon_of: Option<&[u32]>) -> u32 {
    polygon_of.and_then(|p| p.get(face as usize)).copied().unwrap_or(face)
}

/// Why `binding` cannot be used on a sequence of `faces` triangles, if it cannot: a face out of
/// range, a non-finite, negative or unnormalised barycentric coordinate.
pub fn check_binding(binding: &Binding, faces: usize) -> Result<(), String> {
    let [u, v, w] = binding.barycentric;
    if binding.face as usize >= faces {
        return Err(format!(
            "face {} is out of range: the sequence has {faces} triangles",
            binding.face
        ));
    }
    if !binding.barycentric.iter().all(|b| b.is_finite()) {
        return Err(format!("barycentric ({u}, {v}, {w}) is not finite"));
    }
    if binding.barycentric.iter().any(|&b| b < -BARYCENTRIC_TOLERANCE) {
        return Err(format!("barycentric ({u}, {v}, {w}) has a negative weight"));
    }
    let sum = u + v + w;
    if (sum - 1.0).abs() > BARYCENTRIC_TOLERANCE {
        return Err(format!("barycentric ({u}, {v}, {w}) sums to {sum}, not 1"));
    }
    Ok(())
}

/// Writes the bindings of `points` as `id,face,u,v,w,polygon`, atomically.
pub fn write_bindings_csv(path: &Path, points: &[TrackedPoint]) -> Result<(), TrackError> {
    write_atomically(path, |w| {
        writeln!(w, "id,face,u,v,w,polygon")?;
        for p in points {
            let [u, v, b] = p.binding.barycentric;
            writeln!(w, "{},{},{u},{v},{b},{}", p.id, p.binding.face, p.polygon)?;
        }
        Ok(())
    })
    .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    fn resolve(text: &str) -> Result<Vec<(String, Binding)>, TrackError> {
        parse_bindings(text, Path::new("b.csv"))?.resolve(&SQUARE, 5, Some(&[7, 7]))
    }

    #[test]
    fn reads_both_forms_and_finds_each_vertex_on_its_first_triangle() {
        let got =
            resolve("id,vertex,face,u,v,w,polygon\na,,1,0.5,0.25,0.25,7\nb,3,,,,,\nc,0,,,,,\n")
                .unwrap();
        let at = |face, barycentric| Binding { face, barycentric, distance: 0.0 };
        assert_eq!(
            got,
            vec![
                ("a".into(), at(1, [0.5, 0.25, 0.25])),
                ("b".into(), at(1, [0.0, 0.0, 1.0])),
                ("c".into(), at(0, [1.0, 0.0, 0.0])),
            ]
        );
    }

    #[test]
    fn bad_bindings_name_the_file_the_line_and_the_problem() {
        for (text, line, needle) in [
            ("id,x\na,1\n", 1, "no column face or vertex"),
            ("id,face,u,v\na,1,0,0\n", 1, "come together"),
            ("id,face,u,v,w\na,2,1,0,0\n", 2, "face 2 is out of range: the sequence has 2"),
            ("id,vertex\na,0\nb,5\n", 3, "vertex 5 is out of range"),
            ("id,vertex\na,4\n", 2, "vertex 4 is in no triangle"),
            ("id,vertex\na,-1\n", 2, "`-1` is not an index"),
            ("id,face,u,v,w\na,0,0.5,0.5,0.5\n", 2, "sums to 1.5, not 1"),
            ("id,face,u,v,w\na,0,1.5,-0.5,0\n", 2, "negative weight"),
            ("id,face,u,v,w\na,0,NaN,0.5,0.5\n", 2, "not a finite number for column `u`"),
            ("id,face,u,v,w,vertex\na,0,1,0,0,2\n", 2, "both a face and a vertex"),
            ("id,face,u,v,w,vertex\na,,,,,\n", 2, "neither a face nor a vertex"),
            ("id,face,u,v,w,polygon\na,0,1,0,0,3\n", 2, "not in polygon 3"),
            ("id,vertex\na,0\na,1\n", 3, "duplicate id `a`"),
        ] {
            let e = resolve(text).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("b.csv: line {line}: ")) && e.contains(needle),
                "{text:?} -> {e}"
            );
        }
    }

    #[test]
    fn anchors_given_directly_resolve_as_rows_do_and_errors_name_the_point() {
        let anchors =
            |anchor| vec![("a".to_string(), Anchor::Vertex(3)), ("b".to_string(), anchor)];
        let got = resolve_anchors(&anchors(Anchor::Vertex(0)), &SQUARE, 5).unwrap();
        let from_file = resolve("id,vertex\na,3\nb,0\n").unwrap();
        assert_eq!(got, from_file);
        for (anchor, needle) in [
            (Anchor::Vertex(5), "vertex 5 is out of range: the sequence has 5 vertices"),
            (Anchor::Vertex(4), "vertex 4 is in no triangle"),
            (Anchor::Surface { face: 2, barycentric: [1.0, 0.0, 0.0] }, "face 2 is out of range"),
            (Anchor::Surface { face: 0, barycentric: [0.5, 0.75, 0.0] }, "sums to 1.25, not 1"),
        ] {
            let e = resolve_anchors(&anchors(anchor), &SQUARE, 5).unwrap_err().to_string();
            assert!(e.starts_with("binding of point b: ") && e.contains(needle), "{e}");
        }
    }
}
