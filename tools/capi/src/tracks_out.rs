//! What a `tagsplat_tracks` holds, copied into caller buffers, and the files `tagsplat track`
//! writes of it, each by the engine writer the program calls.

use crate::buffers::{optional_text, output, output_text, store, to_path};
use crate::handles::get;
use crate::status::{call, engine, Error, Status};
use crate::tracks::Tracks;
use std::ffi::c_char;
use tagsplat::sequence::orient::{SignedAxis, UpAxis};
use tagsplat::track::bindings::write_bindings_csv;
use tagsplat::track::output::{write_pinned_tracks_csv, write_report_json};
use tagsplat::track::pins::write_pins_glb;
use tagsplat::track::TrackedPoint;

/// A tracking run's sizes and clock: what its copy calls need.
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
    /// Frames per second: the file's rate, else its times' mean rate, else 24.
    pub fps: f64,
    /// The scene frame of frame 0 (its time × fps): frame k plays at start_frame + k.
    pub start_frame: f64,
}

/// Where a bound query sits on the frame-0 surface.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Binding {
    /// Its index among the queries given (for a bindings file: its row, from 0).
    pub query: usize,
    /// The frame-0 triangle it lies on.
    pub face: u32,
    /// The file polygon that triangle was fanned from (the triangle itself when the file's
    /// faces are triangles).
    pub polygon: u32,
    /// Its barycentric coordinates in that triangle (≥ 0, summing to 1).
    pub barycentric: [f64; 3],
    /// Its distance from the surface (0 for a pixel's ray hit or a given binding), scene units.
    pub distance: f64,
}

/// The run's counts and clock.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_info(
    tracks: *const Tracks,
    info: *mut TracksCounts,
) -> Status {
    call("tagsplat_tracks_info", || unsafe {
        let tracks = get("tracks", tracks)?;
        let (report, clock) = (&tracks.tracked.report, &tracks.tracked.clock);
        let summary = TracksCounts {
            frames: report.frames,
            points: report.points.len(),
            unbound: report.unbound.len(),
            max_distance: report.max_distance,
            fps: clock.fps,
            start_frame: clock.start_frame,
        };
        store("info", info, summary)
    })
}

/// Copies `of` every bound point in every frame into the caller's `len` doubles at `buf`:
/// points × frames × 3, point-major.
unsafe fn per_frame(
    tracks: *const Tracks,
    of: fn(&TrackedPoint) -> &[[f64; 3]],
    buf: *mut f64,
    len: usize,
) -> Result<(), Error> {
    let tracks = get("tracks", tracks)?;
    let all: Vec<f64> =
        tracks.tracked.report.points.iter().flat_map(|p| of(p).as_flattened()).copied().collect();
    unsafe { output("buf", &all, buf, len) }
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
        per_frame(tracks, |p| &p.trajectory, buf, len)
    })
}

/// Copies the bound triangle's unit normal per point per frame into `buf`, which holds `len`
/// doubles: points × frames × 3 are needed, as for the trajectories.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_normals(
    tracks: *const Tracks,
    buf: *mut f64,
    len: usize,
) -> Status {
    call("tagsplat_tracks_normals", || unsafe { per_frame(tracks, |p| &p.normal, buf, len) })
}

/// Copies the unit tangent per point per frame (along the bound triangle's first edge,
/// orthogonal to the normal; with it, the frame a locator pinned there follows) into `buf`,
/// which holds `len` doubles: points × frames × 3 are needed, as for the trajectories.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_tangents(
    tracks: *const Tracks,
    buf: *mut f64,
    len: usize,
) -> Status {
    call("tagsplat_tracks_tangents", || unsafe { per_frame(tracks, |p| &p.tangent, buf, len) })
}

/// Copies, per point per frame, 1 where the bound triangle had no area (its normal and tangent
/// are held from a neighbouring frame) and 0 elsewhere, into `buf`, which holds `len` bytes:
/// points × frames are needed, point-major.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_orientation_held(
    tracks: *const Tracks,
    buf: *mut u8,
    len: usize,
) -> Status {
    call("tagsplat_tracks_orientation_held", || unsafe {
        let tracks = get("tracks", tracks)?;
        let report = &tracks.tracked.report;
        let frames = report.frames as u32;
        let held: Vec<u8> = report
            .points
            .iter()
            .flat_map(|p| (0..frames).map(|k| u8::from(p.orientation_held.contains(&k))))
            .collect();
        output("buf", &held, buf, len)
    })
}

