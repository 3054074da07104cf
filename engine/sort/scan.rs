//! Exclusive prefix sum of u32 (wrapping) on the GPU, in place, by reduce-then-scan: block sums,
//! a recursive scan of those, then each block scanned with its offset added. Scratch buffers are
//! sized once for the capacity given at creation.

use crate::gpu::{
    push_layout, ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult, PipelineDesc,
    Recorder,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const ITEMS_PER_THREAD: u32 = 4;

/// Push constants of scan_reduce.comp / scan_downsweep.comp (shaders/sort/scan_common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ScanParams {
    len: u32,
    has_block_offsets: u32,
}
push_layout!(ScanParams: [SORT_SCAN_REDUCE, SORT_SCAN_DOWNSWEEP], [len, has_block_offsets]);

/// A GPU exclusive prefix scan of u32 for up to a fixed capacity, with its pipelines and block-sum
/// buffers.
pub struct PrefixScan {
    reduce: ComputePipeline,
    downsweep: ComputePipeline,
    block_len: usize,
    capacity: usize,
    /// Block sums of each level: level 0 sums the input, level 1 sums level 0, …
    levels: Vec<GpuBuffer<u32>>,
}

impl PrefixScan {
    /// A scan for up to `capacity` elements.
    pub fn new(ctx: &Arc<GpuContext>, capacity: usize) -> GpuResult<Self> {
        let workgroup_size =
            ctx.limits().subgroup_size.max(256).min(ctx.limits().max_workgroup_invocations);
        let specialization = [workgroup_size, ctx.limits().subgroup_size, ITEMS_PER_THREAD];
        let pipeline = |name, shader| {
            ComputePipeline::new(
                ctx,
                &PipelineDesc { name, shader, specialization: &specialization },
            )
        };
        let block_len = (workgroup_size * ITEMS_PER_THREAD) as usize;
        let mut levels = Vec::new();
        for (depth, len) in level_lengths(capacity, block_len).into_iter().enumerate().skip(1) {
            levels.push(GpuBuffer::new(ctx, &format!("scan block sums, level {depth}"), len)?);
        }
        Ok(Self {
            reduce: pipeline("scan_reduce", &shaders::SORT_SCAN_REDUCE)?,
            downsweep: pipeline("scan_downsweep", &shaders::SORT_SCAN_DOWNSWEEP)?,
            block_len,
            capacity,
            levels,
        })
    }

    /// The most elements one scan takes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Records an in-place exclusive scan of the first `len` elements of `data`:
    /// `data[i] = data[0] + … + data[i - 1]` (wrapping), `data[0] = 0`.
    pub fn record<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        data: &'a GpuBuffer<u32>,
        len: usize,
    ) -> GpuResult<()> {
        if len > self.capacity || len > data.len() {
            return Err(GpuError::LengthMismatch {
                what: "prefix scan",
                name: data.name().into(),
                len,
                capacity: self.capacity.min(data.len()),
            });
        }
        let lengths = level_lengths(len, self.block_len);
        let buffers: Vec<&GpuBuffer<u32>> = std::iter::once(data).chain(&self.levels).collect();
        let top = lengths.len() - 1;
        recorder.begin_pass("scan");
        for level in 0..top {
            let params = ScanParams { len: lengths[level] as u32, has_block_offsets: 0 };
            let bindings =
                [("data", buffers[level].binding()), ("block_sums", buffers[level + 1].binding())];
            recorder.dispatch_1d(&self.reduce, &bindings, &params, lengths[level + 1] as u64)?;
        }
        for level in (0..=top).rev() {
            let params =
                ScanParams { len: lengths[level] as u32, has_block_offsets: (level < top) as u32 };
            // The top level is one block and reads no offsets; bind any buffer there.
            let offsets = buffers[(level + 1).min(top)];
            let bindings =
                [("data", buffers[level].binding()), ("block_offsets", offsets.binding())];
            let blocks = lengths[level].div_ceil(self.block_len) as u64;
            recorder.dispatch_1d(&self.downsweep, &bindings, &params, blocks)?;
        }
        recorder.end_pass();
        Ok(())
    }
}

/// Element counts per level: `len`, then block sums until one block remains.
fn level_lengths(len: usize, block_len: usize) -> Vec<usize> {
    let mut lengths = vec![len];
    while *lengths.last().unwrap() > block_len {
        lengths.push(lengths.last().unwrap().div_ceil(block_len));
    }
    lengths
}

/// The CPU reference: exclusive wrapping prefix sum.
pub fn exclusive_scan_cpu(data: &[u32]) -> Vec<u32> {
    let mut running = 0u32;
    data.iter()
        .map(|&x| {
            let out = running;
            running = running.wrapping_add(x);
            out
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_shrink_to_one_block() {
        assert_eq!(level_lengths(0, 1024), vec![0]);
        assert_eq!(level_lengths(1024, 1024), vec![1024]);
        assert_eq!(level_lengths(1025, 1024), vec![1025, 2]);
        assert_eq!(level_lengths(1 << 21, 1024), vec![1 << 21, 2048, 2]);
    }

    #[test]
    fn cpu_scan_is_exclusive_and_wraps() {
        assert_eq!(exclusive_scan_cpu(&[3, 1, 4]), vec![0, 3, 4]);
        assert_eq!(exclusive_scan_cpu(&[u32::MAX, 2, 0]), vec![0, u32::MAX, 1]);
    }
}
