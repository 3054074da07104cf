//! The results of a tracking run and their files: `tracks.csv` and a JSON report that adds
//! each point's binding and the points that could not be bound.
//!
//! `tracks.csv` as `track` writes it ([`write_pinned_tracks_csv`]) is one header line
//! `id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame`, then one row per point per frame:
//! position, unit normal and unit tangent ([`super::frame`]), the frame's time in seconds, the
//! frame rate and the scene frame of frame 0 (the same on every row), so that frame k plays at
//! scene frame `start_frame + k`. Its first five columns are the trajectory CSV's
//! ([`crate::io::trajectories`], `id,frame,x,y,z`, which the generator and `eval` share), so
//! `eval` reads it as it is.

use super::bind::Binding;
use super::clock::Clock;
use super::frame::SurfaceFrame;
use super::project::ImagePoint;
use super::TrackError;
use crate::io::{write_atomically, write_json_atomically};
use serde::Serialize;
use std::io::Write;
use std::path::Path;

/// Everything a tracking run found.
#[derive(Clone, Debug, Serialize)]
pub struct TrackReport {
    /// Frames in the sequence.
    pub frames: usize,
    /// Vertices per frame.
    pub vertices: usize,
    /// Faces of the sequence.
    pub faces: usize,
    /// Largest accepted distance from a 3D query point to the frame-0 surface (scene units).
    pub max_distance: f64,
    /// The bound points, in query order.
    pub points: Vec<TrackedPoint>,
    /// The queries that could not be bound, in query order.
    pub unbound: Vec<UnboundPoint>,
}

/// A bound point and its position in every frame.
#[derive(Clone, Debug, Serialize)]
pub struct TrackedPoint {
    /// The query's id.
    pub id: String,
    /// Where on the frame-0 surface it is bound.
    #[serde(flatten)]
    pub binding: Binding,
    /// The file polygon its triangle was fanned from (the face itself when the file's faces
    /// are triangles; see [`TrackReport::in_polygons`]).
    pub polygon: u32,
    /// Position per frame (scene units).
    pub trajectory: Vec<[f64; 3]>,
    /// The bound triangle's unit normal per frame.
    pub normal: Vec<[f64; 3]>,
    /// The unit tangent along the bound triangle's first edge per frame, orthogonal to the
    /// normal.
    pub tangent: Vec<[f64; 3]>,
    /// The frames whose triangle had no area, where the normal and tangent are held from a
    /// neighbouring frame (see [`super::frame`]); usually empty.
    pub orientation_held: Vec<u32>,
}

impl TrackedPoint {
    /// The orientation frame in frame `t` (None past the end).
    pub fn surface_frame(&self, t: usize) -> Option<SurfaceFrame> {
        Some(SurfaceFrame { normal: *self.normal.get(t)?, tangent: *self.tangent.get(t)? })
    }
}

impl TrackReport {
    /// The report with each point's polygon read from `polygon_of` (per triangle, the file
    /// polygon it was fanned from, as [`crate::sequence::SequenceInfo::polygon_of`] gives it).
    ///
    /// Errors: `polygon_of` not one entry per face.
    pub fn in_polygons(mut self, polygon_of: &[u32]) -> Result<Self, TrackError> {
        if polygon_of.len() != self.faces {
            return Err(TrackError::Polygons { polygons: polygon_of.len(), faces: self.faces });
        }
        for p in &mut self.points {
            p.polygon = polygon_of[p.binding.face as usize];
        }
        Ok(self)
    }
}

/// A query that was not bound, and why.
#[derive(Clone, Debug, Serialize)]
pub struct UnboundPoint {
    /// The query's id.
    pub id: String,
    /// Why it was not bound, in words.
    pub reason: String,
    /// Distance to the surface when that was the reason.
    pub distance: Option<f64>,
}

/// Writes the points as `tracks.csv` with their orientation frames on `clock` (see the module
/// doc), atomically, floats as shortest round-trip decimals.
///
/// Errors: a clock whose frame count is not the trajectories'; a write failure.
pub fn write_pinned_tracks_csv(
    path: &Path,
    points: &[TrackedPoint],
    clock: &Clock,
) -> Result<(), TrackError> {
    check_clock(points, clock)?;
    write_atomically(path, |w| {
        writeln!(w, "id,frame,x,y,z,nx,ny,nz,tx,ty,tz,time,fps,start_frame")?;
        for p in points {
            for (t, ((x, n), tangent)) in
                p.trajectory.iter().zip(&p.normal).zip(&p.tangent).enumerate()
            {
                let [[x, y, z], [nx, ny, nz], [tx, ty, tz]] = [x, n, tangent].map(|v| *v);
                let (time, fps, start) = (clock.times[t], clock.fps, clock.start_frame);
                writeln!(
                    w,
                    "{},{t},{x},{y},{z},{nx},{ny},{nz},{tx},{ty},{tz},{time},{fps},{start}",
                    p.id
                )?;
            }
        }
        Ok(())
    })
    .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// An error unless `clock` has a time for every frame of every trajectory.
pub(crate) fn check_clock(points: &[TrackedPoint], clock: &Clock) -> Result<(), TrackError> {
    match points.iter().find(|p| p.trajectory.len() != clock.times.len()) {
        Some(p) => Err(TrackError::Clock(format!(
            "{} frame times for the {} frames of point {}",
            clock.times.len(),
            p.trajectory.len(),
            p.id
        ))),
        None => Ok(()),
    }
}

/// Writes `id,distance,tolerance,reason`, one row per query that was not bound, atomically:
/// distance (to the frame-0 surface) and tolerance ([`TrackReport::max_distance`]) in scene
/// units, distance empty when the reason is not the distance (a ray that misses, NaN input).
pub fn write_unbound_csv(path: &Path, report: &TrackReport) -> Result<(), TrackError> {
    write_atomically(path, |w| {
        writeln!(w, "id,distance,tolerance,reason")?;
        for u in &report.unbound {
            let distance = u.distance.map(|d| d.to_string()).unwrap_or_default();
            writeln!(
                w,
                "{},{distance},{},{}",
                u.id,
                report.max_distance,
                u.reason.replace(',', ";")
            )?;
        }
        Ok(())
    })
    .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// Writes `id,frame,u,v,visible` (pixel coordinates, visible 1 or 0; u, v empty behind the
/// camera), one row per point per frame, atomically.
pub fn write_image_tracks_csv(path: &Path, rows: &[ImagePoint]) -> Result<(), TrackError> {
    write_atomically(path, |w| {
        writeln!(w, "id,frame,u,v,visible")?;
        for r in rows {
            let coordinate = |c: f64| if c.is_finite() { c.to_string() } else { String::new() };
            let (u, v, seen) = (coordinate(r.u), coordinate(r.v), u8::from(r.visible));
            writeln!(w, "{},{},{u},{v},{seen}", r.id, r.frame)?;
        }
        Ok(())
    })
    .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// Writes the report as pretty JSON, atomically, with the `clock` of its frames (`fps`,
/// `start_frame`, `times`) beside the report's own fields.
///
/// Errors: a clock whose frame count is not the trajectories'; a write failure.
pub fn write_report_json(
    path: &Path,
    report: &TrackReport,
    clock: &Clock,
) -> Result<(), TrackError> {
    check_clock(&report.points, clock)?;
    #[derive(Serialize)]
    struct Timed<'a> {
        #[serde(flatten)]
        clock: &'a Clock,
        #[serde(flatten)]
        report: &'a TrackReport,
    }
    write_json_atomically(path, &Timed { clock, report })
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}
