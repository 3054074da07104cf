//! The deformation graph on the GPU: its bindings and node transforms, the blend (node
//! transforms → Gaussian positions and rotations), the node gradients (vertex gradients pulled
//! back, plus as-rigid-as-possible between nodes) and Adam on the nodes.

use super::graph::{DeformGraph, NODES_PER_VERTEX};
use super::reference::NodeTransforms;
use crate::gpu::{
    push_layout, ComputePipeline, FixedPrecision, FixedSums, GpuBuffer, GpuContext, GpuResult,
    PipelineDesc, Recorder,
};
use crate::optim::{Adam, AdamParams, LearningRates};
use crate::shaders;
use crate::splat::{GaussianBuffers, GaussianScene};
use bytemuck::{Pod, Zeroable};
use std::sync::Arc;

const WORKGROUP: u32 = 128;

/// Push constants of every kernel (shaders/deform/common.glsl `Push`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    vertices: u32,
    nodes: u32,
    arap_scale: f32,
    unused: u32,
}
push_layout!(Push: [DEFORM_BLEND, DEFORM_NODE_GRADIENTS], [vertices, nodes, arap_scale, unused]);

/// Node k's vertices (the CSR inverse of the bindings) and their weights.
struct Members {
    ranges: Vec<[u32; 2]>,
    vertices: Vec<u32>,
    weights: Vec<f32>,
}

fn members_of(graph: &DeformGraph) -> Members {
    let mut lists = vec![Vec::new(); graph.node_vertices.len()];
    for (i, (nodes, weights)) in graph.bound_nodes.iter().zip(&graph.bound_weights).enumerate() {
        for s in 0..NODES_PER_VERTEX {
            if weights[s] > 0.0 {
                lists[nodes[s] as usize].push((i as u32, weights[s]));
            }
        }
    }
    let mut members = Members { ranges: Vec::new(), vertices: Vec::new(), weights: Vec::new() };
    for list in lists {
        members.ranges.push([members.vertices.len() as u32, list.len() as u32]);
        members.vertices.extend(list.iter().map(|m| m.0));
        members.weights.extend(list.iter().map(|m| m.1));
    }
    members
}

/// The graph's buffers and pipelines. The node transforms live in a [`GaussianBuffers`] with
/// one row per node (translation in `positions`, rotation in `rotations`, the other groups
/// unused at learning rate 0), so the fused Adam serves them unchanged.
pub struct GraphDeformer {
    blend: ComputePipeline,
    node_gradients: ComputePipeline,
    rest_positions: GpuBuffer<f32>,
    rest_rotations: GpuBuffer<[f32; 4]>,
    bound_nodes: GpuBuffer<[u32; NODES_PER_VERTEX]>,
    bound_weights: GpuBuffer<[f32; NODES_PER_VERTEX]>,
    node_rest: GpuBuffer<[f32; 4]>,
    member_ranges: GpuBuffer<[u32; 2]>,
    members: GpuBuffer<u32>,
    member_weights: GpuBuffer<f32>,
    neighbour_ranges: GpuBuffer<[u32; 2]>,
    neighbours: GpuBuffer<u32>,
    nodes: GaussianBuffers,
    node_grads: GaussianBuffers,
    adam: Adam,
    loss_sum: FixedSums,
    push: Push,
}

