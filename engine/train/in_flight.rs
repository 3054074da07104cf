//! Training steps recorded once and replayed, several on the queue at a time.
//!
//! A step is two recorded command buffers submitted together: the view's (forward, loss, the
//! stage's terms, backward; recorded once per view and reused until a buffer it names is
//! replaced, its frame changes or, streamed (`train::targets`), its target leaves the device)
//! and the slot's tail (Adam with the parameters the host wrote into the slot, then the
//! intersection count copied out into the slot). What changes from one iteration to the next,
//! the learning rates and the iteration's bias corrections, is written into the slot before
//! the submit; nothing is recorded.
//!
//! With `depth` slots, the host prepares step `i` while steps `i - depth + 1 .. i` may still
//! run, and learns a step's intersection count (which sizes the splatter) when its slot comes
//! round again. Steps finish in submission order, so the result does not depend on timing: a
//! given depth (`GpuContext::steps_in_flight`) gives the same bytes every run. Depth 1 is the
//! plain loop (each step finished before the next is prepared); a larger depth differs from it
//! only where a step's intersections outgrew the buffers (its successors in flight were sized
//! without knowing).

use super::{TrainError, Trainer};
use crate::gpu::MAX_STEPS_IN_FLIGHT;
use crate::gpu::{Batch, GpuContext, GpuError, HostRing, PassTimes, Recorder, Replay};
use crate::optim::AdamParams;
use crate::splat::{FrameParams, RenderSettings};
use std::collections::VecDeque;
use std::sync::Arc;

/// What a replayed step records, and how the host sets a step's parameters.
pub(crate) trait StepTerms {
    /// Records a step's terms on training view `view`: the splatting loss (weights per rgba
    /// channel) and whatever the stage adds, every gradient added to the trainer's. The
    /// splatting loss alone by default.
    fn record_step<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        view: usize,
        frame: &FrameParams,
        splat_weights: [f32; 4],
    ) -> Result<(), TrainError> {
        trainer.record_splat(rec, view, frame, splat_weights, None)
    }

    /// Records the end of a step: what moves the parameters, with the parameters of ring slot
    /// `counts.1`, then the copy of the forward's intersection count into that slot of
    /// `counts`. The Gaussians' Adam by default ([`Trainer::record_step_tail`]).
    fn record_tail<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        counts: (&'a HostRing<u32>, usize),
    ) -> Result<(), TrainError> {
        trainer.record_step_tail(rec, frame, counts)
    }

    /// Writes a step's parameters into ring slot `slot` for its tail; the Gaussians' Adam by
    /// default.
    fn set_step(&self, trainer: &Trainer, slot: usize, adam: &AdamParams) {
        trainer.set_adam_step(slot, adam);
    }
}

/// What a finished step reports.
pub(crate) struct Finished {
    /// GPU time of each pass of the step.
    pub times: PassTimes,
    /// Whether every intersection fit the splatter's buffers ([`Trainer::finish_step`]).
    pub complete: bool,
}

/// A view's recorded step and the frame it was recorded for.
struct ViewStep {
    frame: FrameParams,
    replay: Replay,
}

/// One step on the queue: its batch, view and frame.
struct Slot {
    batch: Batch,
    step: Option<(usize, FrameParams)>,
    /// The tail recorded for this slot, and the Gaussian count its copy reads at.
    tail: Option<(usize, Replay)>,
}

/// The ring of steps in flight over one trainer (see the module docs).
pub(crate) struct StepRing {
    ctx: Arc<GpuContext>,
    slots: Vec<Slot>,
    counts: HostRing<u32>,
    views: Vec<Option<ViewStep>>,
    /// Slots on the queue, oldest first.
    queued: VecDeque<usize>,
    next: usize,
}

impl StepRing {
    /// A ring of `depth` slots (at least 1) for `trainer`'s steps.
    pub fn new(trainer: &mut Trainer, depth: usize) -> Result<Self, TrainError> {
        let (ctx, depth) = (trainer.context().clone(), depth.clamp(1, MAX_STEPS_IN_FLIGHT));
        trainer.reserve_step_slots(depth)?;
        let slots = (0..depth)
            .map(|_| Ok(Slot { batch: Batch::new(&ctx)?, step: None, tail: None }))
            .collect::<Result<_, GpuError>>()?;
        Ok(Self {
            counts: HostRing::new(&ctx, "step intersection counts", depth)?,
            ctx,
            slots,
            views: (0..trainer.views()).map(|_| None).collect(),
            queued: VecDeque::new(),
            next: 0,
        })
    }

