//! What a capture will hold in memory, known before any work: `train` refuses a capture that
//! cannot fit, naming the memory and the `--scale` that would fit, and `dataset info` prints it.
//!
//! The model counts what grows with the capture. On the device: every training view's target
//! (16 bytes a pixel; when they do not all fit in the device's memory, only as many as do, of
//! the largest view's size, the rest streamed from the host: `train::targets`) and mask
//! distance field (4), the per-pixel working buffers of the renders, losses and rasterizers
//! (several copies, sized by the largest view), and a fixed part for the Gaussians, the mesh
//! and the sort. On the host: the views' targets again, the
//! decoded-image cache, the images being decoded, the first mesh's hull grid, the background
//! plates of a capture whose masks are refined, and, on a device that is the CPU, the device's
//! memory too. The per-pixel and fixed parts were measured
//! (docs/log/2026-11-28-capture-memory.md) and rounded up, so the figure is a bound, not a
//! guess: `tests/pipeline.rs` checks it against the buffers a run holds.

use crate::dataset::matte::PLATE_FRAMES;
use crate::dataset::{scaled_size, Dataset, DEFAULT_CACHE_BYTES};
use crate::gpu::DeviceLimits;
use crate::init::InitOptions;

/// Device bytes per pixel of the largest view held by the working buffers (splatting, the
/// image loss and its SSIM moments, the mesh rasterizers of training and evaluation: 615
/// measured, docs/log/2026-11-28-capture-memory.md, less the 128 of a one-render loss's
/// scratch that the two-render loss now shares, docs/log/2026-11-29-streamed-targets.md,
/// rounded up), and the camera colour maps' renders as seen and their gradients (two of each,
/// 64).
const WORKING_BYTES_PER_PIXEL: u64 = 512 + 64;
/// Device bytes that do not grow with the capture's pixels (Gaussians, their gradients and
/// moments, the mesh, the sort's buffers), rounded up.
const FIXED_DEVICE_BYTES: u64 = 256 << 20;
/// Host bytes of the program itself and of what does not grow with the capture.
const FIXED_HOST_BYTES: u64 = 768 << 20;
/// Device bytes of a training view's target pixel (rgba as f32), while it is on the device.
const TARGET_BYTES_PER_PIXEL: u64 = 16;
/// Device bytes of a training view's mask distance field pixel (f32): every view's field stays
/// on the device, since every step scores every view's silhouette.
const FIELD_BYTES_PER_PIXEL: u64 = 4;
/// Bytes of a decoded pixel: colour (3 f32) and mask (1 f32).
const DECODED_BYTES_PER_PIXEL: u64 = 16;

/// The memory a capture will need (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct CaptureMemory {
    /// Device memory, bytes.
    pub device_bytes: u64,
    /// Host memory, bytes (the device's included when the device is the CPU).
    pub host_bytes: u64,
    /// The largest single buffer, bytes (a per-pixel working buffer of the largest view).
    pub largest_buffer_bytes: u64,
    /// Whether the device's memory is the host's (then counted in `host_bytes`).
    pub device_is_host: bool,
    /// Training views whose targets stay on the device ([`targets_on_device`]); fewer than
    /// `training_views` when the rest are streamed.
    pub targets_on_device: usize,
    /// Training views.
    pub training_views: usize,
}

/// The views of one frame as the run will hold them.
pub struct CaptureViews<'a> {
    /// Training views' sizes (width, height) after any scaling.
    pub train: &'a [(u32, u32)],
    /// Held-out views' sizes after any scaling.
    pub held_out: &'a [(u32, u32)],
    /// The largest image as stored in the files (decoded at full size before any scaling).
    pub largest_file_pixels: u64,
    /// Whether the device's memory is the host's (a CPU device such as lavapipe).
    pub device_is_host: bool,
    /// The device memory the run may plan for ([`DeviceLimits::device_budget`]); None: no
    /// limit but the host's.
    pub device_budget: Option<u64>,
}

fn area(&(w, h): &(u32, u32)) -> u64 {
    w as u64 * h as u64
}

