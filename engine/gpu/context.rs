//! The Vulkan context: instance, chosen physical device, logical device with one compute queue,
//! memory allocator, pipeline cache and (optionally) the validation messenger. Shared as
//! `Arc<GpuContext>`; buffers and pipelines hold a clone, so it outlives them.

use super::error::{GpuError, GpuResult, VkContext};
use super::features::{DeviceCapabilities, REQUIRED_EXTENSIONS};
use super::host_clock::{ClockReading, HostClock};
use super::replay::ReplayState;
use super::select::{choose_device, DeviceInfo, DEVICE_ENV};
use super::staging::StagingPool;
use super::usage::{BufferBytes, BufferUsage};
use super::validation::{self, ValidationLog, VALIDATION_ENV, VALIDATION_LAYER};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::sync::{Arc, Mutex, MutexGuard};

/// How to create a context. `None` fields fall back to the environment (`TAGSPLAT_DEVICE`,
/// `TAGSPLAT_VALIDATION=1`, `TAGSPLAT_FORCE_STAGING=1`, `TAGSPLAT_IN_FLIGHT=N`,
/// `TAGSPLAT_DEVICE_MEMORY=SIZE`) and then to the defaults (policy, off, off, by device, the
/// device's own). Forced staging sends every upload and readback through staging buffers even
/// where the device's memory is host-visible (lavapipe), so CI runs a discrete GPU's path.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// The device: an index or a case-insensitive piece of its name (see [`choose_device`]).
    pub device: Option<String>,
    /// Whether to enable the Khronos validation layer and count its messages.
    pub validation: Option<bool>,
    /// Whether to send every upload and readback through staging buffers.
    pub force_staging: Option<bool>,
    /// Training steps on the queue at once, 1 to [`MAX_STEPS_IN_FLIGHT`] (default: 1 on a CPU
    /// device, whose host and device share the cores, 3 elsewhere). Every depth gives the same
    /// bytes run to run; depths differ from one another only where a step's intersections
    /// outgrew the splatter's buffers.
    pub steps_in_flight: Option<usize>,
    /// The device memory a run may plan for, bytes, when less than the device has (a GPU
    /// shared with other work; on a CPU device, a cap on what the device side may hold). A
    /// training run keeps its views' targets on the device only as far as they fit in it, and
    /// streams the rest ([`crate::train::memory`]).
    pub device_memory: Option<u64>,
}

/// Set to a size (`6GiB`, `512MiB`, `1000000`): [`ContextOptions::device_memory`].
pub const DEVICE_MEMORY_ENV: &str = "TAGSPLAT_DEVICE_MEMORY";

/// The device-memory cap `options` ask for, else [`DEVICE_MEMORY_ENV`]'s.
fn device_memory(options: &ContextOptions) -> GpuResult<Option<u64>> {
    match (options.device_memory, std::env::var(DEVICE_MEMORY_ENV)) {
        (Some(bytes), _) => Ok(Some(bytes)),
        (None, Ok(value)) => parse_bytes(&value).map(Some).ok_or(GpuError::InvalidSetting {
            variable: DEVICE_MEMORY_ENV,
            value,
            expected: "a size in bytes, KiB, MiB or GiB (6GiB, 512MiB, 1000000)",
        }),
        (None, Err(_)) => Ok(None),
    }
}

/// A size: a whole number of bytes, or a number followed by KiB, MiB or GiB (case-insensitive,
/// spaces allowed); None for anything else, zero included.
pub fn parse_bytes(text: &str) -> Option<u64> {
    let text = text.trim().to_ascii_lowercase();
    let units = [("kib", 1u64 << 10), ("mib", 1 << 20), ("gib", 1 << 30)];
    let (number, unit) = units
        .iter()
        .find_map(|&(suffix, unit)| Some((text.strip_suffix(suffix)?.trim_end(), unit)))
        .unwrap_or((text.as_str(), 1));
    let bytes = match number.parse::<u64>() {
        Ok(n) => n.checked_mul(unit)?,
        Err(_) => {
            let bytes = number.parse::<f64>().ok()? * unit as f64;
            (bytes < u64::MAX as f64).then_some(bytes as u64)?
        }
    };
    (bytes > 0).then_some(bytes)
}

