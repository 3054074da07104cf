//! Each camera's own colour response, learned with the reconstruction: a render is scored as
//! its camera sees it, through the camera's affine map of the subject's colour
//! (shaders/loss/colour_map.glsl), so the scene's colours need not average cameras whose
//! exposure and white balance differ, and a view-dependent colour need not explain a camera.
//!
//! The maps are not optimised by gradient: while the renders are scored, the forward sums the
//! moments of each camera's renders against its targets, and [`CameraColour::refit`] (between
//! steps, when none is in flight) solves each camera's least-squares map from them and fixes
//! the gauge the maps share with the colours ([`affine::fix_gauge`]).

pub mod affine;
pub mod reference;

use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult,
    PipelineDesc, Recorder,
};
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

/// A camera's map: three rows `(A_k0, A_k1, A_k2, b_k)`; the camera sees `A p + b α` of the
/// subject's premultiplied colour `p` and coverage `α`.
pub type ColourMap = [[f32; 4]; 3];

/// Moments a camera's renders sum per refit (colour_map_forward.comp `MOMENTS`).
pub const MOMENTS: usize = 22;
const WORKGROUP: u32 = 64;
/// Pixels one invocation of the forward maps (colour_map_forward.comp `RUN`).
const RUN: u32 = 16;
const BACKWARD_WORKGROUP: u32 = 128;

/// Push constants of both kernels (`ColourMapParams` in colour_map.glsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ColourMapParams {
    background: [f32; 4],
    size: [u32; 4],
}
push_layout!(ColourMapParams: [LOSS_COLOUR_MAP_FORWARD, LOSS_COLOUR_MAP_BACKWARD], [background, size]);

/// The maps of a set of cameras on the GPU, the moments their renders sum, and the seen
/// renders and their gradients of one step (one plane per render a step scores).
pub struct CameraColour {
    forward: ComputePipeline,
    backward: ComputePipeline,
    maps: GpuBuffer<[f32; 4]>,
    moments: FixedSums,
    cameras: usize,
    /// Per render slot: the render as its camera sees it, and dL/d(that).
    seen: Vec<[GpuBuffer<[f32; 4]>; 2]>,
}

/// One render a step maps: the render, the slot of scratch it is seen in, and whether its
/// moments go to the camera's next fit (a view's Gaussian render; not its mesh render).
#[derive(Clone, Copy)]
pub struct MappedRender<'a> {
    /// The camera (index into the maps).
    pub camera: usize,
    /// The render over `background`.
    pub render: &'a GpuBuffer<[f32; 4]>,
    /// Which of the [`CameraColour::new`] scratch slots holds it.
    pub slot: usize,
    /// The target whose moments are summed with the render's, when they are.
    pub fit_against: Option<&'a GpuBuffer<[f32; 4]>>,
    /// Pixels of the image.
    pub pixels: usize,
    /// The colour behind the subject.
    pub background: [f32; 3],
}

