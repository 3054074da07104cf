//! One view as the vertex-pulling kernels read it (`View` in silhouette.comp and flow.comp):
//! the camera's world-to-camera matrix, its intrinsics and its size, and two words the kernel
//! gives its own meaning.

use crate::camera::Camera;
use bytemuck::{Pod, Zeroable};

/// A camera in the kernels' layout (std430: a mat4, a vec4, a uvec4).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct PinholeView {
    world_to_camera: [f32; 16],
    intrinsics: [f32; 4],
    /// Width, height, then the kernel's two words.
    dims: [u32; 4],
}

impl PinholeView {
    /// `camera` in f32, with the kernel's `extra` words after its size.
    pub(crate) fn new(camera: &Camera, extra: [u32; 2]) -> Self {
        Self {
            world_to_camera: camera.world_to_camera.to_cols_array().map(|v| v as f32),
            intrinsics: [camera.fx, camera.fy, camera.cx, camera.cy].map(|v| v as f32),
            dims: [camera.width, camera.height, extra[0], extra[1]],
        }
    }
}
