//! Criterion benchmarks of the GPU prefix scan and radix sort, timed on the host around one
//! submission each (recording, submit and the wait for the fence included).
//!
//! Short by default (10 samples, 1 s warm-up, 3 s measurement per benchmark) so the whole run
//! stays a few minutes on a 2-core CPU running lavapipe; criterion's own flags override that,
//! e.g. `cargo bench --bench sort -- --measurement-time 10 radix_sort_u32`. The device is the
//! one `TAGSPLAT_DEVICE` and the loader's ICDs give (scripts/env.sh picks lavapipe); without a
//! usable Vulkan device the benchmarks are skipped, not failed.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;
use tagsplat::gpu::{ContextOptions, GpuBuffer, GpuContext, GpuResult, Recorder};
use tagsplat::rng::SplitMix64;
use tagsplat::sort::{PrefixScan, RadixKey, RadixSort};

const SCAN_SIZES: [usize; 2] = [1 << 16, 1 << 20];
const SORT_U32_SIZES: [usize; 2] = [1 << 16, 1 << 20];
const SORT_U64_SIZES: [usize; 1] = [1 << 20];
const SORT_U64_BITS: u32 = 48;

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new(&ContextOptions::default()) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("sort benches skipped: cannot create a Vulkan context: {e}");
            return;
        }
    };
    eprintln!("sort benches on {} ({})", ctx.info().name, ctx.info().kind_name());
    if ctx.validation_enabled() {
        eprintln!("note: the validation layer is on (TAGSPLAT_VALIDATION=1); timings include its overhead");
    }
    report(bench_scan(c, &ctx), "scan");
    report(
        bench_sort::<u32>(c, &ctx, "radix_sort_u32", &SORT_U32_SIZES, 32, |x| (x >> 32) as u32),
        "radix_sort_u32",
    );
    report(
        bench_sort::<u64>(c, &ctx, "radix_sort_u64", &SORT_U64_SIZES, SORT_U64_BITS, |x| x),
        "radix_sort_u64",
    );
}

/// A GPU error while setting a group up (out of memory, a missing feature) skips the rest of
/// that group instead of aborting the run.
fn report(result: GpuResult<()>, group: &str) {
    if let Err(e) = result {
        eprintln!("{group}: skipped: {e}");
    }
}

fn bench_scan(c: &mut Criterion, ctx: &Arc<GpuContext>) -> GpuResult<()> {
    let mut group = c.benchmark_group("scan");
    let mut rng = SplitMix64::new(1);
    for n in SCAN_SIZES {
        let data: Vec<u32> = (0..n).map(|_| rng.next_u32() % 1000).collect();
        let buffer = GpuBuffer::from_slice(ctx, "scan data", &data)?;
        let scan = PrefixScan::new(ctx, n)?;
        group.throughput(Throughput::Elements(n as u64));
        // Every iteration scans the previous one's output in place: the values change, the
        // work does not.
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let mut recorder = Recorder::new(ctx).expect("command recorder");
                scan.record(&mut recorder, &buffer, n).expect("record scan");
                black_box(recorder.submit_and_wait().expect("scan submission"))
            })
        });
    }
    group.finish();
    Ok(())
}

/// Sorts the same random pairs every iteration: the recorder first restores the keys from a
/// pristine copy, then sorts. The values are left permuted; they do not change the work.
fn bench_sort<K: RadixKey>(
    c: &mut Criterion,
    ctx: &Arc<GpuContext>,
    name: &str,
    sizes: &[usize],
    bits: u32,
    make_key: impl Fn(u64) -> K,
) -> GpuResult<()> {
    let mut group = c.benchmark_group(name);
    let mut rng = SplitMix64::new(2);
    for &n in sizes {
        let keys: Vec<K> = (0..n).map(|_| make_key(rng.next_u64())).collect();
        let values: Vec<u32> = (0..n as u32).collect();
        let pristine_keys = GpuBuffer::from_slice(ctx, "pristine keys", &keys)?;
        let key_buffer = GpuBuffer::<K>::new(ctx, "keys", n)?;
        let value_buffer = GpuBuffer::from_slice(ctx, "values", &values)?;
        let sorter = RadixSort::<K>::new(ctx, n)?;
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function(BenchmarkId::new(format!("bits_{bits}"), n), |b| {
            b.iter(|| {
                let mut recorder = Recorder::new(ctx).expect("command recorder");
                recorder.copy_buffer(&pristine_keys, &key_buffer, n);
                sorter
                    .record(&mut recorder, &key_buffer, &value_buffer, n, bits)
                    .expect("record radix sort");
                black_box(recorder.submit_and_wait().expect("radix sort submission"))
            })
        });
    }
    group.finish();
    Ok(())
}

fn config() -> Criterion {
    // Set here rather than on each group so criterion's command-line flags can override it.
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
}

criterion_group! {
    name = sort;
    config = config();
    targets = benches
}
criterion_main!(sort);
