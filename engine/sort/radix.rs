//! Stable LSD radix sort of (key, u32 value) pairs, 8 bits per pass, sorting only the low
//! `bits` of each key. Each pass: per-tile digit counts, an exclusive scan of those counts
//! (digit-major, so it yields every (digit, tile) its output start), and a stable scatter.
//! Passes ping-pong between the caller's buffers and scratch buffers owned by the sorter; on
//! CPU devices the scratch holds key-value records (see shaders/sort/radix_lanes_common.glsl).
//!
//! The Onesweep variant (GPUs with wide subgroups) instead counts the digits of every pass in
//! one read of the keys, then runs one kernel per pass that finds each tile's offsets by a
//! look-back over earlier tiles (shaders/sort/radix_onesweep.comp).
//!
//! CPU devices sort more than 8 bits by the bucket path when they can: one pass on the top
//! digit, then each of its 256 buckets sorted alone by the low bits while it stays in cache
//! (shaders/sort/radix_bucket_lanes.comp). A kernel on the device checks that every bucket
//! fits (radix_plan_lanes.comp); when one does not, the LSD passes run instead, so skewed
//! keys cost one histogram pass more than LSD alone.

use super::scan::PrefixScan;
use super::{RadixTuning, RadixVariant};
use crate::gpu::{
    push_layout, BufferBinding, ComputePipeline, GpuBuffer, GpuContext, GpuError, GpuResult,
    PassTimes, PipelineDesc, Recorder, Shader,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const RADIX_BITS: u32 = 8;
const RADIX: usize = 1 << RADIX_BITS;
/// Passes of a u64 key (`MAX_PASSES` in shaders/sort/radix_onesweep_common.glsl).
const MAX_PASSES: usize = 8;

/// A key type the GPU radix sort handles: u32 or u64 (stored as two little-endian words).
pub trait RadixKey: Pod + Ord + Send + Sync {
    /// 32-bit words per key: 1 for u32, 2 for u64.
    const WORDS: u32;
    /// Bits per key.
    const BITS: u32 = 32 * Self::WORDS;
    /// The key with every bit from `bits` up cleared.
    fn low_bits(self, bits: u32) -> Self;
}

impl RadixKey for u32 {
    const WORDS: u32 = 1;
    #[inline]
    fn low_bits(self, bits: u32) -> Self {
        if bits >= 32 {
            self
        } else {
            self & ((1 << bits) - 1)
        }
    }
}

impl RadixKey for u64 {
    const WORDS: u32 = 2;
    #[inline]
    fn low_bits(self, bits: u32) -> Self {
        if bits >= 64 {
            self
        } else {
            self & ((1 << bits) - 1)
        }
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
    bits: u32,
    max_bucket_len: u32,
    gate: u32,
}
push_layout!(
    RadixParams: [
        SORT_RADIX_HISTOGRAM,
        SORT_RADIX_SCATTER,
        SORT_RADIX_HISTOGRAM_LANES,
        SORT_RADIX_SCATTER_LANES,
        SORT_RADIX_PLAN_LANES,
        SORT_RADIX_BUCKET_LANES,
        SORT_RADIX_ONESWEEP_HISTOGRAM,
        SORT_RADIX_ONESWEEP_SCAN,
        SORT_RADIX_ONESWEEP,
    ],
    [len, word, shift, digit_bits, tile_count, bits, max_bucket_len, gate]
);

/// Which path of the CPU variant's sort a kernel belongs to (`GATE_*` in
/// shaders/sort/radix_pair.glsl); the plan kernel chooses one on the device.
#[derive(Clone, Copy)]
enum Gate {
    Always = 0,
    BucketPath = 1,
    LsdPath = 2,
}

impl RadixParams {
    fn new(len: usize, tile_count: usize, bits: u32) -> Self {
        let (len, tile_count) = (len as u32, tile_count as u32);
        Self {
            len,
            word: 0,
            shift: 0,
            digit_bits: 0,
            tile_count,
            bits,
            max_bucket_len: 0,
            gate: Gate::Always as u32,
        }
    }

    /// The pass over the `digit_bits` key bits from bit `low`.
    fn digit(self, low: u32, digit_bits: u32) -> Self {
        Self { word: low / 32, shift: low % 32, digit_bits, ..self }
    }

    /// LSD pass `pass`: the 8-bit digit from bit 8 * pass, narrower at the top of `bits`.
    fn lsd_pass(self, pass: u32) -> Self {
        let low = pass * RADIX_BITS;
        self.digit(low, self.bits.saturating_sub(low).min(RADIX_BITS))
    }

    fn gated(self, gate: Gate) -> Self {
        Self { gate: gate as u32, ..self }
    }
}

/// Longest bucket the bucket path sorts in one invocation with `local_passes` passes under the
/// top digit. lavapipe ends an invocation's loops after 65535 iterations in all; the bucket
/// kernel loops over the bucket `local_passes + 1` times, unrolled by 8, and 256 times per pass
/// over the digits. The budget keeps a margin under 65535.
fn bucket_len_for_loop_budget(local_passes: u32) -> u32 {
    const LOOP_BUDGET: u32 = 60_000;
    const UNROLL: u32 = 8;
    let loops_over_bucket = local_passes + 1;
    let fixed = RADIX as u32 * (1 + local_passes) + 16 * local_passes + UNROLL * loops_over_bucket;
    LOOP_BUDGET.saturating_sub(fixed) / loops_over_bucket * UNROLL
}

/// The variant's kernels and scratch memory.
// One per sorter, built once and never moved in a loop: boxing a variant would save nothing.
#[allow(clippy::large_enum_variant)]
enum Passes<K: RadixKey> {
    Subgroups(SubgroupPasses<K>),
    Lanes(LanesPasses),
    Onesweep(OnesweepPasses<K>),
}

/// A copy of keys and values that passes ping-pong with the caller's (GPU variants).
struct Scratch<K: RadixKey> {
    keys: GpuBuffer<K>,
    values: GpuBuffer<u32>,
}

/// Per pass: histogram, scan of the tile counts, scatter.
struct SubgroupPasses<K: RadixKey> {
    histogram: ComputePipeline,
    scatter: ComputePipeline,
    scratch: Scratch<K>,
}

/// One histogram of every pass and its scan, then one kernel per pass. `digit_starts` holds
/// the counts, then the first position, of every (pass, digit); `progress` each pass's next
/// tile and the count of look-back fallbacks. The tiles' status words are the sorter's
/// `tile_counts`.
struct OnesweepPasses<K: RadixKey> {
    histogram: ComputePipeline,
    scan: ComputePipeline,
    pass: ComputePipeline,
    scratch: Scratch<K>,
    digit_starts: GpuBuffer<u32>,
    progress: GpuBuffer<u32>,
}

/// The first pass turns the caller's pairs into records, the last turns them back, the passes
/// between ping-pong records. Kernels are indexed by [`lanes_kernels`]; `plan` and `buckets`
/// serve the bucket path, `plan_flag` holds its choice.
struct LanesPasses {
    histograms: [ComputePipeline; 2],
    scatters: [ComputePipeline; 3],
    plan: ComputePipeline,
    buckets: ComputePipeline,
    run_counts: GpuBuffer<u32>,
    records: [GpuBuffer<u32>; 2],
    plan_flag: GpuBuffer<u32>,
}

/// A GPU radix sorter of (key, u32 value) pairs for up to a fixed capacity, with its pipelines
/// and scratch buffers.
pub struct RadixSort<K: RadixKey> {
    tuning: RadixTuning,
    passes: Passes<K>,
    scan: PrefixScan,
    capacity: usize,
    /// Per (tile, digit): the tile's count, then its output start; for Onesweep the
    /// look-back's status words, two passes' worth (radix_onesweep_common.glsl).
    tile_counts: GpuBuffer<u32>,
}

impl<K: RadixKey> RadixSort<K> {
    /// 32-bit words of one record of the CPU variant: the key's words and the value, padded
    /// to whole 64-bit words.
    const RECORD_WORDS: usize = 2 * K::WORDS as usize;

    /// A sorter for up to `capacity` pairs, tuned for the device. Scratch memory: one more
    /// copy of keys and values, plus 256 counts per tile; on CPU devices two copies as records
    /// and 256 counts per run, unless records that large exceed a buffer's range, when the
    /// GPU variant runs instead.
    pub fn new(ctx: &Arc<GpuContext>, capacity: usize) -> GpuResult<Self> {
        Self::with_tuning(ctx, capacity, Self::tuning_for(ctx, capacity))
    }

    /// The tuning [`Self::new`] picks for `capacity` pairs on this device: the variant that
    /// `TAGSPLAT_SORT` names, else [`RadixTuning::for_device`]'s; the CPU variant gives way to
    /// [`RadixTuning::subgroups`] where its records would exceed a buffer's range. A bad
    /// `TAGSPLAT_SORT` is ignored here and refused by [`Self::with_tuning`].
    pub fn tuning_for(ctx: &GpuContext, capacity: usize) -> RadixTuning {
        let tuning = match RadixVariant::from_env() {
            Ok(Some(variant)) => RadixTuning::of_variant(ctx, variant),
            _ => RadixTuning::for_device(ctx),
        };
        let record_bytes = (capacity as u64).saturating_mul(Self::RECORD_WORDS as u64 * 4);
        if tuning.variant() == RadixVariant::Lanes
            && record_bytes > ctx.limits().max_storage_buffer_range
        {
            return RadixTuning::subgroups(ctx);
        }
        tuning
    }

    /// A sorter with an explicit tuning, e.g. [`RadixTuning::subgroups`] on a CPU device.
    /// Fails on a `TAGSPLAT_SORT` that names no variant, so that every sorter reports it.
    pub fn with_tuning(
        ctx: &Arc<GpuContext>,
        capacity: usize,
        tuning: RadixTuning,
    ) -> GpuResult<Self> {
        RadixVariant::from_env()?;
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
        let tiles = capacity.div_ceil(tuning.tile_len());
        let tile_digit_words = if tuning.variant() == RadixVariant::Onesweep { 2 } else { 1 };
        let passes = match tuning.variant() {
            RadixVariant::Subgroups => Self::subgroup_passes(ctx, capacity, tuning)?,
            RadixVariant::Lanes => Self::lanes_passes(ctx, capacity, tuning)?,
            RadixVariant::Onesweep => Self::onesweep_passes(ctx, capacity, tuning)?,
        };
        Ok(Self {
            tuning,
            passes,
            scan: PrefixScan::new(ctx, tiles * RADIX)?,
            capacity,
            tile_counts: GpuBuffer::new(
                ctx,
                "radix tile counts",
                tiles * RADIX * tile_digit_words,
            )?,
        })
    }

    /// A sort kernel; `variant_constants` are specialization constants 4 and 5, whose meaning
    /// is the variant's: whether the pass reads records and writes records (CPU variant), the
    /// look-back's polls (Onesweep).
    fn pipeline(
        ctx: &Arc<GpuContext>,
        tuning: RadixTuning,
        name: &'static str,
        shader: &'static Shader,
        variant_constants: [u32; 2],
    ) -> GpuResult<ComputePipeline> {
        let specialization = [
            tuning.workgroup_size(),
            ctx.limits().subgroup_size,
            tuning.keys_per_thread(),
            K::WORDS,
            variant_constants[0],
            variant_constants[1],
        ];
        ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &specialization })
    }

    fn subgroup_passes(
        ctx: &Arc<GpuContext>,
        capacity: usize,
        tuning: RadixTuning,
    ) -> GpuResult<Passes<K>> {
        // Scratch first: an impossible capacity fails here, before any pipeline is built.
        let scratch = Scratch::new(ctx, capacity)?;
        Ok(Passes::Subgroups(SubgroupPasses {
            histogram: Self::pipeline(
                ctx,
                tuning,
                "radix_histogram",
                &shaders::SORT_RADIX_HISTOGRAM,
                [0, 0],
            )?,
            scatter: Self::pipeline(
                ctx,
                tuning,
                "radix_scatter",
                &shaders::SORT_RADIX_SCATTER,
                [0, 0],
            )?,
            scratch,
        }))
    }

    fn onesweep_passes(
        ctx: &Arc<GpuContext>,
        capacity: usize,
        tuning: RadixTuning,
    ) -> GpuResult<Passes<K>> {
        let scratch = Scratch::new(ctx, capacity)?;
        let polls = [tuning.lookback_polls(), 0];
        let pipeline = |name, shader| Self::pipeline(ctx, tuning, name, shader, polls);
        Ok(Passes::Onesweep(OnesweepPasses {
            histogram: pipeline(
                "radix_onesweep_histogram",
                &shaders::SORT_RADIX_ONESWEEP_HISTOGRAM,
            )?,
            scan: pipeline("radix_onesweep_scan", &shaders::SORT_RADIX_ONESWEEP_SCAN)?,
            pass: pipeline("radix_onesweep", &shaders::SORT_RADIX_ONESWEEP)?,
            scratch,
            digit_starts: GpuBuffer::new(ctx, "radix digit starts", MAX_PASSES * RADIX)?,
            progress: GpuBuffer::new(ctx, "radix onesweep progress", MAX_PASSES + 1)?,
        }))
    }

    fn lanes_passes(
        ctx: &Arc<GpuContext>,
        capacity: usize,
        tuning: RadixTuning,
    ) -> GpuResult<Passes<K>> {
        let record_words =
            capacity.checked_mul(Self::RECORD_WORDS).ok_or(GpuError::LimitExceeded {
                what: "radix sort records".into(),
                count: capacity as u64,
                limit: usize::MAX as u64 / Self::RECORD_WORDS as u64,
                limit_name: "address space",
            })?;
        let records = [
            GpuBuffer::new(ctx, "radix records A", record_words)?,
            GpuBuffer::new(ctx, "radix records B", record_words)?,
        ];
        let runs = capacity.div_ceil(tuning.tile_len()) * tuning.workgroup_size() as usize;
        let histogram = |records_in| {
            Self::pipeline(
                ctx,
                tuning,
                "radix_histogram_lanes",
                &shaders::SORT_RADIX_HISTOGRAM_LANES,
                [records_in, 0],
            )
        };
        let scatter = |records_in, records_out| {
            Self::pipeline(
                ctx,
                tuning,
                "radix_scatter_lanes",
                &shaders::SORT_RADIX_SCATTER_LANES,
                [records_in, records_out],
            )
        };
        Ok(Passes::Lanes(LanesPasses {
            histograms: [histogram(0)?, histogram(1)?],
            scatters: [scatter(0, 1)?, scatter(1, 1)?, scatter(1, 0)?],
            plan: Self::pipeline(
                ctx,
                tuning,
                "radix_plan_lanes",
                &shaders::SORT_RADIX_PLAN_LANES,
                [0, 0],
            )?,
            buckets: Self::pipeline(
                ctx,
                tuning,
                "radix_bucket_lanes",
                &shaders::SORT_RADIX_BUCKET_LANES,
                [0, 0],
            )?,
            run_counts: GpuBuffer::new(ctx, "radix run counts", runs * RADIX)?,
            records,
            plan_flag: GpuBuffer::from_slice(ctx, "radix plan", &[0])?,
        }))
    }

    /// The tuning the sorter was built with.
    pub fn tuning(&self) -> RadixTuning {
        self.tuning
    }

    /// The most pairs one sort takes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Number of 8-bit digit passes for `bits` significant bits.
    pub fn passes(bits: u32) -> u32 {
        bits.min(K::BITS).div_ceil(RADIX_BITS)
    }

    /// The largest top-digit bucket the bucket path sorts for a sort of `bits` bits; 0 where
    /// it is not used (GPUs, 8 bits or fewer, a tuning capped at 0): then the sort records the
    /// LSD passes alone. A larger bucket sends the sort down the LSD passes.
    pub fn bucket_limit(&self, bits: u32) -> usize {
        let passes = Self::passes(bits);
        if self.tuning.variant() != RadixVariant::Lanes || passes < 2 {
            return 0;
        }
        bucket_len_for_loop_budget(passes - 1).min(self.tuning.max_bucket_len()) as usize
    }

    /// Records a stable sort of the first `len` pairs of `keys` and `values` by the low `bits`
    /// of each key (higher bits travel with the key but do not affect the order).
    pub fn record<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        len: usize,
        bits: u32,
    ) -> GpuResult<()> {
        let room = self.capacity.min(keys.len()).min(values.len());
        if len > room {
            return Err(GpuError::LengthMismatch {
                what: "radix sort",
                name: keys.name().into(),
                len,
                capacity: room,
            });
        }
        if bits > K::BITS {
            return Err(GpuError::LimitExceeded {
                what: "radix sort key bits".into(),
                count: bits as u64,
                limit: K::BITS as u64,
                limit_name: "key width",
            });
        }
        let passes = Self::passes(bits);
        if len <= 1 || passes == 0 {
            return Ok(());
        }
        let tile_count = len.div_ceil(self.tuning.tile_len());
        let base = RadixParams::new(len, tile_count, bits);
        recorder.begin_pass("radix sort");
        match &self.passes {
            Passes::Subgroups(subgroups) => {
                self.record_subgroups(recorder, subgroups, keys, values, &base)?
            }
            Passes::Lanes(lanes) => self.record_lanes(recorder, lanes, keys, values, &base)?,
            Passes::Onesweep(onesweep) => {
                self.record_onesweep(recorder, onesweep, keys, values, &base)?
            }
        }
        recorder.end_pass();
        Ok(())
    }

    fn record_subgroups<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        kernels: &'a SubgroupPasses<K>,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        base: &RadixParams,
    ) -> GpuResult<()> {
        let SubgroupPasses { histogram, scatter, scratch } = kernels;
        scratch.ping_pong(recorder, keys, values, base, |recorder, pass, input, output| {
            let counts = self.tile_counts.binding();
            let histogram_io = [("key_words", input[0]), ("tile_counts", counts)];
            let scatter_io = [
                ("keys_in", input[0]),
                ("values_in", input[1]),
                ("tile_offsets", counts),
                ("keys_out", output[0]),
                ("values_out", output[1]),
            ];
            self.record_pass(
                recorder,
                [(histogram, &histogram_io), (scatter, &scatter_io)],
                &base.lsd_pass(pass),
            )
        })
    }

    /// The histogram of every pass and its scan, then one kernel per pass.
    fn record_onesweep<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        kernels: &'a OnesweepPasses<K>,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        base: &RadixParams,
    ) -> GpuResult<()> {
        let OnesweepPasses { histogram, scan, pass, scratch, digit_starts, progress } = kernels;
        recorder.fill_buffer(digit_starts, 0);
        recorder.fill_buffer(progress, 0);
        recorder.begin_pass("radix histogram");
        let (starts, status, progress) =
            (digit_starts.binding(), self.tile_counts.binding(), progress.binding());
        let histogram_io =
            [("key_words", keys.binding()), ("digit_counts", starts), ("status", status)];
        recorder.dispatch_1d(histogram, &histogram_io, base, base.tile_count as u64)?;
        recorder.dispatch_1d(
            scan,
            &[("digit_counts", starts)],
            base,
            Self::passes(base.bits) as u64,
        )?;
        recorder.end_pass();
        scratch.ping_pong(recorder, keys, values, base, |recorder, pass_index, input, output| {
            let io = [
                ("keys_in", input[0]),
                ("values_in", input[1]),
                ("digit_starts", starts),
                ("keys_out", output[0]),
                ("values_out", output[1]),
                ("status", status),
                ("progress", progress),
            ];
            recorder.begin_pass("radix onesweep");
            recorder.dispatch_1d(pass, &io, &base.lsd_pass(pass_index), base.tile_count as u64)?;
            recorder.end_pass();
            Ok(())
        })
    }

    /// The bucket path where the tuning allows it, then the LSD passes, gated to run only if
    /// the plan turned the bucket path down.
    fn record_lanes<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        kernels: &'a LanesPasses,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        base: &RadixParams,
    ) -> GpuResult<()> {
        let LanesPasses { histograms, scatters, run_counts, records, plan_flag, .. } = kernels;
        let bucket_limit = self.bucket_limit(base.bits);
        let lsd_gate = if bucket_limit > 0 {
            let top = RadixParams {
                max_bucket_len: bucket_limit as u32,
                ..base.digit(base.bits - RADIX_BITS, RADIX_BITS)
            };
            self.record_bucket_path(recorder, kernels, keys, values, &top)?;
            Gate::LsdPath
        } else {
            recorder.fill_buffer(plan_flag, 0); // for took_bucket_path
            Gate::Always
        };
        let (counts, runs, plan_io) =
            (self.tile_counts.binding(), run_counts.binding(), plan_flag.binding());
        // A pass over zero bits moves the records home unchanged when one pass sorts.
        let passes = Self::passes(base.bits).max(2);
        for pass in 0..passes {
            let (first, last) = (pass == 0, pass + 1 == passes);
            let input = if first {
                [keys.binding(), values.binding()]
            } else {
                [records[(pass as usize + 1) % 2].binding(); 2]
            };
            let output = if last {
                [keys.binding(), values.binding()]
            } else {
                [records[pass as usize % 2].binding(); 2]
            };
            let histogram_io = [
                ("wide_in", input[0]),
                ("tile_counts", counts),
                ("run_counts", runs),
                ("plan", plan_io),
            ];
            let scatter_io = [
                ("wide_in", input[0]),
                ("value_words_in", input[1]),
                ("tile_offsets", counts),
                ("run_counts", runs),
                ("keys_out", output[0]),
                ("values_out", output[1]),
                ("plan", plan_io),
            ];
            let (histogram, scatter) = lanes_kernels(first, last);
            let params = base.lsd_pass(pass).gated(lsd_gate);
            self.record_pass(
                recorder,
                [(&histograms[histogram], &histogram_io), (&scatters[scatter], &scatter_io)],
                &params,
            )?;
        }
        Ok(())
    }

    /// The top digit's histogram and scan, the plan, then (if every bucket fits) its scatter
    /// into records A and the bucket sort. `top`: the top digit's pass with its bucket limit.
    fn record_bucket_path<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        kernels: &'a LanesPasses,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        top: &RadixParams,
    ) -> GpuResult<()> {
        let LanesPasses { histograms, scatters, plan, buckets, run_counts, records, plan_flag } =
            kernels;
        let (counts, runs, plan_io) =
            (self.tile_counts.binding(), run_counts.binding(), plan_flag.binding());
        let top_histogram_io = [
            ("wide_in", keys.binding()),
            ("tile_counts", counts),
            ("run_counts", runs),
            ("plan", plan_io),
        ];
        let top_scatter_io = [
            ("wide_in", keys.binding()),
            ("value_words_in", values.binding()),
            ("tile_offsets", counts),
            ("run_counts", runs),
            ("records_out", records[0].binding()),
            // Writing records leaves the values binding unused, but it must be bound.
            ("values_out", records[0].binding()),
            ("plan", plan_io),
        ];
        let bucket_io = [
            ("records_a", records[0].binding()),
            ("records_b", records[1].binding()),
            ("keys_out", keys.binding()),
            ("values_out", values.binding()),
            ("tile_offsets", counts),
            ("plan", plan_io),
        ];
        self.record_counts(recorder, &histograms[0], &top_histogram_io, top)?;
        recorder.dispatch_1d(plan, &[("tile_offsets", counts), ("plan", plan_io)], top, 1)?;
        self.record_scatter(recorder, &scatters[0], &top_scatter_io, &top.gated(Gate::BucketPath))?;
        recorder.begin_pass("radix buckets");
        let bucket_groups = RADIX.div_ceil(self.tuning.workgroup_size() as usize);
        recorder.dispatch_1d(
            buckets,
            &bucket_io,
            &top.gated(Gate::BucketPath),
            bucket_groups as u64,
        )?;
        recorder.end_pass();
        Ok(())
    }

    /// One pass: the histogram, the scan of its tile counts, the scatter, each kernel with
    /// its bindings.
    fn record_pass<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        [histogram, scatter]: [(&'a ComputePipeline, &[(&str, BufferBinding<'a>)]); 2],
        params: &RadixParams,
    ) -> GpuResult<()> {
        self.record_counts(recorder, histogram.0, histogram.1, params)?;
        self.record_scatter(recorder, scatter.0, scatter.1, params)
    }

    /// A pass's histogram and the scan that turns its tile counts into output offsets.
    fn record_counts<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        histogram: &'a ComputePipeline,
        io: &[(&str, BufferBinding<'a>)],
        params: &RadixParams,
    ) -> GpuResult<()> {
        recorder.begin_pass("radix histogram");
        recorder.dispatch_1d(histogram, io, params, params.tile_count as u64)?;
        recorder.end_pass();
        self.scan.record(
            recorder,
            &self.tile_counts,
            (params.tile_count as usize) << params.digit_bits,
        )
    }

    fn record_scatter<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        scatter: &'a ComputePipeline,
        io: &[(&str, BufferBinding<'a>)],
        params: &RadixParams,
    ) -> GpuResult<()> {
        recorder.begin_pass("radix scatter");
        recorder.dispatch_1d(scatter, io, params, params.tile_count as u64)?;
        recorder.end_pass();
        Ok(())
    }

    /// Whether the last sort that ran took the bucket path (a readback of the plan the device
    /// chose; false on GPUs, after sorts of 8 bits or fewer and with buckets capped at 0). For
    /// benchmarks and tests.
    pub fn took_bucket_path(&self) -> GpuResult<bool> {
        match &self.passes {
            Passes::Lanes(lanes) => Ok(lanes.plan_flag.read()?[0] == 1),
            Passes::Subgroups(_) | Passes::Onesweep(_) => Ok(false),
        }
    }

    /// How many times the last sort's look-back counted a tile itself because its status
    /// stayed empty (a readback; 0 outside the Onesweep variant). For benchmarks and tests.
    pub fn lookback_fallbacks(&self) -> GpuResult<u32> {
        match &self.passes {
            Passes::Onesweep(onesweep) => Ok(onesweep.progress.read()?[MAX_PASSES]),
            Passes::Subgroups(_) | Passes::Lanes(_) => Ok(0),
        }
    }

    /// Sorts in one submission and returns the GPU pass times.
    pub fn sort(
        &self,
        keys: &GpuBuffer<K>,
        values: &GpuBuffer<u32>,
        len: usize,
        bits: u32,
    ) -> GpuResult<PassTimes> {
        let mut recorder = Recorder::new(keys.context())?;
        self.record(&mut recorder, keys, values, len, bits)?;
        recorder.submit_and_wait()
    }
}

impl<K: RadixKey> Scratch<K> {
    fn new(ctx: &Arc<GpuContext>, capacity: usize) -> GpuResult<Self> {
        Ok(Self {
            keys: GpuBuffer::new(ctx, "radix scratch keys", capacity)?,
            values: GpuBuffer::new(ctx, "radix scratch values", capacity)?,
        })
    }

    /// Records the LSD passes of `base.bits` with `record_pass(recorder, pass, input,
    /// output)`, each a (keys, values) pair, alternating between the caller's buffers and
    /// this scratch; an odd pass count then copies the result home.
    fn ping_pong<'a>(
        &'a self,
        recorder: &mut Recorder<'a>,
        keys: &'a GpuBuffer<K>,
        values: &'a GpuBuffer<u32>,
        base: &RadixParams,
        mut record_pass: impl FnMut(
            &mut Recorder<'a>,
            u32,
            [BufferBinding<'a>; 2],
            [BufferBinding<'a>; 2],
        ) -> GpuResult<()>,
    ) -> GpuResult<()> {
        let buffers =
            [[keys.binding(), values.binding()], [self.keys.binding(), self.values.binding()]];
        let passes = RadixSort::<K>::passes(base.bits);
        for pass in 0..passes {
            let parity = (pass % 2) as usize;
            record_pass(recorder, pass, buffers[parity], buffers[1 - parity])?;
        }
        if passes % 2 == 1 {
            let len = base.len as usize;
            recorder.copy_buffer(&self.keys, keys, len);
            recorder.copy_buffer(&self.values, values, len);
        }
        Ok(())
    }
}

/// Indices into `Passes::Lanes` of a pass's histogram (reads pairs, reads records) and scatter
/// (pairs to records, records to records, records to pairs); the CPU variant always runs two
/// passes or more.
#[inline]
fn lanes_kernels(first: bool, last: bool) -> (usize, usize) {
    match (first, last) {
        (true, _) => (0, 0),
        (false, false) => (1, 1),
        (false, true) => (1, 2),
    }
}
