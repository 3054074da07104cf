//! The deformation graph: its f64 reference against central finite differences, the GPU blend
//! and node gradients against the reference, and the GPU solver moving a surface onto a target
//! pose through node transforms alone, with validation on.

mod common;

use common::{gpu, rng};
use tagsplat::deform::reference::{arap_energy, blend, node_gradients};
use tagsplat::deform::{build_graph, DeformGraph, GraphDeformer, NodeTransforms};
use tagsplat::gpu::{GpuBuffer, Recorder};
use tagsplat::regularize::Neighbourhoods;
use tagsplat::rng::SplitMix64;
use tagsplat::splat::{GaussianBuffers, GaussianScene};
use tagsplat::synth::icosphere::icosphere;
use tagsplat::topology::{gaussians_from_mesh, InitConfig, ManifoldMesh};

/// A sphere's Gaussians and a graph of `nodes` nodes over it.
fn sphere(nodes: usize) -> (GaussianScene, DeformGraph) {
    let (p, f) = icosphere(2);
    let mesh = ManifoldMesh::new(p.iter().map(|p| p.map(|c| c as f32)).collect(), f).unwrap();
    let scene = gaussians_from_mesh(&mesh, &[], &InitConfig { sh_degree: 0, ..Default::default() });
    let nb = Neighbourhoods::from_mesh(&mesh);
    let graph = build_graph(&scene.positions, |i| nb.neighbours(i), nodes);
    (scene, graph)
}

/// Node transforms a little away from the identity (rotations not unit on purpose).
fn random_nodes(nodes: usize, r: &mut SplitMix64) -> NodeTransforms {
    let mut u = || r.next_f64() * 2.0 - 1.0;
    NodeTransforms {
        translations: (0..nodes).map(|_| [0.1 * u(), 0.1 * u(), 0.1 * u()]).collect(),
        rotations: (0..nodes).map(|_| [1.3 + 0.2 * u(), 0.2 * u(), 0.2 * u(), 0.2 * u()]).collect(),
    }
}

fn random_vectors(n: usize, r: &mut SplitMix64) -> Vec<[f64; 3]> {
    (0..n).map(|_| [r.next_f64() - 0.5, r.next_f64() - 0.5, r.next_f64() - 0.5]).collect()
}

/// E = Σ_i ⟨a_i, p_i⟩ + ARAP: the energy whose gradient `node_gradients` returns.
fn energy(
    scene: &GaussianScene,
    graph: &DeformGraph,
    nodes: &NodeTransforms,
    adjoint: &[[f64; 3]],
    c: f64,
) -> f64 {
    let (positions, _) = blend((&scene.positions, &scene.rotations), graph, nodes);
    positions.iter().zip(adjoint).map(|(p, a)| p[0] * a[0] + p[1] * a[1] + p[2] * a[2]).sum::<f64>()
        + arap_energy(&scene.positions, graph, nodes, c)
}

#[test]
fn reference_gradients_match_central_differences() {
    let (scene, graph) = sphere(24);
    let mut r = rng(3);
    let nodes = random_nodes(24, &mut r);
    let adjoint = random_vectors(scene.len(), &mut r);
    let c = 0.7;
    let (gt, gq, arap) = node_gradients(&scene.positions, &graph, &nodes, &adjoint, c);
    assert!((arap - arap_energy(&scene.positions, &graph, &nodes, c)).abs() < 1e-12);
    assert!(arap > 0.0);
    let h = 1e-6;
    for k in 0..24 {
        for a in 0..7 {
            let shifted = |delta: f64| {
                let mut n = nodes.clone();
                if a < 3 {
                    n.translations[k][a] += delta
                } else {
                    n.rotations[k][a - 3] += delta
                }
                energy(&scene, &graph, &n, &adjoint, c)
            };
            let numeric = (shifted(h) - shifted(-h)) / (2.0 * h);
            let analytic = if a < 3 { gt[k][a] } else { gq[k][a - 3] };
            assert!(
                (numeric - analytic).abs() < 1e-5 * (1.0 + numeric.abs()),
                "node {k} component {a}: {analytic} vs {numeric}"
            );
        }
    }
}

