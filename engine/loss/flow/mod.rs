//! The optical-flow term (shaders/loss/flow.comp): a vertex seen in a view at frame t − 1 is
//! pulled to where that view's images say its pixel moved by frame t. The image terms compare
//! a render with frame 0's colours against the image, and pull only within a few pixels; flow
//! compares two consecutive images (the same light, nearly the same shading) and, through its
//! pyramid, follows motion of many pixels. The targets come from the caller (plain arrays, see
//! `crate::train::flow_targets`); this module scores them on the GPU.

pub mod reference;

use crate::camera::Camera;
use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult,
    PipelineDesc, Recorder,
};
use crate::loss::pinhole_view::PinholeView;
use crate::shaders;
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Scale of the Cauchy loss, pixels: a flow target further off than this pulls less and less
/// (Lucas–Kanade's forward-backward-checked error is about a pixel on the benchmarks).
pub const FLOW_TAU_PIXELS: f32 = 2.0;

/// Push constants of flow.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    vertices: u32,
    views: u32,
    scale: f32,
    near: f32,
    tau: f32,
}
push_layout!(Push: [LOSS_FLOW], [vertices, views, scale, near, tau]);

/// Where a vertex should project in one view: index coordinates (pixel centres at integers)
/// and a confidence (0: no target).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct FlowTarget {
    /// Column, index coordinates.
    pub u: f32,
    /// Row, index coordinates.
    pub v: f32,
    /// Confidence; 0 (or not positive) leaves the pair out.
    pub weight: f32,
    /// Padding to 16 bytes (the shader's vec4).
    pub unused: f32,
}

/// The flow kernel with every view's camera and the targets uploaded.
pub struct FlowTerm {
    pipeline: ComputePipeline,
    views: GpuBuffer<PinholeView>,
    targets: GpuBuffer<FlowTarget>,
    loss_sum: FixedSums,
    vertices: usize,
    view_count: usize,
    /// (vertex, view) pairs with a target.
    pairs: usize,
}

impl FlowTerm {
    /// `targets`: vertex-major, `cameras.len()` per vertex.
    pub fn new(
        ctx: &Arc<GpuContext>,
        cameras: &[Camera],
        targets: &[FlowTarget],
    ) -> Result<Self, crate::gpu::GpuError> {
        let views: Vec<PinholeView> = cameras.iter().map(|c| PinholeView::new(c, [0, 0])).collect();
        // An empty buffer cannot be bound: one unused row stands in.
        let rows = if targets.is_empty() { &[FlowTarget::default()][..] } else { targets };
        let pairs = targets.iter().filter(|t| t.weight > 0.0).count();
        Ok(Self {
            pipeline: ComputePipeline::new(
                ctx,
                &PipelineDesc {
                    name: "flow",
                    shader: &shaders::LOSS_FLOW,
                    specialization: &[WORKGROUP],
                },
            )?,
            views: GpuBuffer::from_slice(ctx, "flow views", &views)?,
            targets: GpuBuffer::from_slice(ctx, "flow targets", rows)?,
            loss_sum: FixedSums::new(ctx, "flow loss", 1, FixedPrecision::Total)?,
            vertices: if cameras.is_empty() { 0 } else { targets.len() / cameras.len() },
            view_count: cameras.len(),
            pairs,
        })
    }

    /// (vertex, view) pairs with a target.
    pub fn pairs(&self) -> usize {
        self.pairs
    }

    /// Records the term, ADDING `weight` × its gradient (the mean over the pairs with a target)
    /// into `grad_positions`; the weighted value is summed for [`Self::take_loss`]. The
    /// positions must be the vertices the targets were made for; `near`: closer points are
    /// skipped.
    pub fn record<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        positions: &'a GpuBuffer<f32>,
        grad_positions: &'a GpuBuffer<f32>,
        weight: f32,
        near: f32,
    ) -> GpuResult<()> {
        let vertices = (positions.len() / 3).min(self.vertices);
        if vertices == 0 || self.pairs == 0 || weight == 0.0 {
            return Ok(());
        }
        let push = Push {
            vertices: vertices as u32,
            views: self.view_count as u32,
            scale: weight / self.pairs as f32,
            near,
            tau: FLOW_TAU_PIXELS,
        };
        let buffers = [
            ("positions", positions.binding()),
            ("views", self.views.binding()),
            ("targets", self.targets.binding()),
            ("grad_positions", grad_positions.binding()),
            ("loss_sum", self.loss_sum.binding()),
        ];
        rec.dispatch_1d(
            &self.pipeline,
            &buffers,
            &push,
            (vertices as u64).div_ceil(WORKGROUP as u64),
        )
    }

    /// The weighted loss summed since the last call (which restarts the sum).
    pub fn take_loss(&self) -> GpuResult<f32> {
        Ok(self.loss_sum.take()?[0] as f32)
    }
}