/// Set to a number from 1 to [`MAX_STEPS_IN_FLIGHT`]: [`ContextOptions::steps_in_flight`].
pub const IN_FLIGHT_ENV: &str = "TAGSPLAT_IN_FLIGHT";
/// The most training steps on the queue at once.
pub const MAX_STEPS_IN_FLIGHT: usize = 8;

/// The steps in flight `options` ask for, else [`IN_FLIGHT_ENV`], else the device's default.
fn steps_in_flight(options: &ContextOptions, info: &DeviceInfo) -> GpuResult<usize> {
    let (value, variable) = match (options.steps_in_flight, std::env::var(IN_FLIGHT_ENV)) {
        (Some(n), _) => (n.to_string(), "ContextOptions::steps_in_flight"),
        (None, Ok(value)) => (value, IN_FLIGHT_ENV),
        (None, Err(_)) if info.kind == vk::PhysicalDeviceType::CPU => return Ok(1),
        (None, Err(_)) => return Ok(3),
    };
    match value.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_STEPS_IN_FLIGHT).contains(&n) => Ok(n),
        _ => Err(GpuError::InvalidSetting { variable, value, expected: "a number from 1 to 8" }),
    }
}

/// Device limits and properties the engine sizes its work by.
#[derive(Clone, Debug)]
pub struct DeviceLimits {
    /// `maxStorageBufferRange`: the largest storage-buffer binding, in bytes.
    pub max_storage_buffer_range: u64,
    /// `maxMemoryAllocationSize`: the largest single allocation, in bytes.
    pub max_memory_allocation_size: u64,
    /// The size of the largest device-local memory heap, bytes (on a CPU device: host memory).
    pub device_memory_bytes: u64,
    /// The cap [`ContextOptions::device_memory`] put on it, if any.
    pub device_memory_cap: Option<u64>,
    /// `maxComputeWorkGroupCount`: workgroups per dispatch along x, y and z.
    pub max_workgroup_count: [u32; 3],
    /// `maxComputeWorkGroupInvocations`: invocations in one workgroup.
    pub max_workgroup_invocations: u32,
    /// `maxComputeSharedMemorySize`: shared memory of one workgroup, in bytes.
    pub max_shared_memory_bytes: u32,
    /// The default subgroup size.
    pub subgroup_size: u32,
    /// Nanoseconds per timestamp tick; `None` when the compute queue cannot write timestamps.
    pub timestamp_period_ns: Option<f64>,
    /// Valid bits of a timestamp on the compute queue (0 without timestamps).
    pub timestamp_valid_bits: u32,
    /// Pipelines can require full subgroups (see [`DeviceCapabilities::full_subgroups`]).
    pub full_subgroups: bool,
    /// The largest subgroup size the device may use (the default size without subgroup size
    /// control).
    pub max_subgroup_size: u32,
}

impl DeviceLimits {
    /// The largest buffer the engine can bind as storage: under both `maxStorageBufferRange`
    /// and `maxMemoryAllocationSize`.
    pub fn max_buffer_bytes(&self) -> u64 {
        self.max_storage_buffer_range.min(self.max_memory_allocation_size)
    }

    /// The device memory a run may plan for: the device's own, under any cap. None on a device
    /// that is the CPU (`device_is_host`) without a cap: its heap is the host's memory, which
    /// the host's own check covers.
    pub fn device_budget(&self, device_is_host: bool) -> Option<u64> {
        match (device_is_host, self.device_memory_cap) {
            (true, cap) => cap,
            (false, cap) => {
                Some(cap.map_or(self.device_memory_bytes, |c| c.min(self.device_memory_bytes)))
            }
        }
    }
}