impl GraphDeformer {
    /// Uploads `graph` over the start pose `rest` (its positions and rotations; one row per
    /// vertex) with every node at the identity. `arap_weight` weighs the mean squared ARAP
    /// residual measured in node spacings.
    pub fn new(
        ctx: &Arc<GpuContext>,
        graph: &DeformGraph,
        rest: &GaussianScene,
        arap_weight: f32,
    ) -> Result<Self, super::DeformError> {
        let (n, m) = (rest.len(), graph.node_vertices.len());
        if graph.bound_nodes.len() != n {
            return Err(super::DeformError::Shape(format!(
                "a graph over {} vertices for {n} Gaussians",
                graph.bound_nodes.len()
            )));
        }
        let pipeline = |name, shader| {
            ComputePipeline::new(ctx, &PipelineDesc { name, shader, specialization: &[WORKGROUP] })
        };
        let node_scene = GaussianScene {
            positions: vec![[0.0; 3]; m],
            log_scales: vec![[0.0; 3]; m],
            rotations: vec![[1.0, 0.0, 0.0, 0.0]; m],
            opacity_logits: vec![0.0; m],
            sh: vec![0.0; 3 * m],
            sh_degree: 0,
        };
        let nodes = GaussianBuffers::from_scene(ctx, &node_scene)?;
        // Adam reads every gradient group; the unused ones must hold zeros, not garbage.
        let node_grads = GaussianBuffers::shaped_like(ctx, &nodes)?;
        let mut rec = Recorder::new(ctx)?;
        node_grads.record_zero(&mut rec);
        rec.submit_and_wait()?;
        let members = members_of(graph);
        let spacing = graph.node_spacing.max(f32::MIN_POSITIVE);
        let directed_edges = graph.neighbours.len().max(1) as f32;
        let node_rest: Vec<[f32; 4]> = graph
            .node_vertices
            .iter()
            .map(|&v| {
                let p = rest.positions[v as usize];
                [p[0], p[1], p[2], 0.0]
            })
            .collect();
        Ok(Self {
            blend: pipeline("deform blend", &shaders::DEFORM_BLEND)?,
            node_gradients: pipeline("deform node gradients", &shaders::DEFORM_NODE_GRADIENTS)?,
            rest_positions: GpuBuffer::from_slice(
                ctx,
                "deform rest positions",
                &rest.positions.concat(),
            )?,
            rest_rotations: GpuBuffer::from_slice(ctx, "deform rest rotations", &rest.rotations)?,
            bound_nodes: GpuBuffer::from_slice(ctx, "deform bound nodes", &graph.bound_nodes)?,
            bound_weights: GpuBuffer::from_slice(
                ctx,
                "deform bound weights",
                &graph.bound_weights,
            )?,
            node_rest: GpuBuffer::from_slice(ctx, "deform node rest positions", &node_rest)?,
            member_ranges: GpuBuffer::from_slice(ctx, "deform member ranges", &members.ranges)?,
            members: GpuBuffer::from_slice(ctx, "deform members", &members.vertices)?,
            member_weights: GpuBuffer::from_slice(ctx, "deform member weights", &members.weights)?,
            neighbour_ranges: GpuBuffer::from_slice(
                ctx,
                "deform neighbour ranges",
                &graph.neighbour_ranges,
            )?,
            neighbours: GpuBuffer::from_slice(ctx, "deform neighbours", &graph.neighbours)?,
            node_grads,
            adam: Adam::new(ctx, &nodes)?,
            nodes,
            loss_sum: FixedSums::new(ctx, "deform ARAP loss", 1, FixedPrecision::Total)?,
            push: Push {
                vertices: n as u32,
                nodes: m as u32,
                arap_scale: arap_weight / (directed_edges * spacing * spacing),
                unused: 0,
            },
        })
    }

    /// The number of graph nodes.
    pub fn nodes(&self) -> usize {
        self.push.nodes as usize
    }

