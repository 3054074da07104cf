//! The mesh terms of a training step: the mesh whose vertices are the Gaussians (positions
//! from the Gaussian buffer, colours from their SH DC) rendered by the visibility-buffer
//! rasterizer, scored against the view's target (colour and mask) in the same run of the fused
//! image loss as the Gaussian render ([`Trainer::record_splat`]), and differentiated back
//! into the Gaussians' position and SH gradients, all recorded into the training step's
//! submission.

use super::{TrainError, Trainer};
use crate::camera::Camera;
use crate::gpu::{
    push_layout, ComputePipeline, FixedSums, GpuBuffer, GpuContext, PipelineDesc, Recorder,
};
use crate::loss::{LossTerms, ScoredRender};
use crate::raster::{MeshRasterizer, RasterMesh, RasterSettings};
use crate::shaders;
use crate::splat::{FrameParams, GaussianBuffers};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of shaders/train/*.comp (`BridgeParams` in bridge.glsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BridgeParams {
    background: [f32; 4],
    sizes: [u32; 4],
}
push_layout!(
    BridgeParams: [
        TRAIN_MESH_COLORS,
        TRAIN_SH_DC_GRADIENT,
        TRAIN_PACK_MESH_RENDER,
        TRAIN_UNPACK_MESH_GRADIENT,
    ],
    [background, sizes]
);

pub struct MeshTerm {
    ctx: Arc<GpuContext>,
    raster: MeshRasterizer,
    settings: RasterSettings,
    mesh_colors: ComputePipeline,
    sh_dc_gradient: ComputePipeline,
    pack: ComputePipeline,
    unpack: ComputePipeline,
    /// Per pixel: the render as the loss reads it, and its gradient.
    packed: GpuBuffer<[f32; 4]>,
    packed_grad: GpuBuffer<[f32; 4]>,
    color_grad: GpuBuffer<f32>,
    mask_grad: GpuBuffer<f32>,
    /// Per vertex (3 floats).
    vertex_color_grads: GpuBuffer<f32>,
    /// Loss terms summed since the last [`MeshTerm::take_terms`].
    terms: FixedSums,
}

impl MeshTerm {
    /// For `faces` over the Gaussians at `positions`, rendering `width × height` views.
    pub fn new(
        ctx: &Arc<GpuContext>,
        positions: &[[f32; 3]],
        faces: &[[u32; 3]],
        width: u32,
        height: u32,
    ) -> Result<Self, TrainError> {
        let mesh = RasterMesh::uniform(positions.to_vec(), faces.to_vec(), [0.5; 3])?;
        let pixels = width as usize * height as usize;
        let pipeline = |name, shader| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[WORKGROUP] })
        };
        let term = Self {
            ctx: ctx.clone(),
            raster: MeshRasterizer::new(ctx, &mesh, width, height)?,
            settings: RasterSettings::scaled_to(positions),
            mesh_colors: pipeline("mesh colours from SH", &shaders::TRAIN_MESH_COLORS)?,
            sh_dc_gradient: pipeline(
                "SH DC gradient from mesh colours",
                &shaders::TRAIN_SH_DC_GRADIENT,
            )?,
            pack: pipeline("pack mesh render", &shaders::TRAIN_PACK_MESH_RENDER)?,
            unpack: pipeline("unpack mesh gradient", &shaders::TRAIN_UNPACK_MESH_GRADIENT)?,
            packed: GpuBuffer::new(ctx, "mesh render rgba", pixels)?,
            packed_grad: GpuBuffer::new(ctx, "mesh render rgba gradient", pixels)?,
            color_grad: GpuBuffer::new(ctx, "mesh colour image gradient", 3 * pixels)?,
            mask_grad: GpuBuffer::new(ctx, "mesh mask image gradient", pixels)?,
            vertex_color_grads: GpuBuffer::new(
                ctx,
                "mesh vertex colour gradients",
                3 * positions.len(),
            )?,
            terms: LossTerms::sums(ctx, "mesh loss terms")?,
        };
        let mut rec = Recorder::new(ctx)?;
        term.terms.clear(&mut rec);
        rec.submit_and_wait()?;
        Ok(term)
    }

    /// New faces after a topology change (positions only size the near plane and the buffers).
    pub fn set_mesh(
        &mut self,
        positions: &[[f32; 3]],
        faces: &[[u32; 3]],
    ) -> Result<(), TrainError> {
        self.raster.set_mesh(&RasterMesh::uniform(
            positions.to_vec(),
            faces.to_vec(),
            [0.5; 3],
        )?)?;
        self.settings = RasterSettings::scaled_to(positions);
        self.vertex_color_grads =
            GpuBuffer::new(&self.ctx, "mesh vertex colour gradients", 3 * positions.len())?;
        Ok(())
    }

    fn bridge(&self, items: usize, params: &GaussianBuffers, background: [f32; 3]) -> BridgeParams {
        let [r, g, b] = background;
        let stride = params.sh.len() / params.len().max(1);
        BridgeParams { background: [r, g, b, 0.0], sizes: [items as u32, stride as u32, 0, 0] }
    }

    /// Records the mesh render of `params` from `camera` into [`Self::packed`]'s buffer.
    fn record_render<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        camera: &Camera,
        background: [f32; 3],
    ) -> Result<(), TrainError> {
        let groups = |n: usize| n.div_ceil(WORKGROUP as usize) as u64;
        let vertices = self.bridge(params.len(), params, background);
        rec.dispatch_1d(
            &self.mesh_colors,
            &[("sh", params.sh.binding()), ("colors", self.raster.colors().binding())],
            &vertices,
            groups(params.len()),
        )?;
        let raster = self.raster.params(camera, &self.settings)?;
        self.raster.record_forward_from(rec, &raster, &params.positions)?;
        let pixels = self.packed_grad.len();
        let bindings = [
            ("color", self.raster.color_image().binding()),
            ("mask", self.raster.mask_image().binding()),
            ("packed", self.packed.binding()),
        ];
        rec.dispatch_1d(
            &self.pack,
            &bindings,
            &self.bridge(pixels, params, background),
            groups(pixels),
        )?;
        Ok(())
    }

    /// Records the mesh render of `params` from `camera`; returns it as the view's loss scores
    /// it (λ per rgba channel), with this term's sums and gradient image. After the loss,
    /// [`Self::record_backward`].
    pub fn record_forward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        camera: &Camera,
        lambda: [f32; 4],
        background: [f32; 3],
    ) -> Result<ScoredRender<'a>, TrainError> {
        rec.begin_pass("mesh render");
        self.record_render(rec, params, camera, background)?;
        rec.end_pass();
        Ok(ScoredRender {
            image: &self.packed,
            channel_weights: lambda,
            terms: &self.terms,
            gradient: &self.packed_grad,
        })
    }

    /// Records the backward of the render [`Self::record_forward`] recorded, from the gradient
    /// the loss wrote, ADDING to the position and SH DC gradients in `grads`.
    pub fn record_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &'a GaussianBuffers,
        grads: &'a GaussianBuffers,
        camera: &Camera,
        background: [f32; 3],
    ) -> Result<(), TrainError> {
        let groups = |n: usize| n.div_ceil(WORKGROUP as usize) as u64;
        let raster = self.raster.params(camera, &self.settings)?;
        rec.begin_pass("mesh backward");
        let pixels = self.packed_grad.len();
        let unpack = [
            ("packed_grad", self.packed_grad.binding()),
            ("color_grad", self.color_grad.binding()),
            ("mask_grad", self.mask_grad.binding()),
        ];
        rec.dispatch_1d(
            &self.unpack,
            &unpack,
            &self.bridge(pixels, params, background),
            groups(pixels),
        )?;
        rec.fill_buffer(&self.vertex_color_grads, 0);
        self.raster.record_backward(
            rec,
            &raster,
            (&self.color_grad, &self.mask_grad),
            (&grads.positions, &self.vertex_color_grads),
        )?;
        let dc =
            [("color_grads", self.vertex_color_grads.binding()), ("sh_grads", grads.sh.binding())];
        rec.dispatch_1d(
            &self.sh_dc_gradient,
            &dc,
            &self.bridge(params.len(), params, background),
            groups(params.len()),
        )?;
        rec.end_pass();
        Ok(())
    }

    /// Records a training step on view `view` with this term: the mesh render, the Gaussian
    /// and mesh renders scored against the view's target in one run of the loss (`weights`:
    /// Gaussian, mesh λ per rgba channel), both backwards. `trainer` must be built
    /// [`Trainer::with_second_render`].
    pub fn record_step_with<'a>(
        &'a self,
        trainer: &'a Trainer,
        rec: &mut Recorder<'a>,
        (view, frame): (usize, &FrameParams),
        weights: [[f32; 4]; 2],
        background: [f32; 3],
    ) -> Result<(), TrainError> {
        let (params, camera) = (trainer.params(), trainer.camera(view));
        let mesh = self.record_forward(rec, params, camera, weights[1], background)?;
        trainer.record_splat(rec, view, frame, weights[0], Some(mesh))?;
        self.record_backward(rec, params, trainer.grads(), camera, background)
    }

    /// The loss terms summed since the last call (which restarts the sum).
    pub fn take_terms(&self) -> Result<LossTerms, TrainError> {
        Ok(LossTerms::take(&self.terms)?)
    }

    /// The mesh render of `params` from `camera` (RGB over `background`, clamped to [0, 1]).
    pub fn render(
        &self,
        params: &GaussianBuffers,
        camera: &Camera,
        background: [f32; 3],
    ) -> Result<Vec<f32>, TrainError> {
        let mut rec = Recorder::new(&self.ctx)?;
        self.record_render(&mut rec, params, camera, background)?;
        rec.submit_and_wait()?;
        let pixels = camera.width as usize * camera.height as usize;
        Ok(self
            .packed
            .read_prefix(pixels)?
            .iter()
            .flat_map(|p| [p[0], p[1], p[2]])
            .map(|c| c.clamp(0.0, 1.0))
            .collect())
    }
}
