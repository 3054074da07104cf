//! One tracking run: bind the queries on frame 0, follow them through every frame
//! ([`track`]); and the run on a sequence as a reader gave it ([`track_sequence`]), which the
//! command-line program, Python and C all call.

use super::bind::{bind_point, bind_ray, Binding, Unbound};
use super::bindings::{check_binding, resolve_anchors, Anchor, BindingsFile};
use super::clock::Clock;
use super::frame::surface_frames;
use super::output::{TrackReport, TrackedPoint, UnboundPoint};
use super::trajectory::trajectories;
use super::TrackError;
use crate::camera::Camera;
use crate::geometry::bvh::SurfaceBvh;
use crate::geometry::SurfaceError;
use crate::mesh::bounding_diagonal;
use crate::sequence::orient::{Orientation, SignedAxis, UpAxis};
use crate::sequence::SequenceInfo;
use glam::DVec3;

/// What to track: frame-0 points, or pixels of a camera (ray-cast onto the frame-0 surface).
pub enum Queries {
    /// (id, position) per point, in frame-0 coordinates (scene units).
    Points(Vec<(String, [f64; 3])>),
    /// Pixels of one camera, each cast as a ray onto the frame-0 surface.
    Pixels {
        /// The camera whose rays are cast onto the frame-0 surface.
        camera: Camera,
        /// (id, (u, v)) per point; pixel (i, j) is centred at (i + 0.5, j + 0.5).
        pixels: Vec<(String, [f64; 2])>,
    },
    /// Points bound already, e.g. read from a bindings file
    /// ([`super::bindings::BindingsFile::resolve`]): (id, binding) per point.
    Bindings(Vec<(String, Binding)>),
}

/// Binds `queries` on frame 0 of the sequence (`faces`, vertex positions per frame) and
/// returns every bound point's trajectory and orientation frames ([`super::frame`]); given
/// bindings are used as they are. A 3D point farther from the surface than
/// `max_distance_relative` × the frame-0 bounding-box diagonal, a pixel whose ray misses, or a
/// non-finite query is listed in `unbound`, never snapped. An infinite tolerance binds every
/// finite point.
///
/// Each point's polygon is its face; [`TrackReport::in_polygons`] names the file's polygons.
///
/// Errors: a negative or NaN tolerance, no frames, an unusable frame-0 mesh, frames of
/// different vertex counts, a given binding that is unusable on the mesh.
pub fn track(
    faces: &[[u32; 3]],
    frames: &[Vec<[f32; 3]>],
    queries: &Queries,
    max_distance_relative: f64,
) -> Result<TrackReport, TrackError> {
    if max_distance_relative.is_nan() || max_distance_relative < 0.0 {
        return Err(TrackError::MaxDistance(max_distance_relative));
    }
    let frame0 = frames.first().ok_or(SurfaceError::EmptyMesh)?;
    let bvh = SurfaceBvh::build(frame0, faces)?;
    let max_distance = max_distance_relative * bounding_diagonal(frame0);
    let results: Vec<(&str, Result<Binding, Unbound>)> = match queries {
        Queries::Points(points) => points
            .iter()
            .map(|(id, p)| (id.as_str(), bind_point(&bvh, DVec3::from(*p), max_distance)))
            .collect(),
        Queries::Pixels { camera, pixels } => pixels
            .iter()
            .map(|(id, [u, v])| {
                let (origin, dir) = camera.pixel_ray(*u, *v);
                (id.as_str(), bind_ray(&bvh, origin, dir))
            })
            .collect(),
        Queries::Bindings(given) => {
            for (id, binding) in given {
                check_binding(binding, faces.len())
                    .map_err(|problem| TrackError::Binding { id: id.clone(), problem })?;
            }
            given.iter().map(|(id, b)| (id.as_str(), Ok(*b))).collect()
        }
    };
    let mut bound = Vec::new();
    let mut unbound = Vec::new();
    for (id, result) in results {
        match result {
            Ok(binding) => bound.push((id, binding)),
            Err(why) => unbound.push(UnboundPoint {
                id: id.to_owned(),
                reason: why.to_string(),
                distance: match why {
                    Unbound::TooFar { distance } => Some(distance),
                    _ => None,
                },
            }),
        }
    }
    let bindings: Vec<Binding> = bound.iter().map(|(_, b)| *b).collect();
    let paths = trajectories(&bindings, faces, frames)?;
    let points = bound
        .into_iter()
        .zip(paths)
        .enumerate()
        .map(|(i, ((id, binding), path))| {
            let (oriented, held) =
                surface_frames(&binding, faces, frames).ok_or(TrackError::FaceOutOfRange {
                    binding: i,
                    face: binding.face,
                    faces: faces.len(),
                })?;
            Ok(TrackedPoint {
                id: id.to_owned(),
                binding,
                polygon: binding.face,
                trajectory: path.iter().map(|p| p.to_array()).collect(),
                normal: oriented.iter().map(|o| o.normal).collect(),
                tangent: oriented.iter().map(|o| o.tangent).collect(),
                orientation_held: held,
            })
        })
        .collect::<Result<_, TrackError>>()?;
    Ok(TrackReport {
        frames: frames.len(),
        vertices: frame0.len(),
        faces: faces.len(),
        max_distance,
        points,
        unbound,
    })
}