/// A Vulkan instance and logical device with one compute queue, its allocator and pipeline
/// cache. Created by [`GpuContext::new`] and shared as `Arc<GpuContext>`.
pub struct GpuContext {
    _entry: ash::Entry,
    instance: ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Shared so the messenger's pointer stays valid until the instance is gone, and so a
    /// caller can read messages sent while the context is destroyed.
    validation_log: Arc<ValidationLog>,
    device: ash::Device,
    push_descriptor: ash::khr::push_descriptor::Device,
    queue: Mutex<vk::Queue>,
    queue_family: u32,
    allocator: Mutex<Option<Allocator>>,
    pipeline_cache: vk::PipelineCache,
    info: DeviceInfo,
    limits: DeviceLimits,
    validation_enabled: bool,
    staging: Mutex<StagingPool>,
    force_staging: bool,
    clock: HostClock,
    buffers: BufferUsage,
    replays: ReplayState,
    in_flight: usize,
}

/// Set to 1, forces the staging path (see [`ContextOptions`]).
pub const FORCE_STAGING_ENV: &str = "TAGSPLAT_FORCE_STAGING";

impl GpuContext {
    /// Creates a context on the device chosen by `options` (see [`choose_device`]).
    pub fn new(options: &ContextOptions) -> GpuResult<Arc<Self>> {
        let validation = options
            .validation
            .unwrap_or_else(|| std::env::var(VALIDATION_ENV).is_ok_and(|v| v == "1"));
        let wanted = options.device.clone().or_else(|| std::env::var(DEVICE_ENV).ok());
        let device_memory_cap = device_memory(options)?;
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::Loading(e.to_string()))?;
        let validation_log = Arc::<ValidationLog>::default();
        let instance = create_instance(&entry, validation, &validation_log)?;
        // From here on, a failure must destroy the instance: build the rest in a closure.
        let messenger = if validation {
            match create_messenger(&entry, &instance, &validation_log) {
                Ok(messenger) => Some(messenger),
                Err(e) => {
                    unsafe { destroy_instance(&instance, None) };
                    return Err(e);
                }
            }
        } else {
            None
        };
        let rest = (|| {
            let (handles, devices) = unsafe { enumerate(&instance)? };
            let chosen = choose_device(&devices, wanted.as_deref())?;
            Ok((devices[chosen].clone(), handles[chosen]))
        })();
        let rest =
            rest.and_then(|(info, device)| Ok((steps_in_flight(options, &info)?, info, device)));
        let (in_flight, info, physical_device) = match rest {
            Ok(v) => v,
            Err(e) => {
                unsafe { destroy_instance(&instance, messenger) };
                return Err(e);
            }
        };
        let built =
            unsafe { create_device(&instance, physical_device, info.capabilities.full_subgroups) };
        let (device, queue_family) = match built {
            Ok(v) => v,
            Err(e) => {
                unsafe { destroy_instance(&instance, messenger) };
                return Err(e);
            }
        };
        let limits = DeviceLimits {
            device_memory_cap,
            ..unsafe { read_limits(&instance, physical_device, queue_family, &info.capabilities) }
        };
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let push_descriptor = ash::khr::push_descriptor::Device::new(&instance, &device);
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| GpuError::OutOfMemory {
            name: "allocator".into(),
            bytes: 0,
            reason: e.to_string(),
        });
        let pipeline_cache = allocator.and_then(|allocator| {
            let cache = unsafe {
                device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default(), None)
            };
            cache.during("vkCreatePipelineCache").map(|cache| (allocator, cache))
        });
        let (allocator, pipeline_cache) = match pipeline_cache {
            Ok(v) => v,
            Err(e) => {
                // The allocator, if it was made, is dropped here: it holds no memory yet.
                unsafe {
                    device.destroy_device(None);
                    destroy_instance(&instance, messenger);
                }
                return Err(e);
            }
        };
        Ok(Arc::new(Self {
            _entry: entry,
            instance,
            messenger,
            validation_log,
            device,
            push_descriptor,
            queue: Mutex::new(queue),
            queue_family,
            allocator: Mutex::new(Some(allocator)),
            pipeline_cache,
            info,
            limits,
            validation_enabled: validation,
            staging: Mutex::default(),
            force_staging: options
                .force_staging
                .unwrap_or_else(|| std::env::var(FORCE_STAGING_ENV).is_ok_and(|v| v == "1")),
            clock: HostClock::default(),
            buffers: BufferUsage::default(),
            replays: ReplayState::default(),
            in_flight,
        }))
    }

    /// Every Vulkan device on this machine, with its capabilities (no context needed).
    pub fn list_devices() -> GpuResult<Vec<DeviceInfo>> {
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::Loading(e.to_string()))?;
        let instance = create_instance(&entry, false, &ValidationLog::default())?;
        let devices = unsafe { enumerate(&instance) };
        unsafe { instance.destroy_instance(None) };
        devices.map(|(_, devices)| devices)
    }

    /// The device in use.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The device limits the engine sizes its work by.
    pub fn limits(&self) -> &DeviceLimits {
        &self.limits
    }

    /// Whether the validation layer is on; [`Self::validation`] then counts its messages.
    pub fn validation_enabled(&self) -> bool {
        self.validation_enabled
    }

    /// Whether uploads and readbacks go through staging buffers even on host-visible memory.
    pub fn forces_staging(&self) -> bool {
        self.force_staging
    }

    /// Training steps on the queue at once ([`ContextOptions::steps_in_flight`]).
    pub fn steps_in_flight(&self) -> usize {
        self.in_flight
    }

    /// Recording, waiting and device time of every submission so far (see [`ClockReading`]).
    pub fn clock(&self) -> ClockReading {
        self.clock.read()
    }

    /// Device memory held by buffers now, and the most held at once so far.
    pub fn buffer_bytes(&self) -> BufferBytes {
        self.buffers.read()
    }

    /// The totals every buffer allocation and free updates.
    pub(crate) fn buffer_usage(&self) -> &BufferUsage {
        &self.buffers
    }

    /// The running totals each submission adds to.
    pub(crate) fn host_clock(&self) -> &HostClock {
        &self.clock
    }

    /// What recorded command buffers need to know: whether the resources they name still
    /// exist, and whether any is on the queue (see [`super::Replay`]).
    pub(crate) fn replays(&self) -> &ReplayState {
        &self.replays
    }

    /// Waits until no replayed batch is on the queue. Called before the host touches or frees
    /// GPU memory, which a batch still running may use.
    pub(crate) fn settle(&self) {
        if self.replays.in_flight() {
            // A failed wait leaves nothing to protect: the device is lost.
            let _ = unsafe { self.device.queue_wait_idle(*self.queue()) };
        }
    }

    /// The staging buffers (lock held from the host copy to the fence).
    pub(crate) fn staging(&self) -> MutexGuard<'_, StagingPool> {
        self.staging.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The validation messages so far (always empty unless [`Self::validation_enabled`]).
    pub fn validation(&self) -> &Arc<ValidationLog> {
        &self.validation_log
    }

    /// The logical device, for code that records its own Vulkan commands.
    pub fn device(&self) -> &ash::Device {
        &self.device
    }

    pub(crate) fn push_descriptor(&self) -> &ash::khr::push_descriptor::Device {
        &self.push_descriptor
    }

    /// The queue all work goes to (lock held while submitting). Public so tests can record
    /// their own command buffers, e.g. a graphics pipeline used as an oracle.
    pub fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        self.queue.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Index of the queue family of [`Self::queue`].
    pub fn queue_family(&self) -> u32 {
        self.queue_family
    }

    /// The memory allocator (`None` only while the context is dropped).
    pub fn allocator(&self) -> MutexGuard<'_, Option<Allocator>> {
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub(crate) fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache
    }
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_pipeline_cache(self.pipeline_cache, None);
            self.staging().free_all(self);
            // The allocator frees its memory blocks, so it must go before the device.
            self.allocator().take();
            self.device.destroy_device(None);
            destroy_instance(&self.instance, self.messenger.take());
        }
    }
}

fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    log: &ValidationLog,
) -> GpuResult<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"tagsplat")
        .engine_name(c"tagsplat")
        .api_version(vk::API_VERSION_1_2);
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    let sync_validation = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features =
        vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync_validation);
    let mut messenger_info = messenger_create_info(log);
    let mut create_info = vk::InstanceCreateInfo::default().application_info(&app);
    if validation {
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .during("vkEnumerateInstanceLayerProperties")?;
        if !available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER)) {
            return Err(GpuError::NoValidationLayer);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        extensions.push(ash::ext::validation_features::NAME.as_ptr());
        // Chained here too, so messages from instance creation itself are counted.
        create_info = create_info.push_next(&mut features).push_next(&mut messenger_info);
    }
    let create_info = create_info.enabled_layer_names(&layers).enabled_extension_names(&extensions);
    unsafe { entry.create_instance(&create_info, None) }.map_err(|result| match result {
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDevice,
        result => GpuError::Vulkan { call: "vkCreateInstance", result },
    })
}

fn messenger_create_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(validation::SEVERITIES)
        .message_type(validation::TYPES)
        .pfn_user_callback(Some(validation::on_message))
        .user_data(log as *const ValidationLog as *mut _)
}

/// Requested validation that cannot report its messages is an error: every "no validation
/// messages" check would otherwise pass without checking.
fn create_messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
    log: &ValidationLog,
) -> GpuResult<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let messenger =
        unsafe { loader.create_debug_utils_messenger(&messenger_create_info(log), None) }
            .map_err(GpuError::NoValidationMessenger)?;
    Ok((loader, messenger))
}

