//! A small buffer in memory both the host and the device see, one slot per submission in
//! flight: the host writes what a replayed step should use (learning rates, the iteration) into
//! its slot before submitting, and the step copies what the host should learn (a count, a
//! loss) into its slot, read once its batch is done. No staging copy and no extra submission.

use super::buffer::{allocate, coherent_pointer, free, BufferBinding};
use super::context::GpuContext;
use super::error::{GpuError, GpuResult};
use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;
use std::marker::PhantomData;
use std::sync::Arc;

/// `slots` values of `T` in host-visible, coherent memory, usable as a storage buffer and as a
/// copy destination.
pub struct HostRing<T: Pod> {
    ctx: Arc<GpuContext>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
    mapped: *mut T,
    slots: usize,
    _element: PhantomData<T>,
}

// The mapping is written through `&self` only (see `write`), and the ring is not `Sync`, so
// two threads never write it at once.
unsafe impl<T: Pod> Send for HostRing<T> {}

impl<T: Pod> HostRing<T> {
    /// A ring of `slots` zeroed values (at least one). Fails when the device has no memory the
    /// host sees coherently, naming the ring.
    pub fn new(ctx: &Arc<GpuContext>, name: &str, slots: usize) -> GpuResult<Self> {
        let slots = slots.max(1);
        let bytes = (slots * size_of::<T>()) as u64;
        let (raw, allocation) = allocate(ctx, name, bytes, MemoryLocation::CpuToGpu)?;
        let Some(mapped) = coherent_pointer(&allocation) else {
            free(ctx, raw, allocation);
            return Err(GpuError::OutOfMemory {
                name: name.into(),
                bytes,
                reason: "the device has no host-visible coherent memory".into(),
            });
        };
        let ring = Self {
            ctx: ctx.clone(),
            raw,
            allocation: Some(allocation),
            mapped: mapped as *mut T,
            slots,
            _element: PhantomData,
        };
        (0..slots).for_each(|slot| ring.write(slot, &T::zeroed()));
        Ok(ring)
    }

    /// The number of slots.
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// Writes `value` to `slot`. The caller makes sure no submission that uses the slot is on
    /// the queue (the device would read a half-written value).
    pub fn write(&self, slot: usize, value: &T) {
        assert!(slot < self.slots, "slot {slot} of a ring of {}", self.slots);
        unsafe { self.mapped.add(slot).write_unaligned(*value) };
    }

    /// Reads `slot`, as the last finished submission that wrote it left it.
    pub fn read(&self, slot: usize) -> T {
        assert!(slot < self.slots, "slot {slot} of a ring of {}", self.slots);
        unsafe { self.mapped.add(slot).read_unaligned() }
    }

    /// The whole ring as a dispatch binding.
    pub fn binding(&self) -> BufferBinding<'_> {
        BufferBinding::whole(self.raw)
    }

    pub(crate) fn raw(&self) -> vk::Buffer {
        self.raw
    }
}

impl<T: Pod> Drop for HostRing<T> {
    fn drop(&mut self) {
        self.ctx.settle();
        self.ctx.replays().resource_destroyed();
        if let Some(allocation) = self.allocation.take() {
            free(&self.ctx, self.raw, allocation);
        }
    }
}
