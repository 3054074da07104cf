//! The one camera model of the project (docs/conventions.md): a pinhole with OpenCV axes (x right,
//! y down, z forward), a rigid `world_to_camera`, intrinsics in pixels, and pixel (i, j)
//! centred at (i + 0.5, j + 0.5). Other conventions are converted on the way in, here.
//!
//! `cam.json`: `{"width", "height", "fx", "fy", "cx", "cy", "world_to_camera": [16 numbers,
//! row-major]}`.

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Rotation rows must be orthonormal to this tolerance (f32-written files pass comfortably).
const RIGID_TOLERANCE: f64 = 1e-4;

/// Why a camera could not be built, read or written.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    /// Reading or writing a camera file failed, or its contents are not a valid camera.
    #[error("{}: {problem}", path.display())]
    File {
        /// The `cam.json` file.
        path: PathBuf,
        /// What went wrong with it.
        problem: String,
    },
    /// The numbers fail a check of [`Camera::new`]; the message names the check.
    #[error("invalid camera: {0}")]
    Invalid(String),
}

/// A pinhole camera with OpenCV axes (x right, y down, z forward); pixel (i, j) is centred at
/// (i + 0.5, j + 0.5). Built through [`Camera::new`] (or the other constructors), it is checked;
/// the fields are public and not re-checked when changed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels.
    pub fy: f64,
    /// Principal point x, in pixels (pixel centres at half-integers).
    pub cx: f64,
    /// Principal point y, in pixels (pixel centres at half-integers).
    pub cy: f64,
    /// Rigid transform from world to camera coordinates (last row 0 0 0 1).
    pub world_to_camera: DMat4,
}

/// The JSON form, kept apart so the public type holds glam matrices.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraJson {
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    world_to_camera: [f64; 16],
}

