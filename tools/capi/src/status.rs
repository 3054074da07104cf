//! Status codes, the thread's last error message, and `call`: the wrapper every exported
//! function runs its body in, so that no panic unwinds into C and every failure leaves a
//! message.

use std::cell::RefCell;
use std::ffi::c_char;
use tagsplat::embed::{guard, ErrorKind, Failure};

/// What a call did. Failures leave a message for tagsplat_last_error().
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Success.
    Ok = 0,
    /// An argument, path, config value or array is wrong (NULL, NaN, out of range, missing).
    BadInput = 1,
    /// A file exists but cannot be read as what it should be.
    FileFormat = 2,
    /// The Vulkan device: none suitable, out of memory, lost.
    Device = 3,
    /// The job was cancelled (by tagsplat_job_cancel or its progress callback).
    Cancelled = 4,
    /// Reading or writing a file failed for a reason other than its content.
    Io = 5,
    /// A handle that is NULL where one is needed, freed, never created, or of another kind.
    InvalidHandle = 6,
    /// A caller's buffer is NULL or smaller than the info call said it must be.
    BufferTooSmall = 7,
    /// The job has not finished yet.
    NotFinished = 8,
    /// A bug in tagsplat (a caught panic); the message says where.
    Internal = 9,
}

/// A failed call: its status and message.
pub(crate) struct Error {
    pub status: Status,
    pub message: String,
}

impl Error {
    pub fn new(status: Status, message: impl Into<String>) -> Self {
        Self { status, message: message.into() }
    }

    pub fn bad_input(message: impl Into<String>) -> Self {
        Self::from(Failure::bad_input(message))
    }
}

impl From<Failure> for Error {
    fn from(failure: Failure) -> Self {
        let status = match failure.kind {
            ErrorKind::BadInput => Status::BadInput,
            ErrorKind::FileFormat => Status::FileFormat,
            ErrorKind::Device => Status::Device,
            ErrorKind::Cancelled => Status::Cancelled,
            ErrorKind::Io => Status::Io,
            ErrorKind::Internal => Status::Internal,
        };
        Self { status, message: failure.message }
    }
}

/// Any engine error, classified by the engine.
pub(crate) fn engine(error: &(dyn std::error::Error + 'static)) -> Error {
    Error::from(Failure::of(error))
}

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Runs the body of the exported function `name` behind the engine's panic guard. Its failure's
/// message, prefixed with `name`, becomes this thread's last error; success clears it.
pub(crate) fn call(name: &str, body: impl FnOnce() -> Result<(), Error>) -> Status {
    let outcome = guard(|| Ok(body())).unwrap_or_else(|panic| Err(Error::from(panic)));
    let (status, message) = match outcome {
        Ok(()) => (Status::Ok, String::new()),
        Err(e) => (e.status, format!("{name}: {}", e.message)),
    };
    LAST_ERROR.with(|last| *last.borrow_mut() = message);
    status
}

/// Copies this thread's last error message (empty after a call that succeeded) into `buf`,
/// truncated to `len - 1` bytes and NUL-terminated, as snprintf does; `buf` may be NULL when
/// `len` is 0. Returns the message's full length in bytes, without the NUL.
#[no_mangle]
pub unsafe extern "C" fn tagsplat_last_error(buf: *mut c_char, len: usize) -> usize {
    // Copying a String into caller memory cannot panic; the guard is not needed here.
    LAST_ERROR.with(|last| {
        let message = last.borrow();
        if !buf.is_null() && len > 0 {
            let kept = floor_char_boundary(&message, len - 1);
            // SAFETY: the caller gives `len` writable bytes at `buf`; kept < len.
            unsafe {
                std::ptr::copy_nonoverlapping(message.as_ptr(), buf.cast::<u8>(), kept);
                *buf.add(kept) = 0;
            }
        }
        message.len()
    })
}

/// The largest index ≤ `at` on a character boundary of `text`, so a truncated message stays
/// UTF-8.
fn floor_char_boundary(text: &str, at: usize) -> usize {
    (0..=at.min(text.len())).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0)
}

/// The status's name ("TAGSPLAT_STATUS_BAD_INPUT"), or "unknown status" for a value that is
/// none. The text is static.
#[no_mangle]
pub extern "C" fn tagsplat_status_name(status: i32) -> *const c_char {
    let name: &'static std::ffi::CStr = match status {
        0 => c"TAGSPLAT_STATUS_OK",
        1 => c"TAGSPLAT_STATUS_BAD_INPUT",
        2 => c"TAGSPLAT_STATUS_FILE_FORMAT",
        3 => c"TAGSPLAT_STATUS_DEVICE",
        4 => c"TAGSPLAT_STATUS_CANCELLED",
        5 => c"TAGSPLAT_STATUS_IO",
        6 => c"TAGSPLAT_STATUS_INVALID_HANDLE",
        7 => c"TAGSPLAT_STATUS_BUFFER_TOO_SMALL",
        8 => c"TAGSPLAT_STATUS_NOT_FINISHED",
        9 => c"TAGSPLAT_STATUS_INTERNAL",
        _ => c"unknown status",
    };
    name.as_ptr()
}
