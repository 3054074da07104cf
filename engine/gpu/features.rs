//! What the engine needs from a device, as plain data, so the check is testable with a fake
//! device: [`DeviceCapabilities::missing_features`] lists every requirement a device fails.

use ash::vk;
use std::ffi::CStr;

/// The capabilities of one physical device that the engine cares about.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceCapabilities {
    /// The Vulkan version the device supports, packed as by `vk::make_api_version`; 1.2 or later
    /// is required.
    pub api_version: u32,
    /// `shaderInt64`: 64-bit integers in shaders (required).
    pub shader_int64: bool,
    /// `shaderBufferInt64Atomics`: 64-bit atomics on storage buffers (required).
    pub buffer_int64_atomics: bool,
    /// VK_KHR_push_descriptor is available (required).
    pub push_descriptor: bool,
    /// The default subgroup size; required to be a power of two in 4..=128. 0 below Vulkan 1.2.
    pub subgroup_size: u32,
    /// Subgroup operations are supported in compute shaders (required).
    pub subgroup_in_compute: bool,
    /// Subgroup arithmetic operations are supported (required).
    pub subgroup_arithmetic: bool,
    /// Subgroup ballot operations are supported (required).
    pub subgroup_ballot: bool,
    /// Subgroup shuffle operations are supported (required).
    pub subgroup_shuffle: bool,
    /// Some queue family supports compute (required).
    pub has_compute_queue: bool,
    /// Optional: VK_EXT_subgroup_size_control with computeFullSubgroups, so pipelines can ask
    /// for full subgroups (some drivers, Intel's, may otherwise launch partial ones).
    pub full_subgroups: bool,
    /// The largest subgroup size the device may use: VK_EXT_subgroup_size_control's maximum, at
    /// least [`subgroup_size`](Self::subgroup_size).
    pub max_subgroup_size: u32,
}

/// Device extensions the engine enables.
pub const REQUIRED_EXTENSIONS: [&CStr; 1] = [ash::khr::push_descriptor::NAME];

impl DeviceCapabilities {
    /// Names of the required features this device lacks; empty when it has them all.
    pub fn missing_features(&self) -> Vec<&'static str> {
        let checks = [
            (self.api_version >= vk::API_VERSION_1_2, "Vulkan 1.2"),
            (self.has_compute_queue, "a compute queue"),
            (self.shader_int64, "shaderInt64"),
            (self.buffer_int64_atomics, "shaderBufferInt64Atomics (64-bit buffer atomics)"),
            (self.push_descriptor, "VK_KHR_push_descriptor"),
            (self.subgroup_in_compute, "subgroup operations in compute shaders"),
            (self.subgroup_arithmetic, "subgroup arithmetic"),
            (self.subgroup_ballot, "subgroup ballot"),
            (self.subgroup_shuffle, "subgroup shuffle"),
            // Ballots return uvec4: the shaders handle any power-of-two size up to 128.
            (
                self.subgroup_size.is_power_of_two() && (4..=128).contains(&self.subgroup_size),
                "a subgroup size that is a power of two in 4..=128",
            ),
        ];
        checks.iter().filter(|(ok, _)| !ok).map(|&(_, name)| name).collect()
    }

    /// Reads the capabilities of `physical_device`.
    ///
    /// # Safety
    /// `physical_device` must come from `instance`.
    pub unsafe fn query(instance: &ash::Instance, physical_device: vk::PhysicalDevice) -> Self {
        let properties = instance.get_physical_device_properties(physical_device);
        let extensions =
            instance.enumerate_device_extension_properties(physical_device).unwrap_or_default();
        let has_extension =
            |name: &CStr| extensions.iter().any(|e| e.extension_name_as_c_str() == Ok(name));
        let queues = instance.get_physical_device_queue_family_properties(physical_device);
        let mut capabilities = Self {
            api_version: properties.api_version,
            shader_int64: false,
            buffer_int64_atomics: false,
            push_descriptor: has_extension(ash::khr::push_descriptor::NAME),
            subgroup_size: 0,
            subgroup_in_compute: false,
            subgroup_arithmetic: false,
            subgroup_ballot: false,
            subgroup_shuffle: false,
            has_compute_queue: queues
                .iter()
                .any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE)),
            full_subgroups: false,
            max_subgroup_size: 0,
        };
        if properties.api_version < vk::API_VERSION_1_2 {
            return capabilities; // The 1.2 feature structs below are not defined on such a device.
        }
        let has_size_control = has_extension(ash::ext::subgroup_size_control::NAME);
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut size_control = vk::PhysicalDeviceSubgroupSizeControlProperties::default();
        let mut properties2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
        if has_size_control {
            properties2 = properties2.push_next(&mut size_control);
        }
        instance.get_physical_device_properties2(physical_device, &mut properties2);
        let ops = subgroup.supported_operations;
        capabilities.subgroup_size = subgroup.subgroup_size;
        capabilities.max_subgroup_size = size_control.max_subgroup_size.max(subgroup.subgroup_size);
        capabilities.subgroup_in_compute =
            subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE);
        capabilities.subgroup_arithmetic = ops.contains(vk::SubgroupFeatureFlags::ARITHMETIC);
        capabilities.subgroup_ballot = ops.contains(vk::SubgroupFeatureFlags::BALLOT);
        capabilities.subgroup_shuffle = ops.contains(vk::SubgroupFeatureFlags::SHUFFLE);

        let mut vk12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut size_control_features = vk::PhysicalDeviceSubgroupSizeControlFeatures::default();
        let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut vk12);
        if has_size_control {
            features2 = features2.push_next(&mut size_control_features);
        }
        instance.get_physical_device_features2(physical_device, &mut features2);
        capabilities.shader_int64 = features2.features.shader_int64 == vk::TRUE;
        capabilities.buffer_int64_atomics = vk12.shader_buffer_int64_atomics == vk::TRUE;
        capabilities.full_subgroups = size_control_features.compute_full_subgroups == vk::TRUE;
        capabilities
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full() -> DeviceCapabilities {
        DeviceCapabilities {
            api_version: vk::API_VERSION_1_3,
            shader_int64: true,
            buffer_int64_atomics: true,
            push_descriptor: true,
            subgroup_size: 32,
            subgroup_in_compute: true,
            subgroup_arithmetic: true,
            subgroup_ballot: true,
            subgroup_shuffle: true,
            has_compute_queue: true,
            full_subgroups: false,
            max_subgroup_size: 32,
        }
    }

    #[test]
    fn complete_device_passes() {
        assert!(full().missing_features().is_empty());
    }

    #[test]
    fn each_missing_feature_is_named() {
        type BreakIt = fn(&mut DeviceCapabilities);
        let cases: [(BreakIt, &str); 4] = [
            (|c| c.api_version = vk::API_VERSION_1_1, "Vulkan 1.2"),
            (|c| c.buffer_int64_atomics = false, "64-bit buffer atomics"),
            (|c| c.subgroup_ballot = false, "subgroup ballot"),
            (|c| c.subgroup_size = 24, "subgroup size"),
        ];
        for (break_it, expected) in cases {
            let mut capabilities = full();
            break_it(&mut capabilities);
            let missing = capabilities.missing_features();
            assert_eq!(missing.len(), 1, "{missing:?}");
            assert!(missing[0].contains(expected), "{missing:?} should name {expected}");
        }
    }
}
