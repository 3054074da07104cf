//! Errors of the GPU layer. Each names what failed and why, so a user can act on it.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("cannot load the Vulkan library (is libvulkan1 installed?): {0}")]
    Loading(String),
    #[error("no Vulkan device found (install mesa-vulkan-drivers for the CPU device lavapipe)")]
    NoDevice,
    #[error("no Vulkan device matches \"{wanted}\"; devices: {available}")]
    DeviceNotFound { wanted: String, available: String },
    #[error("device \"{device}\" lacks required features: {}", missing.join(", "))]
    MissingFeatures { device: String, missing: Vec<&'static str> },
    #[error("validation was requested but VK_LAYER_KHRONOS_validation is not installed (Debian: vulkan-validationlayers)")]
    NoValidationLayer,
    #[error("validation was requested but its message callback cannot be set up (vkCreateDebugUtilsMessengerEXT: {0})")]
    NoValidationMessenger(vk::Result),
    #[error(
        "buffer \"{name}\" needs {bytes} bytes, over this device's {limit_name} of {limit} bytes"
    )]
    BufferTooLarge { name: String, bytes: u64, limit: u64, limit_name: &'static str },
    #[error("out of GPU memory allocating buffer \"{name}\" ({bytes} bytes): {reason}")]
    OutOfMemory { name: String, bytes: u64, reason: String },
    #[error("{what}: {count} exceeds the device limit {limit_name} = {limit}")]
    LimitExceeded { what: String, count: u64, limit: u64, limit_name: &'static str },
    #[error("{what}: {len} elements given, buffer \"{name}\" holds {capacity}")]
    LengthMismatch { what: &'static str, name: String, len: usize, capacity: usize },
    #[error("the GPU device was lost (driver crash or timeout) during {0}")]
    DeviceLost(&'static str),
    #[error("cannot create compute pipeline {name}: {result}")]
    Pipeline { name: &'static str, result: vk::Result },
    #[error("Vulkan call {call} failed: {result}")]
    Vulkan { call: &'static str, result: vk::Result },
}

pub type GpuResult<T> = Result<T, GpuError>;

/// Adds the name of the failing call to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn during(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    #[inline]
    fn during(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| match result {
            vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost(call),
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                GpuError::OutOfMemory {
                    name: call.to_string(),
                    bytes: 0,
                    reason: result.to_string(),
                }
            }
            _ => GpuError::Vulkan { call, result },
        })
    }
}
