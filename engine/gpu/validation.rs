//! The Khronos validation layer as a test oracle: a debug messenger that counts every warning
//! and error (synchronization validation included) and keeps their text.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

/// Environment variable that switches validation on ("1") when the caller does not decide.
pub const VALIDATION_ENV: &str = "TAGSPLAT_VALIDATION";
pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Messages the validation layer reported since the context was created.
#[derive(Default)]
pub struct ValidationLog {
    errors: AtomicU32,
    warnings: AtomicU32,
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// Number of error messages so far.
    pub fn error_count(&self) -> u32 {
        self.errors.load(Ordering::Relaxed)
    }

    /// Number of warning messages so far.
    pub fn warning_count(&self) -> u32 {
        self.warnings.load(Ordering::Relaxed)
    }

    /// Every error and warning text so far.
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn record(&self, severity: vk::DebugUtilsMessageSeverityFlagsEXT, text: String) {
        if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            self.errors.fetch_add(1, Ordering::Relaxed);
        } else {
            self.warnings.fetch_add(1, Ordering::Relaxed);
        }
        eprintln!("[vulkan validation] {text}");
        self.messages.lock().unwrap_or_else(|e| e.into_inner()).push(text);
    }
}

/// Severities the messenger listens to: everything that signals a problem.
pub(crate) const SEVERITIES: vk::DebugUtilsMessageSeverityFlagsEXT =
    vk::DebugUtilsMessageSeverityFlagsEXT::from_raw(
        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING.as_raw()
            | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR.as_raw(),
    );

pub(crate) const TYPES: vk::DebugUtilsMessageTypeFlagsEXT =
    vk::DebugUtilsMessageTypeFlagsEXT::from_raw(
        vk::DebugUtilsMessageTypeFlagsEXT::GENERAL.as_raw()
            | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION.as_raw()
            | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE.as_raw(),
    );

/// The messenger callback; `user_data` is the context's `ValidationLog`, which outlives it.
pub(crate) unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    let data = &*data;
    let text = if data.p_message.is_null() {
        String::from("(no message)")
    } else {
        CStr::from_ptr(data.p_message).to_string_lossy().into_owned()
    };
    (*(user_data as *const ValidationLog)).record(severity, text);
    vk::FALSE
}
