//! `tagsplat_tracks`: surface points bound on frame 0 of a sequence and followed through every
//! frame (`tagsplat track`), made from points, pixels or given bindings; `tracks_out` reads
//! them back and writes their files.

use crate::buffers::{finite_rows, input, to_path};
use crate::handles::{create, get, release, Handle};
use crate::sequence::Sequence;
use crate::status::{call, engine, Error, Status};
use glam::DMat4;
use std::collections::HashMap;
use std::ffi::c_char;
use std::sync::Arc;
use tagsplat::track::bindings::{read_bindings, Anchor};
use tagsplat::track::{track_sequence, Targets, Tracked};
use tagsplat::{Camera, Queries};

/// A tracking run's result, immutable.
pub struct Tracks {
    /// The engine's result.
    pub(crate) tracked: Tracked,
    /// Per bound point, its index among the queries given.
    pub(crate) queries: Vec<usize>,
    /// Per query not bound, its index among the queries given.
    pub(crate) unbound: Vec<usize>,
}

impl Handle for Tracks {
    const NAME: &'static str = "tagsplat_tracks";
}

/// A pinhole camera in OpenCV axes (x right, y down, z forward), as a cam.json holds it;
/// pixel (i, j) is centred at (i + 0.5, j + 0.5).
#[repr(C)]
pub struct CameraDesc {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// The rigid world-to-camera transform, 4 × 4, row-major (last row 0 0 0 1).
    pub world_to_camera: [f64; 16],
}

/// Binds `count` frame-0 points (`points`: count × 3 doubles, x y z) to the surface of
/// `sequence`'s frame 0 and follows them through every frame. A point farther than
/// `max_distance` × the frame-0 bounding-box diagonal is not bound, and is listed by
/// tagsplat_tracks_unbound (`tagsplat track --max-distance`; 0.01 is its default). A NaN or
/// infinite coordinate is bad input. Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_track_points(
    sequence: *const Sequence,
    points: *const f64,
    count: usize,
    max_distance: f64,
    out: *mut *mut Tracks,
) -> Status {
    call("tagsplat_track_points", || unsafe {
        create("out", out, || {
            let rows = finite_rows::<3>("points", points, count)?;
            let targets = Targets::Queries(Queries::Points(numbered(rows)));
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &targets, max_distance)
        })
    })
}

/// Casts `count` pixels (`pixels`: count × 2 doubles, u v) of `camera` as rays onto the surface
/// of `sequence`'s frame 0 and follows the hits through every frame. A ray that misses is not
/// bound (tagsplat_tracks_unbound). A NaN pixel, or a camera that is not valid (non-positive
/// focal lengths, a non-rigid pose, a NaN), is bad input. Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_track_pixels(
    sequence: *const Sequence,
    camera: *const CameraDesc,
    pixels: *const f64,
    count: usize,
    out: *mut *mut Tracks,
) -> Status {
    call("tagsplat_track_pixels", || unsafe {
        create("out", out, || {
            let camera =
                camera_of(camera.as_ref().ok_or_else(|| Error::bad_input("camera is NULL"))?)?;
            let pixels = numbered(finite_rows::<2>("pixels", pixels, count)?);
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &Targets::Queries(Queries::Pixels { camera, pixels }), 0.0)
        })
    })
}

/// Follows `count` points bound already through every frame of `sequence`: point i at
/// barycentric `barycentric[3i..3i+3]` (weights of the corners, ≥ 0, summing to 1) on triangle
/// `faces[i]`, as tagsplat_tracks_bindings gives them (`tagsplat track --bindings`). A face out
/// of range or weights that are negative, not finite or not summing to 1 are bad input naming
/// the point. Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_track_bindings(
    sequence: *const Sequence,
    faces: *const u32,
    barycentric: *const f64,
    count: usize,
    out: *mut *mut Tracks,
) -> Status {
    call("tagsplat_track_bindings", || unsafe {
        create("out", out, || {
            let faces = input("faces", faces, count)?;
            let weights = finite_rows::<3>("barycentric", barycentric, count)?;
            let anchors: Vec<Anchor> = faces
                .iter()
                .zip(weights)
                .map(|(&face, &barycentric)| Anchor::Surface { face, barycentric })
                .collect();
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &Targets::Anchors(numbered(&anchors)), 0.0)
        })
    })
}

