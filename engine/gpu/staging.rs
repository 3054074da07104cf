//! Staging memory for devices whose working memory the host cannot see (discrete GPUs): one
//! upload and one readback buffer per context, reused across transfers and grown to the
//! largest so far (rounded up to a power of two), so a training step's small readbacks
//! allocate nothing. Callers hold the pool's lock from the host copy to the fence.

use super::buffer::{allocate, coherent_pointer, free};
use super::context::GpuContext;
use super::error::{GpuError, GpuResult};
use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

/// Which way a staging buffer carries data.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Direction {
    Upload,
    Readback,
}

/// A host-visible, coherent buffer and its mapping.
pub(crate) struct StagingBuffer {
    raw: vk::Buffer,
    allocation: Allocation,
    mapped: *mut u8,
    bytes: u64,
}

// The mapping is only touched with the pool's lock held.
unsafe impl Send for StagingBuffer {}

impl StagingBuffer {
    pub(crate) fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// The start of the mapping: at least as many bytes as were asked of [`StagingPool::get`].
    pub(crate) fn mapped(&self) -> *mut u8 {
        self.mapped
    }
}

#[derive(Default)]
pub(crate) struct StagingPool {
    upload: Option<StagingBuffer>,
    readback: Option<StagingBuffer>,
}

impl StagingPool {
    /// The `direction` buffer, holding at least `bytes` (replaced by a larger one when needed).
    pub(crate) fn get(
        &mut self,
        ctx: &GpuContext,
        direction: Direction,
        bytes: u64,
    ) -> GpuResult<&StagingBuffer> {
        let (slot, name, location) = match direction {
            Direction::Upload => (&mut self.upload, "staging upload", MemoryLocation::CpuToGpu),
            Direction::Readback => {
                (&mut self.readback, "staging readback", MemoryLocation::GpuToCpu)
            }
        };
        if slot.as_ref().is_none_or(|s| s.bytes < bytes) {
            if let Some(old) = slot.take() {
                free(ctx, old.raw, old.allocation);
            }
            let size = bytes.max(1 << 16).next_power_of_two();
            let (raw, allocation) = allocate(ctx, name, size, location)?;
            let Some(mapped) = coherent_pointer(&allocation) else {
                free(ctx, raw, allocation);
                let reason = "the device has no host-visible coherent memory to stage through";
                return Err(GpuError::OutOfMemory {
                    name: name.into(),
                    bytes,
                    reason: reason.into(),
                });
            };
            *slot = Some(StagingBuffer { raw, allocation, mapped, bytes: size });
        }
        Ok(slot.as_ref().expect("filled just above"))
    }

    /// Frees both buffers (the context, before its allocator goes).
    pub(crate) fn free_all(&mut self, ctx: &GpuContext) {
        for staging in [self.upload.take(), self.readback.take()].into_iter().flatten() {
            free(ctx, staging.raw, staging.allocation);
        }
    }
}
