//! Command buffers recorded once and submitted many times, and batches of them in flight.
//!
//! A [`Replay`] is what [`Recorder::reusable`](super::Recorder::reusable) recorded: the same
//! dispatches, push constants and bindings on every submission, so whatever changes from one
//! submission to the next must live in buffers the kernels read (a
//! [`HostRing`](super::HostRing) slot the host writes before submitting). A [`Batch`] submits
//! replays in order under one fence and is waited for later, so the host can prepare the next
//! step while the device runs this one.
//!
//! A replay names its buffers and pipelines by handle, without borrowing them. What keeps that
//! sound: the context counts every buffer and pipeline destroyed, a replay remembers the count
//! it was recorded at, and [`Batch::submit`] refuses a replay recorded before any was
//! destroyed ([`Replay::is_current`]; record it again). While a batch is on the queue, freeing,
//! writing or reading a buffer from the host first waits for the queue to idle
//! (`GpuContext::settle`), so the host never races a batch it forgot.

use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::timing::{PassTimes, Timestamps};
use ash::vk;
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The context's count of destroyed resources and of batches on the queue.
#[derive(Default)]
pub(crate) struct ReplayState {
    destroyed: AtomicU64,
    in_flight: AtomicUsize,
}

impl ReplayState {
    /// A buffer or pipeline is being destroyed: every replay recorded before is stale.
    pub(crate) fn resource_destroyed(&self) {
        self.destroyed.fetch_add(1, Ordering::Relaxed);
    }

    fn generation(&self) -> u64 {
        self.destroyed.load(Ordering::Relaxed)
    }

    pub(crate) fn in_flight(&self) -> bool {
        self.in_flight.load(Ordering::Acquire) > 0
    }
}

/// A recorded command buffer that can be submitted again and again (one submission at a time).
pub struct Replay {
    ctx: Arc<GpuContext>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    timestamps: Timestamps,
    generation: u64,
    /// Submitted in a batch not yet waited for.
    pending: Cell<bool>,
}

impl Replay {
    /// Takes over a command buffer a recorder has ended, recorded at the context's current
    /// resource count.
    pub(crate) fn new(
        ctx: Arc<GpuContext>,
        (pool, cmd): (vk::CommandPool, vk::CommandBuffer),
        timestamps: Timestamps,
    ) -> Self {
        let generation = ctx.replays().generation();
        Self { ctx, pool, cmd, timestamps, generation, pending: Cell::new(false) }
    }

    /// Whether every buffer and pipeline it names still exists: no resource of the context was
    /// destroyed since it was recorded.
    pub fn is_current(&self) -> bool {
        self.generation == self.ctx.replays().generation()
    }

    /// Whether it is in a batch not yet waited for.
    pub fn is_pending(&self) -> bool {
        self.pending.get()
    }
}

impl Drop for Replay {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            if self.pending.get() {
                let _ = device.queue_wait_idle(*self.ctx.queue());
            }
            self.timestamps.destroy(device);
            device.destroy_command_pool(self.pool, None);
        }
    }
}

/// One fence over replays submitted together, waited for when the host needs their results.
pub struct Batch {
    ctx: Arc<GpuContext>,
    fence: vk::Fence,
    /// When the batch was submitted, while it is on the queue.
    submitted: Option<Instant>,
}

impl Batch {
    /// An idle batch with its own fence.
    pub fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        let fence = unsafe { ctx.device().create_fence(&vk::FenceCreateInfo::default(), None) }
            .during("vkCreateFence")?;
        Ok(Self { ctx: ctx.clone(), fence, submitted: None })
    }

    /// Whether it was submitted and not yet waited for.
    pub fn is_pending(&self) -> bool {
        self.submitted.is_some()
    }

    /// Submits `replays` in order under this batch's fence. Refused when the batch is pending,
    /// when a replay is already on the queue (a command buffer runs once at a time), or when a
    /// replay is stale ([`Replay::is_current`]).
    pub fn submit(&mut self, replays: &[&Replay]) -> GpuResult<()> {
        let refuse = |why| Err(GpuError::BatchRefused(why));
        if self.is_pending() {
            return refuse("the batch is still on the queue");
        }
        if replays.iter().any(|r| r.is_pending()) {
            return refuse("a replay is still on the queue");
        }
        if replays.iter().any(|r| !r.is_current()) {
            return refuse("a replay names a buffer or pipeline destroyed since it was recorded");
        }
        let cmds: Vec<_> = replays.iter().map(|r| r.cmd).collect();
        let submit = vk::SubmitInfo::default().command_buffers(&cmds);
        let device = self.ctx.device();
        unsafe { device.queue_submit(*self.ctx.queue(), &[submit], self.fence) }
            .during("vkQueueSubmit")?;
        self.ctx.replays().in_flight.fetch_add(1, Ordering::AcqRel);
        self.submitted = Some(Instant::now());
        replays.iter().for_each(|r| r.pending.set(true));
        Ok(())
    }

    /// Waits for the batch (nothing when it is idle) and returns the pass times of `replays`,
    /// the ones it was submitted with. Each batch adds to the context's host clock: the time
    /// from its submit until this wait saw it done, and the device spans of its replays.
    pub fn wait(&mut self, replays: &[&Replay]) -> GpuResult<PassTimes> {
        let Some(submitted) = self.submitted.take() else { return Ok(PassTimes::default()) };
        let device = self.ctx.device();
        let waited = unsafe { device.wait_for_fences(&[self.fence], true, u64::MAX) };
        self.ctx.replays().in_flight.fetch_sub(1, Ordering::AcqRel);
        waited.during("vkWaitForFences")?;
        unsafe { device.reset_fences(&[self.fence]) }.during("vkResetFences")?;
        let waiting = submitted.elapsed();
        let mut times = PassTimes::default();
        let mut span_ms = Some(0.0);
        for replay in replays {
            replay.pending.set(false);
            let (passes, span) = replay.timestamps.read(device)?;
            times.passes.extend(passes.passes);
            span_ms = span_ms.zip(span).map(|(a, b)| a + b);
        }
        self.ctx.host_clock().add(Duration::ZERO, waiting, span_ms);
        Ok(times)
    }
}

impl Drop for Batch {
    fn drop(&mut self) {
        let device = self.ctx.device();
        unsafe {
            if self.submitted.take().is_some() {
                let _ = device.wait_for_fences(&[self.fence], true, u64::MAX);
                self.ctx.replays().in_flight.fetch_sub(1, Ordering::AcqRel);
            }
            device.destroy_fence(self.fence, None);
        }
    }
}
