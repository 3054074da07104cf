//! The registry of live handles. A handle is a number the registry hands out, never an address,
//! and never handed out twice: a freed, unknown or wrong-kind handle is found in the registry
//! (or not) before anything is touched, and answered with [`Status::InvalidHandle`]. The
//! registry owns every object through an `Arc`; a call clones it and lets the lock go, so a
//! handle freed while another thread's call uses it lives until that call returns.

use crate::buffers::store;
use crate::status::{Error, Status};
use std::any::Any;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard};

/// An object C holds by handle; `NAME` is its C type, for messages.
pub(crate) trait Handle: Any + Send + Sync {
    const NAME: &'static str;
}

struct Registry {
    /// The next handle value; values step by 16 so they look like aligned pointers.
    next: usize,
    live: BTreeMap<usize, Entry>,
}

struct Entry {
    kind: &'static str,
    object: Arc<dyn Any + Send + Sync>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry { next: 0x1000, live: BTreeMap::new() });

/// The registry; every change to it is one insert or remove, so a poisoned lock is whole.
fn registry() -> MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Stores NULL through the out-handle `arg` (so a failed create leaves NULL), runs `make`, and
/// on success registers its object and stores the new handle.
pub(crate) unsafe fn create<T: Handle>(
    arg: &str,
    out: *mut *mut T,
    make: impl FnOnce() -> Result<T, Error>,
) -> Result<(), Error> {
    unsafe { store(arg, out, std::ptr::null_mut()) }?;
    let handle = register(make()?);
    unsafe { store(arg, out, handle) }
}

fn register<T: Handle>(object: T) -> *mut T {
    let mut registry = registry();
    let handle = registry.next;
    registry.next += 16;
    registry.live.insert(handle, Entry { kind: T::NAME, object: Arc::new(object) });
    std::ptr::without_provenance_mut(handle)
}

/// The object behind the handle `arg`.
pub(crate) fn get<T: Handle>(arg: &str, handle: *const T) -> Result<Arc<T>, Error> {
    let registry = registry();
    let entry = registry.live.get(&handle.addr()).ok_or_else(|| unknown::<T>(arg, handle))?;
    let object = Arc::clone(&entry.object);
    object.downcast::<T>().map_err(|_| wrong_kind::<T>(arg, entry.kind))
}

/// Forgets the handle `arg` (NULL: nothing) and drops its object once no call uses it. The drop
/// happens outside the registry's lock: a job's drop waits for its thread, whose callback may
/// call into the library.
pub(crate) fn release<T: Handle>(arg: &str, handle: *mut T) -> Result<(), Error> {
    if handle.is_null() {
        return Ok(());
    }
    let object = {
        let mut registry = registry();
        let key = handle.addr();
        let entry = registry.live.get(&key).ok_or_else(|| unknown::<T>(arg, handle))?;
        if entry.kind != T::NAME {
            return Err(wrong_kind::<T>(arg, entry.kind));
        }
        registry.live.remove(&key)
    };
    drop(object);
    Ok(())
}

fn unknown<T: Handle>(arg: &str, handle: *const T) -> Error {
    let message = match handle.is_null() {
        true => format!("{arg} is NULL"),
        false => {
            format!("{arg} ({handle:p}) is not a live {}: freed already, or never created", T::NAME)
        }
    };
    Error::new(Status::InvalidHandle, message)
}

fn wrong_kind<T: Handle>(arg: &str, kind: &str) -> Error {
    Error::new(Status::InvalidHandle, format!("{arg} is a {kind}, not a {}", T::NAME))
}
