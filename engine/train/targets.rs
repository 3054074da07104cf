//! The training views' targets on the device, all of them or, when the device's memory cannot
//! hold them all (`memory::targets_on_device`), the ones used last.
//!
//! Streamed, the store shares the caller's host copy of every target and holds a few device
//! buffers sized for the largest view; a step on a view whose target is not on the device
//! first uploads it into the buffer of the view used last: a pass visits every view once, so
//! that view is the one needed furthest ahead. A step reads the same bytes either way, so
//! streaming changes a run's time, never its result. An upload waits for the steps on the
//! queue (the buffer it overwrites may be one of theirs), and a step recorded against a buffer
//! now holding another view must be recorded again: [`Targets::evicts`] names that view
//! before the upload.

use super::views::ViewTarget;
use crate::gpu::{GpuBuffer, GpuContext, GpuResult};
use std::sync::Arc;

/// A device buffer and the view whose target it holds.
struct Held {
    buffer: GpuBuffer<[f32; 4]>,
    view: Option<usize>,
    /// When the view's target was last made resident ([`Targets::make_resident`]).
    used: u64,
}

/// The training views' targets (see the module docs).
pub struct Targets {
    held: Vec<Held>,
    /// Per view, its buffer in `held` while its target is on the device.
    slot_of: Vec<Option<usize>>,
    /// Every view's target, shared with the caller's views, kept only when streamed.
    host: Vec<Arc<Vec<[f32; 4]>>>,
    clock: u64,
    uploads: u64,
}

impl Targets {
    /// Uploads `views`' targets: each into its own buffer when `on_device` covers them all,
    /// else into `on_device` (at least one) buffers sized for the largest, the first views
    /// first, the rest kept on the host.
    pub fn new(ctx: &Arc<GpuContext>, views: &[ViewTarget], on_device: usize) -> GpuResult<Self> {
        let streamed = on_device < views.len();
        let slots = if streamed { on_device.max(1) } else { views.len() };
        let largest = views.iter().map(|v| v.target.len()).max().unwrap_or(0);
        let mut held = Vec::with_capacity(slots);
        for (slot, view) in views.iter().enumerate().take(slots) {
            let name = if streamed { format!("target slot {slot}") } else { view.name.clone() };
            let len = if streamed { largest } else { view.target.len() };
            let mut buffer = GpuBuffer::new(ctx, &format!("target {name}"), len)?;
            buffer.write(&view.target)?;
            held.push(Held { buffer, view: Some(slot), used: 0 });
        }
        let host = if streamed { views.iter().map(|v| v.target.clone()).collect() } else { vec![] };
        let slot_of = (0..views.len()).map(|v| (v < slots).then_some(v)).collect();
        Ok(Self { held, slot_of, host, clock: 0, uploads: 0 })
    }

    /// Views whose targets are on the device at once: all of them unless streamed.
    pub fn on_device(&self) -> usize {
        self.held.len()
    }

    /// Targets uploaded since [`Self::new`] for a step on a view not on the device.
    pub fn uploads(&self) -> u64 {
        self.uploads
    }

    /// The view whose target [`Self::make_resident`]`(view)` would take off the device, if any:
    /// steps recorded on it must be finished and recorded again.
    pub fn evicts(&self, view: usize) -> Option<usize> {
        if self.slot_of[view].is_some() {
            return None;
        }
        self.held[self.victim()].view
    }

    /// Makes `view`'s target the content of a device buffer, uploading it into the buffer of
    /// the view used last when it is not there. The upload waits for the queue to be idle.
    pub fn make_resident(&mut self, view: usize) -> GpuResult<()> {
        self.clock += 1;
        if let Some(slot) = self.slot_of[view] {
            self.held[slot].used = self.clock;
            return Ok(());
        }
        let slot = self.victim();
        let held = &mut self.held[slot];
        held.buffer.write(&self.host[view])?;
        if let Some(old) = held.view.replace(view) {
            self.slot_of[old] = None;
        }
        held.used = self.clock;
        self.slot_of[view] = Some(slot);
        self.uploads += 1;
        Ok(())
    }

    /// `view`'s target on the device: its first width × height elements. Panics when it is not
    /// there (a step on a streamed view comes after [`Self::make_resident`]).
    pub fn get(&self, view: usize) -> &GpuBuffer<[f32; 4]> {
        let slot = self.slot_of[view].expect("a step's target is made resident before recording");
        &self.held[slot].buffer
    }

    /// The buffer to upload into: the one used last (the last of equals). A training loop
    /// visits every view once per pass in a fresh order (`schedule::ViewCycle`), so the view
    /// just used is not needed again before the next pass, while one not yet used in this pass
    /// is; least recently used would evict exactly the views still to come.
    fn victim(&self) -> usize {
        (0..self.held.len()).max_by_key(|&slot| self.held[slot].used).unwrap_or(0)
    }
}
