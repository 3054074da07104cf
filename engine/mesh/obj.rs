//! Wavefront OBJ for [`TriMesh`]: `v` and `f` statements in, `v` and `f` out.
//!
//! Reading: `v x y z` (an optional `w` is ignored) or `v x y z r g b` with colours in [0, 1]
//! (the common extension; colours are kept only when every vertex has them); `f` with any of
//! the `i`, `i/t`, `i//n`, `i/t/n` forms, 1-based or negative (relative) indices, polygons
//! fanned into triangles like [`TriMesh::read_ply`]. Other statements (`vt`, `vn`, `o`, `g`,
//! `s`, `usemtl`, `mtllib`, `l`, …) are ignored. Writing: `v` lines (with colours when present,
//! as c/255) in the shortest decimal form that reads back to the same f32, then `f a b c`.

use super::{MeshError, TriMesh};
use std::io::Write;
use std::path::Path;

impl TriMesh {
    /// Reads and validates an OBJ file; every error names the file (and the line).
    pub fn read_obj(path: &Path) -> Result<TriMesh, MeshError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| invalid(path, format!("cannot read: {e}")))?;
        let mesh = parse_obj(path, &text)?;
        mesh.validate(path)?;
        Ok(mesh)
    }

    /// Writes an OBJ file, atomically.
    pub fn write_obj(&self, path: &Path) -> Result<(), MeshError> {
        self.validate(path)?;
        crate::io::write_atomically(path, |w| {
            writeln!(
                w,
                "# tagsplat triangle mesh: {} vertices, {} faces",
                self.positions.len(),
                self.faces.len()
            )?;
            for (i, [x, y, z]) in self.positions.iter().enumerate() {
                match &self.colors {
                    Some(colors) => {
                        let [r, g, b] = colors[i].map(|c| c as f32 / 255.0);
                        writeln!(w, "v {x} {y} {z} {r} {g} {b}")?
                    }
                    None => writeln!(w, "v {x} {y} {z}")?,
                }
            }
            for [a, b, c] in &self.faces {
                writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
            }
            Ok(())
        })
        .map_err(|e| invalid(path, format!("cannot write: {e}")))
    }
}

fn invalid(path: &Path, problem: String) -> MeshError {
    MeshError::Invalid { path: path.to_path_buf(), problem }
}

/// Parses OBJ text; `path` names the source in errors. Not validated (faces may refer to
/// vertices that come later in the file).
pub fn parse_obj(path: &Path, text: &str) -> Result<TriMesh, MeshError> {
    let parsed = parse_obj_text(path, text, None)?;
    let (faces, _) = parsed.faces.unwrap_or_default();
    Ok(TriMesh { positions: parsed.positions, faces, colors: parsed.colors })
}

/// The statements of an OBJ text that tagsplat reads.
#[derive(Debug, Default)]
pub struct ObjText {
    /// `v` positions, in file order.
    pub positions: Vec<[f32; 3]>,
    /// `v` colours, when every vertex has them.
    pub colors: Option<Vec<[u8; 3]>>,
    /// The fanned triangles and, per triangle, the polygon (`f` statement) it came from. None
    /// when the face statements were the `known_faces` text (see [`parse_obj_text`]).
    pub faces: Option<(Vec<[u32; 3]>, Vec<u32>)>,
    /// Byte offset of the first `f` statement when no `v` statement follows it: then the text
    /// from there on, with the vertex count, decides the faces, and a later frame whose text
    /// ends the same way has the same faces.
    pub face_text_start: Option<usize>,
}

/// Parses OBJ text (see the module doc); `path` names the source in errors.
///
/// `known_faces`: the face text of an earlier file (from its [`ObjText::face_text_start`]
/// on). When this text's first `f` statement starts the same bytes to the end, its faces are
/// not parsed again and `faces` is None: they are the earlier file's, provided the caller
/// checks that both have the same number of vertices. Frames of an exported sequence differ
/// only in their `v` lines, so this halves the work of reading them.
pub fn parse_obj_text(
    path: &Path,
    text: &str,
    known_faces: Option<&str>,
) -> Result<ObjText, MeshError> {
    let mut out = ObjText::default();
    let (mut colors, mut counts, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    let mut offset = 0;
    for (n, line) in text.split_inclusive('\n').enumerate() {
        let at = |problem: String| invalid(path, format!("line {}: {problem}", n + 1));
        let (start, mut tokens) = (offset, line.split_ascii_whitespace());
        offset += line.len();
        match tokens.next() {
            Some("v") => {
                // A vertex after a face: the face text alone no longer decides the faces.
                out.face_text_start = None;
                vertex(tokens, &mut out.positions, &mut colors).map_err(at)?;
            }
            Some("f") => {
                if counts.is_empty() {
                    if known_faces == Some(&text[start..]) {
                        out.colors = all_or_none(colors, out.positions.len());
                        return Ok(out);
                    }
                    out.face_text_start = Some(start);
                }
                face(tokens, out.positions.len(), &mut indices)
                    .map(|c| counts.push(c))
                    .map_err(at)?;
            }
            _ => {}
        }
    }
    let fanned = super::polygon::fan_triangulate(&counts, &indices, out.positions.len())
        .map_err(|problem| invalid(path, problem))?;
    out.faces = Some(fanned);
    out.colors = all_or_none(colors, out.positions.len());
    Ok(out)
}

/// Reads a `v` statement's numbers: a position, and a colour when there are six.
fn vertex<'a>(
    tokens: impl Iterator<Item = &'a str>,
    positions: &mut Vec<[f32; 3]>,
    colors: &mut Vec<[u8; 3]>,
) -> Result<(), String> {
    let (mut values, mut k) = ([0.0f32; 6], 0);
    for t in tokens {
        let value = t.parse::<f32>().map_err(|_| format!("`{t}` is not a number"))?;
        if let Some(slot) = values.get_mut(k) {
            *slot = value;
        }
        k += 1;
    }
    match k {
        3 | 4 | 6 => positions.push([values[0], values[1], values[2]]),
        k => return Err(format!("a vertex needs 3, 4 or 6 numbers, found {k}")),
    }
    if k == 6 {
        colors.push(
            [values[3], values[4], values[5]].map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8),
        );
    }
    Ok(())
}