impl Camera {
    /// A checked camera: positive size and focal lengths, finite numbers, and a rigid
    /// `world_to_camera` (orthonormal rotation with determinant +1, last row 0 0 0 1).
    pub fn new(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        world_to_camera: DMat4,
    ) -> Result<Self, CameraError> {
        let invalid = |problem: String| Err(CameraError::Invalid(problem));
        if width == 0 || height == 0 {
            return invalid(format!("image size {width}x{height} is empty"));
        }
        // Phrased as positive checks so NaN fails them.
        if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
            return invalid(format!("focal lengths fx={fx}, fy={fy} must be positive and finite"));
        }
        if !(cx.is_finite() && cy.is_finite()) {
            return invalid(format!("principal point ({cx}, {cy}) is not finite"));
        }
        if !world_to_camera.is_finite() {
            return invalid("world_to_camera has a non-finite entry".into());
        }
        let rotation = DMat3::from_mat4(world_to_camera);
        let error = (rotation * rotation.transpose() - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, e| m.max(e.abs()));
        if !(error < RIGID_TOLERANCE && rotation.determinant() > 0.0) {
            return invalid(format!("world_to_camera is not rigid (rotation orthonormality error {error:.2e}, determinant {:.4})", rotation.determinant()));
        }
        if world_to_camera.row(3) != DVec4::W {
            return invalid(format!(
                "world_to_camera's last row is {:?}, not 0 0 0 1",
                world_to_camera.row(3).to_array()
            ));
        }
        Ok(Self { width, height, fx, fy, cx, cy, world_to_camera })
    }

    /// From an OpenGL/Blender camera-to-world matrix (x right, y up, z backward), the
    /// convention of nerfstudio and D-NeRF: flip y and z, then invert.
    pub fn from_opengl_camera_to_world(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        camera_to_world: DMat4,
    ) -> Result<Self, CameraError> {
        let opencv_to_opengl = DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0));
        let world_to_camera = rigid_inverse(camera_to_world * opencv_to_opengl);
        Self::new(width, height, fx, fy, cx, cy, world_to_camera)
    }

    /// A camera at `eye` looking at `target`, with `up` pointing up in the image (the image y
    /// axis points down, along −up). `eye − target` must not be parallel to `up`.
    #[allow(clippy::too_many_arguments)]
    pub fn look_at(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        eye: DVec3,
        target: DVec3,
        up: DVec3,
    ) -> Result<Self, CameraError> {
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        let down = forward.cross(right);
        let rotation = DMat3::from_cols(right, down, forward).transpose();
        let world_to_camera = DMat4::from_mat3(rotation) * DMat4::from_translation(-eye);
        Self::new(width, height, fx, fy, cx, cy, world_to_camera)
    }

    /// Reads a `cam.json` (format in the module docs) and checks it as [`Camera::new`] does.
    /// Fails with [`CameraError::File`] when the file cannot be read, is not a camera JSON (unknown
    /// fields are rejected), or is not a valid camera.
    pub fn load_json(path: &Path) -> Result<Self, CameraError> {
        let file_error = |problem: String| CameraError::File { path: path.to_path_buf(), problem };
        let text =
            std::fs::read_to_string(path).map_err(|e| file_error(format!("cannot read: {e}")))?;
        let json: CameraJson = serde_json::from_str(&text)
            .map_err(|e| file_error(format!("not a camera JSON: {e}")))?;
        let world_to_camera = DMat4::from_cols_array(&json.world_to_camera).transpose();
        Self::new(json.width, json.height, json.fx, json.fy, json.cx, json.cy, world_to_camera)
            .map_err(|e| file_error(e.to_string()))
    }

    /// Writes `cam.json` atomically.
    pub fn save_json(&self, path: &Path) -> Result<(), CameraError> {
        let json = CameraJson {
            width: self.width,
            height: self.height,
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            world_to_camera: self.world_to_camera.transpose().to_cols_array(),
        };
        let text = serde_json::to_string_pretty(&json).expect("a camera always serializes");
        crate::io::write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))
            .map_err(|e| CameraError::File {
                path: path.to_path_buf(),
                problem: format!("cannot write: {e}"),
            })
    }

    /// A world point in camera coordinates (z is the depth along the optical axis).
    #[inline]
    pub fn to_camera(&self, world: DVec3) -> DVec3 {
        self.world_to_camera.transform_point3(world)
    }

    /// Pixel coordinates of a world point, `None` for points at or behind the camera plane.
    #[inline]
    pub fn project(&self, world: DVec3) -> Option<DVec2> {
        let p = self.to_camera(world);
        (p.z > 0.0)
            .then(|| DVec2::new(self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy))
    }

    /// dE/dx for a world point whose camera-space position is `c`, from dE/dq of its pixel
    /// coordinates q (the chain rule through [`Self::project`]; a constant offset of q alike).
    pub fn pixel_gradient_to_world(&self, c: DVec3, d_pixel: DVec2) -> DVec3 {
        let dc = DVec3::new(
            d_pixel.x * self.fx / c.z,
            d_pixel.y * self.fy / c.z,
            -(d_pixel.x * self.fx * c.x + d_pixel.y * self.fy * c.y) / (c.z * c.z),
        );
        glam::DMat3::from_mat4(self.world_to_camera).transpose() * dc
    }

    /// The camera centre in world coordinates.
    pub fn center(&self) -> DVec3 {
        rigid_inverse(self.world_to_camera).w_axis.truncate()
    }

    /// The camera's "up" in world coordinates (unit): image rows grow along camera +y, so up
    /// is −y of the camera frame.
    pub fn world_up(&self) -> DVec3 {
        -rigid_inverse(self.world_to_camera).y_axis.truncate().normalize()
    }

    /// The world ray through pixel coordinates (u, v): the camera centre and a unit direction.
    pub fn pixel_ray(&self, u: f64, v: f64) -> (DVec3, DVec3) {
        let camera_to_world = rigid_inverse(self.world_to_camera);
        let direction = DVec3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0);
        (
            camera_to_world.w_axis.truncate(),
            camera_to_world.transform_vector3(direction).normalize(),
        )
    }
}

