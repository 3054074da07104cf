//! Order-independent sums on the GPU (shaders/common/fixed_sum.glsl). Kernels that add many
//! contributions to one value (gradients of shared parameters, loss totals) add them in 64-bit
//! fixed point with integer atomics (`shaderBufferInt64Atomics`) instead of float atomics, so the total has the same bits
//! whatever order the device ran them in, and a run repeats bit for bit. [`FixedSums`] owns
//! such a buffer and decodes it; [`FixedResolve`] adds its sums into a float buffer on the GPU
//! for the kernels that read gradients as floats.

use super::{ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult, PipelineDesc, Recorder};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// Fraction bits of the fixed-point sums: a step of 2^-40 (about 9.1e-13); a sum must stay
/// within ±2^23 and one contribution within ±2^22 (fixed_sum.glsl `FIXED_LIMIT`).
pub const FIXED_FRACTION_BITS: u32 = 40;

const WORKGROUP: u32 = 256;

/// `len` sums on the GPU, each a 64-bit fixed-point integer, then one counting dropped
/// (non-finite or out-of-range) contributions. Kernels bind it by its shader name and add
/// with `FIXED_ADD`.
pub struct FixedSums {
    words: GpuBuffer<i64>,
    len: usize,
}

impl FixedSums {
    /// `len` sums, all zero.
    pub fn new(ctx: &Arc<GpuContext>, name: &str, len: usize) -> GpuResult<Self> {
        let words = GpuBuffer::from_slice(ctx, name, &vec![0i64; len + 1])?;
        Ok(Self { words, len })
    }

    /// Number of sums.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds no sums.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The buffer's name, as given to [`Self::new`].
    pub fn name(&self) -> &str {
        self.words.name()
    }

    /// The whole buffer, for a dispatch.
    pub fn binding(&self) -> super::BufferBinding<'_> {
        self.words.binding()
    }

    /// Records zeroing every sum and the dropped count.
    pub fn clear<'a>(&'a self, rec: &mut Recorder<'a>) {
        rec.fill_buffer(&self.words, 0);
    }

    /// The sums (after the recorder that added them was submitted); every one NaN when a
    /// contribution was dropped.
    pub fn read(&self) -> GpuResult<Vec<f64>> {
        Ok(decode_fixed_sums(&self.words.read()?))
    }

    /// The sums, then zeroes them so the next sum starts afresh.
    pub fn take(&self) -> GpuResult<Vec<f64>> {
        let sums = self.read()?;
        let mut rec = Recorder::new(self.words.context())?;
        self.clear(&mut rec);
        rec.submit_and_wait()?;
        Ok(sums)
    }
}

/// The sums held in `words` (the sums, then the dropped count), as [`FixedSums::read`].
pub fn decode_fixed_sums(words: &[i64]) -> Vec<f64> {
    let Some((&dropped, sums)) = words.split_last() else {
        return Vec::new();
    };
    let step = (-(FIXED_FRACTION_BITS as f64)).exp2();
    sums.iter().map(|&sum| if dropped == 0 { sum as f64 * step } else { f64::NAN }).collect()
}

/// Push constants of shaders/common/fixed_resolve.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    count: u32,
}
crate::gpu::push_layout!(Push: [COMMON_FIXED_RESOLVE], [count]);

/// The kernel that adds [`FixedSums`] into a float buffer.
pub struct FixedResolve {
    pipeline: ComputePipeline,
}

impl FixedResolve {
    /// Builds the kernel.
    pub fn new(ctx: &Arc<GpuContext>) -> GpuResult<Self> {
        let desc = PipelineDesc {
            name: "fixed-point resolve",
            shader: &shaders::COMMON_FIXED_RESOLVE,
            specialization: &[WORKGROUP],
        };
        Ok(Self { pipeline: ComputePipeline::new(ctx, &desc)? })
    }

    /// Records `target[i] += sums[i]` for the first `count` sums (NaN in all of them when a
    /// contribution was dropped), then zeroes every sum.
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        sums: &'a FixedSums,
        target: &'a GpuBuffer<f32>,
        count: usize,
    ) -> GpuResult<()> {
        for (name, capacity) in [(sums.name(), sums.len()), (target.name(), target.len())] {
            if capacity < count {
                let name = name.to_string();
                let what = "fixed-point resolve";
                return Err(GpuError::LengthMismatch { what, name, len: count, capacity });
            }
        }
        if count > 0 {
            let bindings = [("sums", sums.binding()), ("target", target.binding())];
            let groups = (count as u64).div_ceil(WORKGROUP as u64);
            rec.dispatch_1d(&self.pipeline, &bindings, &Push { count: count as u32 }, groups)?;
        }
        sums.clear(rec);
        Ok(())
    }
}
