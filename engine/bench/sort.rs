//! `tagsplat bench sort`: GPU radix sort throughput against the copy-bandwidth bound and the
//! CPU's `sort_unstable`, all measured in one run.
//!
//! Two bounds, each `copies × n × (key bytes + 4)` bytes at the measured compute-copy
//! bandwidth. The LSD bound: an LSD pass must read and write every pair once, `passes` copies,
//! the fastest any 8-bit-digit LSD sort could go; `lsd_bound_fraction` is the sort's effective
//! rate against it, whichever path ran. The path bound: the copies the path that ran must make
//! (the bucket path: two, the scatter on the top digit and each bucket's read and final write;
//! its other passes stay in cache); `path_bound_fraction` is the fraction of that bound.

use super::copy::{CopyBandwidth, CopyProbe};
use crate::gpu::{GpuBuffer, GpuContext, GpuError, GpuResult, PassTime, PassTimes, Recorder};
use crate::rng::SplitMix64;
use crate::sort::{RadixKey, RadixSort, RadixTuning, RadixVariant};
use std::sync::Arc;
use std::time::Instant;

const SORT_PASS: &str = "sort";
const MAX_REPETITIONS: usize = 1000;
/// Pair copies to memory the bucket path must make: the top-digit scatter, and each bucket
/// read once and written once in its final place.
const BUCKET_PATH_COPIES: u32 = 2;

/// Results of [`bench_sort`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct SortBenchReport {
    /// Name of the Vulkan device.
    pub device: String,
    /// Number of key–value pairs sorted.
    pub n: usize,
    /// Significant bits of each key.
    pub bits: u32,
    /// Size of one key, bytes (4 or 8).
    pub key_bytes: u32,
    /// LSD passes needed for `bits` (8-bit digits).
    pub passes: u32,
    /// Timed sorts, after one warm-up.
    pub repetitions: usize,
    /// GPU time of the fastest sort (timestamps), ms; `keys_per_s` and the fraction use it.
    pub sort_ms: f64,
    /// Median GPU time of one sort, ms.
    pub sort_median_ms: f64,
    /// Keys sorted per second by the fastest sort.
    pub keys_per_s: f64,
    /// Median GPU time per kind of pass within one sort, ms.
    pub stage_ms: Vec<PassTime>,
    /// Copy bandwidth measured between the sorts of the same submission.
    pub copy: CopyBandwidth,
    /// Compute-copy bandwidth, GB/s (10^9 bytes copied per second).
    pub copy_gb_per_s: f64,
    /// Time `passes` copies of the pairs take at copy bandwidth (the LSD bound), ms.
    pub lsd_bound_ms: f64,
    /// `lsd_bound_ms / sort_ms`: the effective rate against the LSD bound.
    pub lsd_bound_fraction: f64,
    /// Copies of the pairs the path that ran must make: `passes`, or 2 on the bucket path.
    pub path_copies: u32,
    /// Time `path_copies` copies take at copy bandwidth, ms.
    pub path_bound_ms: f64,
    /// `path_bound_ms / sort_ms`: the fraction of the bound for the bytes the path moves.
    pub path_bound_fraction: f64,
    /// Wall time of one `sort_unstable_by_key` of the same pairs on the host, ms.
    pub cpu_sort_ms: f64,
    /// Keys per second of that CPU sort.
    pub cpu_sort_keys_per_s: f64,
    /// The kernel variant: "Lanes" (CPU devices), "Subgroups" or "Onesweep".
    pub variant: String,
    /// Tiles the Onesweep variant's look-back counted itself in the last sort (0 otherwise).
    pub lookback_fallbacks: u32,
    /// The sort took the CPU variant's bucket path, not the LSD passes.
    pub bucket_path: bool,
    /// The GPU result was checked to be the stable sort of the input pairs.
    pub verified: bool,
}

