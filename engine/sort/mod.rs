//! Sorting building blocks for tile binning: an exclusive prefix scan over u32 and a stable
//! LSD radix sort of u32 or u64 keys with a u32 payload. Both are correct for any subgroup
//! size from 4 to 128 (lavapipe 8, NVIDIA 32, AMD 64) whose subgroups are full (see docs/sort.md, "Known limits").

mod radix;
mod scan;

pub use radix::{RadixKey, RadixSort};
pub use scan::{exclusive_scan_cpu, PrefixScan};

use crate::gpu::GpuContext;

/// Which pair of radix-sort kernels runs, and how they split the work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadixVariant {
    /// GPUs: workgroups of many subgroups; the scatter ranks keys by ballot matching within
    /// each subgroup and holds them in registers until the subgroups' offsets are known.
    Subgroups,
    /// CPU devices (lavapipe): each invocation owns a contiguous run of the tile and a private
    /// row of digit counters, so there is no cross-lane matching and no atomic. Sorts of more
    /// than 8 bits take the bucket path where the keys allow (see `radix.rs`).
    Lanes,
}

/// How the radix sort splits its work on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RadixTuning {
    variant: RadixVariant,
    workgroup_size: u32,
    keys_per_thread: u32,
    /// Cap on the bucket path's bucket length (CPU variant), under its own loop-budget limit.
    max_bucket_len: u32,
}

impl RadixTuning {
    /// The tuning for this device: [`RadixVariant::Lanes`] on CPU devices, where a workgroup
    /// runs on one core and every memory access is a loop over the SIMD lanes;
    /// [`RadixVariant::Subgroups`] (at most 16 subgroups, 256 invocations) elsewhere.
    pub fn for_device(ctx: &GpuContext) -> Self {
        if ctx.info().kind == ash::vk::PhysicalDeviceType::CPU {
            return Self::lanes(ctx);
        }
        Self::subgroups(ctx)
    }

    /// The CPU tuning, on any device (tests run it on GPUs too, so the bucket path is tested
    /// wherever the suite runs).
    pub fn lanes(ctx: &GpuContext) -> Self {
        Self {
            variant: RadixVariant::Lanes,
            workgroup_size: ctx.limits().subgroup_size.clamp(4, 16),
            keys_per_thread: 4096,
            max_bucket_len: u32::MAX,
        }
    }

    /// The GPU tuning, on any device (tests run it on lavapipe too).
    pub fn subgroups(ctx: &GpuContext) -> Self {
        let limits = ctx.limits();
        let workgroup_size =
            (limits.subgroup_size * 16).min(256).min(limits.max_workgroup_invocations);
        Self {
            variant: RadixVariant::Subgroups,
            workgroup_size,
            keys_per_thread: 16,
            max_bucket_len: 0,
        }
    }

    /// This tuning with the CPU variant's buckets capped at `len` pairs; 0 makes every sort take
    /// the LSD passes. Tests use it to run both paths on the same keys.
    pub fn with_max_bucket_len(self, len: u32) -> Self {
        Self { max_bucket_len: len, ..self }
    }

    /// Which pair of kernels runs.
    pub fn variant(&self) -> RadixVariant {
        self.variant
    }

    pub(crate) fn workgroup_size(&self) -> u32 {
        self.workgroup_size
    }

    pub(crate) fn keys_per_thread(&self) -> u32 {
        self.keys_per_thread
    }

    /// Cap on the bucket path's bucket length, in pairs; 0 (as in [`subgroups`](Self::subgroups))
    /// means the bucket path is never taken.
    pub fn max_bucket_len(&self) -> u32 {
        self.max_bucket_len
    }

    /// Pairs per tile, the share of one workgroup: workgroup size × keys per invocation.
    pub fn tile_len(&self) -> usize {
        (self.workgroup_size * self.keys_per_thread) as usize
    }

    /// Shared memory the kernels need: one row of 256 digit counters per subgroup or invocation.
    pub(crate) fn shared_bytes(&self, subgroup_size: u32) -> u32 {
        let rows = match self.variant {
            RadixVariant::Subgroups => self.workgroup_size / subgroup_size,
            RadixVariant::Lanes => self.workgroup_size,
        };
        rows * 256 * 4
    }
}