unsafe fn destroy_instance(
    instance: &ash::Instance,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
) {
    if let Some((loader, messenger)) = messenger {
        loader.destroy_debug_utils_messenger(messenger, None);
    }
    instance.destroy_instance(None);
}

/// The physical devices and, at the same indices, what the user sees of them.
unsafe fn enumerate(
    instance: &ash::Instance,
) -> GpuResult<(Vec<vk::PhysicalDevice>, Vec<DeviceInfo>)> {
    let physical_devices =
        instance.enumerate_physical_devices().during("vkEnumeratePhysicalDevices")?;
    let infos = physical_devices
        .iter()
        .copied()
        .enumerate()
        .map(|(index, pd)| {
            let properties = instance.get_physical_device_properties(pd);
            DeviceInfo {
                index,
                name: properties
                    .device_name_as_c_str()
                    .unwrap_or(c"?")
                    .to_string_lossy()
                    .into_owned(),
                kind: properties.device_type,
                driver: driver_description(instance, pd, properties.api_version),
                capabilities: DeviceCapabilities::query(instance, pd),
            }
        })
        .collect();
    Ok((physical_devices, infos))
}

/// The driver's name and version string (`llvmpipe: Mesa 22.3.6 (LLVM 15.0.6)`), from
/// VkPhysicalDeviceDriverProperties, core in Vulkan 1.2; "unknown" on an older device (which
/// the feature check refuses anyway).
unsafe fn driver_description(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    api_version: u32,
) -> String {
    if api_version < vk::API_VERSION_1_2 {
        return "unknown".into();
    }
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut properties2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    instance.get_physical_device_properties2(pd, &mut properties2);
    let text = |s: Result<&std::ffi::CStr, _>| s.unwrap_or(c"?").to_string_lossy().into_owned();
    format!("{}: {}", text(driver.driver_name_as_c_str()), text(driver.driver_info_as_c_str()))
}