/// What [`track_sequence`] follows: queries as [`track`] takes them, or bindings still to be
/// resolved on the sequence's mesh.
pub enum Targets {
    /// Points, pixels, or bindings on the sequence's triangles.
    Queries(Queries),
    /// A bindings file as read: its rows are resolved on the mesh and checked against the
    /// file's polygons ([`BindingsFile::resolve`]).
    File(BindingsFile),
    /// Anchors given directly, (id, anchor) per point: a front's arrays ([`resolve_anchors`]).
    Anchors(Vec<(String, Anchor)>),
}

/// A run on a sequence as a reader gave it.
#[derive(Clone, Debug)]
pub struct Tracked {
    /// The points, each polygon the file's (see [`TrackReport::in_polygons`]).
    pub report: TrackReport,
    /// When each frame plays ([`Clock::of`] the file's times).
    pub clock: Clock,
    /// The up axis the sequence's file declares, when it does.
    pub up: Option<SignedAxis>,
}

impl Tracked {
    /// The turn of a pins GLB onto glTF's +Y: from `from_up` (the sequence's up), else the up
    /// its file declares, else `fallback` (the sequence taken to be `fallback`-up already).
    pub fn pins_orientation(&self, from_up: Option<SignedAxis>, fallback: UpAxis) -> Orientation {
        let source = from_up.or(self.up).unwrap_or(Orientation::keep(fallback).source);
        Orientation::new(source, UpAxis::Y)
    }
}

