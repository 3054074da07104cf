//! Bytes of device memory held in buffers, now and at most: what a run reports and what the
//! capture memory estimate (`train::memory`) is checked against.

use std::sync::atomic::{AtomicU64, Ordering};

/// Running totals of the bytes bound to live buffers (their allocations' sizes).
#[derive(Debug, Default)]
pub(crate) struct BufferUsage {
    now: AtomicU64,
    peak: AtomicU64,
}

/// A reading of the context's buffer totals (`GpuContext::buffer_bytes`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct BufferBytes {
    /// Bytes in live buffers now.
    pub now: u64,
    /// The most bytes live buffers have held at once since the context was made.
    pub peak: u64,
}

impl BufferUsage {
    pub(crate) fn add(&self, bytes: u64) {
        let now = self.now.fetch_add(bytes, Ordering::Relaxed) + bytes;
        self.peak.fetch_max(now, Ordering::Relaxed);
    }

    pub(crate) fn remove(&self, bytes: u64) {
        self.now.fetch_sub(bytes, Ordering::Relaxed);
    }

    pub(crate) fn read(&self) -> BufferBytes {
        BufferBytes {
            now: self.now.load(Ordering::Relaxed),
            peak: self.peak.load(Ordering::Relaxed),
        }
    }
}
