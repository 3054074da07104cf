//! Device copy bandwidth: the same bytes copied by a compute kernel (16-byte loads and stores,
//! what a memory-bound compute pass can reach) and by vkCmdCopyBuffer (the transfer path).
//! Bandwidth counts bytes copied, each read once and written once.

use crate::gpu::{ComputePipeline, GpuBuffer, GpuContext, GpuResult, PipelineDesc, Recorder};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP_SIZE: u32 = 256;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CopyParams {
    len: u32,
    total_threads: u32,
}

/// Copy bandwidths in bytes copied per second (median of the repetitions).
#[derive(Clone, Debug, serde::Serialize)]
pub struct CopyBandwidth {
    pub bytes: u64,
    pub compute_bytes_per_s: f64,
    pub transfer_bytes_per_s: f64,
}

/// Copies `bytes` (rounded down to 16) `repetitions` times each way and times it with GPU
/// timestamps.
pub fn measure_copy_bandwidth(ctx: &Arc<GpuContext>, bytes: u64, repetitions: usize) -> GpuResult<CopyBandwidth> {
    let len = (bytes / 16) as usize;
    let src = GpuBuffer::<[u32; 4]>::new(ctx, "copy source", len)?;
    let dst = GpuBuffer::<[u32; 4]>::new(ctx, "copy destination", len)?;
    let pipeline = ComputePipeline::new(
        ctx,
        &PipelineDesc {
            name: "copy",
            spirv: shaders::BENCH_COPY,
            bindings: 2,
            push_constant_bytes: size_of::<CopyParams>() as u32,
            specialization: &[WORKGROUP_SIZE],
        },
    )?;
    // Enough workgroups to fill any device, few enough that each invocation loops a while.
    let groups = (len as u64).div_ceil(WORKGROUP_SIZE as u64 * 8).clamp(1, 4096);
    let params = CopyParams { len: len as u32, total_threads: groups as u32 * WORKGROUP_SIZE };
    let mut recorder = Recorder::new(ctx)?;
    recorder.fill_buffer(&src, 0x5A5A_5A5A);
    for _ in 0..repetitions + 1 {
        recorder.begin_pass("compute copy");
        recorder.dispatch_1d(&pipeline, &[src.binding(), dst.binding()], &params, groups)?;
        recorder.end_pass();
        recorder.begin_pass("transfer copy");
        recorder.copy_buffer(&src, &dst, len);
        recorder.end_pass();
    }
    let times = recorder.submit_and_wait()?;
    let rate = |name: &str| {
        // The first repetition warms caches and page tables; it is left out.
        let ms: Vec<f64> = times.passes.iter().filter(|p| p.name == name).skip(1).map(|p| p.ms).collect();
        (len * 16) as f64 / (super::median(ms) * 1e-3)
    };
    Ok(CopyBandwidth { bytes: (len * 16) as u64, compute_bytes_per_s: rate("compute copy"), transfer_bytes_per_s: rate("transfer copy") })
}
