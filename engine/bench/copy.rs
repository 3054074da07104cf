//! Device copy bandwidth: the same bytes copied by a compute kernel (16-byte loads and stores,
//! what a memory-bound compute pass can reach) and by vkCmdCopyBuffer (the transfer path).
//! Bandwidth counts bytes copied, each read once and written once.

use crate::gpu::{
    push_layout, ComputePipeline, GpuBuffer, GpuContext, GpuResult, PassTimes, PipelineDesc,
    Recorder,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP_SIZE: u32 = 256;
const COMPUTE_PASS: &str = "compute copy";
const TRANSFER_PASS: &str = "transfer copy";

/// Push constants of copy.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CopyParams {
    len: u32,
    total_threads: u32,
}
push_layout!(CopyParams: [BENCH_COPY], [len, total_threads]);

/// Copy bandwidths in bytes copied per second: the fastest of the timed copies, since the
/// bound is what the device can do (lavapipe copies on a shared host vary by up to 3x).
#[derive(Clone, Debug, serde::Serialize)]
pub struct CopyBandwidth {
    /// Size of one copy, bytes.
    pub bytes: u64,
    /// Bytes copied per second by the compute copy kernel.
    pub compute_bytes_per_s: f64,
    /// Bytes copied per second by `vkCmdCopyBuffer`.
    pub transfer_bytes_per_s: f64,
}

/// Two buffers of `bytes` (rounded down to 16, and to the device's largest storage buffer: a
/// bandwidth needs no larger copy) and the copy kernel, so copies can be recorded between
/// other work of one submission and both see the same machine state.
pub struct CopyProbe {
    pipeline: ComputePipeline,
    src: GpuBuffer<[u32; 4]>,
    dst: GpuBuffer<[u32; 4]>,
}

impl CopyProbe {
    /// Creates the kernel and the two buffers and fills the source; fails when the pipeline or
    /// a buffer cannot be created or the fill cannot be submitted.
    pub fn new(ctx: &Arc<GpuContext>, bytes: u64) -> GpuResult<Self> {
        let len = (bytes.min(ctx.limits().max_storage_buffer_range) / 16) as usize;
        let desc = PipelineDesc {
            name: "copy",
            shader: &shaders::BENCH_COPY,
            specialization: &[WORKGROUP_SIZE],
        };
        let probe = Self {
            pipeline: ComputePipeline::new(ctx, &desc)?,
            src: GpuBuffer::new(ctx, "copy source", len)?,
            dst: GpuBuffer::new(ctx, "copy destination", len)?,
        };
        let mut recorder = Recorder::new(ctx)?;
        recorder.fill_buffer(&probe.src, 0x5A5A_5A5A);
        recorder.submit_and_wait()?;
        Ok(probe)
    }

    /// Records one timed compute copy and one timed transfer copy.
    pub fn record<'a>(&'a self, recorder: &mut Recorder<'a>) -> GpuResult<()> {
        let len = self.src.len();
        // Enough workgroups to fill any device, few enough that each invocation loops a while.
        let groups = (len as u64).div_ceil(WORKGROUP_SIZE as u64 * 8).clamp(1, 4096);
        let params = CopyParams { len: len as u32, total_threads: groups as u32 * WORKGROUP_SIZE };
        recorder.begin_pass(COMPUTE_PASS);
        recorder.dispatch_1d(
            &self.pipeline,
            &[("src", self.src.binding()), ("dst", self.dst.binding())],
            &params,
            groups,
        )?;
        recorder.end_pass();
        recorder.begin_pass(TRANSFER_PASS);
        recorder.copy_buffer(&self.src, &self.dst, len);
        recorder.end_pass();
        Ok(())
    }

    /// Bandwidths of the fastest copies in `times`, leaving out the first (warm-up) pair.
    pub fn bandwidth(&self, times: &PassTimes) -> CopyBandwidth {
        let bytes = self.src.size_bytes();
        let rate = |name: &str| {
            let ms: Vec<f64> =
                times.passes.iter().filter(|p| p.name == name).skip(1).map(|p| p.ms).collect();
            bytes as f64 / (super::fastest(ms) * 1e-3)
        };
        CopyBandwidth {
            bytes,
            compute_bytes_per_s: rate(COMPUTE_PASS),
            transfer_bytes_per_s: rate(TRANSFER_PASS),
        }
    }
}

/// Compute and transfer copy bandwidth of `bytes`, the fastest of four copies in one submission.
pub fn measure_copy(ctx: &Arc<GpuContext>, bytes: u64) -> GpuResult<CopyBandwidth> {
    let probe = CopyProbe::new(ctx, bytes)?;
    let mut rec = Recorder::new(ctx)?;
    for _ in 0..4 {
        probe.record(&mut rec)?;
    }
    Ok(probe.bandwidth(&rec.submit_and_wait()?))
}
