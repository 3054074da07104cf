//! Tracks seen through one camera: each point's pixel coordinates in every frame and whether
//! the camera sees it there, the form an animator matches against the footage.
//!
//! Visible means: in front of the camera, inside the image, and the first surface hit along the
//! ray from the camera centre lies no nearer than the point itself (less a small tolerance, so
//! the surface a point is bound to does not hide it).

use super::output::TrackedPoint;
use super::TrackError;
use crate::camera::Camera;
use crate::geometry::SurfaceBvh;
use glam::DVec3;

/// One point of one frame in the image.
#[derive(Clone, Debug, PartialEq)]
pub struct ImagePoint {
    /// The tracked point's id.
    pub id: String,
    /// The frame index.
    pub frame: usize,
    /// Pixel coordinates (the centre of pixel (i, j) is (i + 0.5, j + 0.5)); NaN when the point
    /// is at or behind the camera plane.
    pub u: f64,
    /// The vertical pixel coordinate (y down), same convention as `u`.
    pub v: f64,
    /// In front of the camera, inside the image and not occluded by the frame's surface.
    pub visible: bool,
}

/// Relative depth slack: a hit nearer than `(1 − SLACK) · distance` occludes the point.
const SLACK: f64 = 1e-4;

/// Projects every point of `points` in every frame of the sequence (`faces`, positions per
/// frame) into `camera`, frame-major. A frame's surface occludes its points.
pub fn project_tracks(
    faces: &[[u32; 3]],
    frames: &[Vec<[f32; 3]>],
    points: &[TrackedPoint],
    camera: &Camera,
) -> Result<Vec<ImagePoint>, TrackError> {
    let mut out = Vec::with_capacity(frames.len() * points.len());
    for (t, positions) in frames.iter().enumerate() {
        let bvh = SurfaceBvh::build(positions, faces)?;
        for point in points {
            let p = DVec3::from(point.trajectory[t]);
            let (u, v) = camera.project(p).map_or((f64::NAN, f64::NAN), |uv| (uv.x, uv.y));
            let visible = bvh.sees(camera, p, SLACK).is_some();
            out.push(ImagePoint { id: point.id.clone(), frame: t, u, v, visible });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::unit_sphere;
    use crate::track::Binding;

    fn point(id: &str, trajectory: Vec<[f64; 3]>) -> TrackedPoint {
        let binding = Binding { face: 0, barycentric: [1.0, 0.0, 0.0], distance: 0.0 };
        let frames = trajectory.len();
        TrackedPoint {
            id: id.into(),
            binding,
            polygon: 0,
            trajectory,
            normal: vec![[0.0, 0.0, 1.0]; frames],
            tangent: vec![[1.0, 0.0, 0.0]; frames],
            orientation_held: Vec::new(),
        }
    }

    #[test]
    fn the_near_side_is_seen_the_far_side_hidden_and_projection_is_the_cameras() {
        let (positions, faces) = unit_sphere(3);
        let camera = Camera::look_at(
            64,
            48,
            40.0,
            40.0,
            32.0,
            24.0,
            DVec3::new(0.0, 0.0, -5.0),
            DVec3::ZERO,
            DVec3::NEG_Y,
        )
        .unwrap();
        // A vertex facing the camera, the one opposite it, and a point off to the side.
        let near = positions.iter().position(|p| p[2] < -0.999).unwrap();
        let far = positions.iter().position(|p| p[2] > 0.999).unwrap();
        let at = |i: usize| positions[i].map(f64::from);
        let points = [
            point("near", vec![at(near); 2]),
            point("far", vec![at(far); 2]),
            point("outside", vec![[40.0, 0.0, 0.0], [0.0, 0.0, -1.5]]),
        ];
        let frames = vec![positions.clone(); 2];
        let seen = project_tracks(&faces, &frames, &points, &camera).unwrap();
        assert_eq!(seen.len(), 6);
        let visible: Vec<bool> = seen.iter().map(|s| s.visible).collect();
        assert_eq!(visible, [true, false, false, true, false, true]);
        let expected = camera.project(DVec3::from(at(near))).unwrap();
        assert_eq!((seen[0].u, seen[0].v), (expected.x, expected.y));
        assert_eq!((seen[3].id.as_str(), seen[3].frame), ("near", 1));
    }
}
