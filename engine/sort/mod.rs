//! Sorting building blocks for tile binning: an exclusive prefix scan over u32 and a stable
//! LSD radix sort of u32 or u64 keys with a u32 payload. Both are correct for any subgroup
//! size from 4 to 128 (lavapipe 8, NVIDIA 32, AMD 64) whose subgroups are full (see docs/sort.md, "Known limits").

mod radix;
mod scan;

pub use radix::{RadixKey, RadixSort};
pub use scan::{exclusive_scan_cpu, PrefixScan};

use crate::gpu::{GpuContext, GpuError, GpuResult};
use std::str::FromStr;

/// Environment variable that forces a radix-sort variant (`lanes`, `subgroups` or `onesweep`)
/// wherever a sorter picks its own tuning ([`RadixSort::new`], [`RadixSort::tuning_for`]).
pub const SORT_VARIANT_ENV: &str = "TAGSPLAT_SORT";

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
    /// GPUs with subgroups of 32 or more (Onesweep, Adinets & Merrill 2022): one read of the
    /// keys counts the digits of every pass, then one kernel per pass ranks each tile like
    /// `Subgroups` and finds its output offsets by looking back over earlier tiles' published
    /// counts, so a pass reads the keys once instead of twice.
    Onesweep,
}

impl RadixVariant {
    /// Every variant with its name in [`SORT_VARIANT_ENV`] and on the command line.
    const NAMES: [(RadixVariant, &'static str); 3] = [
        (RadixVariant::Lanes, "lanes"),
        (RadixVariant::Subgroups, "subgroups"),
        (RadixVariant::Onesweep, "onesweep"),
    ];
    /// The names, for messages.
    const EXPECTED: &'static str = "lanes, subgroups or onesweep";

    /// The variant [`SORT_VARIANT_ENV`] forces, if it is set. The one place that reads it: a
    /// value that names no variant is an error naming the variable, never a silent default.
    pub fn from_env() -> GpuResult<Option<Self>> {
        match std::env::var_os(SORT_VARIANT_ENV) {
            None => Ok(None),
            Some(value) => Self::from_setting(&value.to_string_lossy()).map(Some),
        }
    }

    /// The variant a value of [`SORT_VARIANT_ENV`] names.
    fn from_setting(value: &str) -> GpuResult<Self> {
        value.parse().map_err(|expected| GpuError::InvalidSetting {
            variable: SORT_VARIANT_ENV,
            value: value.into(),
            expected,
        })
    }
}

impl FromStr for RadixVariant {
    /// What a valid value is, for the caller's message.
    type Err = &'static str;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        let name = name.trim().to_ascii_lowercase();
        Self::NAMES.iter().find(|(_, n)| *n == name).map(|(v, _)| *v).ok_or(Self::EXPECTED)
    }
}

/// How the radix sort splits its work on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RadixTuning {
    variant: RadixVariant,
    workgroup_size: u32,
    keys_per_thread: u32,
    /// Cap on the bucket path's bucket length (CPU variant), under its own loop-budget limit.
    max_bucket_len: u32,
    /// Reads of an empty status word before a look-back counts that tile itself (Onesweep).
    lookback_polls: u32,
}

impl RadixTuning {
    /// The tuning for this device: [`RadixVariant::Lanes`] on CPU devices, where a workgroup
    /// runs on one core and every memory access is a loop over the SIMD lanes;
    /// [`RadixVariant::Onesweep`] on other devices with subgroups of 32 or more, where a tile's
    /// 16 subgroups or fewer rank 4096 keys; [`RadixVariant::Subgroups`] elsewhere, where
    /// narrow subgroups make tiles small and a look-back long. Ignores [`SORT_VARIANT_ENV`]
    /// ([`RadixSort::tuning_for`] reads it).
    pub fn for_device(ctx: &GpuContext) -> Self {
        if ctx.info().kind == ash::vk::PhysicalDeviceType::CPU {
            return Self::lanes(ctx);
        }
        if ctx.limits().subgroup_size >= 32 {
            return Self::onesweep(ctx);
        }
        Self::subgroups(ctx)
    }