/// Copies each frame's time in seconds (the file's times, else frame k at k / fps) into `buf`,
/// which holds `len` doubles: frames are needed.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_times(
    tracks: *const Tracks,
    buf: *mut f64,
    len: usize,
) -> Status {
    call("tagsplat_tracks_times", || unsafe {
        output("buf", &get("tracks", tracks)?.tracked.clock.times, buf, len)
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
        let tracks = get("tracks", tracks)?;
        let points = tracks.tracked.report.points.iter().zip(&tracks.queries);
        let bindings: Vec<Binding> = points
            .map(|(p, &query)| Binding {
                query,
                face: p.binding.face,
                polygon: p.polygon,
                barycentric: p.binding.barycentric,
                distance: p.binding.distance,
            })
            .collect();
        output("buf", &bindings, buf, len)
    })
}

/// The id of bound point `point` (its index in the bindings' order, below `points`), as a
/// string of `*needed` bytes with its NUL (the header's buffer convention). Points given as
/// arrays are named by their query index ("0", "1", …); a bindings file's keep the file's ids.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_point_id(
    tracks: *const Tracks,
    point: usize,
    buf: *mut c_char,
    len: usize,
    needed: *mut usize,
) -> Status {
    call("tagsplat_tracks_point_id", || unsafe {
        let points = &get("tracks", tracks)?.tracked.report.points;
        let beyond = || {
            Error::bad_input(format!(
                "point: {point} is not below the {} bound points",
                points.len()
            ))
        };
        let id = &points.get(point).ok_or_else(beyond)?.id;
        output_text("buf", id, (buf, len), needed)
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
        output("buf", &get("tracks", tracks)?.unbound, buf, len)
    })
}

/// Writes the tracks to `path` as `tagsplat track --out` does: CSV
/// `id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame`, one row per point per frame.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_write_csv(
    tracks: *const Tracks,
    path: *const c_char,
) -> Status {
    call("tagsplat_tracks_write_csv", || unsafe {
        let (tracks, path) = (get("tracks", tracks)?, to_path("path", path)?);
        let t = &tracks.tracked;
        write_pinned_tracks_csv(&path, &t.report.points, &t.clock).map_err(|e| engine(&e))
    })
}

/// Writes the JSON report `tagsplat track --json` writes to `path`: the clock, bindings (face,
/// barycentric, distance, polygon), trajectories, normals, tangents and the unbound queries.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_write_json(
    tracks: *const Tracks,
    path: *const c_char,
) -> Status {
    call("tagsplat_tracks_write_json", || unsafe {
        let (tracks, path) = (get("tracks", tracks)?, to_path("path", path)?);
        let t = &tracks.tracked;
        write_report_json(&path, &t.report, &t.clock).map_err(|e| engine(&e))
    })
}

/// Writes the GLB of animated empties `tagsplat track --glb` writes to `path`: one node per
/// point, named by its id, moved and turned by its position and orientation frame at every
/// frame's time. glTF is +Y up: positions are turned onto it from `from_up` ("+x", "-x", "+y",
/// "-y", "+z" or "-z"; NULL: the up the sequence's file declares, else taken as +Y already).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_write_pins(
    tracks: *const Tracks,
    path: *const c_char,
    from_up: *const c_char,
) -> Status {
    call("tagsplat_tracks_write_pins", || unsafe {
        let (tracks, path) = (get("tracks", tracks)?, to_path("path", path)?);
        let from_up = optional_text("from_up", from_up)?.map(signed_axis).transpose()?;
        let t = &tracks.tracked;
        let orientation = t.pins_orientation(from_up, UpAxis::Y);
        write_pins_glb(&path, &t.report.points, &t.clock, orientation).map_err(|e| engine(&e))
    })
}

/// `text` as the axis `from_up` names.
fn signed_axis(text: &str) -> Result<SignedAxis, Error> {
    SignedAxis::parse(text).ok_or_else(|| {
        Error::bad_input(format!("from_up: '{text}' is not one of +x, -x, +y, -y, +z, -z"))
    })
}

/// Writes the bindings to `path` as `tagsplat track --bindings-out` does: CSV
/// `id,face,u,v,w,polygon`, which tagsplat_track_bindings_file reads back bit for bit.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_tracks_write_bindings(
    tracks: *const Tracks,
    path: *const c_char,
) -> Status {
    call("tagsplat_tracks_write_bindings", || unsafe {
        let (tracks, path) = (get("tracks", tracks)?, to_path("path", path)?);
        write_bindings_csv(&path, &tracks.tracked.report.points).map_err(|e| engine(&e))
    })
}
