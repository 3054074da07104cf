//! Reading a folder's frame files ([`super::folder`] says which files they are): frame 0
//! first, then every later frame in parallel over the host's threads, each checked against
//! frame 0's vertex count and faces.
//!
//! An OBJ frame whose face statements repeat frame 0's byte for byte (what exporters write:
//! frames differ only in their `v` lines) has frame 0's faces, so they are not parsed again;
//! any other frame is parsed whole and compared face by face.

use super::{check_same_topology, check_vertex_count, folder, MeshSequence, SequenceError};
use crate::io::host::parallel_map;
use crate::mesh::obj::parse_obj_text;
use crate::mesh::{MeshError, TriMesh};
use std::path::Path;

/// One frame as read.
struct Frame {
    /// Its mesh; no faces when `faces_known`.
    mesh: TriMesh,
    /// Its faces are frame 0's, known from their text.
    faces_known: bool,
    /// Per triangle, the file polygon it came from (OBJ frames).
    polygon_of: Option<Vec<u32>>,
    /// Its face text, when that alone decides its faces (OBJ frames; see
    /// [`crate::mesh::obj::ObjText::face_text_start`]).
    face_text: Option<String>,
}

/// The frames of `dir` in order, and per triangle the polygon of frame 0 it came from (OBJ
/// frames). Guarantees what [`MeshSequence::read_folder`] documents; the error returned is
/// that of the first bad frame in frame order, whatever the threads' timing.
pub fn read_frames(dir: &Path) -> Result<(MeshSequence, Option<Vec<u32>>), SequenceError> {
    let files = folder::frame_files(dir)?;
    let mut first = read_frame(&files[0], None, true)?;
    let known = first.face_text.as_deref();
    let later = parallel_map(&files[1..], |file| read_frame(file, known, false))?;
    let faces = std::mem::take(&mut first.mesh.faces);
    let mut sequence = MeshSequence { faces, ..MeshSequence::default() };
    let mut colors = Some(Vec::with_capacity(files.len()));
    let frames = std::iter::once(Frame { faces_known: true, ..first }).chain(later);
    let mut polygon_of = None;
    for (t, frame) in frames.enumerate() {
        if frame.faces_known {
            check_vertex_count(&sequence, frame.mesh.positions.len(), t, &files[t], &files[0])?;
        } else {
            check_same_topology(&sequence, &frame.mesh, t, &files[t], &files[0])?;
        }
        colors = colors.zip(frame.mesh.colors).map(|(mut all, c)| {
            all.push(c);
            all
        });
        sequence.frames.push(frame.mesh.positions);
        polygon_of = polygon_of.or(frame.polygon_of);
    }
    sequence.colors = colors;
    // As every reader reports it: only when some polygon was not a triangle.
    let fanned = |p: &Vec<u32>| p.iter().enumerate().any(|(i, &q)| q as usize != i);
    Ok((sequence, polygon_of.filter(fanned)))
}

/// Reads and validates one frame file; an OBJ frame whose face text is `known_faces` (frame
/// 0's) skips parsing its faces. `keep_face_text`: return the face text (frame 0's).
fn read_frame(
    file: &Path,
    known_faces: Option<&str>,
    keep_face_text: bool,
) -> Result<Frame, MeshError> {
    if folder::frame_extension(&file.to_string_lossy()) != Some("obj") {
        let mesh = TriMesh::read_ply(file)?;
        return Ok(Frame { mesh, faces_known: false, polygon_of: None, face_text: None });
    }
    let invalid = |problem: String| MeshError::Invalid { path: file.to_path_buf(), problem };
    let text = std::fs::read_to_string(file).map_err(|e| invalid(format!("cannot read: {e}")))?;
    let parsed = parse_obj_text(file, &text, known_faces)?;
    let face_text =
        parsed.face_text_start.filter(|_| keep_face_text).map(|start| text[start..].to_owned());
    let (faces, polygon_of) = parsed.faces.unzip();
    let mesh = TriMesh {
        positions: parsed.positions,
        faces: faces.unwrap_or_default(),
        colors: parsed.colors,
    };
    // Known faces index below frame 0's vertex count, which the caller checks this frame has.
    mesh.validate(file)?;
    Ok(Frame { mesh, faces_known: polygon_of.is_none(), polygon_of, face_text })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder of OBJ frames with the given texts, named frame_0.obj, frame_1.obj, …
    fn folder(name: &str, frames: &[&str]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("tagsplat-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for (t, text) in frames.iter().enumerate() {
            std::fs::write(dir.join(format!("frame_{t}.obj")), text).unwrap();
        }
        dir
    }

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

    #[test]
    fn repeated_face_text_and_rewritten_faces_both_read() {
        let moved = QUAD.replace("v 1 1 0", "v 2 2 0");
        // Same faces written another way: parsed whole, then compared.
        let rewritten = QUAD.replace("f 1 2 3 4", "f 1/1 2/1 3/1 -1/1");
        let dir = folder("folder-read", &[QUAD, &moved, &rewritten]);
        let (sequence, polygon_of) = read_frames(&dir).unwrap();
        assert_eq!(sequence.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(sequence.frames[1][2], [2.0, 2.0, 0.0]);
        assert_eq!(sequence.frames.len(), 3);
        assert_eq!(polygon_of, Some(vec![0, 0]));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_frame_that_differs_is_named() {
        let other_faces = QUAD.replace("f 1 2 3 4", "f 1 2 4\nf 2 3 4");
        let fewer = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3 4\n";
        let late_vertex = format!("{QUAD}v 5 5 5\n");
        for (frames, problem) in [
            (
                vec![QUAD, QUAD, &other_faces],
                "frame 2 differs from frame 0 (frame_0.obj) at face 0",
            ),
            (vec![QUAD, fewer], "frame_1.obj: frame 1 has 3 vertices, frame 0 (frame_0.obj) has 4"),
            (vec![&late_vertex, QUAD], "frame 1 has 4 vertices, frame 0 (frame_0.obj) has 5"),
        ] {
            let dir = folder("folder-differs", &frames);
            let e = read_frames(&dir).map(|_| ()).unwrap_err().to_string();
            assert!(e.contains(problem), "{e}");
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
