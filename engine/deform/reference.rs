//! f64 CPU reference of the deformation-graph kernels (shaders/deform/), what the tests
//! compare the GPU against and differentiate by central differences.

use super::graph::{DeformGraph, NODES_PER_VERTEX};
use crate::regularize::reference::{normalize_backward, rotation_backward};
use glam::{DMat3, DQuat, DVec3};

/// Node transforms: a translation and a (w, x, y, z) rotation, not necessarily unit, per node.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeTransforms {
    /// Per node, the translation t_k added after rotating about the node's rest position
    /// (scene units).
    pub translations: Vec<[f64; 3]>,
    /// Per node, the rotation R_k as a (w, x, y, z) quaternion; normalised where it is used.
    pub rotations: Vec<[f64; 4]>,
}

impl NodeTransforms {
    /// `nodes` identity transforms: zero translations and (1, 0, 0, 0) rotations.
    pub fn identity(nodes: usize) -> Self {
        Self { translations: vec![[0.0; 3]; nodes], rotations: vec![[1.0, 0.0, 0.0, 0.0]; nodes] }
    }
}

fn unit([w, x, y, z]: [f64; 4]) -> DQuat {
    let q = DQuat::from_xyzw(x, y, z, w);
    if q.length() > 0.0 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

fn rest_of(positions: &[[f32; 3]], graph: &DeformGraph, k: usize) -> DVec3 {
    DVec3::from(positions[graph.node_vertices[k] as usize].map(f64::from))
}

/// The blended pose (blend.comp): positions and unit rotations per vertex.
pub fn blend(
    rest: (&[[f32; 3]], &[[f32; 4]]),
    graph: &DeformGraph,
    nodes: &NodeTransforms,
) -> (Vec<[f64; 3]>, Vec<[f64; 4]>) {
    let (positions, rotations) = rest;
    let mut out = (Vec::new(), Vec::new());
    for (i, x) in positions.iter().enumerate() {
        let x = DVec3::from(x.map(f64::from));
        let (mut p, mut q) = (DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0));
        for s in 0..NODES_PER_VERTEX {
            let w = graph.bound_weights[i][s] as f64;
            if w > 0.0 {
                let k = graph.bound_nodes[i][s] as usize;
                let (g, qk) = (rest_of(positions, graph, k), unit(nodes.rotations[k]));
                p += w * (qk * (x - g) + g + DVec3::from(nodes.translations[k]));
                q += qk * w;
            }
        }
        let [w, qx, qy, qz] = rotations[i].map(f64::from);
        let r = if q.length() > 0.0 { q.normalize() } else { DQuat::IDENTITY }
            * DQuat::from_xyzw(qx, qy, qz, w);
        out.0.push(p.to_array());
        out.1.push([r.w, r.x, r.y, r.z]);
    }
    out
}

/// The as-rigid-as-possible energy c Σ_k Σ_{j∈N(k)} ‖R_k (g_j − g_k) + g_k + t_k − g_j − t_j‖².
pub fn arap_energy(rest: &[[f32; 3]], graph: &DeformGraph, nodes: &NodeTransforms, c: f64) -> f64 {
    let mut energy = 0.0;
    for k in 0..graph.node_vertices.len() {
        for j in neighbours(graph, k) {
            energy += c * residual(rest, graph, nodes, k, j).length_squared();
        }
    }
    energy
}

fn neighbours(graph: &DeformGraph, k: usize) -> impl Iterator<Item = usize> + '_ {
    let [start, count] = graph.neighbour_ranges[k];
    graph.neighbours[start as usize..(start + count) as usize].iter().map(|&j| j as usize)
}

fn residual(
    rest: &[[f32; 3]],
    graph: &DeformGraph,
    nodes: &NodeTransforms,
    k: usize,
    j: usize,
) -> DVec3 {
    let (gk, gj) = (rest_of(rest, graph, k), rest_of(rest, graph, j));
    unit(nodes.rotations[k]) * (gj - gk) + gk + DVec3::from(nodes.translations[k])
        - gj
        - DVec3::from(nodes.translations[j])
}

/// node_gradients.comp: per node, the gradient of Σ_i ⟨∂L/∂p_i, p_i⟩ (the vertex gradients
/// pulled back through the blend, rotations of vertices excluded) plus the ARAP energy's;
/// returns (translation gradients, rotation gradients, ARAP energy).
pub fn node_gradients(
    rest: &[[f32; 3]],
    graph: &DeformGraph,
    nodes: &NodeTransforms,
    grad_positions: &[[f64; 3]],
    c: f64,
) -> (Vec<[f64; 3]>, Vec<[f64; 4]>, f64) {
    let m = graph.node_vertices.len();
    let (mut gt, mut gr) = (vec![DVec3::ZERO; m], vec![DMat3::ZERO; m]);
    for (i, x) in rest.iter().enumerate() {
        let x = DVec3::from(x.map(f64::from));
        for s in 0..NODES_PER_VERTEX {
            let (k, w) = (graph.bound_nodes[i][s] as usize, graph.bound_weights[i][s] as f64);
            if w > 0.0 {
                let gp = w * DVec3::from(grad_positions[i]);
                gt[k] += gp;
                gr[k] += outer(gp, x - rest_of(rest, graph, k));
            }
        }
    }
    for k in 0..m {
        for j in neighbours(graph, k) {
            let d = rest_of(rest, graph, j) - rest_of(rest, graph, k);
            let (own, theirs) =
                (residual(rest, graph, nodes, k, j), residual(rest, graph, nodes, j, k));
            gt[k] += 2.0 * c * (own - theirs);
            gr[k] += outer(2.0 * c * own, d);
        }
    }
    let rotations = (0..m)
        .map(|k| {
            normalize_backward(nodes.rotations[k], rotation_backward(nodes.rotations[k], gr[k]))
                .to_array()
        })
        .collect();
    (gt.iter().map(|v| v.to_array()).collect(), rotations, arap_energy(rest, graph, nodes, c))
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}
