//! Stable LSD radix sort of (key, u32 value) pairs, 8 bits per pass, sorting only the low
//! `bits` of each key. Each pass: per-tile digit counts, an exclusive scan of those counts
//! (digit-major, so it yields every (digit, tile) its output start), and a stable scatter.
//! Passes ping-pong between the caller's buffers and scratch buffers owned by the sorter.

use super::scan::PrefixScan;
use super::{RadixTuning, RadixVariant};
use crate::gpu::{ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult, PassTimes, PipelineDesc, Recorder};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const RADIX_BITS: u32 = 8;
const RADIX: usize = 1 << RADIX_BITS;

/// A key type the GPU radix sort handles: u32 or u64 (stored as two little-endian words).
pub trait RadixKey: Pod + Ord + Send + Sync {
    const WORDS: u32;
    const BITS: u32 = 32 * Self::WORDS;
    /// The key with every bit from `bits` up cleared.
    fn low_bits(self, bits: u32) -> Self;
}

impl RadixKey for u32 {
    const WORDS: u32 = 1;
    #[inline]
    fn low_bits(self, bits: u32) -> Self {
        if bits >= 32 { self } else { self & ((1 << bits) - 1) }
    }
}

impl RadixKey for u64 {
    const WORDS: u32 = 2;
    #[inline]
    fn low_bits(self, bits: u32) -> Self {
        if bits >= 64 { self } else { self & ((1 << bits) - 1) }
    }
}

/// Push constants of radix_histogram.comp / radix_scatter.comp (shaders/sort/radix_common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RadixParams {
    len: u32,
    word: u32,
    shift: u32,
    digit_bits: u32,
    tile_count: u32,
}

pub struct RadixSort<K: RadixKey> {
    tuning: RadixTuning,
    histogram: ComputePipeline,
    scatter: ComputePipeline,
    scan: PrefixScan,
    capacity: usize,
    tile_counts: GpuBuffer<u32>,
    /// Digit counts per invocation run ([`RadixVariant::Lanes`] only).
    run_counts: Option<GpuBuffer<u32>>,
    scratch_keys: GpuBuffer<K>,
    scratch_values: GpuBuffer<u32>,
}

impl<K: RadixKey> RadixSort<K> {
    /// A sorter for up to `capacity` pairs, tuned for the device. Scratch memory: one more
    /// copy of keys and values, plus 256 counts per tile (and per run on CPU devices).
    pub fn new(ctx: &Arc<GpuContext>, capacity: usize) -> GpuResult<Self> {
        Self::with_tuning(ctx, capacity, RadixTuning::for_device(ctx))
    }