/// Device bytes of a run over training views of sizes `train`, its working buffers sized for
/// `working_pixels`, with `on_device` of the training targets on the device: each view's own
/// when all are, else `on_device` buffers of the largest training view's size.
pub fn device_bytes(train: &[(u32, u32)], working_pixels: u64, on_device: usize) -> u64 {
    let pixels: u64 = train.iter().map(area).sum();
    let largest = train.iter().map(area).max().unwrap_or(0);
    let targets = if on_device >= train.len() { pixels } else { on_device as u64 * largest };
    FIXED_DEVICE_BYTES
        + FIELD_BYTES_PER_PIXEL * pixels
        + WORKING_BYTES_PER_PIXEL * working_pixels
        + TARGET_BYTES_PER_PIXEL * targets
}

/// How many training views' targets a trainer keeps on the device (`train::targets`): all of
/// them when [`device_bytes`] with all fits in `budget` (None: no limit), else the most that
/// fit, and at least one (a run that cannot fit one is refused by [`CaptureMemory::problem`]).
/// The trainer sizes its working buffers for its largest training view, so that is what the
/// working part is counted at here.
pub fn targets_on_device(budget: Option<u64>, train: &[(u32, u32)]) -> usize {
    let all = train.len();
    let largest = train.iter().map(area).max().unwrap_or(0);
    let fits = |k: usize| budget.is_none_or(|b| device_bytes(train, largest, k) <= b);
    (1..=all).rev().find(|&k| fits(k)).unwrap_or(all.min(1))
}

/// What refining the masks from the images holds, counted whether or not a run refines them:
/// each training camera's plate (3 bytes a pixel) and the decoded frames one plate is built
/// from (`dataset::matte`).
fn plate_bytes(train_pixels: u64, largest_view_pixels: u64) -> u64 {
    3 * train_pixels + PLATE_FRAMES as u64 * DECODED_BYTES_PER_PIXEL * largest_view_pixels
}

impl CaptureMemory {
    /// The estimate for a run over `dataset` with its files scaled by `scale` (1: the files'
    /// size), whatever scale it was loaded at, on a device of `limits` (`device_is_host`: a
    /// CPU device).
    pub fn of_dataset(
        dataset: &Dataset,
        limits: &DeviceLimits,
        device_is_host: bool,
        scale: f64,
    ) -> Self {
        let sizes = |cameras: &[usize]| -> Vec<(u32, u32)> {
            cameras.iter().map(|&c| scaled_size(dataset.file_size(c), scale)).collect()
        };
        let largest_file_pixels = (0..dataset.cameras.len())
            .map(|c| dataset.file_size(c))
            .map(|(w, h)| w as u64 * h as u64)
            .max()
            .unwrap_or(0);
        Self::estimate(&CaptureViews {
            train: &sizes(&dataset.train),
            held_out: &sizes(&dataset.test),
            largest_file_pixels,
            device_is_host,
            device_budget: limits.device_budget(device_is_host),
        })
    }

    /// The estimate for `views`.
    pub fn estimate(views: &CaptureViews) -> Self {
        let train: u64 = views.train.iter().map(area).sum();
        let held_out: u64 = views.held_out.iter().map(area).sum();
        let largest = views.train.iter().chain(views.held_out).map(area).max().unwrap_or(0);
        let on_device = targets_on_device(views.device_budget, views.train);
        let device_bytes = device_bytes(views.train, largest, on_device);
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
        let cache = (DECODED_BYTES_PER_PIXEL * (train + held_out)).min(DEFAULT_CACHE_BYTES as u64);
        let host_bytes = FIXED_HOST_BYTES
            + InitOptions::default().max_grid_bytes as u64
            + 16 * (train + held_out)
            + plate_bytes(train, largest)
            + cache
            + threads * DECODED_BYTES_PER_PIXEL * views.largest_file_pixels
            + if views.device_is_host { device_bytes } else { 0 };
        Self {
            device_bytes,
            host_bytes,
            // The widest per-pixel buffers hold 32 bytes a pixel (the anti-aliasing crossings).
            largest_buffer_bytes: 32 * largest,
            device_is_host: views.device_is_host,
            targets_on_device: on_device,
            training_views: views.train.len(),
        }
    }

    /// Whether some training views' targets are streamed: uploaded when a step needs them.
    pub fn streamed(&self) -> bool {
        self.targets_on_device < self.training_views
    }

    /// What a run does with the training targets when they do not all fit on the device
    /// (None when they do).
    pub fn streaming(&self) -> Option<String> {
        self.streamed().then(|| {
            format!(
                "{} of {} training views' targets on the device at once, the rest uploaded when \
                 a step needs them",
                self.targets_on_device, self.training_views
            )
        })
    }

