//! The results of a tracking run and their files: `tracks.csv` (`id,frame,x,y,z`) and a JSON
//! report that adds each point's binding and the points that could not be bound.

use super::bind::Binding;
use super::project::ImagePoint;
use super::TrackError;
use crate::io::trajectories::{write_trajectories_csv, TrackPoint};
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
    /// Position per frame (scene units).
    pub trajectory: Vec<[f64; 3]>,
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

/// Writes `id,frame,x,y,z`, one row per point per frame, atomically, in the trajectory CSV
/// format of [`crate::io::trajectories::write_trajectories_csv`] (shortest round-trip floats).
pub fn write_tracks_csv(path: &Path, points: &[TrackedPoint]) -> Result<(), TrackError> {
    let rows: Vec<TrackPoint> = points
        .iter()
        .flat_map(|p| {
            p.trajectory.iter().enumerate().map(|(frame, &position)| TrackPoint {
                id: p.id.clone(),
                frame: frame as u32,
                position,
            })
        })
        .collect();
    write_atomically(path, |w| write_trajectories_csv(w, &rows))
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })
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

/// Writes the report as pretty JSON, atomically.
pub fn write_report_json(path: &Path, report: &TrackReport) -> Result<(), TrackError> {
    write_json_atomically(path, report)
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}
