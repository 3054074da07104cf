//! The tagsplat C ABI: `include/tagsplat.h`, generated from this crate by cbindgen (build.rs),
//! over the engine's embedding API (`tagsplat::embed`) and crate root. It converts arguments
//! and results and nothing more: every behaviour, check of a file or config, error message and
//! the job thread are the engine's.
//!
//! - `status`: status codes, the thread's last error, the call wrapper (panic guard).
//! - `handles`: the registry of live handles every call checks first.
//! - `buffers`: caller strings and arrays in, caller buffers out.
//! - One file per handle: `context`, `dataset`, `sequence`, `tracks` (with `tracks_out`, what
//!   its results copy out and write), `job`.
//!
//! The header's preamble (cbindgen.toml) states the contract every call keeps.

// Every exported function takes raw pointers from C; the contract for all of them is stated
// once, in the header's preamble, rather than in a `# Safety` section per function.
#![allow(clippy::missing_safety_doc)]

mod buffers;
mod context;
mod dataset;
mod handles;
mod job;
mod sequence;
mod status;
mod tracks;
mod tracks_out;

/// The library's version, "MAJOR.MINOR.PATCH" (static text): compare it with
/// TAGSPLAT_VERSION_STRING to find a header that does not match the library.
#[no_mangle]
pub extern "C" fn tagsplat_version() -> *const std::ffi::c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}
