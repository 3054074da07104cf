//! GPU core on the real device (lavapipe on CI) with validation on.

mod common;

use tagsplat::gpu::{GpuBuffer, GpuContext, GpuError, Recorder};

#[test]
fn context_reports_device_and_limits() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    assert!(ctx.validation_enabled());
    assert!(ctx.info().capabilities.missing_features().is_empty());
    let limits = ctx.limits();
    assert!(limits.subgroup_size.is_power_of_two());
    assert!(limits.max_storage_buffer_range >= 1 << 27);
    let listed = GpuContext::list_devices().unwrap();
    assert!(listed.iter().any(|d| d.name == ctx.info().name));
}

/// The subgroup-size runs of `scripts/test.sh` set `LP_NATIVE_VECTOR_WIDTH`; this proves that
/// lavapipe took it (128 bits → 4 lanes of 32 bits, 256 → 8, 512 → 16).
#[test]
fn lavapipe_subgroup_size_follows_the_native_vector_width() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let width = std::env::var("LP_NATIVE_VECTOR_WIDTH");
    let (Ok(width), true) = (width, ctx.info().name.contains("llvmpipe")) else {
        eprintln!("not applicable: LP_NATIVE_VECTOR_WIDTH unset or the device is not lavapipe");
        return;
    };
    let bits: u32 = width.parse().expect("LP_NATIVE_VECTOR_WIDTH is a number of bits");
    assert_eq!(ctx.limits().subgroup_size, bits / 32, "{}", ctx.info().name);
}

#[test]
fn buffer_round_trip_and_partial_read() {
    let gpu = common::gpu();
    let data: Vec<u32> = (0..10_000).map(|i| i * 7 + 1).collect();
    let mut buffer = GpuBuffer::from_slice(gpu.ctx(), "round trip", &data).unwrap();
    assert_eq!(buffer.read().unwrap(), data);
    assert_eq!(buffer.read_prefix(5).unwrap(), &data[..5]);
    let too_long = vec![0u32; 10_001];
    assert!(matches!(buffer.write(&too_long), Err(GpuError::LengthMismatch { .. })));
    let empty = GpuBuffer::<u32>::new(gpu.ctx(), "empty", 0).unwrap();
    assert!(empty.read().unwrap().is_empty());
}

/// The discrete-GPU path on any device: with staging forced, every write and read goes
/// through the context's staging buffers, which grow to the largest transfer and are reused;
/// ranges at an offset, `take` and the empty buffer behave as on the direct path.
#[test]
fn forced_staging_round_trips_at_every_size_and_offset() {
    let options = tagsplat::gpu::ContextOptions {
        validation: Some(true),
        force_staging: Some(true),
        ..Default::default()
    };
    let ctx = GpuContext::new(&options).unwrap();
    assert!(ctx.forces_staging());
    for n in [3usize, 100_000, 17, 300_000] {
        let data: Vec<u32> = (0..n as u32).map(|i| i.wrapping_mul(2_654_435_761)).collect();
        let mut buffer = GpuBuffer::<u32>::new(&ctx, "staged", n).unwrap();
        buffer.write(&data).unwrap();
        assert_eq!(buffer.read().unwrap(), data, "{n} elements");
        let start = n / 3;
        assert_eq!(buffer.read_range(start, n - start).unwrap(), &data[start..], "{n} elements");
        assert_eq!(buffer.take().unwrap(), data);
        assert!(buffer.read().unwrap().iter().all(|&x| x == 0), "take zeroes");
    }
    let empty = GpuBuffer::<u32>::new(&ctx, "empty", 0).unwrap();
    assert!(empty.read().unwrap().is_empty());
    let log = ctx.validation().clone();
    drop((empty, ctx));
    assert_eq!(log.error_count(), 0, "{:?}", log.messages());
}

#[test]
fn copy_and_fill_are_ordered_by_barriers() {
    let gpu = common::gpu();
    let n = 1 << 16;
    let a = GpuBuffer::<u32>::new(gpu.ctx(), "a", n).unwrap();
    let b = GpuBuffer::<u32>::new(gpu.ctx(), "b", n).unwrap();
    let mut recorder = Recorder::new(gpu.ctx()).unwrap();
    recorder.begin_pass("fill");
    recorder.fill_buffer(&a, 0xABCD_0123);
    recorder.end_pass();
    recorder.begin_pass("copy");
    recorder.copy_buffer(&a, &b, n);
    recorder.end_pass();
    recorder.fill_buffer(&a, 5);
    let times = recorder.submit_and_wait().unwrap();
    assert!(b.read().unwrap().iter().all(|&x| x == 0xABCD_0123));
    assert!(a.read().unwrap().iter().all(|&x| x == 5));
    if gpu.ctx().limits().timestamp_period_ns.is_some() {
        let names: Vec<_> = times.passes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["fill", "copy"]);
        assert!(times.passes.iter().all(|p| p.ms >= 0.0 && p.ms.is_finite()));
    }
}

