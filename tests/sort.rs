//! Prefix scan and radix sort on the real device against CPU references
//! (`exclusive_scan_cpu`, and a stable sort whose order `sort_unstable` on (key, index) equals).

mod common;

use tagsplat::bench::bench_sort;
use tagsplat::gpu::{GpuBuffer, Recorder};
use tagsplat::sort::{
    exclusive_scan_cpu, PrefixScan, RadixKey, RadixSort, RadixTuning, RadixVariant,
};

fn gpu_scan(gpu: &common::TestGpu, data: &[u32]) -> Vec<u32> {
    let buffer = GpuBuffer::from_slice(gpu.ctx(), "scan data", data).unwrap();
    let scan = PrefixScan::new(gpu.ctx(), data.len()).unwrap();
    let mut recorder = Recorder::new(gpu.ctx()).unwrap();
    scan.record(&mut recorder, &buffer, data.len()).unwrap();
    recorder.submit_and_wait().unwrap();
    buffer.read().unwrap()
}

#[test]
fn scan_matches_cpu_at_edge_sizes() {
    let gpu = common::gpu();
    let mut rng = common::rng(1);
    // Around one and two blocks for any workgroup size the device picks, and a deep recursion.
    for len in [
        0, 1, 2, 3, 255, 256, 257, 511, 512, 513, 1023, 1024, 1025, 2047, 2048, 2049, 4097,
        262_145, 1_234_567,
    ] {
        let data: Vec<u32> = (0..len).map(|_| rng.next_u32() % 1000).collect();
        assert_eq!(gpu_scan(&gpu, &data), exclusive_scan_cpu(&data), "len {len}");
    }
}

#[test]
fn scan_wraps_like_u32() {
    let gpu = common::gpu();
    let data = vec![u32::MAX / 3; 5000];
    assert_eq!(gpu_scan(&gpu, &data), exclusive_scan_cpu(&data));
}

/// Every kernel variant and path on every device: the CPU one (which takes the bucket path
/// where the keys allow), the CPU one held to its LSD passes, the GPU one and Onesweep.
fn tunings(gpu: &common::TestGpu) -> Vec<RadixTuning> {
    let lanes = RadixTuning::lanes(gpu.ctx());
    vec![
        lanes,
        lanes.with_max_bucket_len(0),
        RadixTuning::subgroups(gpu.ctx()),
        RadixTuning::onesweep(gpu.ctx()),
    ]
}

/// Sorts on the GPU with every variant and checks against the CPU: keys equal `sort_unstable`
/// of the masked keys, and values show the sort is stable (equal keys keep their input order).
fn check_sort<K: RadixKey + std::fmt::Debug>(
    gpu: &common::TestGpu,
    keys: &[K],
    bits: u32,
    what: &str,
) {
    for tuning in tunings(gpu) {
        let bucket_path = check_sort_with(gpu, keys, bits, &format!("{what} ({tuning:?})"), tuning);
        assert!(
            !bucket_path || tuning.max_bucket_len() > 0,
            "{what}: bucket path taken with buckets capped at 0"
        );
    }
}

/// Returns whether the sort took the bucket path.
fn check_sort_with<K: RadixKey + std::fmt::Debug>(
    gpu: &common::TestGpu,
    keys: &[K],
    bits: u32,
    what: &str,
    tuning: RadixTuning,
) -> bool {
    check_sorter(gpu, keys, bits, what, tuning).took_bucket_path().unwrap()
}

/// Sorts with `tuning` and checks the result (see [`check_sort`]); returns the sorter, for
/// what it records of the sort.
fn check_sorter<K: RadixKey + std::fmt::Debug>(
    gpu: &common::TestGpu,
    keys: &[K],
    bits: u32,
    what: &str,
    tuning: RadixTuning,
) -> RadixSort<K> {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    let key_buffer = GpuBuffer::from_slice(gpu.ctx(), "keys", keys).unwrap();
    let value_buffer = GpuBuffer::from_slice(gpu.ctx(), "values", &values).unwrap();
    let sorter = RadixSort::<K>::with_tuning(gpu.ctx(), n, tuning).unwrap();
    sorter.sort(&key_buffer, &value_buffer, n, bits).unwrap();
    let sorted_keys = key_buffer.read().unwrap();
    let sorted_values = value_buffer.read().unwrap();

    let mut expected: Vec<(K, u32)> = keys.iter().map(|k| k.low_bits(bits)).zip(values).collect();
    expected.sort_unstable(); // (key, index) pairs are unique: unstable sort gives the stable order.
    for (i, &(key, index)) in expected.iter().enumerate() {
        let got = (sorted_keys[i].low_bits(bits), sorted_values[i]);
        assert_eq!(got, (key, index), "{what}: n {n}, bits {bits}, first difference at {i}");
        // Bits above `bits` travel with their key.
        assert_eq!(sorted_keys[i], keys[index as usize], "{what}: key bits lost at {i}");
    }
    sorter
}