/// Sorts `n` random keys with `bits` significant bits (u64 keys above 32 bits) `repetitions`
/// times. Speeds use the fastest repetition, of the sort as of the copy bound: both are what
/// the device can do when the (shared, noisy) machine lets it.
/// `lsd_only` holds the CPU variant to its LSD passes (`RadixTuning::with_max_bucket_len`);
/// `variant` forces a kernel variant, else the sorter picks its own (`RadixSort::tuning_for`).
pub fn bench_sort(
    ctx: &Arc<GpuContext>,
    n: usize,
    bits: u32,
    repetitions: usize,
    lsd_only: bool,
    variant: Option<RadixVariant>,
) -> GpuResult<SortBenchReport> {
    if ctx.limits().timestamp_period_ns.is_none() {
        return Err(GpuError::MissingFeatures {
            device: ctx.info().name.clone(),
            missing: vec!["timestamp queries on the compute queue"],
        });
    }
    let chosen = match variant {
        Some(variant) => RadixTuning::of_variant(ctx, variant),
        None if bits <= 32 => RadixSort::<u32>::tuning_for(ctx, n),
        None => RadixSort::<u64>::tuning_for(ctx, n),
    };
    let tuning = if lsd_only { chosen.with_max_bucket_len(0) } else { chosen };
    if bits <= 32 {
        run::<u32>(ctx, n, bits, repetitions, tuning, |x| x as u32)
    } else {
        run::<u64>(ctx, n, bits, repetitions, tuning, |x| x)
    }
}

fn run<K: RadixKey>(
    ctx: &Arc<GpuContext>,
    n: usize,
    bits: u32,
    repetitions: usize,
    tuning: RadixTuning,
    make: fn(u64) -> K,
) -> GpuResult<SortBenchReport> {
    if repetitions > MAX_REPETITIONS {
        return Err(GpuError::LimitExceeded {
            what: "bench sort repetitions".into(),
            count: repetitions as u64,
            limit: MAX_REPETITIONS as u64,
            limit_name: "one submission's passes",
        });
    }
    let repetitions = repetitions.max(1);
    // Create the GPU side first: an impossible `n` fails here, before host memory is spent.
    let sorter = RadixSort::<K>::with_tuning(ctx, n, tuning)?;
    let mut input = GpuBuffer::<K>::new(ctx, "bench keys (input)", n)?;
    let mut input_values = GpuBuffer::<u32>::new(ctx, "bench values (input)", n)?;
    let keys = GpuBuffer::<K>::new(ctx, "bench keys", n)?;
    let values = GpuBuffer::<u32>::new(ctx, "bench values", n)?;

    let mut rng = SplitMix64::new(0x5EED ^ n as u64);
    let host_keys: Vec<K> = (0..n).map(|_| make(rng.next_u64()).low_bits(bits)).collect();
    input.write(&host_keys)?;
    input_values.write(&(0..n as u32).collect::<Vec<_>>())?;

    let pair_bytes = (size_of::<K>() + 4) as u64;
    let copy_bytes = (n as u64 * pair_bytes).clamp(1 << 20, ctx.limits().max_storage_buffer_range);
    let probe = CopyProbe::new(ctx, copy_bytes)?;

    // Copies and sorts alternate in one submission, so both see the same machine load.
    let mut recorder = Recorder::new(ctx)?;
    for _ in 0..repetitions + 1 {
        probe.record(&mut recorder)?;
        // Every repetition sorts the same input.
        recorder.copy_buffer(&input, &keys, n);
        recorder.copy_buffer(&input_values, &values, n);
        recorder.begin_pass(SORT_PASS);
        sorter.record(&mut recorder, &keys, &values, n, bits)?;
        recorder.end_pass();
    }
    let times = recorder.submit_and_wait()?;
    let bucket_path = sorter.took_bucket_path()?;
    let verified = is_stable_sort(&host_keys, &keys.read()?, &values.read()?);

    let sort_times: Vec<f64> =
        times.passes.iter().filter(|p| p.name == SORT_PASS).skip(1).map(|p| p.ms).collect();
    let sort_ms = super::fastest(sort_times.clone());
    let sort_median_ms = super::median(sort_times);
    let stage_ms = stage_medians(&times);
    let copy = probe.bandwidth(&times);
    let passes = RadixSort::<K>::passes(bits);
    let path_copies = if bucket_path { BUCKET_PATH_COPIES } else { passes };
    let bytes_per_s = copy.compute_bytes_per_s;
    let bound_ms = |copies: u32| (copies as u64 * n as u64 * pair_bytes) as f64 / bytes_per_s * 1e3;
    let fraction = |bound: f64| if sort_ms > 0.0 { bound / sort_ms } else { 0.0 };

    let mut pairs: Vec<(K, u32)> = host_keys.into_iter().zip(0..).collect();
    let start = Instant::now();
    pairs.sort_unstable_by_key(|p| p.0);
    let cpu_sort_ms = start.elapsed().as_secs_f64() * 1e3;

    let per_s = |ms: f64| if ms > 0.0 { n as f64 / (ms * 1e-3) } else { 0.0 };
    Ok(SortBenchReport {
        device: ctx.info().name.clone(),
        n,
        bits,
        key_bytes: size_of::<K>() as u32,
        passes,
        repetitions,
        sort_ms,
        sort_median_ms,
        keys_per_s: per_s(sort_ms),
        stage_ms,
        copy_gb_per_s: copy.compute_bytes_per_s * 1e-9,
        copy,
        lsd_bound_ms: bound_ms(passes),
        lsd_bound_fraction: fraction(bound_ms(passes)),
        path_copies,
        path_bound_ms: bound_ms(path_copies),
        path_bound_fraction: fraction(bound_ms(path_copies)),
        cpu_sort_ms,
        cpu_sort_keys_per_s: per_s(cpu_sort_ms),
        variant: format!("{:?}", sorter.tuning().variant()),
        lookback_fallbacks: sorter.lookback_fallbacks()?,
        bucket_path,
        verified,
    })
}

