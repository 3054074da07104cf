//! The GPU core: one Vulkan context, typed buffers, compute pipelines, command recording with
//! barriers, timestamps, device choice and feature checks, and validation as a test oracle.

mod buffer;
mod context;
mod error;
mod features;
mod fixed_sum;
mod host_clock;
mod host_ring;
mod pipeline;
mod recorder;
mod replay;
mod select;
mod shader;
mod staging;
mod timing;
mod usage;
mod validation;

pub use buffer::{BufferBinding, GpuBuffer};
pub use context::{
    parse_bytes, ContextOptions, DeviceLimits, GpuContext, DEVICE_MEMORY_ENV, FORCE_STAGING_ENV,
    IN_FLIGHT_ENV, MAX_STEPS_IN_FLIGHT,
};
pub use error::{GpuError, GpuResult};
pub use features::DeviceCapabilities;
pub use fixed_sum::{decode_fixed_sums, FixedPrecision, FixedResolve, FixedSums};
pub use host_clock::ClockReading;
pub use host_ring::HostRing;
pub use pipeline::{ComputePipeline, PipelineDesc};
pub use recorder::Recorder;
pub use replay::{Batch, Replay};
pub use select::{choose_device, DeviceInfo, DEVICE_ENV};
pub(crate) use shader::push_layout;
pub use shader::Shader;
pub use timing::{PassTime, PassTimes};
pub use usage::BufferBytes;
pub use validation::{ValidationLog, VALIDATION_ENV};