    /// The limit it breaks (None when it fits). `host_memory`: the host's physical memory,
    /// when known.
    pub fn problem(&self, limits: &DeviceLimits, host_memory: Option<u64>) -> Option<String> {
        let buffer_limit = limits.max_buffer_bytes();
        if self.largest_buffer_bytes > buffer_limit {
            return Some(format!(
                "its largest view needs buffers of {}, over this device's largest buffer of {} \
                 (maxStorageBufferRange / maxMemoryAllocationSize)",
                mib(self.largest_buffer_bytes),
                mib(buffer_limit)
            ));
        }
        // On a device that is the CPU without a cap the device's memory is the host's (its
        // heap size is not a limit there), and the host check below covers it.
        let budget = limits.device_budget(self.device_is_host);
        if let Some(memory) = budget.filter(|&memory| self.device_bytes > memory) {
            let streamed =
                if self.streamed() { " with one training view on it at a time" } else { "" };
            let capped = if limits.device_memory_cap.is_some() { " (capped)" } else { "" };
            return Some(format!(
                "it needs about {} of device memory{streamed}, over this device's {}{capped}",
                mib(self.device_bytes),
                mib(memory)
            ));
        }
        let host = host_memory.filter(|&total| self.host_bytes > total)?;
        Some(format!(
            "it needs about {} of host memory, over this machine's {}",
            mib(self.host_bytes),
            mib(host)
        ))
    }
}

/// Why a capture cannot run at `scale` (None when it can), and the largest scale in hundredths
/// at which it would: `at(s)` is its estimate with the files scaled by `s`.
pub fn refusal(
    at: impl Fn(f64) -> CaptureMemory,
    scale: f64,
    limits: &DeviceLimits,
    host_memory: Option<u64>,
) -> Option<String> {
    let problem = at(scale).problem(limits, host_memory)?;
    let below = (scale * 100.0).ceil() as u32;
    let fitting = (1..below)
        .rev()
        .map(|hundredths| hundredths as f64 / 100.0)
        .find(|&s| at(s).problem(limits, host_memory).is_none());
    Some(match fitting {
        Some(s) => format!("{problem}; --scale {s} would fit"),
        None => format!("{problem}; no --scale down to 0.01 fits"),
    })
}

