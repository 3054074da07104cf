//! One tracking run: bind the queries on frame 0, follow them through every frame.

use super::bind::{bind_point, bind_ray, Binding, Unbound};
use super::bindings::check_binding;
use super::frame::surface_frames;
use super::output::{TrackReport, TrackedPoint, UnboundPoint};
use super::trajectory::trajectories;
use super::TrackError;
use crate::camera::Camera;
use crate::geometry::bvh::SurfaceBvh;
use crate::geometry::SurfaceError;
use crate::mesh::bounding_diagonal;
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
