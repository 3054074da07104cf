//! Devices and the `Context` every GPU call takes.

use crate::errors::{bad_input, run};
use pyo3::prelude::*;
use std::sync::Arc;
use tagsplat::gpu::{choose_device, parse_bytes, DeviceInfo, DEVICE_ENV};
use tagsplat::{ContextOptions, GpuContext};

/// A Vulkan device as `tagsplat devices` lists it.
#[pyclass(frozen, module = "tagsplat", get_all)]
pub struct Device {
    /// Index in the device list (what `Context(device=...)` takes).
    index: usize,
    /// The driver's device name.
    name: String,
    /// "discrete GPU", "integrated GPU", "virtual GPU", "CPU" or "other".
    r#type: String,
    /// The driver's name and version.
    driver: String,
    /// The required features the device lacks (empty when it can run the engine).
    missing: Vec<String>,
    /// Whether a `Context()` without a device would choose it (TAGSPLAT_DEVICE, then the policy).
    chosen: bool,
}

#[pymethods]
impl Device {
    fn __repr__(&self) -> String {
        format!("Device({}: {} ({}, {}))", self.index, self.name, self.r#type, self.driver)
    }
}

impl Device {
    fn of(d: &DeviceInfo, chosen: Option<usize>) -> Self {
        Device {
            index: d.index,
            name: d.name.clone(),
            r#type: d.kind_name().to_string(),
            driver: d.driver.clone(),
            missing: d.capabilities.missing_features().iter().map(|s| s.to_string()).collect(),
            chosen: chosen == Some(d.index),
        }
    }
}

/// The Vulkan devices, each with what it lacks and whether it would be chosen.
#[pyfunction]
pub fn devices(py: Python<'_>) -> PyResult<Vec<Device>> {
    let list = run(py, GpuContext::list_devices)?;
    let wanted = std::env::var(DEVICE_ENV).ok();
    let chosen = choose_device(&list, wanted.as_deref()).ok();
    Ok(list.iter().map(|d| Device::of(d, chosen)).collect())
}

/// A Vulkan context on one device: what every GPU call (training, rendering) runs on. Safe to
/// share between threads; jobs on one context run one after another on its queue.
#[pyclass(frozen, module = "tagsplat")]
pub struct Context {
    /// The engine's context.
    pub inner: Arc<GpuContext>,
}

#[pymethods]
impl Context {
    /// Opens a context. `device`: an index or a piece of a device name (default: the
    /// TAGSPLAT_DEVICE variable, then discrete > integrated > virtual > CPU). `validation`: the
    /// Khronos validation layer on or off (default: TAGSPLAT_VALIDATION). `device_memory`: the
    /// device memory a run may plan for, bytes or a size such as "512MiB" (default:
    /// TAGSPLAT_DEVICE_MEMORY, then all of it).
    #[new]
    #[pyo3(signature = (device = None, validation = None, device_memory = None))]
    fn new(
        py: Python<'_>,
        device: Option<&Bound<'_, PyAny>>,
        validation: Option<bool>,
        device_memory: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let device = device.map(|d| d.str().map(|s| s.to_string())).transpose()?;
        let device_memory = device_memory.map(|m| memory_size(py, m)).transpose()?;
        let options = ContextOptions { device, validation, device_memory, ..Default::default() };
        Ok(Context { inner: run(py, || GpuContext::new(&options))? })
    }

    /// The device the context runs on.
    #[getter]
    fn device(&self) -> Device {
        let info = self.inner.info();
        Device::of(info, Some(info.index))
    }

    /// Whether the validation layer is on.
    #[getter]
    fn validation(&self) -> bool {
        self.inner.validation_enabled()
    }

    /// The validation layer's messages so far (always empty with validation off). A test that
    /// turns validation on fails when there is any.
    fn validation_messages(&self) -> Vec<String> {
        self.inner.validation().messages()
    }

    fn __repr__(&self) -> String {
        format!("Context({})", self.inner.info().name)
    }
}

/// Bytes from an int or a size such as "6GiB", with the command-line program's message.
fn memory_size(py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<u64> {
    let text = value.str()?.to_string();
    parse_bytes(&text).ok_or_else(|| {
        bad_input(
            py,
            format!("device_memory: '{text}': expected a size: 6GiB, 512MiB, 1000000 (bytes)"),
        )
    })
}