/// Inverse of a rigid transform without a general 4×4 inverse (exact for rotations).
fn rigid_inverse(m: DMat4) -> DMat4 {
    let rotation_t = DMat3::from_mat4(m).transpose();
    let translation = -(rotation_t * m.w_axis.truncate());
    DMat4::from_cols(
        rotation_t.x_axis.extend(0.0),
        rotation_t.y_axis.extend(0.0),
        rotation_t.z_axis.extend(0.0),
        translation.extend(1.0),
    )
}

/// The mean of the cameras' up vectors ([`Camera::world_up`]): a capture rig's idea of "up".
/// Zero for no cameras.
pub fn mean_up(cameras: &[Camera]) -> DVec3 {
    cameras.iter().map(Camera::world_up).sum::<DVec3>() / cameras.len().max(1) as f64
}

/// The point with the least summed squared distance to every ray (origin, unit direction):
/// where an inward-looking rig's rays meet. None for fewer than two rays, or rays within about
/// a degree of parallel.
pub fn nearest_point_to_rays(rays: impl IntoIterator<Item = (DVec3, DVec3)>) -> Option<DVec3> {
    let (mut a, mut b, mut count) = (DMat3::ZERO, DVec3::ZERO, 0);
    for (origin, dir) in rays {
        // Σ (I − d dᵀ)(x − o) = 0.
        let m = DMat3::IDENTITY - DMat3::from_cols(dir * dir.x, dir * dir.y, dir * dir.z);
        a += m;
        b += m * origin;
        count += 1;
    }
    // det(A) ~ sin² of the angle between rays; 1e-4 relative keeps angles above about 1°.
    let scale = (a.x_axis.x + a.y_axis.y + a.z_axis.z) / 3.0;
    (count >= 2 && a.determinant() > 1e-4 * scale.powi(3)).then(|| a.inverse() * b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rig_up_is_the_look_at_up() {
        let ring = |up: DVec3, side: DVec3| -> Vec<Camera> {
            (0..6)
                .map(|k| {
                    let a = k as f64 * 1.047;
                    let eye = (side * a.cos() + up.cross(side) * a.sin()) * 3.0 + up * 0.5;
                    Camera::look_at(64, 64, 50.0, 50.0, 32.0, 32.0, eye, DVec3::ZERO, up).unwrap()
                })
                .collect()
        };
        // Slightly above the subject, looking down: each camera's up tilts, the mean stays.
        for up in [DVec3::Z, DVec3::Y, DVec3::NEG_Y] {
            let side = if up.x.abs() < 0.5 && up.z.abs() < 0.5 { DVec3::X } else { DVec3::Y };
            let mean = mean_up(&ring(up, side));
            assert!(mean.normalize().dot(up) > 0.98, "{mean} for {up}");
        }
        assert_eq!(mean_up(&[]), DVec3::ZERO);
    }

    fn look_from_minus_z() -> Camera {
        // Camera at (0, 0, -4) looking along +z: world_to_camera is a translation by +4 in z.
        Camera::new(
            64,
            48,
            50.0,
            50.0,
            32.0,
            24.0,
            DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0)),
        )
        .unwrap()
    }

    #[test]
    fn projects_known_points() {
        let cam = look_from_minus_z();
        assert_eq!(cam.project(DVec3::ZERO), Some(DVec2::new(32.0, 24.0)));
        assert_eq!(cam.project(DVec3::new(0.4, -0.8, 0.0)), Some(DVec2::new(37.0, 14.0)));
        assert_eq!(cam.project(DVec3::new(0.0, 0.0, -5.0)), None);
        assert!((cam.center() - DVec3::new(0.0, 0.0, -4.0)).length() < 1e-12);
    }

    #[test]
    fn pixel_ray_hits_the_projected_point() {
        let cam = Camera::new(
            80,
            60,
            70.0,
            65.0,
            41.0,
            29.0,
            DMat4::from_rotation_y(0.3) * DMat4::from_translation(DVec3::new(0.2, -0.1, 5.0)),
        )
        .unwrap();
        let point = DVec3::new(0.3, 0.2, -0.4);
        let pixel = cam.project(point).unwrap();
        let (origin, direction) = cam.pixel_ray(pixel.x, pixel.y);
        let along = (point - origin).dot(direction);
        assert!((origin + along * direction - point).length() < 1e-9);
    }

    #[test]
    fn look_at_centres_the_target() {
        let eye = DVec3::new(3.0, 1.0, -2.0);
        let cam = Camera::look_at(
            64,
            48,
            50.0,
            50.0,
            32.0,
            24.0,
            eye,
            DVec3::new(0.5, 0.2, 0.1),
            DVec3::Y,
        )
        .unwrap();
        assert!(
            (cam.project(DVec3::new(0.5, 0.2, 0.1)).unwrap() - DVec2::new(32.0, 24.0)).length()
                < 1e-9
        );
        assert!((cam.center() - eye).length() < 1e-12);
        // Up in the world is up in the image (smaller v).
        assert!(cam.project(DVec3::new(0.5, 1.2, 0.1)).unwrap().y < 24.0);
        assert!(Camera::look_at(8, 8, 1.0, 1.0, 4.0, 4.0, DVec3::Y, DVec3::ZERO, DVec3::Y).is_err());
    }

    #[test]
    fn opengl_import_flips_y_and_z() {
        // An OpenGL camera at (0, 0, 4) looking down -z sees the origin at the image centre,
        // and world +y (up) lands above it (smaller v).
        let c2w = DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0));
        let cam = Camera::from_opengl_camera_to_world(64, 48, 50.0, 50.0, 32.0, 24.0, c2w).unwrap();
        assert_eq!(cam.project(DVec3::ZERO), Some(DVec2::new(32.0, 24.0)));
        assert!(cam.project(DVec3::new(0.0, 1.0, 0.0)).unwrap().y < 24.0);
    }

    #[test]
    fn json_round_trip_and_bad_cameras() {
        let dir = std::env::temp_dir();
        let path = dir.join(format!("tagsplat-cam-{}.json", std::process::id()));
        let cam = Camera::new(
            67,
            33,
            40.0,
            41.0,
            33.5,
            16.5,
            DMat4::from_rotation_x(0.7) * DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0)),
        )
        .unwrap();
        cam.save_json(&path).unwrap();
        let back = Camera::load_json(&path).unwrap();
        assert!(
            back.world_to_camera.abs_diff_eq(cam.world_to_camera, 1e-15)
                && back.fx == cam.fx
                && back.width == 67
        );
        let scaled = DMat4::from_scale(DVec3::splat(2.0));
        let reflected = DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
        let mut nan = DMat4::IDENTITY;
        nan.w_axis.x = f64::NAN;
        for (m, expected) in [(scaled, "not rigid"), (reflected, "not rigid"), (nan, "non-finite")]
        {
            let message = Camera::new(4, 4, 1.0, 1.0, 2.0, 2.0, m).unwrap_err().to_string();
            assert!(message.contains(expected), "{message}");
        }
        assert!(Camera::new(4, 4, f64::NAN, 1.0, 2.0, 2.0, DMat4::IDENTITY).is_err());
        assert!(Camera::new(0, 4, 1.0, 1.0, 2.0, 2.0, DMat4::IDENTITY).is_err());
        std::fs::write(&path, r#"{"width": 4, "height": 4, "fx": 1, "fy": 1, "cx": 2, "cy": 2, "world_to_camera": [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}"#).unwrap();
        let message = Camera::load_json(&path).unwrap_err().to_string();
        assert!(
            message.contains(&path.display().to_string()) && message.contains("not rigid"),
            "{message}"
        );
        std::fs::write(&path, r#"{"width": 4}"#).unwrap();
        assert!(Camera::load_json(&path).unwrap_err().to_string().contains("missing field"));
        std::fs::remove_file(&path).unwrap();
    }
}