    /// Submits one step on training view `view` (`terms` with `weights`, then their tail with
    /// `adam`) and returns the steps that had to finish first to make room, oldest first.
    pub fn step(
        &mut self,
        trainer: &mut Trainer,
        (terms, weights): (&dyn StepTerms, [f32; 4]),
        view: usize,
        settings: &RenderSettings,
        adam: &AdamParams,
    ) -> Result<Vec<Finished>, TrainError> {
        let slot = self.next;
        let mut finished =
            self.finish_until(trainer, |ring| !ring.slots[slot].batch.is_pending())?;
        if let Some(evicted) = trainer.target_evicts(view) {
            // Its recorded step names the buffer the upload overwrites.
            finished.extend(self.finish_until(trainer, |ring| !ring.pending(evicted))?);
            self.views[evicted] = None;
        }
        trainer.make_target_resident(view)?;
        let frame = trainer.prepare_step(view, settings)?;
        finished.extend(self.finish_until(trainer, |ring| !ring.pending(view))?);
        let stale = |v: &ViewStep| !v.replay.is_current() || !same_frame(&v.frame, &frame);
        if self.views[view].as_ref().is_none_or(stale) {
            self.views[view] = None;
            let mut rec = Recorder::reusable(&self.ctx)?;
            terms.record_step(trainer, &mut rec, view, &frame, weights)?;
            self.views[view] = Some(ViewStep { frame, replay: rec.finish()? });
        }
        let gaussians = frame.gaussians();
        let tail = &mut self.slots[slot].tail;
        if tail.as_ref().is_none_or(|(n, t)| *n != gaussians || !t.is_current()) {
            *tail = None;
            let mut rec = Recorder::reusable(&self.ctx)?;
            terms.record_tail(trainer, &mut rec, &frame, (&self.counts, slot))?;
            *tail = Some((gaussians, rec.finish()?));
        }
        terms.set_step(trainer, slot, adam);
        let s = &mut self.slots[slot];
        let view_replay = &self.views[view].as_ref().expect("recorded above").replay;
        s.batch.submit(&[view_replay, &s.tail.as_ref().expect("recorded above").1])?;
        s.step = Some((view, frame));
        self.queued.push_back(slot);
        self.next = (slot + 1) % self.slots.len();
        Ok(finished)
    }

    /// Finishes every step on the queue, oldest first: after it, the host may read and change
    /// the trainer's buffers.
    pub fn drain(&mut self, trainer: &mut Trainer) -> Result<Vec<Finished>, TrainError> {
        self.finish_until(trainer, |ring| ring.queued.is_empty())
    }

    /// Whether a step on `view` is on the queue.
    fn pending(&self, view: usize) -> bool {
        self.views[view].as_ref().is_some_and(|v| v.replay.is_pending())
    }

    /// Finishes the oldest step on the queue until `done` holds.
    fn finish_until(
        &mut self,
        trainer: &mut Trainer,
        done: impl Fn(&Self) -> bool,
    ) -> Result<Vec<Finished>, TrainError> {
        let mut finished = Vec::new();
        while !done(self) {
            let slot = self.queued.pop_front().expect("a pending slot is queued");
            let s = &mut self.slots[slot];
            let (view, frame) = s.step.take().expect("a queued slot holds its step");
            let view_replay = &self.views[view].as_ref().expect("a queued view is recorded").replay;
            let times = s.batch.wait(&[view_replay, &s.tail.as_ref().expect("recorded").1])?;
            let complete = trainer.finish_counted(frame, self.counts.read(slot))?;
            finished.push(Finished { times, complete });
        }
        Ok(finished)
    }
}

/// Whether two frames record the same commands (camera, image, settings, scene size).
fn same_frame(a: &FrameParams, b: &FrameParams) -> bool {
    bytemuck::bytes_of(a) == bytemuck::bytes_of(b)
}