/// The compute queue family: one that also writes timestamps if any does.
unsafe fn compute_queue_family(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
) -> u32 {
    let families = instance.get_physical_device_queue_family_properties(physical_device);
    let compute = |f: &vk::QueueFamilyProperties| f.queue_flags.contains(vk::QueueFlags::COMPUTE);
    let position = families
        .iter()
        .position(|f| compute(f) && f.timestamp_valid_bits > 0)
        .or_else(|| families.iter().position(compute));
    // `missing_features` already refused devices without a compute queue.
    position.unwrap_or(0) as u32
}

unsafe fn create_device(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
    full_subgroups: bool,
) -> GpuResult<(ash::Device, u32)> {
    let queue_family = compute_queue_family(instance, physical_device);
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let mut extensions: Vec<*const i8> = REQUIRED_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
    let core = vk::PhysicalDeviceFeatures::default().shader_int64(true);
    let mut vk12 = vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(true);
    let mut size_control =
        vk::PhysicalDeviceSubgroupSizeControlFeatures::default().compute_full_subgroups(true);
    let mut features = vk::PhysicalDeviceFeatures2::default().features(core).push_next(&mut vk12);
    if full_subgroups {
        extensions.push(ash::ext::subgroup_size_control::NAME.as_ptr());
        features = features.push_next(&mut size_control);
    }
    let create_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .push_next(&mut features);
    let device =
        instance.create_device(physical_device, &create_info, None).during("vkCreateDevice")?;
    Ok((device, queue_family))
}

/// The largest heap flagged device-local (any heap when none is).
unsafe fn largest_device_heap(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
) -> u64 {
    let memory = instance.get_physical_device_memory_properties(physical_device);
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    let local = heaps.iter().filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL));
    local.map(|h| h.size).max().or_else(|| heaps.iter().map(|h| h.size).max()).unwrap_or(0)
}

unsafe fn read_limits(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
    queue_family: u32,
    capabilities: &DeviceCapabilities,
) -> DeviceLimits {
    let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut properties2 = vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
    instance.get_physical_device_properties2(physical_device, &mut properties2);
    let limits = properties2.properties.limits;
    let family = instance.get_physical_device_queue_family_properties(physical_device)
        [queue_family as usize];
    DeviceLimits {
        max_storage_buffer_range: limits.max_storage_buffer_range as u64,
        max_memory_allocation_size: maintenance3.max_memory_allocation_size,
        device_memory_bytes: largest_device_heap(instance, physical_device),
        device_memory_cap: None,
        max_workgroup_count: limits.max_compute_work_group_count,
        max_workgroup_invocations: limits.max_compute_work_group_invocations,
        max_shared_memory_bytes: limits.max_compute_shared_memory_size,
        subgroup_size: capabilities.subgroup_size,
        timestamp_period_ns: (family.timestamp_valid_bits > 0)
            .then_some(limits.timestamp_period as f64),
        timestamp_valid_bits: family.timestamp_valid_bits,
        full_subgroups: capabilities.full_subgroups,
        max_subgroup_size: capabilities.max_subgroup_size,
    }
}

#[cfg(test)]
mod tests {
    use super::parse_bytes;

    #[test]
    fn sizes_parse_with_and_without_units() {
        assert_eq!(parse_bytes("1000000"), Some(1_000_000));
        assert_eq!(parse_bytes(" 6GiB "), Some(6 << 30));
        assert_eq!(parse_bytes("512 mib"), Some(512 << 20));
        assert_eq!(parse_bytes("1.5GiB"), Some(3 << 29));
        assert_eq!(parse_bytes("4KiB"), Some(4096));
        for bad in ["", "0", "GiB", "-1GiB", "6GB", "lots", "99999999999999999999GiB"] {
            assert_eq!(parse_bytes(bad), None, "{bad:?}");
        }
    }
}
