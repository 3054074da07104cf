//! Typed storage buffers sized by the caller, with upload and readback. Memory the host can see
//! coherently (every type on lavapipe, resizable BAR on GPUs) is written and read in place;
//! otherwise (or when the context forces it, to test that path on lavapipe) the copy goes
//! through the context's staging buffers.

use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::recorder::Recorder;
use super::staging::Direction;
use ash::vk;
use bytemuck::Pod;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::marker::PhantomData;
use std::sync::Arc;

/// A buffer of `len` elements of `T` in device memory, usable as a storage buffer and as the
/// source or destination of copies.
pub struct GpuBuffer<T: Pod> {
    ctx: Arc<GpuContext>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
    len: usize,
    name: String,
    _element: PhantomData<T>,
}

/// A range of a buffer bound to one storage-buffer slot of a dispatch. It borrows the buffer,
/// so a buffer cannot be dropped while a recorder that uses it is alive.
#[derive(Clone, Copy, Debug)]
pub struct BufferBinding<'a> {
    pub(crate) buffer: vk::Buffer,
    pub(crate) offset: u64,
    pub(crate) range: u64,
    _buffer: PhantomData<&'a ()>,
}

impl BufferBinding<'_> {
    /// The whole of `buffer`; the caller keeps it alive as long as the binding is used.
    pub(crate) fn whole(buffer: vk::Buffer) -> Self {
        Self { buffer, offset: 0, range: vk::WHOLE_SIZE, _buffer: PhantomData }
    }
}

impl<T: Pod> GpuBuffer<T> {
    /// A device buffer of `len` elements (contents undefined). Refuses sizes over the device's
    /// `maxStorageBufferRange` or `maxMemoryAllocationSize` with an error naming the buffer.
    pub fn new(ctx: &Arc<GpuContext>, name: &str, len: usize) -> GpuResult<Self> {
        let bytes = checked_bytes::<T>(ctx, name, len)?;
        let (raw, allocation) = allocate(ctx, name, bytes, MemoryLocation::GpuOnly)?;
        Ok(Self {
            ctx: ctx.clone(),
            raw,
            allocation: Some(allocation),
            len,
            name: name.into(),
            _element: PhantomData,
        })
    }

    /// A device buffer holding a copy of `data`.
    pub fn from_slice(ctx: &Arc<GpuContext>, name: &str, data: &[T]) -> GpuResult<Self> {
        let mut buffer = Self::new(ctx, name, data.len())?;
        buffer.write(data)?;
        Ok(buffer)
    }

    /// Number of elements.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the buffer holds no elements.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Size in bytes: `len() * size_of::<T>()`.
    #[inline]
    pub fn size_bytes(&self) -> u64 {
        (self.len * size_of::<T>()) as u64
    }

    /// The name given at creation, used in error messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The context the buffer lives in.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The whole buffer as a dispatch binding.
    #[inline]
    pub fn binding(&self) -> BufferBinding<'_> {
        BufferBinding::whole(self.raw)
    }

    #[inline]
    pub(crate) fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// Writes `data` to the start of the buffer. `&mut` because it writes through a shared
    /// mapping; no GPU work can be using the buffer, since recorders borrow what they use and
    /// [`Recorder::submit_and_wait`] returns only when the work is done.
    pub fn write(&mut self, data: &[T]) -> GpuResult<()> {
        self.check_len("write", data.len())?;
        if data.is_empty() {
            return Ok(());
        }
        self.ctx.settle();
        if let Some(mapped) = self.coherent_mapping() {
            let bytes: &[u8] = bytemuck::cast_slice(data);
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), mapped, bytes.len()) };
            return Ok(());
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut pool = self.ctx.staging();
        let staging = pool.get(&self.ctx, Direction::Upload, bytes.len() as u64)?;
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), staging.mapped(), bytes.len()) };
        let mut recorder = Recorder::new(&self.ctx)?;
        recorder.copy_bytes((staging.raw(), 0), (self.raw, 0), bytes.len() as u64);
        recorder.submit_and_wait()?;
        Ok(())
    }

    /// Reads the whole buffer, then zeroes it: an accumulator's sum since the last take.
    pub fn take(&self) -> GpuResult<Vec<T>> {
        let values = self.read()?;
        let mut recorder = Recorder::new(&self.ctx)?;
        recorder.fill_buffer(self, 0);
        recorder.submit_and_wait()?;
        Ok(values)
    }

    /// Reads the whole buffer.
    pub fn read(&self) -> GpuResult<Vec<T>> {
        self.read_prefix(self.len)
    }

    /// Reads the first `len` elements.
    pub fn read_prefix(&self, len: usize) -> GpuResult<Vec<T>> {
        self.read_range(0, len)
    }

    /// Reads elements `start..start + len`.
    pub fn read_range(&self, start: usize, len: usize) -> GpuResult<Vec<T>> {
        self.check_len("read", start.saturating_add(len))?;
        let mut out = vec![T::zeroed(); len];
        if len == 0 {
            return Ok(out);
        }
        self.ctx.settle();
        if let Some(mapped) = self.coherent_mapping() {
            let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
            unsafe {
                std::ptr::copy_nonoverlapping(
                    mapped.add(start * size_of::<T>()),
                    bytes.as_mut_ptr(),
                    bytes.len(),
                )
            };
            return Ok(out);
        }
        let element = size_of::<T>() as u64;
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        let mut pool = self.ctx.staging();
        let staging = pool.get(&self.ctx, Direction::Readback, bytes.len() as u64)?;
        let mut recorder = Recorder::new(&self.ctx)?;
        recorder.copy_bytes(
            (self.raw, start as u64 * element),
            (staging.raw(), 0),
            bytes.len() as u64,
        );
        recorder.submit_and_wait()?;
        unsafe { std::ptr::copy_nonoverlapping(staging.mapped(), bytes.as_mut_ptr(), bytes.len()) };
        Ok(out)
    }

    fn check_len(&self, what: &'static str, len: usize) -> GpuResult<()> {
        if len > self.len {
            return Err(GpuError::LengthMismatch {
                what,
                name: self.name.clone(),
                len,
                capacity: self.len,
            });
        }
        Ok(())
    }

    /// The host pointer, if this memory is mapped and coherent (no flush or invalidate needed)
    /// and the context does not force the staging path.
    fn coherent_mapping(&self) -> Option<*mut u8> {
        if self.ctx.forces_staging() {
            return None;
        }
        coherent_pointer(self.allocation.as_ref()?)
    }
}

