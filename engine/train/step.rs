//! One training step on the GPU, and the state it carries between steps: forward, loss,
//! backward and Adam in one submission. After it, one counter is read (the intersections, which
//! size the next step's buffers); nothing else unless the caller asks.

use super::memory::targets_on_device;
use super::targets::Targets;
use super::views::ViewTarget;
use super::TrainError;
use crate::camera::Camera;
use crate::gpu::{FixedSums, GpuBuffer, GpuContext, HostRing, Recorder};
use crate::loss::colour_map::{CameraColour, ColourMap, MappedRender};
use crate::loss::{ImageLoss, LossTarget, LossTerms, ScoredRender};
use crate::optim::{Adam, AdamParams};
use crate::splat::{FrameParams, GaussianBuffers, GaussianScene, RenderSettings, Splatter};
use std::sync::Arc;

/// Everything on the GPU that has one row per Gaussian.
struct GaussianState {
    params: GaussianBuffers,
    grads: GaussianBuffers,
    /// The parameters at the last [`Trainer::checkpoint`].
    last_good: GaussianBuffers,
    densify_stats: GpuBuffer<[f32; 2]>,
}

impl GaussianState {
    fn new(ctx: &Arc<GpuContext>, scene: &GaussianScene) -> Result<Self, TrainError> {
        let params = GaussianBuffers::from_scene(ctx, scene)?;
        let state = Self {
            grads: GaussianBuffers::shaped_like(ctx, &params)?,
            last_good: GaussianBuffers::from_scene(ctx, scene)?,
            densify_stats: GpuBuffer::new(ctx, "densify statistics", scene.len())?,
            params,
        };
        let mut rec = Recorder::new(ctx)?;
        rec.fill_buffer(&state.densify_stats, 0);
        rec.submit_and_wait()?;
        Ok(state)
    }
}

/// A set of Gaussians being optimised against a fixed set of training views, on the GPU: the
/// parameters, their gradients, Adam's moments and the views' targets (see the module docs).
pub struct Trainer {
    ctx: Arc<GpuContext>,
    splatter: Splatter,
    /// Scores the Gaussian render, and with [`Trainer::with_second_render`] another render of
    /// the same view in the same run.
    loss: ImageLoss,
    cameras: Vec<Camera>,
    targets: Targets,
    grad_rgba: GpuBuffer<[f32; 4]>,
    /// Zero: no depth loss.
    grad_depth: GpuBuffer<f32>,
    /// The loss terms summed since the last [`Trainer::take_terms`].
    terms: FixedSums,
    state: GaussianState,
    /// Its moments follow the Gaussian set through [`Trainer::replace`].
    adam: Adam,
    /// The cameras' colour maps the renders are scored through ([`Trainer::with_camera_colour`]).
    colour: Option<Colour>,
}

/// Each training view's colour map, and whether the steps sum the moments of its next fit.
struct Colour {
    maps: CameraColour,
    background: [f32; 3],
    learn: bool,
}

impl Trainer {
    /// Uploads `scene` and the views' targets, all of them when the device's memory holds them
    /// beside the working buffers, else as many as fit, the rest streamed (`train::targets`);
    /// the optimizer starts at zero moments.
    pub fn new(
        ctx: &Arc<GpuContext>,
        scene: &GaussianScene,
        views: &[ViewTarget],
    ) -> Result<Self, TrainError> {
        let sizes: Vec<(u32, u32)> =
            views.iter().map(|v| (v.camera.width, v.camera.height)).collect();
        let budget = ctx.limits().device_budget(ctx.info().shares_host_memory());
        Self::with_targets_on_device(ctx, scene, views, targets_on_device(budget, &sizes))
    }

    /// [`Self::new`] with `on_device` of the views' targets on the device at once: all when it
    /// covers them, else the rest streamed (at least one on the device).
    pub fn with_targets_on_device(
        ctx: &Arc<GpuContext>,
        scene: &GaussianScene,
        views: &[ViewTarget],
        on_device: usize,
    ) -> Result<Self, TrainError> {
        scene.check().map_err(crate::splat::SplatError::from)?;
        let max_pixels = views.iter().map(|v| v.target.len()).max().unwrap_or(0);
        let mut loss = ImageLoss::new(ctx, 1)?;
        loss.reserve(max_pixels)?;
        let state = GaussianState::new(ctx, scene)?;
        let mut trainer = Self {
            ctx: ctx.clone(),
            splatter: Splatter::new(ctx)?,
            loss,
            cameras: views.iter().map(|v| v.camera).collect(),
            targets: Targets::new(ctx, views, on_device)?,
            grad_rgba: GpuBuffer::new(ctx, "loss gradient", max_pixels)?,
            grad_depth: GpuBuffer::new(ctx, "depth gradient (unused)", max_pixels)?,
            terms: LossTerms::sums(ctx, "loss terms")?,
            adam: Adam::new(ctx, &state.params)?,
            state,
            colour: None,
        };
        let mut rec = Recorder::new(ctx)?;
        rec.fill_buffer(&trainer.grad_depth, 0);
        trainer.terms.clear(&mut rec);
        rec.submit_and_wait()?;
        trainer.size_for_views()?;
        Ok(trainer)
    }