    /// The tuning of `variant` on this device, as [`lanes`](Self::lanes),
    /// [`subgroups`](Self::subgroups) or [`onesweep`](Self::onesweep) make it.
    pub fn of_variant(ctx: &GpuContext, variant: RadixVariant) -> Self {
        match variant {
            RadixVariant::Lanes => Self::lanes(ctx),
            RadixVariant::Subgroups => Self::subgroups(ctx),
            RadixVariant::Onesweep => Self::onesweep(ctx),
        }
    }

    /// The CPU tuning, on any device (tests run it on GPUs too, so the bucket path is tested
    /// wherever the suite runs).
    pub fn lanes(ctx: &GpuContext) -> Self {
        Self {
            variant: RadixVariant::Lanes,
            workgroup_size: ctx.limits().subgroup_size.clamp(4, 16),
            keys_per_thread: 4096,
            max_bucket_len: u32::MAX,
            lookback_polls: 0,
        }
    }

    /// The GPU tuning, on any device (tests run it on lavapipe too).
    pub fn subgroups(ctx: &GpuContext) -> Self {
        Self::ranking_tiles(ctx, RadixVariant::Subgroups)
    }

    /// The tuning for wide subgroups, on any device (tests run it on lavapipe too): the tiles
    /// of [`subgroups`](Self::subgroups), a look-back that reads an empty status word 64
    /// times before it counts that tile itself (not tuned on a GPU yet).
    pub fn onesweep(ctx: &GpuContext) -> Self {
        Self { lookback_polls: 64, ..Self::ranking_tiles(ctx, RadixVariant::Onesweep) }
    }

    /// Tiles of 16 keys per invocation in workgroups of at most 16 subgroups and 256
    /// invocations: the ballot-ranking kernels' registers and shared rows (radix_rank.glsl).
    fn ranking_tiles(ctx: &GpuContext, variant: RadixVariant) -> Self {
        let limits = ctx.limits();
        let workgroup_size =
            (limits.subgroup_size * 16).min(256).min(limits.max_workgroup_invocations);
        Self { variant, workgroup_size, keys_per_thread: 16, max_bucket_len: 0, lookback_polls: 0 }
    }

    /// This tuning with a look-back that reads an empty status word `polls` times before it
    /// counts that tile itself; only [`RadixVariant::Onesweep`] looks back. With 0 every tile
    /// counts every tile before it from its keys, whatever the timing: tests use it to run
    /// the fallback on every tile.
    pub fn with_lookback_polls(self, polls: u32) -> Self {
        Self { lookback_polls: polls, ..self }
    }

    /// Reads of an empty status word before the look-back's fallback (Onesweep; the other
    /// variants ignore it).
    pub fn lookback_polls(&self) -> u32 {
        self.lookback_polls
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

    /// Shared memory the kernels need: one row of 256 digit counters per subgroup or
    /// invocation; Onesweep's scatter one more row for its fallback, its histogram one per
    /// pass of a u64 key.
    pub(crate) fn shared_bytes(&self, subgroup_size: u32) -> u32 {
        let rows = match self.variant {
            RadixVariant::Subgroups => self.workgroup_size / subgroup_size,
            RadixVariant::Lanes => self.workgroup_size,
            RadixVariant::Onesweep => (self.workgroup_size / subgroup_size + 1).max(8),
        };
        rows * 256 * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variant_settings() {
        assert_eq!(RadixVariant::from_setting("onesweep").unwrap(), RadixVariant::Onesweep);
        assert_eq!(RadixVariant::from_setting(" Lanes ").unwrap(), RadixVariant::Lanes);
        assert_eq!("subgroups".parse(), Ok(RadixVariant::Subgroups));
        let message = RadixVariant::from_setting("fast").unwrap_err().to_string();
        assert!(message.contains(SORT_VARIANT_ENV) && message.contains("\"fast\""), "{message}");
        assert!(message.contains("lanes, subgroups or onesweep"), "{message}");
    }
}
