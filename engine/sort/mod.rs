//! Sorting building blocks for tile binning: an exclusive prefix scan over u32 and a stable
//! LSD radix sort of u32 or u64 keys with a u32 payload. Both are correct for any subgroup
//! size from 4 to 128 (lavapipe 8, NVIDIA 32, AMD 64).

mod radix;
mod scan;

pub use radix::{RadixKey, RadixSort};
pub use radix::sort_pairs_cpu;
pub use scan::{exclusive_scan_cpu, PrefixScan};

use crate::gpu::GpuContext;

/// Workgroup size for kernels that keep one row of shared memory per subgroup: at most 16
/// subgroups (16 KiB of digit counts for the radix sort), at most 256 invocations.
pub(crate) fn workgroup_size(ctx: &GpuContext) -> u32 {
    let limits = ctx.limits();
    (limits.subgroup_size * 16).min(256).min(limits.max_workgroup_invocations)
}