/// Whether (`sorted_keys`, `sorted_values`) is the stable sort of `keys` paired with their
/// indices: keys in order, each with its own index, equal keys in input order.
fn is_stable_sort<K: RadixKey>(keys: &[K], sorted_keys: &[K], sorted_values: &[u32]) -> bool {
    let own_index =
        sorted_keys.iter().zip(sorted_values).all(|(k, &v)| keys.get(v as usize) == Some(k));
    let pair = |i: usize| (sorted_keys[i], sorted_values[i]);
    let in_order = (1..sorted_keys.len()).all(|i| pair(i - 1) < pair(i));
    own_index && in_order
}

/// Median time per stage of one sort: passes nested in each top-level "sort" pass are summed
/// by name per repetition, the warm-up repetition left out.
fn stage_medians(times: &PassTimes) -> Vec<PassTime> {
    let mut repetitions: Vec<Vec<PassTime>> = Vec::new();
    let mut inside_sort = false;
    for pass in &times.passes {
        if pass.depth == 0 {
            inside_sort = pass.name == SORT_PASS;
            if inside_sort {
                repetitions.push(Vec::new());
            }
        } else if let (true, Some(stages)) = (inside_sort, repetitions.last_mut()) {
            match stages.iter_mut().find(|s| s.name == pass.name) {
                Some(stage) => stage.ms += pass.ms,
                None => stages.push(pass.clone()),
            }
        }
    }
    let Some(first) = repetitions.get(1) else { return Vec::new() };
    first
        .iter()
        .map(|stage| {
            let ms = repetitions[1..]
                .iter()
                .filter_map(|r| r.iter().find(|s| s.name == stage.name))
                .map(|s| s.ms)
                .collect();
            PassTime { name: stage.name.clone(), ms: super::median(ms), depth: stage.depth }
        })
        .collect()
}