fn random_keys<K: RadixKey>(n: usize, seed: u64, make: impl Fn(u64) -> K) -> Vec<K> {
    let mut rng = common::rng(seed);
    (0..n).map(|_| make(rng.next_u64())).collect()
}

#[test]
fn sort_u32_distributions_and_sizes() {
    let gpu = common::gpu();
    // Around a workgroup, a GPU tile (at most 4096 keys) and a lavapipe tile (8 runs of 4096).
    for n in [0, 1, 2, 3, 5, 255, 257, 2047, 2049, 4095, 4097, 32_767, 32_769, 100_003] {
        check_sort(&gpu, &random_keys(n, n as u64, |x| x as u32), 32, "uniform");
    }
    let n = 70_001;
    check_sort(&gpu, &vec![0xDEAD_BEEFu32; n], 32, "all equal");
    check_sort(&gpu, &(0..n as u32).collect::<Vec<_>>(), 32, "sorted");
    check_sort(&gpu, &(0..n as u32).rev().collect::<Vec<_>>(), 32, "reversed");
    check_sort(&gpu, &random_keys(n, 9, |x| (x % 5) as u32 * 0x0101_0101), 32, "few unique");
}

#[test]
fn sort_u32_partial_bits() {
    let gpu = common::gpu();
    let n = 50_000;
    for bits in [1, 13] {
        check_sort(
            &gpu,
            &random_keys(n, bits as u64, |x| (x as u32).low_bits(bits)),
            bits,
            "in range",
        );
        // Garbage above `bits` must not change the order.
        check_sort(&gpu, &random_keys(n, 77 + bits as u64, |x| x as u32), bits, "high garbage");
    }
    check_sort(&gpu, &random_keys(n, 3, |x| x as u32), 0, "zero bits is the identity");
}

#[test]
fn sort_u64_keys() {
    let gpu = common::gpu();
    let n = 40_001;
    for bits in [1, 13, 32, 48, 64] {
        check_sort(
            &gpu,
            &random_keys(n, 100 + bits as u64, |x| x.low_bits(bits)),
            bits,
            "u64 uniform",
        );
    }
    // Tile id in the high word, depth in the low word: the binning key layout.
    check_sort(&gpu, &random_keys(n, 5, |x| ((x % 37) << 32) | (x >> 40)), 48, "few tiles");
    check_sort(&gpu, &(0..n as u64).rev().map(|x| x << 20).collect::<Vec<_>>(), 64, "u64 reversed");
}

#[test]
fn sort_millions_non_power_of_two() {
    let gpu = common::gpu();
    let keys = random_keys(3_000_017, 11, |x| x as u32);
    check_sort(&gpu, &keys, 32, "millions");
    // Uniform keys are what the bucket path is for: the CPU variant must take it.
    let tuning = RadixTuning::lanes(gpu.ctx());
    let bucket_path = check_sort_with(&gpu, &keys, 32, "millions", tuning);
    assert_eq!(bucket_path, tuning.max_bucket_len() > 0, "millions of uniform keys: wrong path");
}

