//! Gaussian parameters on the GPU, one buffer per parameter group (so an optimizer can give each
//! its own learning rate). The same type holds gradients, shaped like the parameters.

use super::GaussianScene;
use crate::gpu::{BufferBinding, GpuBuffer, GpuContext, GpuResult, Recorder};
use std::sync::Arc;

/// A Gaussian set's parameters (or their gradients) on the GPU, one buffer per group, with
/// its Gaussian count and SH degree.
pub struct GaussianBuffers {
    /// 3 floats per Gaussian.
    pub positions: GpuBuffer<f32>,
    /// 3 floats per Gaussian.
    pub log_scales: GpuBuffer<f32>,
    /// (w, x, y, z) per Gaussian.
    pub rotations: GpuBuffer<[f32; 4]>,
    /// 1 float per Gaussian: the opacity before the sigmoid.
    pub opacity_logits: GpuBuffer<f32>,
    /// `sh_coefficients(sh_degree) * 3` floats per Gaussian, as in [`GaussianScene::sh`].
    pub sh: GpuBuffer<f32>,
    len: usize,
    sh_degree: u32,
}

impl GaussianBuffers {
    /// Uploads a scene (checked for consistent row counts first).
    pub fn from_scene(
        ctx: &Arc<GpuContext>,
        scene: &GaussianScene,
    ) -> Result<Self, super::SplatError> {
        scene.check()?;
        let flat = |rows: &[[f32; 3]]| rows.iter().flatten().copied().collect::<Vec<f32>>();
        Ok(Self {
            positions: GpuBuffer::from_slice(ctx, "gaussian positions", &flat(&scene.positions))?,
            log_scales: GpuBuffer::from_slice(
                ctx,
                "gaussian log-scales",
                &flat(&scene.log_scales),
            )?,
            rotations: GpuBuffer::from_slice(ctx, "gaussian rotations", &scene.rotations)?,
            opacity_logits: GpuBuffer::from_slice(
                ctx,
                "gaussian opacity logits",
                &scene.opacity_logits,
            )?,
            sh: GpuBuffer::from_slice(ctx, "gaussian SH", &scene.sh)?,
            len: scene.len(),
            sh_degree: scene.sh_degree,
        })
    }

    /// Buffers shaped like `like`, contents undefined until [`Self::record_zero`].
    pub fn shaped_like(ctx: &Arc<GpuContext>, like: &GaussianBuffers) -> GpuResult<Self> {
        Ok(Self {
            positions: GpuBuffer::new(ctx, "gaussian position gradients", like.positions.len())?,
            log_scales: GpuBuffer::new(ctx, "gaussian log-scale gradients", like.log_scales.len())?,
            rotations: GpuBuffer::new(ctx, "gaussian rotation gradients", like.rotations.len())?,
            opacity_logits: GpuBuffer::new(
                ctx,
                "gaussian opacity-logit gradients",
                like.opacity_logits.len(),
            )?,
            sh: GpuBuffer::new(ctx, "gaussian SH gradients", like.sh.len())?,
            len: like.len,
            sh_degree: like.sh_degree,
        })
    }

    /// The number of Gaussians.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The SH degree the `sh` buffer is laid out for.
    pub fn sh_degree(&self) -> u32 {
        self.sh_degree
    }

    /// Records zeroing every buffer.
    pub fn record_zero<'a>(&'a self, recorder: &mut Recorder<'a>) {
        recorder.fill_buffer(&self.positions, 0);
        recorder.fill_buffer(&self.log_scales, 0);
        recorder.fill_buffer(&self.rotations, 0);
        recorder.fill_buffer(&self.opacity_logits, 0);
        recorder.fill_buffer(&self.sh, 0);
    }

    /// Bindings named by `names`, one per buffer in this order: positions, log-scales,
    /// rotations, opacity logits, SH (each kernel names them its own way).
    pub(crate) fn bindings(
        &self,
        names: [&'static str; 5],
    ) -> [(&'static str, BufferBinding<'_>); 5] {
        let [positions, log_scales, rotations, opacity_logits, sh] = names;
        [
            (positions, self.positions.binding()),
            (log_scales, self.log_scales.binding()),
            (rotations, self.rotations.binding()),
            (opacity_logits, self.opacity_logits.binding()),
            (sh, self.sh.binding()),
        ]
    }

    /// Reads everything back as a host scene.
    pub fn to_scene(&self) -> GpuResult<GaussianScene> {
        let rows = |flat: Vec<f32>| flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(GaussianScene {
            positions: rows(self.positions.read()?),
            log_scales: rows(self.log_scales.read()?),
            rotations: self.rotations.read()?,
            opacity_logits: self.opacity_logits.read()?,
            sh: self.sh.read()?,
            sh_degree: self.sh_degree,
        })
    }
}
