//! The caller's memory: strings and arrays in, arrays, text and out-parameters back. Each
//! check names the argument; nothing here can check that a pointer really points to as much
//! memory as its length says (the header's contract).

use crate::status::{Error, Status};
use std::ffi::{c_char, CStr};
use std::path::PathBuf;

/// The NUL-terminated UTF-8 string `arg`; NULL or invalid UTF-8 is bad input.
pub(crate) unsafe fn text<'a>(arg: &str, ptr: *const c_char) -> Result<&'a str, Error> {
    optional_text(arg, ptr)?.ok_or_else(|| Error::bad_input(format!("{arg} is NULL")))
}

/// [`text`], with NULL meaning "not given".
pub(crate) unsafe fn optional_text<'a>(
    arg: &str,
    ptr: *const c_char,
) -> Result<Option<&'a str>, Error> {
    if ptr.is_null() {
        return Ok(None);
    }
    // SAFETY: the caller passes a NUL-terminated string that outlives the call.
    let text = unsafe { CStr::from_ptr(ptr) }.to_str();
    text.map(Some).map_err(|e| Error::bad_input(format!("{arg} is not UTF-8: {e}")))
}

/// The path `arg` (a UTF-8 string; empty is bad input).
pub(crate) unsafe fn to_path(arg: &str, ptr: *const c_char) -> Result<PathBuf, Error> {
    match text(arg, ptr)? {
        "" => Err(Error::bad_input(format!("{arg} is an empty path"))),
        path => Ok(PathBuf::from(path)),
    }
}

/// [`to_path`], with NULL meaning "not given".
pub(crate) unsafe fn optional_path(
    arg: &str,
    ptr: *const c_char,
) -> Result<Option<PathBuf>, Error> {
    match ptr.is_null() {
        true => Ok(None),
        false => to_path(arg, ptr).map(Some),
    }
}

/// The `len` values at `ptr` (NULL is allowed when `len` is 0).
pub(crate) unsafe fn input<'a, T>(arg: &str, ptr: *const T, len: usize) -> Result<&'a [T], Error> {
    if len == 0 {
        return Ok(&[]);
    }
    check_pointer(arg, ptr, Status::BadInput)?;
    // SAFETY: the caller gives `len` readable values at `ptr`, aligned (checked) and not NULL.
    Ok(unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// `rows` of `N` finite numbers at `ptr`; the first row with a NaN or infinity is named.
pub(crate) unsafe fn finite_rows<'a, const N: usize>(
    arg: &str,
    ptr: *const f64,
    rows: usize,
) -> Result<&'a [[f64; N]], Error> {
    let len = rows
        .checked_mul(N)
        .ok_or_else(|| Error::bad_input(format!("{arg}: {rows} rows overflow")))?;
    let values = unsafe { input(arg, ptr, len) }?;
    let (rows, _) = values.as_chunks::<N>();
    match rows.iter().position(|row| !row.iter().all(|v| v.is_finite())) {
        Some(i) => Err(Error::bad_input(format!("{arg}[{i}] is {:?}: not finite", rows[i]))),
        None => Ok(rows),
    }
}

/// Copies `data` to the caller's buffer of `len` values at `ptr`: too small (or NULL) is
/// [`Status::BufferTooSmall`], naming the size needed.
pub(crate) unsafe fn output<T: Copy>(
    arg: &str,
    data: &[T],
    ptr: *mut T,
    len: usize,
) -> Result<(), Error> {
    if len < data.len() {
        let message = format!("{arg} holds {len} values, {} are needed", data.len());
        return Err(Error::new(Status::BufferTooSmall, message));
    }
    if data.is_empty() {
        return Ok(());
    }
    check_pointer(arg, ptr, Status::BufferTooSmall)?;
    // SAFETY: `ptr` is non-NULL, aligned, and the caller gives `len` ≥ data.len() values there.
    unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), ptr, data.len()) };
    Ok(())
}

/// Copies `text` and a NUL into `buf` (`len` bytes) and stores its size with the NUL in
/// `needed` (when not NULL). `buf` NULL with `len` 0 only asks for the size; any other buffer
/// too small is [`Status::BufferTooSmall`].
pub(crate) unsafe fn output_text(
    arg: &str,
    text: &str,
    (buf, len): (*mut c_char, usize),
    needed: *mut usize,
) -> Result<(), Error> {
    let size = text.len() + 1;
    if !needed.is_null() {
        // SAFETY: a non-NULL `needed` points to a writable size_t.
        unsafe { needed.write(size) };
    }
    if buf.is_null() && len == 0 {
        return Ok(());
    }
    let with_nul: Vec<u8> = text.bytes().chain([0]).collect();
    unsafe { output(arg, &with_nul, buf.cast::<u8>(), len) }
}

/// Stores `value` through the out-parameter `arg`.
pub(crate) unsafe fn store<T>(arg: &str, ptr: *mut T, value: T) -> Result<(), Error> {
    check_pointer(arg, ptr, Status::BadInput)?;
    // SAFETY: `ptr` is non-NULL and aligned; the caller gives a writable T there.
    unsafe { ptr.write(value) };
    Ok(())
}

/// NULL or misaligned `ptr` fails with `status`, naming `arg`.
fn check_pointer<T>(arg: &str, ptr: *const T, status: Status) -> Result<(), Error> {
    if ptr.is_null() {
        return Err(Error::new(status, format!("{arg} is NULL")));
    }
    if !ptr.is_aligned() {
        let align = std::mem::align_of::<T>();
        return Err(Error::new(status, format!("{arg} is not aligned to {align} bytes")));
    }
    Ok(())
}