/// Which step of [`track_sequence`] failed; the source says why.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Given bindings do not fit the sequence (a file's error names its line, an anchor's
    /// its point).
    #[error("cannot use the bindings on the sequence")]
    Bindings(#[source] TrackError),
    /// Binding, following, the polygon map or the clock.
    #[error("cannot track on the sequence")]
    Track(#[source] TrackError),
}

/// Tracks `targets` on a sequence as a reader gave it (`faces`, positions per frame, and the
/// `info` its file gave): given bindings resolved on its mesh first, then [`track`] with
/// `max_distance_relative`, each point's polygon named from `info.polygon_of`, and the frames'
/// clock from its times. Every front's `track` is this one call.
///
/// Errors: as [`RunError`] says, with the failing step's [`TrackError`] as the source.
pub fn track_sequence(
    faces: &[[u32; 3]],
    frames: &[Vec<[f32; 3]>],
    info: &SequenceInfo,
    targets: &Targets,
    max_distance_relative: f64,
) -> Result<Tracked, RunError> {
    let vertices = frames.first().map_or(0, Vec::len);
    let polygon_of = info.polygon_of.as_deref();
    // Bindings resolved here live as long as the borrowed queries.
    let resolved;
    let queries = match targets {
        Targets::Queries(queries) => queries,
        Targets::File(file) => {
            let bound = file.resolve(faces, vertices, polygon_of).map_err(RunError::Bindings)?;
            resolved = Queries::Bindings(bound);
            &resolved
        }
        Targets::Anchors(anchors) => {
            let bound = resolve_anchors(anchors, faces, vertices).map_err(RunError::Bindings)?;
            resolved = Queries::Bindings(bound);
            &resolved
        }
    };
    let report = track(faces, frames, queries, max_distance_relative).map_err(RunError::Track)?;
    let report = match polygon_of {
        Some(polygon_of) => report.in_polygons(polygon_of).map_err(RunError::Track)?,
        None => report,
    };
    let clock = Clock::of(info, frames.len()).map_err(RunError::Track)?;
    Ok(Tracked { report, clock, up: info.up })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sequence::SourceSequence;

    /// Two quads side by side, fanned into triangles 0, 1 (quad 0) and 2, 3 (quad 1), on a
    /// Z-up clock of frames 10 and 11 at 24 per second.
    fn strip() -> (crate::sequence::MeshSequence, SequenceInfo) {
        let flat: Vec<[f32; 3]> = (0..6).map(|i| [(i % 3) as f32, (i / 3) as f32, 0.0]).collect();
        let lifted = flat.iter().map(|p| [p[0], p[1], 0.5 * p[0]]).collect();
        let source = SourceSequence {
            counts: vec![4, 4],
            indices: vec![0, 1, 4, 3, 1, 2, 5, 4],
            frames: vec![flat, lifted],
            times: vec![10.0 / 24.0, 11.0 / 24.0],
            up: SignedAxis::parse("+z"),
            ..SourceSequence::default()
        };
        source.into_sequence().unwrap()
    }

    #[test]
    fn given_anchors_are_tracked_with_the_files_polygons_clock_and_up() {
        let (seq, info) = strip();
        let anchors = vec![("v5".to_string(), Anchor::Vertex(5)), ("v0".into(), Anchor::Vertex(0))];
        let targets = Targets::Anchors(anchors);
        let tracked = track_sequence(&seq.faces, &seq.frames, &info, &targets, 0.0).unwrap();
        let points = &tracked.report.points;
        assert_eq!(points.iter().map(|p| p.polygon).collect::<Vec<_>>(), [1, 0]);
        assert_eq!(points[0].trajectory, [[2.0, 1.0, 0.0], [2.0, 1.0, 1.0]]);
        assert!((tracked.clock.start_frame - 10.0).abs() < 1e-9);
        assert_eq!(tracked.clock.times, [10.0 / 24.0, 11.0 / 24.0]);
        // Z up turned onto glTF's +Y unless the caller says the sequence is Y-up.
        assert!(!tracked.pins_orientation(None, UpAxis::Y).is_identity());
        assert!(tracked.pins_orientation(SignedAxis::parse("+y"), UpAxis::Y).is_identity());
    }

    #[test]
    fn errors_say_which_step_failed() {
        let (seq, info) = strip();
        let far = Targets::Anchors(vec![("p".into(), Anchor::Vertex(6))]);
        let error = track_sequence(&seq.faces, &seq.frames, &info, &far, 0.0).unwrap_err();
        assert!(matches!(error, RunError::Bindings(_)), "{error:?}");
        let points = Targets::Queries(Queries::Points(vec![("p".into(), [0.5, 0.5, 0.0])]));
        let error = track_sequence(&seq.faces, &seq.frames, &info, &points, -1.0).unwrap_err();
        assert!(matches!(error, RunError::Track(TrackError::MaxDistance(_))), "{error:?}");
    }
}