impl<T: Pod> Drop for GpuBuffer<T> {
    fn drop(&mut self) {
        self.ctx.settle();
        self.ctx.replays().resource_destroyed();
        if let Some(allocation) = self.allocation.take() {
            free(&self.ctx, self.raw, allocation);
        }
    }
}

/// Bytes for `len` elements of `T`, or the error naming the limit it breaks.
fn checked_bytes<T>(ctx: &GpuContext, name: &str, len: usize) -> GpuResult<u64> {
    let limits = ctx.limits();
    let too_large = |bytes, limit, limit_name| GpuError::BufferTooLarge {
        name: name.into(),
        bytes,
        limit,
        limit_name,
    };
    let bytes = (len as u64).checked_mul(size_of::<T>() as u64).ok_or_else(|| {
        too_large(u64::MAX, limits.max_storage_buffer_range, "maxStorageBufferRange")
    })?;
    if bytes > limits.max_storage_buffer_range {
        return Err(too_large(bytes, limits.max_storage_buffer_range, "maxStorageBufferRange"));
    }
    if bytes > limits.max_memory_allocation_size {
        return Err(too_large(bytes, limits.max_memory_allocation_size, "maxMemoryAllocationSize"));
    }
    Ok(bytes)
}

/// A buffer of `bytes` bytes (at least 16: Vulkan forbids empty buffers, and an empty one must
/// still bind) in memory at `location`, usable for storage and copies; errors name the buffer.
pub(crate) fn allocate(
    ctx: &GpuContext,
    name: &str,
    bytes: u64,
    location: MemoryLocation,
) -> GpuResult<(vk::Buffer, Allocation)> {
    let device = ctx.device();
    let info = vk::BufferCreateInfo::default()
        .size(bytes.max(16))
        .usage(
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST,
        )
        .sharing_mode(vk::SharingMode::EXCLUSIVE);
    let raw = unsafe { device.create_buffer(&info, None) }.during("vkCreateBuffer")?;
    let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
    let allocated =
        ctx.allocator().as_mut().expect("allocator lives as long as the context").allocate(
            &AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            },
        );
    let allocation = match allocated {
        Ok(allocation) => allocation,
        Err(e) => {
            unsafe { device.destroy_buffer(raw, None) };
            return Err(GpuError::OutOfMemory { name: name.into(), bytes, reason: e.to_string() });
        }
    };
    ctx.buffer_usage().add(allocation.size());
    let bound = unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) };
    if let Err(e) = bound.during("vkBindBufferMemory") {
        free(ctx, raw, allocation);
        return Err(e);
    }
    Ok((raw, allocation))
}

/// Destroys a buffer made by [`allocate`] and frees its memory.
pub(crate) fn free(ctx: &GpuContext, raw: vk::Buffer, allocation: Allocation) {
    unsafe { ctx.device().destroy_buffer(raw, None) };
    ctx.buffer_usage().remove(allocation.size());
    if let Some(allocator) = ctx.allocator().as_mut() {
        // Freeing only fails for an allocation of another allocator: a bug, not input.
        allocator.free(allocation).expect("allocation belongs to this context");
    }
}

/// The host pointer of host-visible, coherent memory (no flush or invalidate needed).
pub(crate) fn coherent_pointer(allocation: &Allocation) -> Option<*mut u8> {
    let coherent = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
    if !allocation.memory_properties().contains(coherent) {
        return None;
    }
    allocation.mapped_ptr().map(|p| p.as_ptr() as *mut u8)
}