/// `bytes` as MiB, or GiB from 10 GiB on.
pub fn mib(bytes: u64) -> String {
    match bytes {
        b if b >= 10 << 30 => format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64),
        b => format!("{} MiB", b.div_ceil(1 << 20)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(buffer: u64, memory: u64) -> DeviceLimits {
        DeviceLimits {
            max_storage_buffer_range: buffer,
            max_memory_allocation_size: u64::MAX,
            device_memory_bytes: memory,
            device_memory_cap: None,
            max_workgroup_count: [65535; 3],
            max_workgroup_invocations: 1024,
            max_shared_memory_bytes: 32768,
            subgroup_size: 32,
            timestamp_period_ns: None,
            timestamp_valid_bits: 0,
            full_subgroups: false,
            max_subgroup_size: 32,
        }
    }

    /// 30 views (27 training) of 3000 × 4000 files scaled by `s`, on a device of `limits`.
    fn capture_on(s: f64, device_is_host: bool, limits: &DeviceLimits) -> CaptureMemory {
        let size = scaled_size((3000, 4000), s);
        let (train, held_out) = (vec![size; 27], vec![size; 3]);
        let largest_file_pixels = 12_000_000;
        CaptureMemory::estimate(&CaptureViews {
            train: &train,
            held_out: &held_out,
            largest_file_pixels,
            device_is_host,
            device_budget: limits.device_budget(device_is_host),
        })
    }

    /// The refusal's scale, parsed back out of its message.
    fn scale_in(message: &str) -> f64 {
        let tail = message.split("--scale ").nth(1).expect("names a scale");
        tail.split(' ').next().unwrap().parse().unwrap()
    }

    #[test]
    fn a_refused_capture_names_a_scale_that_fits() {
        let refused = |s, host, limits: &DeviceLimits, memory| {
            refusal(|s| capture_on(s, host, limits), s, limits, memory)
        };
        // The buffer limit of lavapipe: a 3000 × 4000 view's widest buffer is 366 MiB.
        let lavapipe = limits(128 << 20, 2 << 30);
        let why = refused(1.0, true, &lavapipe, Some(64 << 30)).expect("refused");
        assert!(why.contains("367 MiB") && why.contains("128 MiB"), "{why}");
        let s = scale_in(&why);
        assert_eq!(refused(s, true, &lavapipe, Some(64 << 30)), None, "--scale {s}");
        assert!(refused(s + 0.01, true, &lavapipe, Some(64 << 30)).is_some());
        // A discrete GPU with 4 GiB: the device memory is the limit; the heap of a CPU device is
        // not, the host's memory is.
        let small_gpu = limits(4 << 30, 4 << 30);
        let why = refused(1.0, false, &small_gpu, None).expect("refused");
        assert!(why.contains("device memory with one training view on it at a time"), "{why}");
        let s = scale_in(&why);
        assert_eq!(refused(s, false, &small_gpu, None), None);
        // The largest scale that fits streams its targets: a larger one would fit a target
        // only if the working buffers shrank.
        assert!(capture_on(s, false, &small_gpu).streamed(), "{s}");
        // A 12 GiB GPU runs the capture at full scale with 22 of its 27 targets on it; all 27
        // would need 13.7 GB.
        let gpu_12 = limits(4 << 30, 12 << 30);
        let full = capture_on(1.0, false, &gpu_12);
        assert_eq!((full.targets_on_device, full.problem(&gpu_12, None)), (22, None));
        let all = device_bytes(&[(3000, 4000); 27], 12_000_000, 27);
        assert_eq!(all / 100_000_000, 136, "{all}");
        let why = refused(0.5, true, &small_gpu, Some(4 << 30)).expect("refused");
        assert!(why.contains("host memory"), "{why}");
        let s = scale_in(&why);
        assert!(s < 0.5 && refused(s, true, &small_gpu, Some(4 << 30)).is_none(), "{s}");
        assert_eq!(refused(0.5, true, &small_gpu, Some(64 << 30)), None);
        // Nothing fits a host without memory for the program itself.
        let why = refused(0.5, true, &small_gpu, Some(1 << 20)).expect("refused");
        assert!(why.contains("no --scale"), "{why}");
    }

    #[test]
    fn targets_that_do_not_fit_are_streamed_down_to_one() {
        let train = vec![(1000, 1000); 10];
        let working = 1_000_000;
        let all = device_bytes(&train, working, 10);
        assert_eq!(targets_on_device(None, &train), 10);
        assert_eq!(targets_on_device(Some(all), &train), 10);
        // One byte short of all: the streamed buffers are of the largest view's size, so the
        // most that fit is one fewer.
        assert_eq!(targets_on_device(Some(all - 1), &train), 9);
        let three = device_bytes(&train, working, 3);
        assert_eq!(three + 16 * 1_000_000, device_bytes(&train, working, 4));
        assert_eq!(targets_on_device(Some(three), &train), 3);
        assert_eq!(targets_on_device(Some(three + 16 * 999_999), &train), 3);
        // Below one target the trainer still keeps one; the run is refused before it starts.
        assert_eq!(targets_on_device(Some(1), &train), 1);
        assert_eq!(targets_on_device(Some(1), &[]), 0);
        // Views of different sizes: streamed buffers take the largest.
        let mixed = [(1000, 1000), (10, 10), (10, 10)];
        let bytes = device_bytes(&mixed, working, 3);
        assert_eq!(bytes - device_bytes(&mixed, working, 1), 16 * 200);
        assert_eq!(targets_on_device(Some(bytes - 1), &mixed), 1);
    }

    #[test]
    fn a_capped_cpu_device_streams_and_holds_less() {
        let cap =
            |bytes| DeviceLimits { device_memory_cap: Some(bytes), ..limits(1 << 40, 64 << 30) };
        let free = capture_on(0.25, true, &limits(1 << 40, 64 << 30));
        assert!(!free.streamed() && free.streaming().is_none());
        let capped = capture_on(0.25, true, &cap(free.device_bytes - 1));
        assert!(capped.streamed(), "{capped:?}");
        assert_eq!(capped.targets_on_device, 26);
        assert!(capped.device_bytes < free.device_bytes);
        // The device's memory is the host's: one target fewer on it is one fewer on the host.
        assert_eq!(free.device_bytes - capped.device_bytes, 16 * 750 * 1000);
        assert_eq!(free.host_bytes - capped.host_bytes, 16 * 750 * 1000);
        assert!(capped.streaming().unwrap().starts_with("26 of 27 training views"));
        let why = capped.problem(&cap(free.device_bytes - 1), None);
        assert_eq!(why, None);
    }
}
