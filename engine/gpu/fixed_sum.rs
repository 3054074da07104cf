//! Order-independent sums on the GPU (shaders/common/fixed_sum.glsl). Kernels that add many
//! contributions to one value (gradients of shared parameters, loss totals) add them in 64-bit
//! fixed point with integer atomics (`shaderBufferInt64Atomics`) instead of float atomics, so
//! the total has the same bits whatever order the device ran them in, and a run repeats bit
//! for bit. [`FixedSums`] owns such a buffer and decodes it; [`FixedResolve`] adds its sums into
//! a float buffer on the GPU for the kernels that read gradients as floats.

use super::{ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult, PipelineDesc, Recorder};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// The step of a buffer's sums (fixed_sum.glsl `FIXED_GRADIENT_ONE`, `FIXED_TOTAL_ONE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FixedPrecision {
    /// Gradients, which the next kernel reads ([`FixedResolve`]): steps of 2^-40 (about
    /// 9.1e-13), totals within ±2^23.
    Gradient,
    /// Loss totals, which the host reads: steps of 2^-24 (about 6e-8), totals within ±2^39.
    Total,
}

impl FixedPrecision {
    /// Fraction bits of the 64-bit fixed-point value.
    pub const fn fraction_bits(self) -> u32 {
        match self {
            Self::Gradient => 40,
            Self::Total => 24,
        }
    }
}

const WORKGROUP: u32 = 256;

/// `len` sums on the GPU: `len` fixed-point `i64` values, then per sum the count of
/// contributions it dropped (non-finite, out of range, or overflowing the total). Kernels bind it by its
/// shader name and add with `FIXED_ADD_GRADIENT` or `FIXED_ADD_TOTAL`, as its precision says.
pub struct FixedSums {
    words: GpuBuffer<i64>,
    len: usize,
    precision: FixedPrecision,
}

impl FixedSums {
    /// `len` sums of `precision`, all zero.
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        len: usize,
        precision: FixedPrecision,
    ) -> GpuResult<Self> {
        // Exactly 2·len words: the kernels find the counts at half the bound length.
        let words = GpuBuffer::from_slice(ctx, name, &vec![0i64; 2 * len])?;
        Ok(Self { words, len, precision })
    }

    /// Number of sums.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it holds no sums.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The step of its sums.
    pub fn precision(&self) -> FixedPrecision {
        self.precision
    }

    /// The buffer's name, as given to [`Self::new`].
    pub fn name(&self) -> &str {
        self.words.name()
    }

    /// The whole buffer, for a dispatch.
    pub fn binding(&self) -> super::BufferBinding<'_> {
        self.words.binding()
    }

    /// Records zeroing every sum and its dropped count.
    pub fn clear<'a>(&'a self, rec: &mut Recorder<'a>) {
        rec.fill_buffer(&self.words, 0);
    }

    /// The sums (after the recorder that added them was submitted); NaN for a sum that dropped
    /// a contribution.
    pub fn read(&self) -> GpuResult<Vec<f64>> {
        let words = self.words.read_prefix(2 * self.len)?;
        Ok(decode_fixed_sums(&words, self.precision))
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

/// The sums held in `words` (the values, then the dropped counts) of `precision`, as
/// [`FixedSums::read`] gives them.
pub fn decode_fixed_sums(words: &[i64], precision: FixedPrecision) -> Vec<f64> {
    let step = (-(precision.fraction_bits() as f64)).exp2();
    let (values, dropped) = words.split_at(words.len() / 2);
    let sum = |(&v, &d): (&i64, &i64)| if d == 0 { v as f64 * step } else { f64::NAN };
    values.iter().zip(dropped).map(sum).collect()
}

/// Push constants of shaders/common/fixed_resolve.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    count: u32,
    /// 2^fraction bits of the sums' precision.
    one: f32,
}
crate::gpu::push_layout!(Push: [COMMON_FIXED_RESOLVE], [count, one]);

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

    /// Records `target[i] += sums[i]` for the first `count` sums (NaN where a sum dropped a
    /// contribution), then zeroes every sum.
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
            let one = (sums.precision().fraction_bits() as f32).exp2();
            rec.dispatch_1d(&self.pipeline, &bindings, &Push { count: count as u32, one }, groups)?;
        }
        sums.clear(rec);
        Ok(())
    }
}
