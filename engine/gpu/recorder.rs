//! Command recording: dispatches, copies and fills into one command buffer, a barrier between
//! every two commands, timestamps around named passes, then one submit that waits on a fence,
//! or, for a command buffer run many times, a [`Replay`] to submit in [`Batch`](super::Batch)es.
//!
//! Barriers: every command may read what the one before it wrote, so the recorder puts a full
//! compute/transfer memory barrier between consecutive commands, and one before the first
//! (what earlier submissions wrote, when several are on the queue). Kernels in this engine are
//! chained (project → bin → sort → rasterize), so almost every pair depends anyway, and this
//! keeps synchronization validation clean by construction.

use super::buffer::{BufferBinding, GpuBuffer};
use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::host_ring::HostRing;
use super::pipeline::ComputePipeline;
use super::replay::Replay;
use super::timing::{PassTimes, Timestamps};
use ash::vk;
use bytemuck::Pod;
use std::marker::PhantomData;
use std::sync::Arc;
use std::time::Instant;

/// Records commands; `'a` is the lifetime of the buffers and pipelines they use, so none of
/// them can be dropped before the recorder is submitted or dropped.
pub struct Recorder<'a> {
    ctx: Arc<GpuContext>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    timestamps: Timestamps,
    /// Whether a command was recorded since the last barrier.
    pending_writes: bool,
    /// Submitted and not yet waited for: Drop must wait before freeing.
    in_flight: bool,
    /// When recording began (the context's host clock counts recording time from here).
    started: Instant,
    _resources: PhantomData<&'a ()>,
}

const STAGES: vk::PipelineStageFlags = vk::PipelineStageFlags::from_raw(
    vk::PipelineStageFlags::COMPUTE_SHADER.as_raw() | vk::PipelineStageFlags::TRANSFER.as_raw(),
);

