//! Sorting building blocks for tile binning: an exclusive prefix scan over u32 and a stable
//! LSD radix sort of u32 or u64 keys with a u32 payload. Both are correct for any subgroup
//! size from 4 to 128 (lavapipe 8, NVIDIA 32, AMD 64).

mod radix;
mod scan;

pub use radix::{RadixKey, RadixSort};
pub use radix::sort_pairs_cpu;
pub use scan::{exclusive_scan_cpu, PrefixScan};

use crate::gpu::GpuContext;

/// How the radix sort splits its work on this device.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RadixTuning {
    pub workgroup_size: u32,
    pub keys_per_thread: u32,
}

impl RadixTuning {
    /// GPUs: workgroups of many subgroups (at most 16, at most 256 invocations) with 16 keys per
    /// invocation held in registers. CPU devices run a workgroup on one core, so a workgroup of
    /// one subgroup walking a long tile avoids the cross-subgroup bookkeeping.
    pub fn for_device(ctx: &GpuContext) -> Self {
        let limits = ctx.limits();
        if ctx.info().kind == ash::vk::PhysicalDeviceType::CPU {
            return Self { workgroup_size: limits.subgroup_size, keys_per_thread: 8192 / limits.subgroup_size };
        }
        let workgroup_size = (limits.subgroup_size * 16).min(256).min(limits.max_workgroup_invocations);
        Self { workgroup_size, keys_per_thread: 16 }
    }

    pub fn subgroups(&self, ctx: &GpuContext) -> u32 {
        self.workgroup_size / ctx.limits().subgroup_size
    }

    pub fn tile_len(&self) -> usize {
        (self.workgroup_size * self.keys_per_thread) as usize
    }
}