    /// Records writing the blended positions and rotations into `target` (one row per vertex).
    pub fn record_blend<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        target: &'a GaussianBuffers,
    ) -> GpuResult<()> {
        let buffers = [
            ("rest_positions", self.rest_positions.binding()),
            ("rest_rotations", self.rest_rotations.binding()),
            ("bound_nodes", self.bound_nodes.binding()),
            ("bound_weights", self.bound_weights.binding()),
            ("node_rest", self.node_rest.binding()),
            ("node_translations", self.nodes.positions.binding()),
            ("node_rotations", self.nodes.rotations.binding()),
            ("positions", target.positions.binding()),
            ("rotations", target.rotations.binding()),
        ];
        rec.dispatch_1d(
            &self.blend,
            &buffers,
            &self.push,
            (self.push.vertices as u64).div_ceil(WORKGROUP as u64),
        )
    }

    /// Records the node gradients from the vertex position gradients `grad_positions` (3
    /// floats per vertex) plus ARAP, overwriting the previous ones; the ARAP energy goes to
    /// [`Self::take_arap_loss`]'s sum.
    pub fn record_gradients<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        grad_positions: &'a GpuBuffer<f32>,
    ) -> GpuResult<()> {
        let buffers = [
            ("rest_positions", self.rest_positions.binding()),
            ("node_rest", self.node_rest.binding()),
            ("node_translations", self.nodes.positions.binding()),
            ("node_rotations", self.nodes.rotations.binding()),
            ("member_ranges", self.member_ranges.binding()),
            ("members", self.members.binding()),
            ("member_weights", self.member_weights.binding()),
            ("neighbour_ranges", self.neighbour_ranges.binding()),
            ("neighbours", self.neighbours.binding()),
            ("grad_positions", grad_positions.binding()),
            ("node_grad_translations", self.node_grads.positions.binding()),
            ("node_grad_rotations", self.node_grads.rotations.binding()),
            ("loss_sum", self.loss_sum.binding()),
        ];
        rec.dispatch_1d(
            &self.node_gradients,
            &buffers,
            &self.push,
            (self.push.nodes as u64).div_ceil(WORKGROUP as u64),
        )
    }

    /// Records one Adam step of the node transforms (`step` counts from 1).
    pub fn record_adam<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        translation_rate: f32,
        rotation_rate: f32,
        step: u32,
    ) -> GpuResult<()> {
        let adam = self.adam_params(translation_rate, rotation_rate, step);
        self.adam.record_step(rec, &self.nodes, &self.node_grads, &adam)
    }

    /// The Adam parameters of step `step` (from 1) of the node transforms.
    pub fn adam_params(&self, translation_rate: f32, rotation_rate: f32, step: u32) -> AdamParams {
        let rates = LearningRates {
            positions: translation_rate,
            log_scales: 0.0,
            rotations: rotation_rate,
            opacity_logits: 0.0,
            sh_dc: 0.0,
            sh_rest: 0.0,
        };
        AdamParams::new(&rates, step, self.nodes(), 0)
    }

    /// Makes room for `slots` steps in flight ([`Self::record_adam_from`]).
    pub fn reserve_step_slots(&mut self, slots: usize) -> GpuResult<()> {
        self.adam.reserve_slots(slots)
    }

    /// Sets the parameters ([`Self::adam_params`]) of the step recorded with ring slot `slot`;
    /// no submission that uses the slot may be on the queue.
    pub fn set_step(&self, slot: usize, adam: &AdamParams) {
        self.adam.set_step(slot, adam);
    }

    /// Records one Adam step of the node transforms with the parameters in ring slot `slot`
    /// when it runs: a step recorded once and replayed.
    pub fn record_adam_from<'a>(&'a self, rec: &mut Recorder<'a>, slot: usize) -> GpuResult<()> {
        self.adam.record_step_from(rec, &self.nodes, &self.node_grads, slot)
    }

    /// The ARAP energy summed since the last call (which restarts the sum).
    pub fn take_arap_loss(&self) -> GpuResult<f32> {
        Ok(self.loss_sum.take()?[0] as f32)
    }

    /// The node transforms and their last gradients, read back.
    pub fn read_nodes(&self) -> GpuResult<(NodeTransforms, NodeTransforms)> {
        let read = |b: &GaussianBuffers| -> GpuResult<NodeTransforms> {
            let t = b.positions.read()?;
            Ok(NodeTransforms {
                translations: t.chunks(3).map(|c| [c[0], c[1], c[2]].map(f64::from)).collect(),
                rotations: b.rotations.read()?.iter().map(|q| q.map(f64::from)).collect(),
            })
        };
        Ok((read(&self.nodes)?, read(&self.node_grads)?))
    }

    /// Replaces the node transforms (a starting pose, or a test's; Adam's moments are kept).
    pub fn write_nodes(&mut self, nodes: &NodeTransforms) -> GpuResult<()> {
        let t: Vec<f32> = nodes.translations.iter().flatten().map(|&v| v as f32).collect();
        self.nodes.positions.write(&t)?;
        self.nodes
            .rotations
            .write(&nodes.rotations.iter().map(|q| q.map(|v| v as f32)).collect::<Vec<_>>())
    }

    /// ARAP's weight per squared residual (for the reference).
    pub fn arap_scale(&self) -> f32 {
        self.push.arap_scale
    }
}