    /// Builds the loss that scores the Gaussian render beside another render of the same view
    /// in one run ([`Self::record_splat`] with another render).
    pub fn with_second_render(mut self) -> Result<Self, TrainError> {
        // The one-render loss goes before the new one's scratch is made.
        self.loss = ImageLoss::new(&self.ctx, 2)?;
        self.loss.reserve(self.grad_rgba.len())?;
        Ok(self)
    }

    /// Scores every render as its view's camera sees it: through `maps[view]`
    /// ([`crate::loss::colour_map`]) over `background` (the render settings'). With `learn`,
    /// each step also sums the moments of its camera's next map, which
    /// [`Self::refit_camera_colour`] fits. Needs one map per view.
    pub fn with_camera_colour(
        mut self,
        maps: &[ColourMap],
        background: [f32; 3],
        learn: bool,
    ) -> Result<Self, TrainError> {
        if maps.len() != self.views() {
            return Err(TrainError::ColourMaps { maps: maps.len(), views: self.views() });
        }
        let maps = CameraColour::new(&self.ctx, maps, 2, self.grad_rgba.len())?;
        self.colour = Some(Colour { maps, background, learn });
        Ok(self)
    }

    /// With no step in flight, after a run of steps: each camera's map refitted from the
    /// moments its renders summed, pulled toward the identity by `ridge`, or with `None` the
    /// moments dropped and the maps kept. Nothing without learned camera colour.
    pub fn refit_camera_colour(&mut self, ridge: Option<f64>) -> Result<(), TrainError> {
        match (self.colour.as_mut(), ridge) {
            (Some(c), Some(ridge)) if c.learn => drop(c.maps.refit(ridge)?),
            (Some(c), None) if c.learn => drop(c.maps.take_moments()?),
            _ => {}
        }
        Ok(())
    }

    /// Each view's colour map (None without camera colour).
    pub fn camera_colour(&self) -> Result<Option<Vec<ColourMap>>, TrainError> {
        Ok(self.colour.as_ref().map(|c| c.maps.maps()).transpose()?)
    }

    /// Counts every view's intersections once, so the splatter's buffers fit them all.
    fn size_for_views(&mut self) -> Result<(), TrainError> {
        let settings = RenderSettings::default();
        for camera in &self.cameras {
            self.splatter.reserve_for(&self.state.params, camera, &settings)?;
        }
        Ok(())
    }

    /// The number of training views.
    pub fn views(&self) -> usize {
        self.cameras.len()
    }

    /// The GPU context it runs on.
    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The number of Gaussians.
    pub fn gaussians(&self) -> usize {
        self.state.params.len()
    }

    /// The SH degree stored per Gaussian.
    pub fn sh_degree(&self) -> u32 {
        self.state.params.sh_degree()
    }

    /// Sizes the splatter for training view `view`; the frame goes to the record calls of
    /// this step and then to [`Self::finish_step`] (or [`Self::finish_counted`]). A step with
    /// more terms than the splatting loss records them after [`Self::record_splat`] and before
    /// [`Self::record_step_tail`], adding their gradients to [`Self::grads`].
    pub fn prepare_step(
        &mut self,
        view: usize,
        settings: &RenderSettings,
    ) -> Result<FrameParams, TrainError> {
        Ok(self.splatter.prepare_forward(&self.state.params, &self.cameras[view], settings)?)
    }