/// Each submission adds its recording, waiting and device time to the context's clock; the
/// device span lies inside the wait and covers the timed passes within it.
#[test]
fn the_clock_splits_a_submission_into_recording_waiting_and_device_time() {
    let gpu = common::gpu();
    let n = 1 << 20;
    let (a, b) = (
        GpuBuffer::<u32>::new(gpu.ctx(), "a", n).unwrap(),
        GpuBuffer::<u32>::new(gpu.ctx(), "b", n).unwrap(),
    );
    let before = gpu.ctx().clock();
    let mut recorder = Recorder::new(gpu.ctx()).unwrap();
    recorder.begin_pass("fill");
    recorder.fill_buffer(&a, 7);
    recorder.end_pass();
    recorder.begin_pass("copy");
    recorder.copy_buffer(&a, &b, n);
    recorder.end_pass();
    let times = recorder.submit_and_wait().unwrap();
    let c = gpu.ctx().clock().since(&before);
    assert_eq!(c.submissions, 1);
    assert!(c.recording_s > 0.0 && c.waiting_s > 0.0, "{c:?}");
    if gpu.ctx().limits().timestamp_period_ns.is_some() {
        assert_eq!(c.timed_submissions, 1);
        let passes: f64 = times.passes.iter().map(|p| p.ms * 1e-3).sum();
        assert!(c.device_s >= passes * 0.999 && c.device_s <= c.waiting_s, "{c:?} {passes}");
        assert!(c.host_share(c.recording_s + c.waiting_s).is_some());
    }
}

#[test]
fn oversized_buffer_is_refused_with_the_limit_named() {
    let gpu = common::gpu();
    let limit = gpu.ctx().limits().max_storage_buffer_range;
    let len = (limit / 4 + 1) as usize;
    let err = GpuBuffer::<u32>::new(gpu.ctx(), "huge keys", len).err().expect("must be refused");
    let text = err.to_string();
    assert!(text.contains("huge keys") && text.contains("maxStorageBufferRange"), "{text}");
    let err =
        GpuBuffer::<u64>::new(gpu.ctx(), "overflow", usize::MAX).err().expect("must be refused");
    assert!(matches!(err, GpuError::BufferTooLarge { .. }));
}

#[test]
fn unknown_device_is_a_named_error() {
    let options = tagsplat::gpu::ContextOptions {
        device: Some("no such device 42".into()),
        validation: Some(false),
        ..Default::default()
    };
    let err = GpuContext::new(&options).err().expect("must fail");
    assert!(err.to_string().contains("no such device 42"), "{err}");
}

/// The oracle itself: a Vulkan object left alive when the context goes away is reported by the
/// validation layer, and the messenger counts it.
#[test]
fn validation_layer_reports_a_leaked_object() {
    use ash::vk;
    let options = tagsplat::gpu::ContextOptions { validation: Some(true), ..Default::default() };
    let ctx = GpuContext::new(&options).unwrap();
    let log = ctx.validation().clone();
    let info = vk::BufferCreateInfo::default().size(64).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    let leaked = unsafe { ctx.device().create_buffer(&info, None) }.unwrap();
    assert_ne!(leaked, vk::Buffer::null());
    assert_eq!(log.error_count(), 0);
    drop(ctx);
    assert!(log.error_count() > 0, "the leak went unreported: {:?}", log.messages());
    assert!(log.messages().iter().any(|m| m.contains("VkBuffer")), "{:?}", log.messages());
}

/// A copy probe asked for more than the device's largest storage buffer copies that much
/// instead of failing: `bench train --width 1920 --height 1080` on lavapipe asked for 132 MiB
/// after minutes of work and was refused.
#[test]
fn a_copy_probe_past_the_largest_buffer_copies_the_largest() {
    let gpu = common::gpu();
    let largest = gpu.ctx().limits().max_storage_buffer_range;
    if largest > 1 << 30 {
        // Two buffers past 1 GiB each: more memory than a test should take.
        assert!(std::env::var("CI").as_deref() != Ok("true"), "CI runs on lavapipe (128 MiB)");
        eprintln!("SKIPPED: the device's largest storage buffer is over 1 GiB");
        return;
    }
    let probe = tagsplat::bench::CopyProbe::new(gpu.ctx(), largest + (1 << 20)).unwrap();
    let mut rec = tagsplat::gpu::Recorder::new(gpu.ctx()).unwrap();
    probe.record(&mut rec).unwrap();
    probe.record(&mut rec).unwrap();
    let bandwidth = probe.bandwidth(&rec.submit_and_wait().unwrap());
    assert_eq!(bandwidth.bytes, largest / 16 * 16);
    assert!(bandwidth.compute_bytes_per_s > 0.0 && bandwidth.transfer_bytes_per_s > 0.0);
}