/// Keys whose top digit (the `bits` - 8 bits up) is 0 for `heavy` of them and spread over the
/// other 255 values for the rest, in random order.
fn one_heavy_bucket<K: RadixKey>(
    heavy: usize,
    rest: usize,
    bits: u32,
    seed: u64,
    make: impl Fn(u64) -> K,
) -> Vec<K> {
    let mut rng = common::rng(seed);
    let low_mask = (1u64 << (bits - 8)) - 1;
    let mut keys: Vec<u64> = (0..heavy).map(|_| rng.next_u64() & low_mask).collect();
    keys.extend(
        (0..rest).map(|_| ((1 + rng.next_u64() % 255) << (bits - 8)) | (rng.next_u64() & low_mask)),
    );
    for i in (1..keys.len()).rev() {
        keys.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    keys.into_iter().map(make).collect()
}

/// The bucket path sorts a bucket of exactly its limit in one invocation; lavapipe would cut
/// the loops short (silently) if the limit ignored its loop budget. One pair more sends the
/// sort down the LSD passes. The CPU variant on every device, so this runs on GPUs too.
#[test]
fn sort_bucket_at_its_limit() {
    let gpu = common::gpu();
    let tuning = RadixTuning::lanes(gpu.ctx());
    let u32_limit = RadixSort::<u32>::with_tuning(gpu.ctx(), 1, tuning).unwrap().bucket_limit(32);
    let u64_limit = RadixSort::<u64>::with_tuning(gpu.ctx(), 1, tuning).unwrap().bucket_limit(64);
    assert!(u32_limit > 0 && u64_limit > 0, "the CPU variant has a bucket path");
    for heavy in [u32_limit, u32_limit + 1] {
        let keys = one_heavy_bucket(heavy, 60_000, 32, heavy as u64, |x| x as u32);
        let bucket_path = check_sort_with(
            &gpu,
            &keys,
            32,
            &format!("u32 bucket of {heavy}, limit {u32_limit}"),
            tuning,
        );
        assert_eq!(
            bucket_path,
            heavy == u32_limit,
            "u32 bucket of {heavy}, limit {u32_limit}: wrong path"
        );
    }
    for heavy in [u64_limit, u64_limit + 1] {
        let keys = one_heavy_bucket(heavy, 30_000, 64, heavy as u64, |x| x);
        let bucket_path = check_sort_with(
            &gpu,
            &keys,
            64,
            &format!("u64 bucket of {heavy}, limit {u64_limit}"),
            tuning,
        );
        assert_eq!(
            bucket_path,
            heavy == u64_limit,
            "u64 bucket of {heavy}, limit {u64_limit}: wrong path"
        );
    }
}

#[test]
fn sort_rejects_bad_arguments() {
    let gpu = common::gpu();
    let keys = GpuBuffer::<u32>::from_slice(gpu.ctx(), "keys", &[3, 2, 1]).unwrap();
    let values = GpuBuffer::<u32>::from_slice(gpu.ctx(), "values", &[0, 1, 2]).unwrap();
    let sorter = RadixSort::<u32>::new(gpu.ctx(), 3).unwrap();
    assert!(sorter.sort(&keys, &values, 4, 32).is_err(), "more pairs than the buffers hold");
    assert!(sorter.sort(&keys, &values, 3, 33).is_err(), "more bits than the key has");
}

/// `bench sort` reports both bounds: the LSD one (passes copies of the pairs) whatever ran,
/// and the one for the copies of the path that ran (2 on the bucket path).
#[test]
fn bench_sort_reports_the_bound_of_the_path_that_ran() {
    let gpu = common::gpu();
    let chosen = RadixSort::<u32>::tuning_for(gpu.ctx(), 200_000).variant();
    let lanes = chosen == RadixVariant::Lanes;
    for lsd_only in [false, true] {
        let report = bench_sort(gpu.ctx(), 200_000, 32, 2, lsd_only, None).unwrap();
        assert!(report.verified);
        assert_eq!(report.bucket_path, lanes && !lsd_only, "lsd_only {lsd_only}");
        let copies = if report.bucket_path { 2 } else { 4 };
        assert_eq!((report.passes, report.path_copies), (4, copies));
        let per_copy = report.lsd_bound_ms / 4.0;
        assert!((report.path_bound_ms - copies as f64 * per_copy).abs() <= 1e-9 * per_copy);
        let rate = report.lsd_bound_fraction / report.lsd_bound_ms;
        assert!((report.path_bound_fraction - rate * report.path_bound_ms).abs() <= 1e-9);
    }
}

/// `--variant` forces the kernels whatever the device: Onesweep makes one copy per pass.
#[test]
fn bench_sort_runs_the_variant_asked_for() {
    let gpu = common::gpu();
    let report =
        bench_sort(gpu.ctx(), 100_000, 24, 1, false, Some(RadixVariant::Onesweep)).unwrap();
    assert!(report.verified);
    assert_eq!(report.variant, "Onesweep");
    assert_eq!((report.bucket_path, report.passes, report.path_copies), (false, 3, 3));
}

/// The look-back's fallback: with no wait at all, every tile counts every tile before it from
/// its keys, one fallback per tile and earlier tile in every pass, whatever the timing. With
/// one read of an empty status word, the mix of published prefixes and fallbacks the timing
/// gives must sort the same.
#[test]
fn onesweep_look_back_and_its_fallback() {
    let gpu = common::gpu();
    let onesweep = RadixTuning::onesweep(gpu.ctx());
    let tiles = |n: usize| n.div_ceil(onesweep.tile_len());
    for (n, seed, polls) in [(100_003, 21, 0), (1_000_003, 22, 1)] {
        let tuning = onesweep.with_lookback_polls(polls);
        let uniform = random_keys(n, seed, |x| x as u32);
        let clustered = random_keys(n, seed, |x| (x % 3) as u32 * 0x0100_0001);
        for keys in [uniform, clustered] {
            let what = format!("onesweep, {} tiles, {polls} polls", tiles(n));
            let sorter = check_sorter(&gpu, &keys, 32, &what, tuning);
            let (passes, t) = (RadixSort::<u32>::passes(32) as usize, tiles(n));
            if polls == 0 {
                assert_eq!(sorter.lookback_fallbacks().unwrap() as usize, passes * t * (t - 1) / 2);
            }
        }
    }
    let keys = random_keys(150_001, 23, |x| x >> 7);
    check_sorter(&gpu, &keys, 57, "onesweep u64, no wait", onesweep.with_lookback_polls(0));
}