/// Appends an `f` statement's vertex indices (0-based) to `indices`; returns how many.
fn face<'a>(
    tokens: impl Iterator<Item = &'a str>,
    defined: usize,
    indices: &mut Vec<u32>,
) -> Result<u32, String> {
    let before = indices.len();
    for t in tokens {
        let index = vertex_index(t, defined);
        indices.push(index.ok_or_else(|| format!("`{t}` is not a valid vertex reference"))?);
    }
    let count = indices.len() - before;
    if count < 3 {
        return Err(format!("a face needs at least 3 vertices, found {count}"));
    }
    Ok(count as u32)
}

/// Colours are kept only when every vertex has one.
fn all_or_none(colors: Vec<[u8; 3]>, vertices: usize) -> Option<Vec<[u8; 3]>> {
    (!colors.is_empty() && colors.len() == vertices).then_some(colors)
}

/// The 0-based vertex index of an `f` token (`i`, `i/t`, `i//n`, `i/t/n`); negative indices
/// count back from the `defined` vertices so far. None for 0, garbage, or before the start.
fn vertex_index(token: &str, defined: usize) -> Option<u32> {
    let i: i64 = token.split('/').next()?.parse().ok()?;
    let index = match i {
        0 => return None,
        i if i > 0 => i - 1,
        i => defined as i64 + i,
    };
    u32::try_from(index).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_usual_forms_and_fans_polygons() {
        let text = "# c\nmtllib m.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
                    f 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 -1//1\nf 1 2 3 4\ns off\n";
        let mesh = parse_obj(Path::new("a.obj"), text).unwrap();
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.colors, None);
    }

    #[test]
    fn face_text_is_shared_only_when_no_vertex_follows_it() {
        let path = Path::new("a.obj");
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\n";
        let first = parse_obj_text(path, text, None).unwrap();
        let start = first.face_text_start.unwrap();
        assert_eq!(&text[start..], "f 1 2 3\n");
        let later = "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n";
        let known = parse_obj_text(path, later, Some(&text[start..])).unwrap();
        assert!(known.faces.is_none());
        assert_eq!(known.positions[2], [0.0, 1.0, 1.0]);
        let after = parse_obj_text(path, "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", None).unwrap();
        assert_eq!(after.face_text_start, None);
        assert_eq!(after.faces.unwrap().0, vec![[0, 1, 2]]);
    }

    #[test]
    fn colours_need_every_vertex() {
        let all = parse_obj(
            Path::new("a.obj"),
            "v 0 0 0 1 0 0.5\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n",
        )
        .unwrap();
        assert_eq!(all.colors, Some(vec![[255, 0, 128], [0, 255, 0], [0, 0, 255]]));
        let some =
            parse_obj(Path::new("a.obj"), "v 0 0 0 1 0 0.5\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(some.colors, None);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        for (text, needle) in [
            ("v 0 0\n", "a.obj: line 1: a vertex needs 3, 4 or 6 numbers, found 2"),
            ("v 0 0 x\n", "a.obj: line 1: `x` is not a number"),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", "a.obj: line 3: a face needs at least 3 vertices"),
            ("v 0 0 0\nf 1 0 1\n", "a.obj: line 2: `0` is not a valid vertex reference"),
            ("v 0 0 0\nf 1 -2 1\n", "a.obj: line 2: `-2` is not a valid vertex reference"),
        ] {
            let e = parse_obj(Path::new("a.obj"), text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?} -> {e}");
        }
    }

    #[test]
    fn write_then_read_is_exact() {
        let path = std::env::temp_dir().join(format!("tagsplat-obj-{}.obj", std::process::id()));
        let mesh = TriMesh {
            positions: vec![
                [0.1, -2.5e-7, 3.0e8],
                [1.0 / 3.0, f32::MIN_POSITIVE, -0.0],
                [7.0, 8.0, 9.0],
            ],
            faces: vec![[0, 1, 2], [2, 1, 0]],
            colors: Some(vec![[0, 1, 2], [127, 128, 129], [253, 254, 255]]),
        };
        mesh.write_obj(&path).unwrap();
        assert_eq!(TriMesh::read_obj(&path).unwrap(), mesh);
        let bad = TriMesh { faces: vec![[0, 1, 3]], ..mesh };
        assert!(bad.write_obj(&path).unwrap_err().to_string().contains("past the 3 vertices"));
        std::fs::write(&path, "v 0 0 0\nf 1 2 3\n").unwrap();
        assert!(TriMesh::read_obj(&path).unwrap_err().to_string().contains("past the 1 vertices"));
        std::fs::remove_file(&path).unwrap();
        assert!(TriMesh::read_obj(&path).unwrap_err().to_string().contains("cannot read"));
    }
}