impl CameraColour {
    /// The maps `maps` (one per camera) with `slots` renders per step of at most `pixels`.
    pub fn new(
        ctx: &Arc<GpuContext>,
        maps: &[ColourMap],
        slots: usize,
        pixels: usize,
    ) -> GpuResult<Self> {
        let rows: Vec<[f32; 4]> = maps.iter().flatten().copied().collect();
        let pipeline = |name, shader, workgroup| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[workgroup] })
        };
        let plane =
            |name: &str, slot: usize| GpuBuffer::new(ctx, &format!("{name} {slot}"), pixels);
        Ok(Self {
            forward: pipeline("colour map forward", &shaders::LOSS_COLOUR_MAP_FORWARD, WORKGROUP)?,
            backward: pipeline(
                "colour map backward",
                &shaders::LOSS_COLOUR_MAP_BACKWARD,
                BACKWARD_WORKGROUP,
            )?,
            maps: GpuBuffer::from_slice(ctx, "camera colour maps", &rows)?,
            moments: FixedSums::new(
                ctx,
                "camera colour moments",
                MOMENTS * maps.len(),
                FixedPrecision::Total,
            )?,
            cameras: maps.len(),
            seen: (0..slots)
                .map(|s| Ok([plane("render as seen", s)?, plane("seen render gradient", s)?]))
                .collect::<GpuResult<_>>()?,
        })
    }

    /// The render of `slot` as its camera sees it (written by [`Self::record_forward`]).
    pub fn seen(&self, slot: usize) -> &GpuBuffer<[f32; 4]> {
        &self.seen[slot][0]
    }

    /// Where the loss writes dL/d(the seen render of `slot`), read by [`Self::record_backward`].
    pub fn seen_gradient(&self, slot: usize) -> &GpuBuffer<[f32; 4]> {
        &self.seen[slot][1]
    }

    fn params(r: &MappedRender) -> ColourMapParams {
        let [r0, g0, b0] = r.background;
        let fit = r.fit_against.is_some() as u32;
        ColourMapParams {
            background: [r0, g0, b0, 0.0],
            size: [r.pixels as u32, r.camera as u32, fit, 0],
        }
    }

    /// Records the render seen through its camera's map into [`Self::seen`], and, with
    /// `fit_against`, ADDS the moments of the camera's next fit.
    pub fn record_forward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        r: &MappedRender<'a>,
    ) -> GpuResult<()> {
        let buffers = [
            ("maps", self.maps.binding()),
            ("render", r.render.binding()),
            ("target", r.fit_against.unwrap_or(r.render).binding()),
            ("mapped", self.seen(r.slot).binding()),
            ("moments", self.moments.binding()),
        ];
        let groups = (r.pixels as u64).div_ceil((WORKGROUP * RUN) as u64);
        rec.dispatch_1d(&self.forward, &buffers, &Self::params(r), groups)
    }

    /// Records dL/d(render) from dL/d(the seen render of `r.slot`), WRITTEN to `gradient`.
    pub fn record_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        r: &MappedRender<'a>,
        gradient: &'a GpuBuffer<[f32; 4]>,
    ) -> GpuResult<()> {
        let buffers = [
            ("maps", self.maps.binding()),
            ("seen_gradient", self.seen_gradient(r.slot).binding()),
            ("gradient", gradient.binding()),
        ];
        let groups = (r.pixels as u64).div_ceil(BACKWARD_WORKGROUP as u64);
        let params =
            ColourMapParams { size: [r.pixels as u32, r.camera as u32, 0, 0], ..Self::params(r) };
        rec.dispatch_1d(&self.backward, &buffers, &params, groups)
    }

    /// The maps, one per camera.
    pub fn maps(&self) -> GpuResult<Vec<ColourMap>> {
        let rows = self.maps.read()?;
        Ok(rows.chunks_exact(3).map(|r| [r[0], r[1], r[2]]).collect())
    }

    /// Each camera's map fitted from the moments summed since the last refit (a camera whose
    /// renders covered nothing keeps its map), the gauge fixed; the moments restart. `ridge`
    /// pulls each fit toward the identity ([`affine::fit_map`]). Returns the maps: unchanged
    /// when no camera's renders covered anything.
    pub fn refit(&mut self, ridge: f64) -> GpuResult<Vec<ColourMap>> {
        let sums = self.moments.take()?;
        let old = self.maps()?;
        let fits: Vec<Option<ColourMap>> = (0..self.cameras)
            .map(|c| affine::fit_map(&sums[c * MOMENTS..(c + 1) * MOMENTS], ridge))
            .collect();
        if fits.iter().all(Option::is_none) {
            return Ok(old);
        }
        let fitted: Vec<ColourMap> = fits.iter().zip(&old).map(|(f, o)| f.unwrap_or(*o)).collect();
        let maps = affine::fix_gauge(&fitted);
        self.maps.write(&maps.iter().flatten().copied().collect::<Vec<_>>())?;
        Ok(maps)
    }

    /// The moments summed since the last refit, `MOMENTS` per camera (for tests).
    pub fn take_moments(&self) -> GpuResult<Vec<f64>> {
        self.moments.take()
    }
}
