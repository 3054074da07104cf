//! `tagsplat_context`: a Vulkan device opened for the engine's work.

use crate::buffers::{optional_text, output_text, store};
use crate::handles::{create, get, release, Handle};
use crate::status::{call, engine, Error, Status};
use std::ffi::c_char;
use std::sync::Arc;
use tagsplat::{ContextOptions, GpuContext};

/// A Vulkan device and its queue. Datasets and jobs made from it keep it open: freeing the
/// context while a job runs is allowed, the device closes when the last of them ends.
pub struct Context {
    pub(crate) gpu: Arc<GpuContext>,
}

impl Handle for Context {
    const NAME: &'static str = "tagsplat_context";
}

/// Opens a context on `device` (an index or a case-insensitive part of a device name, as
/// `tagsplat devices` lists them; NULL: the TAGSPLAT_DEVICE environment variable, else the
/// engine's choice). `validation`: 1 turns the Khronos validation layer on, 0 off, -1 leaves it
/// to TAGSPLAT_VALIDATION=1. Stores the new handle in `*out` (NULL on failure).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_context_create(
    device: *const c_char,
    validation: i32,
    out: *mut *mut Context,
) -> Status {
    call("tagsplat_context_create", || unsafe {
        create("out", out, || {
            let validation = match validation {
                -1 => None,
                0 | 1 => Some(validation == 1),
                other => {
                    return Err(Error::bad_input(format!("validation is {other}: give -1, 0 or 1")))
                }
            };
            let device = optional_text("device", device)?.map(String::from);
            let options = ContextOptions { device, validation, ..Default::default() };
            let gpu = GpuContext::new(&options).map_err(|e| engine(&e))?;
            Ok(Context { gpu })
        })
    })
}

/// Frees `context` (NULL: nothing). Datasets and jobs made from it stay usable.
#[no_mangle]
pub extern "C" fn tagsplat_context_free(context: *mut Context) -> Status {
    call("tagsplat_context_free", || release("context", context))
}

/// The device's name, as a string of `*needed` bytes with its NUL (see the header's buffer
/// convention: `buf` NULL and `len` 0 only ask for the size).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_context_device_name(
    context: *const Context,
    buf: *mut c_char,
    len: usize,
    needed: *mut usize,
) -> Status {
    call("tagsplat_context_device_name", || unsafe {
        let context = get("context", context)?;
        output_text("buf", &context.gpu.info().name, (buf, len), needed)
    })
}

/// The number of messages (warnings and errors) the validation layer sent so far on
/// `context`; always 0 with validation off. Each message was also printed to stderr, prefixed
/// with "[vulkan validation]".
#[no_mangle]
pub unsafe extern "C" fn tagsplat_context_validation_messages(
    context: *const Context,
    count: *mut u64,
) -> Status {
    call("tagsplat_context_validation_messages", || unsafe {
        let log = get("context", context)?.gpu.validation().clone();
        store("count", count, u64::from(log.error_count()) + u64::from(log.warning_count()))
    })
}
