//! `tagsplat_tracks`: surface points bound on frame 0 of a sequence and followed through every
//! frame (`tagsplat track`).

use crate::buffers::{finite_rows, output, store};
use crate::handles::{create, get, release, Handle};
use crate::sequence::Sequence;
use crate::status::{call, engine, Error, Status};
use glam::DMat4;
use std::sync::Arc;
use tagsplat::TrackReport;
use tagsplat::{track, Camera, Queries};

/// A tracking run's result, immutable.
pub struct Tracks {
    report: TrackReport,
}

impl Handle for Tracks {
    const NAME: &'static str = "tagsplat_tracks";
}

/// A tracking run's sizes: what its copy calls need.
#[repr(C)]
pub struct TracksCounts {
    /// Frames of the sequence: positions per trajectory.
    pub frames: usize,
    /// The queries that were bound (each has a trajectory and a binding).
    pub points: usize,
    /// The queries that were not (too far from the surface, a ray that misses).
    pub unbound: usize,
    /// The largest distance from a point to the frame-0 surface that was accepted, scene units.
    pub max_distance: f64,
}

/// Where a bound query sits on the frame-0 surface.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Binding {
    /// Its index among the queries given.
    pub query: usize,
    /// The frame-0 face it lies on.
    pub face: u32,
    /// Its barycentric coordinates in that face (≥ 0, summing to 1).
    pub barycentric: [f64; 3],
    /// Its distance from the surface (0 for a pixel's ray hit), scene units.
    pub distance: f64,
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
            let queries = Queries::Points(numbered(rows));
            let sequence: Arc<Sequence> = get("sequence", sequence)?;
            run(&sequence, &queries, max_distance)
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
            run(&sequence, &Queries::Pixels { camera, pixels }, 0.0)
        })
    })
}

/// The engine's tracking on `sequence`.
fn run(sequence: &Sequence, queries: &Queries, max_distance: f64) -> Result<Tracks, Error> {
    let mesh = &sequence.mesh;
    let report = track(&mesh.faces, &mesh.frames, queries, max_distance).map_err(|e| engine(&e))?;
    Ok(Tracks { report })
}

/// The queries with their index as id, which the results give back as `query`.
fn numbered<const N: usize>(rows: &[[f64; N]]) -> Vec<(String, [f64; N])> {
    rows.iter().enumerate().map(|(i, row)| (i.to_string(), *row)).collect()
}

/// The query index a result's id holds (see [`numbered`]).
fn query_of(id: &str) -> Result<usize, Error> {
    id.parse().map_err(|_| Error::new(Status::Internal, format!("query id '{id}' is not an index")))
}

/// The engine's camera, checked as a cam.json is.
fn camera_of(c: &CameraDesc) -> Result<Camera, Error> {
    let world_to_camera = DMat4::from_cols_array(&c.world_to_camera).transpose();
    Camera::new(c.width, c.height, c.fx, c.fy, c.cx, c.cy, world_to_camera)
        .map_err(|e| Error::bad_input(format!("camera: {e}")))
}

/// The run's counts.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_info(
    tracks: *const Tracks,
    info: *mut TracksCounts,
) -> Status {
    call("tagsplat_tracks_info", || unsafe {
        let report = &get("tracks", tracks)?.report;
        let summary = TracksCounts {
            frames: report.frames,
            points: report.points.len(),
            unbound: report.unbound.len(),
            max_distance: report.max_distance,
        };
        store("info", info, summary)
    })
}

/// Copies the trajectories into `buf`, which holds `len` doubles: points × frames × 3 are
/// needed (point-major, in the order of tagsplat_tracks_bindings).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_trajectories(
    tracks: *const Tracks,
    buf: *mut f64,
    len: usize,
) -> Status {
    call("tagsplat_tracks_trajectories", || unsafe {
        let report = &get("tracks", tracks)?.report;
        let all: Vec<[f64; 3]> =
            report.points.iter().flat_map(|p| p.trajectory.iter().copied()).collect();
        output("buf", all.as_flattened(), buf, len)
    })
}

/// Copies the bound points' bindings into `buf`, which holds `len` of them: one per bound
/// point is needed, in query order.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_bindings(
    tracks: *const Tracks,
    buf: *mut Binding,
    len: usize,
) -> Status {
    call("tagsplat_tracks_bindings", || unsafe {
        let report = &get("tracks", tracks)?.report;
        let bindings = report.points.iter().map(|p| {
            let b = &p.binding;
            let query = query_of(&p.id)?;
            Ok(Binding { query, face: b.face, barycentric: b.barycentric, distance: b.distance })
        });
        output("buf", &bindings.collect::<Result<Vec<_>, Error>>()?, buf, len)
    })
}

/// Copies the indices of the queries that were not bound into `buf`, which holds `len` of them:
/// one per unbound query is needed, in query order.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_unbound(
    tracks: *const Tracks,
    buf: *mut usize,
    len: usize,
) -> Status {
    call("tagsplat_tracks_unbound", || unsafe {
        let report = &get("tracks", tracks)?.report;
        let queries: Result<Vec<usize>, Error> =
            report.unbound.iter().map(|u| query_of(&u.id)).collect();
        output("buf", &queries?, buf, len)
    })
}

/// Frees `tracks` (NULL: nothing).
#[no_mangle]
pub extern "C" fn tagsplat_tracks_free(tracks: *mut Tracks) -> Status {
    call("tagsplat_tracks_free", || release("tracks", tracks))
}