impl<'a> Recorder<'a> {
    /// An empty recorder with its own command pool, command buffer and fence.
    pub fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        Self::begin(ctx, vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT)
    }

    /// An empty recorder whose commands become a [`Replay`] ([`Self::finish`]), submitted as
    /// often as wanted. Anything that changes between submissions must be read from a buffer:
    /// push constants and bindings are fixed at recording.
    pub fn reusable(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        Self::begin(ctx, vk::CommandBufferUsageFlags::empty())
    }

    fn begin(ctx: &Arc<GpuContext>, usage: vk::CommandBufferUsageFlags) -> GpuResult<Self> {
        let device = ctx.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family())
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        let mut recorder = Self {
            ctx: ctx.clone(),
            pool: unsafe { device.create_command_pool(&pool_info, None) }
                .during("vkCreateCommandPool")?,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            timestamps: Timestamps::new(ctx),
            pending_writes: true,
            in_flight: false,
            started: Instant::now(),
            _resources: PhantomData,
        };
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(recorder.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        recorder.cmd = unsafe { device.allocate_command_buffers(&alloc_info) }
            .during("vkAllocateCommandBuffers")?[0];
        recorder.fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .during("vkCreateFence")?;
        let begin = vk::CommandBufferBeginInfo::default().flags(usage);
        unsafe { device.begin_command_buffer(recorder.cmd, &begin) }
            .during("vkBeginCommandBuffer")?;
        recorder.timestamps.mark_span(device, recorder.cmd, false);
        Ok(recorder)
    }

    /// Records `pipeline` over `groups` workgroups with `push` as push constants and each of
    /// `buffers` at the binding its name has in the shader. Panics, naming the shader and the
    /// binding, unless the names are exactly the shader's bindings (one name per binding).
    pub fn dispatch<P: Pod>(
        &mut self,
        pipeline: &'a ComputePipeline,
        buffers: &[(&str, BufferBinding<'a>)],
        push: &P,
        groups: [u32; 3],
    ) {
        let shader = pipeline.shader;
        let names: Vec<_> = buffers.iter().map(|&(name, _)| name).collect();
        let slots =
            shader.binding_slots(&names).unwrap_or_else(|e| panic!("{}: {e}", pipeline.name));
        assert_eq!(
            size_of::<P>(),
            shader.push_size,
            "{} ({}): wrong push-constant size",
            pipeline.name,
            shader.path
        );
        if groups.contains(&0) {
            return;
        }
        self.barrier_if_needed();
        let device = self.ctx.device();
        let infos: Vec<_> = buffers
            .iter()
            .map(|(_, b)| vk::DescriptorBufferInfo {
                buffer: b.buffer,
                offset: b.offset,
                range: b.range,
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .zip(slots)
            .map(|(info, slot)| {
                vk::WriteDescriptorSet::default()
                    .dst_binding(slot)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(std::slice::from_ref(info))
            })
            .collect();
        unsafe {
            device.cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, pipeline.pipeline);
            if !writes.is_empty() {
                self.ctx.push_descriptor().cmd_push_descriptor_set(
                    self.cmd,
                    vk::PipelineBindPoint::COMPUTE,
                    pipeline.layout,
                    0,
                    &writes,
                );
            }
            if size_of::<P>() > 0 {
                device.cmd_push_constants(
                    self.cmd,
                    pipeline.layout,
                    vk::ShaderStageFlags::COMPUTE,
                    0,
                    bytemuck::bytes_of(push),
                );
            }
            device.cmd_dispatch(self.cmd, groups[0], groups[1], groups[2]);
        }
        self.pending_writes = true;
    }

    /// Like [`Self::dispatch`] for a 1-D grid of `groups` workgroups, folded into x and y when
    /// it exceeds `maxComputeWorkGroupCount[0]`. Shaders recover the flat index with
    /// `flat_workgroup_id()` (shaders/common/grid.glsl) and skip ids past their work.
    pub fn dispatch_1d<P: Pod>(
        &mut self,
        pipeline: &'a ComputePipeline,
        buffers: &[(&str, BufferBinding<'a>)],
        push: &P,
        groups: u64,
    ) -> GpuResult<()> {
        let grid = grid_for(groups, self.ctx.limits().max_workgroup_count).ok_or_else(|| {
            GpuError::LimitExceeded {
                what: format!("{}: workgroups", pipeline.name),
                count: groups,
                limit: self.ctx.limits().max_workgroup_count[0] as u64
                    * self.ctx.limits().max_workgroup_count[1] as u64,
                limit_name: "maxComputeWorkGroupCount[0] * [1]",
            }
        })?;
        self.dispatch(pipeline, buffers, push, grid);
        Ok(())
    }

    /// Copies the first `len` elements of `src` to `dst`.
    pub fn copy_buffer<T: Pod>(
        &mut self,
        src: &'a GpuBuffer<T>,
        dst: &'a GpuBuffer<T>,
        len: usize,
    ) {
        self.copy_buffer_range(src, 0, dst, len);
    }

    /// Copies elements `src_start..src_start + len` of `src` to the start of `dst`.
    pub fn copy_buffer_range<T: Pod>(
        &mut self,
        src: &'a GpuBuffer<T>,
        src_start: usize,
        dst: &'a GpuBuffer<T>,
        len: usize,
    ) {
        assert!(
            src_start + len <= src.len() && len <= dst.len(),
            "copy of {len} elements out of bounds"
        );
        if len == 0 {
            return;
        }
        let element = size_of::<T>() as u64;
        let bytes = len as u64 * element;
        self.copy_bytes((src.raw(), src_start as u64 * element), (dst.raw(), 0), bytes);
    }

    /// Copies `bytes` bytes between raw buffers given as (buffer, byte offset); the caller keeps
    /// both alive until the submission completes (the staging path holds its pool's lock).
    pub(crate) fn copy_bytes(
        &mut self,
        (src, src_offset): (vk::Buffer, u64),
        (dst, dst_offset): (vk::Buffer, u64),
        bytes: u64,
    ) {
        self.barrier_if_needed();
        let region = vk::BufferCopy { src_offset, dst_offset, size: bytes };
        unsafe { self.ctx.device().cmd_copy_buffer(self.cmd, src, dst, &[region]) };
        self.pending_writes = true;
    }

    /// Copies element `index` of `src` into slot `slot` of `ring`, for the host to read once
    /// the submission is done.
    pub fn copy_to_ring<T: Pod>(
        &mut self,
        (src, index): (&'a GpuBuffer<T>, usize),
        (ring, slot): (&'a HostRing<T>, usize),
    ) {
        assert!(index < src.len() && slot < ring.slots(), "copy to a ring out of bounds");
        let element = size_of::<T>() as u64;
        self.copy_bytes(
            (src.raw(), index as u64 * element),
            (ring.raw(), slot as u64 * element),
            element,
        );
    }

    /// Fills the whole buffer with copies of the 32-bit `value`.
    pub fn fill_buffer<T: Pod>(&mut self, buffer: &'a GpuBuffer<T>, value: u32) {
        if buffer.is_empty() {
            return;
        }
        self.barrier_if_needed();
        let bytes = buffer.size_bytes() & !3;
        unsafe { self.ctx.device().cmd_fill_buffer(self.cmd, buffer.raw(), 0, bytes, value) };
        self.pending_writes = true;
    }

    /// Starts a named pass; its GPU time is reported by [`Self::submit_and_wait`]. Passes nest.
    pub fn begin_pass(&mut self, name: &str) {
        self.timestamps.begin(self.ctx.device(), self.cmd, name);
    }

    /// Ends the innermost open pass; does nothing when none is open.
    pub fn end_pass(&mut self) {
        self.timestamps.end(self.ctx.device(), self.cmd);
    }

    /// Submits everything recorded, waits until the GPU has finished, and returns the pass times.
    pub fn submit_and_wait(mut self) -> GpuResult<PassTimes> {
        let recording = self.end()?;
        let submitted = Instant::now();
        let device = self.ctx.device();
        unsafe {
            let cmds = [self.cmd];
            let submit = vk::SubmitInfo::default().command_buffers(&cmds);
            {
                let queue = self.ctx.queue();
                device.queue_submit(*queue, &[submit], self.fence).during("vkQueueSubmit")?;
            }
            self.in_flight = true;
            device.wait_for_fences(&[self.fence], true, u64::MAX).during("vkWaitForFences")?;
            self.in_flight = false;
        }
        let waiting = submitted.elapsed();
        let (times, device_ms) = self.timestamps.read(device)?;
        self.ctx.host_clock().add(recording, waiting, device_ms);
        Ok(times)
    }

    /// Ends the recording as a [`Replay`]. Its recording time goes to the context's host clock
    /// now, its waiting and device time with each [`Batch`](super::Batch) that runs it.
    pub fn finish(mut self) -> GpuResult<Replay> {
        let recording = self.end()?;
        self.ctx.host_clock().add_recording(recording);
        let commands = (self.pool, self.cmd);
        // The replay owns the pool, command buffer and queries now; Drop frees only the fence.
        (self.pool, self.cmd) = (vk::CommandPool::null(), vk::CommandBuffer::null());
        let timestamps = std::mem::replace(&mut self.timestamps, Timestamps::new(&self.ctx));
        Ok(Replay::new(self.ctx.clone(), commands, timestamps))
    }

    /// Makes every write visible to the host (which reads results after the fence), marks the
    /// device span's end and ends the command buffer; returns the time spent recording.
    fn end(&mut self) -> GpuResult<std::time::Duration> {
        let device = self.ctx.device();
        unsafe {
            let to_host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            device.cmd_pipeline_barrier(
                self.cmd,
                STAGES,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[to_host],
                &[],
                &[],
            );
            self.timestamps.mark_span(device, self.cmd, true);
            device.end_command_buffer(self.cmd).during("vkEndCommandBuffer")?;
        }
        Ok(self.started.elapsed())
    }

    fn barrier_if_needed(&mut self) {
        if !self.pending_writes {
            return;
        }
        let barrier = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(
                vk::AccessFlags::SHADER_READ
                    | vk::AccessFlags::SHADER_WRITE
                    | vk::AccessFlags::TRANSFER_READ
                    | vk::AccessFlags::TRANSFER_WRITE,
            );
        unsafe {
            self.ctx.device().cmd_pipeline_barrier(
                self.cmd,
                STAGES,
                STAGES,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            );
        }
        self.pending_writes = false;
    }
}

impl Drop for Recorder<'_> {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            // A recorder whose wait failed may still be running on the GPU.
            if self.in_flight {
                let _ = device.queue_wait_idle(*self.ctx.queue());
            }
            self.timestamps.destroy(device);
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.pool, None);
        }
    }
}

/// A 2-D grid with at least `groups` workgroups within `max` (x first), or `None` if none fits.
pub(crate) fn grid_for(groups: u64, max: [u32; 3]) -> Option<[u32; 3]> {
    let x = groups.min(max[0] as u64).max(1);
    let y = groups.div_ceil(x);
    (y <= max[1] as u64).then_some([x as u32, y as u32, 1])
}

#[cfg(test)]
mod tests {
    use super::grid_for;

    #[test]
    fn grid_covers_groups_within_limits() {
        let max = [65535, 65535, 65535];
        assert_eq!(grid_for(1, max), Some([1, 1, 1]));
        assert_eq!(grid_for(65535, max), Some([65535, 1, 1]));
        assert_eq!(grid_for(65536, max), Some([65535, 2, 1]));
        assert_eq!(grid_for(65535 * 65535 + 1, max), None);
    }
}
