//! Physical-device choice: discrete > integrated > virtual > CPU, among devices that have every
//! required feature, unless the user names one (by index or by a piece of its name).

use super::error::{GpuError, GpuResult};
use super::features::DeviceCapabilities;
use ash::vk;

/// Environment variable that picks a device, like the CLI's `--device`.
pub const DEVICE_ENV: &str = "TAGSPLAT_DEVICE";

/// One physical device as the user sees it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// Index in the instance's device list, as the `wanted` of [`choose_device`] takes it.
    pub index: usize,
    /// The driver's device name.
    pub name: String,
    /// Discrete, integrated, virtual, CPU or other.
    pub kind: vk::PhysicalDeviceType,
    /// The driver's name and version (`llvmpipe: Mesa 22.3.6 (LLVM 15.0.6)`).
    pub driver: String,
    /// What the device offers of what the engine needs.
    pub capabilities: DeviceCapabilities,
}

impl DeviceInfo {
    /// Short words for the device type.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }

    /// Whether the device's memory is the host's (a CPU device, an integrated GPU).
    pub fn shares_host_memory(&self) -> bool {
        matches!(self.kind, vk::PhysicalDeviceType::CPU | vk::PhysicalDeviceType::INTEGRATED_GPU)
    }

    fn rank(&self) -> u32 {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        }
    }
}

/// Picks the device to use. `wanted` is an index ("1") or a case-insensitive piece of the
/// device name ("llvmpipe"); `None` applies the policy. The chosen device must have every
/// required feature, otherwise the error names the missing ones.
pub fn choose_device(devices: &[DeviceInfo], wanted: Option<&str>) -> GpuResult<usize> {
    let chosen = match wanted.map(str::trim).filter(|w| !w.is_empty()) {
        Some(wanted) => {
            let lowered = wanted.to_lowercase();
            let by_index = wanted.parse::<usize>().ok().filter(|&i| i < devices.len());
            by_index
                .or_else(|| devices.iter().position(|d| d.name.to_lowercase().contains(&lowered)))
                .ok_or_else(|| GpuError::DeviceNotFound {
                    wanted: wanted.to_string(),
                    available: describe(devices),
                })?
        }
        None => {
            let best = |usable: bool| {
                devices
                    .iter()
                    .filter(|d| d.capabilities.missing_features().is_empty() == usable)
                    .min_by_key(|d| (d.rank(), d.index))
                    .map(|d| d.index)
            };
            // With no usable device, "choose" the best one anyway so the error names its gaps.
            best(true).or_else(|| best(false)).ok_or(GpuError::NoDevice)?
        }
    };
    let missing = devices[chosen].capabilities.missing_features();
    if missing.is_empty() {
        Ok(chosen)
    } else {
        Err(GpuError::MissingFeatures { device: devices[chosen].name.clone(), missing })
    }
}

fn describe(devices: &[DeviceInfo]) -> String {
    if devices.is_empty() {
        return "none".into();
    }
    let names: Vec<String> = devices.iter().map(|d| format!("{}: {}", d.index, d.name)).collect();
    names.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(index: usize, name: &str, kind: vk::PhysicalDeviceType, usable: bool) -> DeviceInfo {
        let capabilities = DeviceCapabilities {
            api_version: vk::API_VERSION_1_2,
            shader_int64: true,
            buffer_int64_atomics: usable,
            push_descriptor: true,
            subgroup_size: 32,
            subgroup_in_compute: true,
            subgroup_arithmetic: true,
            subgroup_ballot: true,
            subgroup_shuffle: true,
            has_compute_queue: true,
            full_subgroups: true,
            max_subgroup_size: 32,
        };
        DeviceInfo { index, name: name.into(), kind, driver: "test".into(), capabilities }
    }

    #[test]
    fn policy_prefers_discrete_then_integrated_then_cpu() {
        let devices = [
            device(0, "llvmpipe", vk::PhysicalDeviceType::CPU, true),
            device(1, "Intel UHD", vk::PhysicalDeviceType::INTEGRATED_GPU, true),
            device(2, "NVIDIA H200", vk::PhysicalDeviceType::DISCRETE_GPU, true),
        ];
        assert_eq!(choose_device(&devices, None).unwrap(), 2);
        assert_eq!(choose_device(&devices[..2], None).unwrap(), 1);
        assert_eq!(choose_device(&devices[..1], None).unwrap(), 0);
    }

    #[test]
    fn policy_skips_devices_without_features() {
        let devices = [
            device(0, "old GPU", vk::PhysicalDeviceType::DISCRETE_GPU, false),
            device(1, "llvmpipe", vk::PhysicalDeviceType::CPU, true),
        ];
        assert_eq!(choose_device(&devices, None).unwrap(), 1);
    }

    #[test]
    fn override_by_index_or_name_and_errors() {
        let devices = [
            device(0, "llvmpipe (LLVM 15)", vk::PhysicalDeviceType::CPU, true),
            device(1, "NVIDIA H200", vk::PhysicalDeviceType::DISCRETE_GPU, true),
            device(2, "old GPU", vk::PhysicalDeviceType::DISCRETE_GPU, false),
        ];
        assert_eq!(choose_device(&devices, Some("0")).unwrap(), 0);
        assert_eq!(choose_device(&devices, Some("LLVMpipe")).unwrap(), 0);
        assert!(matches!(
            choose_device(&devices, Some("radeon")),
            Err(GpuError::DeviceNotFound { .. })
        ));
        let err = choose_device(&devices, Some("old")).unwrap_err().to_string();
        assert!(err.contains("old GPU") && err.contains("64-bit buffer atomics"), "{err}");
        assert!(matches!(choose_device(&[], None), Err(GpuError::NoDevice)));
    }
}