#[test]
fn gpu_matches_reference() {
    let test = gpu();
    let ctx = test.ctx();
    let (scene, graph) = sphere(40);
    let mut r = rng(5);
    let nodes = random_nodes(40, &mut r);
    let vertex_grads = random_vectors(scene.len(), &mut r);
    let mut deformer = GraphDeformer::new(ctx, &graph, &scene, 2.0).unwrap();
    deformer.write_nodes(&nodes).unwrap();
    let target = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let grads = GpuBuffer::from_slice(
        ctx,
        "vertex gradients",
        &vertex_grads.iter().flatten().map(|&v| v as f32).collect::<Vec<_>>(),
    )
    .unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    deformer.record_blend(&mut rec, &target).unwrap();
    deformer.record_gradients(&mut rec, &grads).unwrap();
    rec.submit_and_wait().unwrap();

    let (positions, rotations) = blend((&scene.positions, &scene.rotations), &graph, &nodes);
    let got = target.to_scene().unwrap();
    for i in 0..scene.len() {
        for (&x, want) in got.positions[i].iter().zip(positions[i]) {
            assert!((x as f64 - want).abs() < 1e-5, "vertex {i}");
        }
        for (&x, want) in got.rotations[i].iter().zip(rotations[i]) {
            assert!((x as f64 - want).abs() < 1e-5, "vertex {i} rotation");
        }
    }
    let (gt, gq, arap) = node_gradients(
        &scene.positions,
        &graph,
        &nodes,
        &vertex_grads,
        deformer.arap_scale() as f64,
    );
    let (_, node_grads) = deformer.read_nodes().unwrap();
    let scale = gt.iter().flatten().chain(gq.iter().flatten()).fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..40 {
        for (x, want) in node_grads.translations[k].iter().zip(gt[k]) {
            assert!((x - want).abs() < 1e-4 * scale, "node {k} translation");
        }
        for (x, want) in node_grads.rotations[k].iter().zip(gq[k]) {
            assert!((x - want).abs() < 1e-4 * scale, "node {k} rotation");
        }
    }
    let gpu_arap = deformer.take_arap_loss().unwrap() as f64;
    assert!((gpu_arap - arap).abs() < 1e-4 * arap.max(1e-6), "ARAP {gpu_arap} vs {arap}");
    assert_eq!(deformer.take_arap_loss().unwrap(), 0.0);
}

/// Node transforms alone carry the sphere onto a rotated and shifted copy of itself: the
/// gradient of ½‖p − target‖² goes through the node gradients and Adam, then the blend.
#[test]
fn solver_reaches_a_rigidly_moved_target() {
    let test = gpu();
    let ctx = test.ctx();
    let (scene, graph) = sphere(30);
    let motion = glam::Quat::from_rotation_z(0.3);
    let shift = glam::Vec3::new(0.2, -0.1, 0.05);
    let goal: Vec<glam::Vec3> =
        scene.positions.iter().map(|p| motion * glam::Vec3::from(*p) + shift).collect();
    let deformer = GraphDeformer::new(ctx, &graph, &scene, 1.0).unwrap();
    let target = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut grads = GpuBuffer::<f32>::new(ctx, "vertex gradients", 3 * scene.len()).unwrap();
    let error = |positions: &[[f32; 3]]| {
        positions
            .iter()
            .zip(&goal)
            .map(|(p, g)| (glam::Vec3::from(*p) - *g).length())
            .fold(0.0f32, f32::max)
    };
    let start = error(&scene.positions);
    for step in 1..=300 {
        let now = target.to_scene().unwrap();
        let g: Vec<f32> = now
            .positions
            .iter()
            .zip(&goal)
            .flat_map(|(p, t)| (glam::Vec3::from(*p) - *t).to_array())
            .collect();
        grads.write(&g).unwrap();
        let mut rec = Recorder::new(ctx).unwrap();
        deformer.record_gradients(&mut rec, &grads).unwrap();
        deformer.record_adam(&mut rec, 0.01, 0.01, step).unwrap();
        deformer.record_blend(&mut rec, &target).unwrap();
        rec.submit_and_wait().unwrap();
    }
    let end = error(&target.to_scene().unwrap().positions);
    assert!(
        end < 0.03 * start,
        "largest distance to the target: {start} at the start, {end} after 300 steps"
    );
}
