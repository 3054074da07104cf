//! `tagsplat_sequence`: a topology-consistent mesh sequence (one face list, positions per
//! frame), read from a file or folder, or copied from caller arrays.

use crate::buffers::{input, optional_text, output, store, to_path};
use crate::handles::{create, get, release, Handle};
use crate::status::{call, engine, Error, Status};
use std::ffi::c_char;
use tagsplat::sequence::{ReadOptions, SequenceInfo};
use tagsplat::{FrameFormat as EngineFormat, MeshSequence};

/// A mesh sequence, immutable once made, with what its file said (its clock, polygons, up).
pub struct Sequence {
    pub(crate) mesh: MeshSequence,
    pub(crate) info: SequenceInfo,
}

impl Handle for Sequence {
    const NAME: &'static str = "tagsplat_sequence";
}

/// A sequence's sizes: what its copy calls need.
#[repr(C)]
pub struct SequenceCounts {
    /// Frames.
    pub frames: usize,
    /// Vertices per frame.
    pub vertices: usize,
    /// Triangles (the same in every frame).
    pub faces: usize,
    /// 1 when the sequence has vertex colours, else 0.
    pub has_colors: i32,
}

/// The file kind of each frame when a sequence is written to a folder.
#[repr(i32)]
#[derive(Clone, Copy)]
pub enum FrameFormat {
    /// Binary PLY (vertex colours when present).
    Ply = 0,
    /// Wavefront OBJ.
    Obj = 1,
}

/// Reads the sequence at `path`: anything `tagsplat convert` reads (a folder of .ply/.obj frames,
/// a .pc2 or .mdd with the .obj of the same name beside it, glTF, USD, Alembic, FBX), with the
/// default choices (see [`tagsplat_sequence_read_with`]). Every frame is checked against frame
/// 0. Stores the new handle in `*out` (NULL on failure).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_read(
    path: *const c_char,
    out: *mut *mut Sequence,
) -> Status {
    unsafe { tagsplat_sequence_read_with(path, std::ptr::null(), 0.0, std::ptr::null(), out) }
}

/// [`tagsplat_sequence_read`] with the CLI's read options: `animation` (glTF, FBX: a name or
/// index; NULL: the file's only one), `fps` (the rate an animation is sampled at, or the clock
/// of a folder or PC2; 0: the default) and `mesh` (which mesh of a file that holds several: a
/// USD prim path, an Alembic object path, a glTF or FBX node name; NULL: the only one). The
/// sequence keeps what the file said beside its frames, which tracking uses: its frame times,
/// the polygons its triangles were fanned from, its up axis.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_read_with(
    path: *const c_char,
    animation: *const c_char,
    fps: f64,
    mesh: *const c_char,
    out: *mut *mut Sequence,
) -> Status {
    call("tagsplat_sequence_read_with", || unsafe {
        create("out", out, || {
            let options = ReadOptions {
                animation: optional_text("animation", animation)?.map(str::to_owned),
                fps: (fps != 0.0).then_some(fps),
                mesh: optional_text("mesh", mesh)?.map(str::to_owned),
            };
            let path = to_path("path", path)?;
            let (mesh, info) = MeshSequence::read_with(&path, &options).map_err(|e| engine(&e))?;
            Ok(Sequence { mesh, info })
        })
    })
}

/// A sequence copied from caller arrays: `positions` holds `frames` × `vertices` × 3 floats
/// (frame-major, x y z per vertex), `faces` holds `face_count` × 3 vertex indices. The arrays are
/// copied; the caller may free them on return. Checked as a read sequence is (a non-finite
/// position or an index out of range is bad input). Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_create(
    positions: *const f32,
    frames: usize,
    vertices: usize,
    faces: *const u32,
    face_count: usize,
    out: *mut *mut Sequence,
) -> Status {
    call("tagsplat_sequence_create", || unsafe {
        create("out", out, || {
            if frames == 0 || vertices == 0 {
                let problem = format!("{frames} frames of {vertices} vertices: none is empty");
                return Err(Error::bad_input(problem));
            }
            let too_many = || Error::bad_input(format!("{frames} × {vertices} vertices overflow"));
            let count = frames.checked_mul(vertices).and_then(|n| n.checked_mul(3));
            let values = input("positions", positions, count.ok_or_else(too_many)?)?;
            let count = face_count.checked_mul(3).ok_or_else(too_many)?;
            let indices = input("faces", faces, count)?;
            let points = values.as_chunks::<3>().0;
            let mesh = MeshSequence {
                faces: indices.as_chunks::<3>().0.to_vec(),
                frames: points.chunks(vertices).map(<[_]>::to_vec).collect(),
                colors: None,
            };
            match mesh.problem() {
                Some(problem) => Err(Error::bad_input(format!("positions and faces: {problem}"))),
                None => Ok(Sequence { mesh, info: SequenceInfo::default() }),
            }
        })
    })
}

/// The sequence's frame, vertex and face counts.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_info(
    sequence: *const Sequence,
    info: *mut SequenceCounts,
) -> Status {
    call("tagsplat_sequence_info", || unsafe {
        let mesh = &get("sequence", sequence)?.mesh;
        let summary = SequenceCounts {
            frames: mesh.frames.len(),
            vertices: mesh.frames.first().map_or(0, Vec::len),
            faces: mesh.faces.len(),
            has_colors: i32::from(mesh.colors.is_some()),
        };
        store("info", info, summary)
    })
}

/// Copies every frame's positions into `buf`, which holds `len` floats: frames × vertices × 3
/// are needed (frame-major, as tagsplat_sequence_create takes them).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_positions(
    sequence: *const Sequence,
    buf: *mut f32,
    len: usize,
) -> Status {
    call("tagsplat_sequence_positions", || unsafe {
        let mesh = &get("sequence", sequence)?.mesh;
        output("buf", mesh.frames.concat().as_flattened(), buf, len)
    })
}

/// Copies the faces into `buf`, which holds `len` indices: faces × 3 are needed.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_faces(
    sequence: *const Sequence,
    buf: *mut u32,
    len: usize,
) -> Status {
    call("tagsplat_sequence_faces", || unsafe {
        let mesh = &get("sequence", sequence)?.mesh;
        output("buf", mesh.faces.as_flattened(), buf, len)
    })
}

/// Writes the sequence to `path`: a .pc2 (and its base .obj beside it), a .glb at `fps` frames
/// per second, or otherwise a new folder of frame files in `format` (a folder that already
/// holds frames is refused).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_sequence_write(
    sequence: *const Sequence,
    path: *const c_char,
    format: i32,
    fps: f64,
) -> Status {
    call("tagsplat_sequence_write", || unsafe {
        let mesh = &get("sequence", sequence)?.mesh;
        let format = match format {
            f if f == FrameFormat::Ply as i32 => EngineFormat::Ply,
            f if f == FrameFormat::Obj as i32 => EngineFormat::Obj,
            other => {
                return Err(Error::bad_input(format!(
                    "format is {other}: give TAGSPLAT_FRAME_FORMAT_PLY or _OBJ"
                )))
            }
        };
        mesh.write(&to_path("path", path)?, format, fps).map_err(|e| engine(&e))
    })
}

/// Frees `sequence` (NULL: nothing).
#[no_mangle]
pub extern "C" fn tagsplat_sequence_free(sequence: *mut Sequence) -> Status {
    call("tagsplat_sequence_free", || release("sequence", sequence))
}