/// Follows `count` vertices of `sequence` (`vertices`: their indices) through every frame,
/// each bound with weight 1 on the corner of the first triangle that has it, so its trajectory
/// is the vertex's own. A vertex out of range or in no triangle is bad input naming the point.
/// Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_track_vertices(
    sequence: *const Sequence,
    vertices: *const u32,
    count: usize,
    out: *mut *mut Tracks,
) -> Status {
    call("tagsplat_track_vertices", || unsafe {
        create("out", out, || {
            let anchors: Vec<Anchor> =
                input("vertices", vertices, count)?.iter().map(|&v| Anchor::Vertex(v)).collect();
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &Targets::Anchors(numbered(&anchors)), 0.0)
        })
    })
}

/// Follows the points of the bindings file at `path` through every frame of `sequence`: CSV
/// `id,face,u,v,w` or `id,vertex` (with an optional `polygon` column, checked against the
/// sequence's), as tagsplat_tracks_write_bindings and `tagsplat track --bindings-out` write it.
/// The points keep the file's ids (in the files written of them); a binding's `query` is its
/// row among the file's rows, from 0. A malformed file or a row that does not fit the sequence
/// is bad input naming the file and the line. Stores the new handle in `*out`.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_track_bindings_file(
    sequence: *const Sequence,
    path: *const c_char,
    out: *mut *mut Tracks,
) -> Status {
    call("tagsplat_track_bindings_file", || unsafe {
        create("out", out, || {
            let file = read_bindings(&to_path("path", path)?).map_err(|e| engine(&e))?;
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &Targets::File(file), 0.0)
        })
    })
}

/// The engine's tracking on `sequence` (`tagsplat track`'s run), each result's query found.
fn run(sequence: &Sequence, targets: &Targets, max_distance: f64) -> Result<Tracks, Error> {
    let (mesh, info) = (&sequence.mesh, &sequence.info);
    let tracked = track_sequence(&mesh.faces, &mesh.frames, info, targets, max_distance)
        .map_err(|e| engine(&e))?;
    let order: HashMap<&str, usize> =
        query_ids(targets).into_iter().enumerate().map(|(i, id)| (id, i)).collect();
    let query = |id: &str| {
        let lost = || Error::new(Status::Internal, format!("point '{id}' is not a query"));
        order.get(id).copied().ok_or_else(lost)
    };
    let report = &tracked.report;
    let queries = report.points.iter().map(|p| query(&p.id)).collect::<Result<_, _>>()?;
    let unbound = report.unbound.iter().map(|u| query(&u.id)).collect::<Result<_, _>>()?;
    Ok(Tracks { tracked, queries, unbound })
}

/// The ids of the queries, in the order given.
fn query_ids(targets: &Targets) -> Vec<&str> {
    fn ids<T>(named: &[(String, T)]) -> Vec<&str> {
        named.iter().map(|(id, _)| id.as_str()).collect()
    }
    match targets {
        Targets::Queries(Queries::Points(points)) => ids(points),
        Targets::Queries(Queries::Pixels { pixels, .. }) => ids(pixels),
        Targets::Queries(Queries::Bindings(bindings)) => ids(bindings),
        Targets::Anchors(anchors) => ids(anchors),
        Targets::File(file) => file.rows.iter().map(|row| row.id.as_str()).collect(),
    }
}

/// The queries with their index as id.
fn numbered<T: Copy>(rows: &[T]) -> Vec<(String, T)> {
    rows.iter().enumerate().map(|(i, row)| (i.to_string(), *row)).collect()
}

/// The engine's camera, checked as a cam.json is.
fn camera_of(c: &CameraDesc) -> Result<Camera, Error> {
    let world_to_camera = DMat4::from_cols_array(&c.world_to_camera).transpose();
    Camera::new(c.width, c.height, c.fx, c.fy, c.cx, c.cy, world_to_camera)
        .map_err(|e| Error::bad_input(format!("camera: {e}")))
}

/// Frees `tracks` (NULL: nothing).
#[no_mangle]
pub extern "C" fn tagsplat_tracks_free(tracks: *mut Tracks) -> Status {
    call("tagsplat_tracks_free", || release("tracks", tracks))
}