    /// A sorter with an explicit tuning, e.g. [`RadixTuning::subgroups`] on a CPU device.
    pub fn with_tuning(ctx: &Arc<GpuContext>, capacity: usize, tuning: RadixTuning) -> GpuResult<Self> {
        let limits = ctx.limits();
        let shared_bytes = tuning.shared_bytes(limits.subgroup_size);
        if shared_bytes > limits.max_shared_memory_bytes {
            return Err(GpuError::LimitExceeded {
                what: "radix sort digit counters (shared memory bytes)".into(),
                count: shared_bytes as u64,
                limit: limits.max_shared_memory_bytes as u64,
                limit_name: "maxComputeSharedMemorySize",
            });
        }
        // Scratch first: an impossible capacity fails here, before any size arithmetic.
        let scratch_keys = GpuBuffer::new(ctx, "radix scratch keys", capacity)?;
        let scratch_values = GpuBuffer::new(ctx, "radix scratch values", capacity)?;
        let tiles = capacity.div_ceil(tuning.tile_len());
        let specialization = [tuning.workgroup_size(), limits.subgroup_size, tuning.keys_per_thread(), K::WORDS];
        let pipeline = |name, spirv, bindings| {
            let push_constant_bytes = size_of::<RadixParams>() as u32;
            ComputePipeline::new(ctx, &PipelineDesc { name, spirv, bindings, push_constant_bytes, specialization: &specialization })
        };
        let (histogram, scatter, run_counts) = match tuning.variant() {
            RadixVariant::Subgroups => (
                pipeline("radix_histogram", shaders::SORT_RADIX_HISTOGRAM, 2)?,
                pipeline("radix_scatter", shaders::SORT_RADIX_SCATTER, 5)?,
                None,
            ),
            RadixVariant::Lanes => (
                pipeline("radix_histogram_lanes", shaders::SORT_RADIX_HISTOGRAM_LANES, 3)?,
                pipeline("radix_scatter_lanes", shaders::SORT_RADIX_SCATTER_LANES, 6)?,
                Some(GpuBuffer::new(ctx, "radix run counts", tiles * tuning.workgroup_size() as usize * RADIX)?),
            ),
        };
        Ok(Self {
            tuning,
            histogram,
            scatter,
            scan: PrefixScan::new(ctx, tiles * RADIX)?,
            capacity,
            tile_counts: GpuBuffer::new(ctx, "radix tile counts", tiles * RADIX)?,
            run_counts,
            scratch_keys,
            scratch_values,
        })
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Number of passes for `bits` significant bits.
    pub fn passes(bits: u32) -> u32 {
        bits.min(K::BITS).div_ceil(RADIX_BITS)
    }

    /// Records a stable sort of the first `len` pairs of `keys` and `values` by the low `bits`
    /// of each key (higher bits travel with the key but do not affect the order).
    pub fn record<'a>(&'a self, recorder: &mut Recorder<'a>, keys: &'a GpuBuffer<K>, values: &'a GpuBuffer<u32>, len: usize, bits: u32) -> GpuResult<()> {
        let room = self.capacity.min(keys.len()).min(values.len());
        if len > room {
            return Err(GpuError::LengthMismatch { what: "radix sort", name: keys.name().into(), len, capacity: room });
        }
        if bits > K::BITS {
            return Err(GpuError::LimitExceeded { what: "radix sort key bits".into(), count: bits as u64, limit: K::BITS as u64, limit_name: "key width" });
        }
        let passes = Self::passes(bits);
        if len <= 1 || passes == 0 {
            return Ok(());
        }
        let tile_count = len.div_ceil(self.tuning.tile_len());
        let buffers = [(keys, values), (&self.scratch_keys, &self.scratch_values)];
        recorder.begin_pass("radix sort");
        for pass in 0..passes {
            let (keys_in, values_in) = buffers[(pass % 2) as usize];
            let (keys_out, values_out) = buffers[((pass + 1) % 2) as usize];
            let low = pass * RADIX_BITS;
            let params = RadixParams {
                len: len as u32,
                word: low / 32,
                shift: low % 32,
                digit_bits: (bits - low).min(RADIX_BITS),
                tile_count: tile_count as u32,
            };
            let counts_len = tile_count << params.digit_bits;
            // The Lanes kernels also read and write the per-run counts, after the tile counts.
            let runs = self.run_counts.as_ref().map(|r| r.binding());
            let counts = self.tile_counts.binding();
            let histogram_bindings: Vec<_> = [keys_in.binding(), counts].into_iter().chain(runs).collect();
            let scatter_bindings: Vec<_> = [keys_in.binding(), values_in.binding(), counts]
                .into_iter()
                .chain(runs)
                .chain([keys_out.binding(), values_out.binding()])
                .collect();
            recorder.begin_pass("radix histogram");
            recorder.dispatch_1d(&self.histogram, &histogram_bindings, &params, tile_count as u64)?;
            recorder.end_pass();
            self.scan.record(recorder, &self.tile_counts, counts_len)?;
            recorder.begin_pass("radix scatter");
            recorder.dispatch_1d(&self.scatter, &scatter_bindings, &params, tile_count as u64)?;
            recorder.end_pass();
        }
        if passes % 2 == 1 {
            // An odd pass count leaves the result in scratch: bring it home.
            recorder.copy_buffer(&self.scratch_keys, keys, len);
            recorder.copy_buffer(&self.scratch_values, values, len);
        }
        recorder.end_pass();
        Ok(())
    }

    /// Sorts in one submission and returns the GPU pass times.
    pub fn sort(&self, keys: &GpuBuffer<K>, values: &GpuBuffer<u32>, len: usize, bits: u32) -> GpuResult<PassTimes> {
        let mut recorder = Recorder::new(keys.context())?;
        self.record(&mut recorder, keys, values, len, bits)?;
        recorder.submit_and_wait()
    }
}