    /// Records zeroing the gradients, the splatting forward, its loss against the view's
    /// target (λ per rgba channel) and its backward. `other` (a render of the same view
    /// recorded before, with its λ, sums and gradient image) is scored against the target in
    /// the same run of the loss; it needs [`Self::with_second_render`].
    pub fn record_splat<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        view: usize,
        frame: &FrameParams,
        lambda: [f32; 4],
        other: Option<ScoredRender<'a>>,
    ) -> Result<(), TrainError> {
        let (state, splatter, camera) = (&self.state, &self.splatter, &self.cameras[view]);
        splatter.record_forward(rec, &state.params, frame)?;
        rec.begin_pass("loss");
        state.grads.record_zero(rec);
        let target = LossTarget {
            width: camera.width,
            height: camera.height,
            image: self.targets.get(view),
            weight: None,
        };
        let render = ScoredRender {
            image: splatter.rgba(),
            channel_weights: lambda,
            terms: &self.terms,
            gradient: &self.grad_rgba,
        };
        let renders: Vec<ScoredRender> = [Some(render), other].into_iter().flatten().collect();
        if renders.len() > self.loss.max_renders() {
            return Err(TrainError::NoSecondRender);
        }
        let seen = self.record_seen(rec, view, &renders)?;
        self.loss.record(rec, &target, &seen)?;
        self.record_seen_backward(rec, view, &renders)?;
        rec.end_pass();
        splatter.record_backward_of(
            rec,
            frame,
            &state.params,
            (&self.grad_rgba, &self.grad_depth),
            &state.grads,
            &state.densify_stats,
        )?;
        Ok(())
    }

    /// The renders as view `view`'s camera sees them (the renders themselves without camera
    /// colour): the first, the Gaussian render, sums its camera's moments when learning.
    fn record_seen<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        view: usize,
        renders: &[ScoredRender<'a>],
    ) -> Result<Vec<ScoredRender<'a>>, TrainError> {
        let Some(colour) = &self.colour else { return Ok(renders.to_vec()) };
        let mut seen = Vec::new();
        for (slot, r) in renders.iter().enumerate() {
            colour.maps.record_forward(rec, &self.mapped(colour, view, slot, r.image))?;
            let (image, gradient) = (colour.maps.seen(slot), colour.maps.seen_gradient(slot));
            seen.push(ScoredRender { image, gradient, ..*r });
        }
        Ok(seen)
    }

    /// dL/d(each render) from dL/d(what the camera saw of it); nothing without camera colour
    /// (the loss wrote the renders' gradients itself).
    fn record_seen_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        view: usize,
        renders: &[ScoredRender<'a>],
    ) -> Result<(), TrainError> {
        if let Some(colour) = &self.colour {
            for (slot, r) in renders.iter().enumerate() {
                let mapped = self.mapped(colour, view, slot, r.image);
                colour.maps.record_backward(rec, &mapped, r.gradient)?;
            }
        }
        Ok(())
    }

    /// Render `slot` of a step on view `view`, as the colour maps take it.
    fn mapped<'a>(
        &'a self,
        colour: &'a Colour,
        view: usize,
        slot: usize,
        render: &'a GpuBuffer<[f32; 4]>,
    ) -> MappedRender<'a> {
        let camera = &self.cameras[view];
        MappedRender {
            camera: view,
            render,
            slot,
            fit_against: (colour.learn && slot == 0).then_some(self.targets.get(view)),
            pixels: camera.width as usize * camera.height as usize,
            background: colour.background,
        }
    }

    /// After the step's submission completed: whether every intersection fit the splatter's
    /// buffers. When not, the step rendered without those past the capacity (its gradient is
    /// slightly off) and the buffers have grown for the next.
    pub fn finish_step(&mut self, frame: FrameParams) -> Result<bool, TrainError> {
        Ok(self.splatter.finish_forward(frame)?)
    }

    /// Makes room for `slots` steps in flight ([`Self::record_step_tail`]).
    pub fn reserve_step_slots(&mut self, slots: usize) -> Result<(), TrainError> {
        Ok(self.adam.reserve_slots(slots)?)
    }

    /// Sets the Adam parameters of the step recorded with ring slot `slot`; no submission that
    /// uses the slot may be on the queue.
    pub fn set_adam_step(&self, slot: usize, adam: &AdamParams) {
        self.adam.set_step(slot, adam);
    }

    /// Records the end of a step replayed with others in flight: the Adam step with the
    /// parameters of ring slot `slot` ([`Self::set_adam_step`]) and the copy of the forward's
    /// intersection count (of `frame`) into `counts[slot]`, for [`Self::finish_counted`].
    pub fn record_step_tail<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        (counts, slot): (&'a HostRing<u32>, usize),
    ) -> Result<(), TrainError> {
        rec.begin_pass("adam");
        self.adam.record_step_from(rec, &self.state.params, &self.state.grads, slot)?;
        rec.end_pass();
        self.record_count_copy(rec, frame, (counts, slot));
        Ok(())
    }

    /// Records copying the intersection count of the step's forward (of `frame`) into
    /// `counts[slot]`, for [`Self::finish_counted`].
    pub fn record_count_copy<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        frame: &FrameParams,
        counts: (&'a HostRing<u32>, usize),
    ) {
        self.splatter.record_count_copy(rec, frame, counts);
    }

    /// [`Self::finish_step`] with the intersection count already read.
    pub fn finish_counted(&mut self, frame: FrameParams, count: u32) -> Result<bool, TrainError> {
        Ok(self.splatter.finish_counted(frame, count)?)
    }

    /// The Gaussian parameters on the GPU.
    pub fn params(&self) -> &GaussianBuffers {
        &self.state.params
    }

    /// Their gradients, zeroed by [`Self::record_splat`] and added to by every term after it.
    pub fn grads(&self) -> &GaussianBuffers {
        &self.state.grads
    }

    /// The last Gaussian render (rgba per pixel; alpha is its coverage).
    pub fn rendered(&self) -> &GpuBuffer<[f32; 4]> {
        self.splatter.rgba()
    }

    /// Training view `view`'s target (rgb over the background, mask), on the GPU: its first
    /// width × height elements. Panics unless the view is on the device
    /// ([`Self::make_target_resident`]; every view is, unless streamed).
    pub fn target(&self, view: usize) -> &GpuBuffer<[f32; 4]> {
        self.targets.get(view)
    }

    /// The view whose target [`Self::make_target_resident`]`(view)` would take off the device
    /// (streamed targets only): its recorded steps must be finished and recorded again.
    pub fn target_evicts(&self, view: usize) -> Option<usize> {
        self.targets.evicts(view)
    }

    /// Puts `view`'s target on the device if it is not there (streamed targets only), waiting
    /// for the queue to be idle first.
    pub fn make_target_resident(&mut self, view: usize) -> Result<(), TrainError> {
        Ok(self.targets.make_resident(view)?)
    }

    /// Training views whose targets are on the device at once (all of them unless streamed).
    pub fn targets_on_device(&self) -> usize {
        self.targets.on_device()
    }

    /// Targets uploaded so far because they were streamed (0 when all are on the device).
    pub fn target_uploads(&self) -> u64 {
        self.targets.uploads()
    }

    /// Training view `view`'s camera.
    pub fn camera(&self, view: usize) -> &Camera {
        &self.cameras[view]
    }

    /// The loss terms summed since the last call (which restarts the sum).
    pub fn take_terms(&self) -> Result<LossTerms, TrainError> {
        Ok(LossTerms::take(&self.terms)?)
    }

    /// Keeps a GPU copy of the current parameters, what [`Self::last_good_scene`] returns.
    pub fn checkpoint(&self) -> Result<(), TrainError> {
        let (from, to) = (&self.state.params, &self.state.last_good);
        let mut rec = Recorder::new(&self.ctx)?;
        rec.copy_buffer(&from.positions, &to.positions, from.positions.len());
        rec.copy_buffer(&from.log_scales, &to.log_scales, from.log_scales.len());
        rec.copy_buffer(&from.rotations, &to.rotations, from.rotations.len());
        rec.copy_buffer(&from.opacity_logits, &to.opacity_logits, from.opacity_logits.len());
        rec.copy_buffer(&from.sh, &to.sh, from.sh.len());
        rec.submit_and_wait()?;
        Ok(())
    }

    /// Reads the current parameters back as a scene.
    pub fn scene(&self) -> Result<GaussianScene, TrainError> {
        Ok(self.state.params.to_scene()?)
    }

    /// Reads back the parameters kept by the last [`Self::checkpoint`], or the scene given to
    /// [`Self::new`] or [`Self::replace`] when that came later.
    pub fn last_good_scene(&self) -> Result<GaussianScene, TrainError> {
        Ok(self.state.last_good.to_scene()?)
    }

    /// Per Gaussian: summed 2D mean-gradient norm (pixels) and renders on screen, since the
    /// Gaussian set last changed.
    pub fn densify_stats(&self) -> Result<Vec<[f32; 2]>, TrainError> {
        Ok(self.state.densify_stats.read()?)
    }

    /// Replaces the Gaussian set: the optimizer's moments follow `old_of_new` (see
    /// `Adam::remap`), the densification statistics restart, the checkpoint is the new set.
    pub fn replace(&mut self, scene: &GaussianScene, old_of_new: &[u32]) -> Result<(), TrainError> {
        scene.check().map_err(crate::splat::SplatError::from)?;
        self.adam.remap(old_of_new)?;
        // The splatter's capacity follows the Gaussian count (intersections per Gaussian), so
        // the views need not be rendered again here.
        self.state = GaussianState::new(&self.ctx, scene)?;
        Ok(())
    }

    /// Renders the current (or checkpointed) Gaussians from `camera`: RGB per pixel in [0, 1].
    pub fn render(
        &mut self,
        camera: &Camera,
        settings: &RenderSettings,
        last_good: bool,
    ) -> Result<Vec<f32>, TrainError> {
        let params = if last_good { &self.state.last_good } else { &self.state.params };
        self.splatter.forward(params, camera, settings)?;
        Ok(self
            .splatter
            .read_rgba()?
            .iter()
            .flat_map(|p| [p[0], p[1], p[2]])
            .map(|c| c.clamp(0.0, 1.0))
            .collect())
    }
}
