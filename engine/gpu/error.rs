//! Errors of the GPU layer. Each names what failed and why, so a user can act on it.

use ash::vk;

/// Why a GPU operation failed.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// The Vulkan loader library cannot be loaded; the message is the loader's.
    #[error("cannot load the Vulkan library (is libvulkan1 installed?): {0}")]
    Loading(String),
    /// No Vulkan device found: none is installed, or the driver is incompatible.
    #[error("no Vulkan device found (install mesa-vulkan-drivers for the CPU device lavapipe)")]
    NoDevice,
    /// No device matches the index or name asked for.
    #[error("no Vulkan device matches \"{wanted}\"; devices: {available}")]
    DeviceNotFound {
        /// What was asked for: a device index or a piece of a device name.
        wanted: String,
        /// The devices there are, as one line.
        available: String,
    },
    /// The chosen device lacks features the engine requires.
    #[error("device \"{device}\" lacks required features: {}", missing.join(", "))]
    MissingFeatures {
        /// Name of the device.
        device: String,
        /// Names of the requirements it fails.
        missing: Vec<&'static str>,
    },
    /// Validation was requested and the Khronos validation layer is not installed.
    #[error("validation was requested but VK_LAYER_KHRONOS_validation is not installed (Debian: vulkan-validationlayers)")]
    NoValidationLayer,
    /// Validation was requested and its debug messenger cannot be created.
    #[error("validation was requested but its message callback cannot be set up (vkCreateDebugUtilsMessengerEXT: {0})")]
    NoValidationMessenger(vk::Result),
    /// A buffer's size is over the device's `maxStorageBufferRange` or
    /// `maxMemoryAllocationSize`.
    #[error(
        "buffer \"{name}\" needs {bytes} bytes, over this device's {limit_name} of {limit} bytes"
    )]
    BufferTooLarge {
        /// Name of the buffer.
        name: String,
        /// Bytes it needs (`u64::MAX` when the size overflows).
        bytes: u64,
        /// The limit, in bytes.
        limit: u64,
        /// The Vulkan name of the limit.
        limit_name: &'static str,
    },
    /// An allocation failed: memory ran out, or no suitable memory type exists.
    #[error("out of GPU memory allocating buffer \"{name}\" ({bytes} bytes): {reason}")]
    OutOfMemory {
        /// Name of the buffer, or of the Vulkan call that ran out.
        name: String,
        /// Bytes requested; 0 where unknown.
        bytes: u64,
        /// The allocator's or driver's message.
        reason: String,
    },
    /// A request is over a device limit (workgroups, shared memory) or another fixed bound.
    #[error("{what}: {count} exceeds the device limit {limit_name} = {limit}")]
    LimitExceeded {
        /// What was asked for.
        what: String,
        /// How much was asked for, in the limit's unit.
        count: u64,
        /// The limit.
        limit: u64,
        /// The name of the limit (a Vulkan limit where there is one).
        limit_name: &'static str,
    },
    /// A length given to an operation does not fit, or does not match, a buffer's length.
    #[error("{what}: {len} elements given, buffer \"{name}\" holds {capacity}")]
    LengthMismatch {
        /// The operation.
        what: &'static str,
        /// Name of the buffer.
        name: String,
        /// Elements the operation was given or needs.
        len: usize,
        /// Elements the buffer (or the object sized for it) holds.
        capacity: usize,
    },
    /// The device was lost (driver crash or timeout); the string names the Vulkan call.
    #[error("the GPU device was lost (driver crash or timeout) during {0}")]
    DeviceLost(&'static str),
    /// Creating a compute pipeline failed.
    #[error("cannot create compute pipeline {name}: {result}")]
    Pipeline {
        /// Name of the pipeline.
        name: &'static str,
        /// The driver's result.
        result: vk::Result,
    },
    /// A batch of recorded command buffers cannot go on the queue (see `Batch::submit`).
    #[error("cannot submit the batch: {0}")]
    BatchRefused(&'static str),
    /// An environment variable that tunes the engine holds a value it does not accept.
    #[error("environment variable {variable}=\"{value}\" is not valid; expected {expected}")]
    InvalidSetting {
        /// The variable.
        variable: &'static str,
        /// Its value.
        value: String,
        /// The values it accepts.
        expected: &'static str,
    },
    /// Any other failed Vulkan call.
    #[error("Vulkan call {call} failed: {result}")]
    Vulkan {
        /// The Vulkan function (or step) that failed.
        call: &'static str,
        /// Its result.
        result: vk::Result,
    },
}

/// The result of GPU operations.
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
