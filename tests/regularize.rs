//! Regularizers: the f64 reference against central finite differences, the GPU kernels against
//! the reference (values and gradients, added on top of existing gradients), and the GPU
//! gradient against central finite differences of the GPU loss, with validation on.

mod common;

use common::{gpu, rng};
use tagsplat::gpu::Recorder;
use tagsplat::regularize::reference::{evaluate, Params};
use tagsplat::regularize::{Neighbourhoods, RegularizeError, Regularizers, Temporal, Weights};
use tagsplat::rng::SplitMix64;
use tagsplat::splat::{GaussianBuffers, GaussianScene};
use tagsplat::synth::icosphere::icosphere;
use tagsplat::topology::shapes::grid;
use tagsplat::topology::{gaussians_from_mesh, InitConfig, ManifoldMesh};

/// A closed sphere and an open disk (boundary fans), each with a current and a previous frame:
/// initial Gaussians, then noise on positions (a fraction of an edge), rotations (unnormalised
/// on purpose) and log-scales. The sphere's vertices get stiffness in [0.1, 1], the disk's 1.
fn cases() -> Vec<(&'static str, Neighbourhoods, GaussianScene, GaussianScene)> {
    let (sp, sf) = icosphere(1);
    let sphere = ManifoldMesh::new(sp.iter().map(|p| p.map(|c| c as f32)).collect(), sf).unwrap();
    let (gp, gf) = grid(4, 3);
    let disk = ManifoldMesh::new(
        gp.iter().map(|p| [p[0] * 0.3, p[1] * 0.3, 0.05 * (p[0] * p[1]).sin()]).collect(),
        gf,
    )
    .unwrap();
    let (mut r, mut stiff) = (rng(11), rng(12));
    [("sphere", sphere), ("disk", disk)]
        .into_iter()
        .map(|(name, mesh)| {
            let mut nb = Neighbourhoods::from_mesh(&mesh);
            if name == "sphere" {
                nb.stiffness.iter_mut().for_each(|s| *s = 0.1 + 0.9 * stiff.next_f64() as f32);
            }
            let base =
                gaussians_from_mesh(&mesh, &[], &InitConfig { sh_degree: 0, ..Default::default() });
            let noise = 0.2 * nb.mean_edge_length;
            let current = perturb(&base, &mut r, noise);
            let previous = perturb(&base, &mut r, noise);
            (name, nb, current, previous)
        })
        .collect()
}

fn perturb(scene: &GaussianScene, r: &mut SplitMix64, noise: f32) -> GaussianScene {
    let mut s = scene.clone();
    let mut u = || r.next_f64() as f32 * 2.0 - 1.0;
    for p in &mut s.positions {
        p.iter_mut().for_each(|c| *c += noise * u());
    }
    for q in &mut s.rotations {
        let scale = 1.0 + 0.5 * u().abs();
        q.iter_mut().for_each(|c| *c = (*c + 0.2 * u()) * scale);
    }
    for l in &mut s.log_scales {
        l.iter_mut().for_each(|c| *c += 0.3 * u());
    }
    s
}

fn params(s: &GaussianScene) -> Params {
    Params {
        positions: s.positions.iter().map(|p| p.map(|c| c as f64)).collect(),
        log_scales: s.log_scales.iter().map(|p| p.map(|c| c as f64)).collect(),
        rotations: s.rotations.iter().map(|p| p.map(|c| c as f64)).collect(),
    }
}

/// Each term alone (weight 1.5; edge length and rigidity also with a Huber δ), then all at
/// their default weights, and with a δ.
fn weight_sets() -> Vec<(&'static str, Weights)> {
    let zero = Weights {
        scale_2d: 0.0,
        laplacian: 0.0,
        normal: 0.0,
        edge_length: 0.0,
        rigidity: 0.0,
        rotation: 0.0,
        lambda_w: 1.0,
        huber: 0.0,
    };
    vec![
        ("scale_2d", Weights { scale_2d: 1.5, ..zero }),
        ("laplacian", Weights { laplacian: 1.5, ..zero }),
        ("normal", Weights { normal: 1.5, ..zero }),
        ("edge_length", Weights { edge_length: 1.5, ..zero }),
        ("rigidity", Weights { rigidity: 1.5, ..zero }),
        ("rotation", Weights { rotation: 1.5, ..zero }),
        // δ near the residuals' size (noise of 0.2 edge lengths on both frames), so some are
        // below it and some beyond.
        ("edge_length huber", Weights { edge_length: 1.5, huber: 0.2, ..zero }),
        ("rigidity huber", Weights { rigidity: 1.5, huber: 0.2, ..zero }),
        ("all", Weights::default()),
        ("all huber", Weights { huber: 0.2, ..Weights::default() }),
    ]
}

fn weighted(l: &tagsplat::regularize::Losses<f64>, w: &Weights) -> f64 {
    let ws = [w.scale_2d, w.laplacian, w.normal, w.edge_length, w.rigidity, w.rotation];
    l.slots().iter().zip(ws).map(|(v, w)| v * w as f64).sum()
}

/// Every scalar parameter as (array, row, component) for finite differences.
fn coordinates(n: usize) -> Vec<(usize, usize, usize)> {
    (0..n)
        .flat_map(|i| {
            (0..3)
                .map(move |k| (0, i, k))
                .chain((0..3).map(move |k| (1, i, k)))
                .chain((0..4).map(move |k| (2, i, k)))
        })
        .collect()
}

fn coordinate(p: &mut Params, (array, i, k): (usize, usize, usize)) -> &mut f64 {
    match array {
        0 => &mut p.positions[i][k],
        1 => &mut p.log_scales[i][k],
        _ => &mut p.rotations[i][k],
    }
}

#[test]
fn reference_gradients_match_central_differences() {
    for (name, nb, current, previous) in cases() {
        let (x, prev) = (params(&current), params(&previous));
        for (term, w) in weight_sets() {
            let (_, grads) = evaluate(&nb, &x, Some(&prev), &w);
            let mut worst: f64 = 0.0;
            for c in coordinates(x.positions.len()) {
                let h = 1e-6;
                let mut plus = x.clone();
                *coordinate(&mut plus, c) += h;
                let mut minus = x.clone();
                *coordinate(&mut minus, c) -= h;
                let fd = (weighted(&evaluate(&nb, &plus, Some(&prev), &w).0, &w)
                    - weighted(&evaluate(&nb, &minus, Some(&prev), &w).0, &w))
                    / (2.0 * h);
                let analytic = *coordinate(&mut grads.clone(), c);
                let err = (fd - analytic).abs() / (1.0 + analytic.abs());
                worst = worst.max(err);
                assert!(
                    err < 1e-5,
                    "{name} {term} {c:?}: analytic {analytic}, central difference {fd}"
                );
            }
            assert!(worst.is_finite());
        }
    }
}

#[test]
fn temporal_terms_vanish_when_nothing_moved_and_need_a_previous_frame() {
    for (name, nb, current, _) in cases() {
        let x = params(&current);
        let (still, _) = evaluate(&nb, &x, Some(&x), &Weights::default());
        assert!(
            [still.edge_length, still.rigidity, still.rotation].iter().all(|&l| l < 1e-12),
            "{name}: {still:?}"
        );
        let (none, _) = evaluate(&nb, &x, None, &Weights::default());
        assert_eq!([none.edge_length, none.rigidity, none.rotation], [0.0; 3], "{name}");
        // A rigid motion of the whole frame: edge lengths and 1-ring rigidity are unchanged.
        let q = glam::DQuat::from_axis_angle(glam::DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let moved = Params {
            positions: x
                .positions
                .iter()
                .map(|p| {
                    (q * glam::DVec3::from_array(*p) + glam::DVec3::new(0.3, -0.1, 0.2)).to_array()
                })
                .collect(),
            log_scales: x.log_scales.clone(),
            rotations: x
                .rotations
                .iter()
                .map(|r| {
                    let m = q * glam::DQuat::from_xyzw(r[1], r[2], r[3], r[0]);
                    [m.w, m.x, m.y, m.z]
                })
                .collect(),
        };
        let (rigid, _) = evaluate(&nb, &moved, Some(&x), &Weights::default());
        assert!(rigid.edge_length < 1e-9 && rigid.rigidity < 1e-9, "{name}: {rigid:?}");
    }
}

/// Runs the kernels on `scene` with gradients starting at `initial`; returns losses and the
/// gradient buffers read back.
fn run_gpu(
    ctx: &std::sync::Arc<tagsplat::gpu::GpuContext>,
    reg: &Regularizers,
    scene: &GaussianScene,
    previous: &GaussianScene,
    w: &Weights,
    initial: f32,
) -> ([f32; 6], GaussianScene) {
    let params = GaussianBuffers::from_scene(ctx, scene).unwrap();
    let prev = GaussianBuffers::from_scene(ctx, previous).unwrap();
    let mut filled = scene.clone();
    filled.positions.iter_mut().flatten().for_each(|c| *c = initial);
    filled.log_scales.iter_mut().flatten().for_each(|c| *c = initial);
    filled.rotations.iter_mut().flatten().for_each(|c| *c = initial);
    let grads = GaussianBuffers::from_scene(ctx, &filled).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    reg.record(&mut rec, &params, &grads, w, Some(Temporal::of(&prev))).unwrap();
    rec.submit_and_wait().unwrap();
    (reg.read_losses().unwrap().slots(), grads.to_scene().unwrap())
}

#[test]
fn gpu_matches_the_reference_and_adds_to_existing_gradients() {
    let g = gpu();
    let mut reg = Regularizers::new(g.ctx()).unwrap();
    for (name, nb, current, previous) in cases() {
        reg.upload(&nb).unwrap();
        for (term, w) in weight_sets() {
            let (want, want_grads) = evaluate(&nb, &params(&current), Some(&params(&previous)), &w);
            let initial = 0.25;
            let (got, got_grads) = run_gpu(g.ctx(), &reg, &current, &previous, &w, initial);
            for (k, (g, r)) in got.iter().zip(want.slots()).enumerate() {
                assert!(
                    (*g as f64 - r).abs() <= 1e-4 * (1.0 + r.abs()),
                    "{name} {term} loss slot {k}: GPU {g}, reference {r}"
                );
            }
            let pairs = |a: &GaussianScene, b: &Params| -> Vec<(f64, f64)> {
                let gpu = a
                    .positions
                    .iter()
                    .flatten()
                    .chain(a.log_scales.iter().flatten())
                    .chain(a.rotations.iter().flatten());
                let cpu = b
                    .positions
                    .iter()
                    .flatten()
                    .chain(b.log_scales.iter().flatten())
                    .chain(b.rotations.iter().flatten());
                gpu.zip(cpu).map(|(g, c)| (*g as f64 - initial as f64, *c)).collect()
            };
            let all = pairs(&got_grads, &want_grads);
            let scale = all.iter().map(|(_, c)| c.abs()).fold(0.0, f64::max);
            for (idx, (g, c)) in all.iter().enumerate() {
                assert!(
                    (g - c).abs() <= 2e-4 * scale.max(1e-3),
                    "{name} {term} gradient {idx}: GPU {g}, reference {c} (scale {scale})"
                );
            }
        }
    }
}

#[test]
fn gpu_gradient_matches_central_differences_of_the_gpu_loss() {
    let g = gpu();
    let mut reg = Regularizers::new(g.ctx()).unwrap();
    for (name, nb, current, previous) in cases() {
        reg.upload(&nb).unwrap();
        let w = Weights::default();
        let ws = [w.scale_2d, w.laplacian, w.normal, w.edge_length, w.rigidity, w.rotation];
        let total = |scene: &GaussianScene| {
            run_gpu(g.ctx(), &reg, scene, &previous, &w, 0.0)
                .0
                .iter()
                .zip(ws)
                .map(|(l, w)| (*l * w) as f64)
                .sum::<f64>()
        };
        let (_, grads) = run_gpu(g.ctx(), &reg, &current, &previous, &w, 0.0);
        let h = 1e-2 * nb.mean_edge_length;
        // A few vertices, every parameter of each.
        for i in [0usize, 5, 9] {
            for k in 0..10 {
                let bump = |s: &mut GaussianScene, d: f32| match k {
                    0..=2 => s.positions[i][k] += d,
                    3..=5 => s.log_scales[i][k - 3] += d,
                    _ => s.rotations[i][k - 6] += d,
                };
                let step = if k < 3 { h } else { 1e-2 };
                let (mut plus, mut minus) = (current.clone(), current.clone());
                bump(&mut plus, step);
                bump(&mut minus, -step);
                let fd = (total(&plus) - total(&minus)) / (2.0 * step as f64);
                let analytic = match k {
                    0..=2 => grads.positions[i][k],
                    3..=5 => grads.log_scales[i][k - 3],
                    _ => grads.rotations[i][k - 6],
                } as f64;
                assert!((fd - analytic).abs() <= 0.03 * analytic.abs() + 2e-3, "{name} vertex {i} parameter {k}: GPU gradient {analytic}, central difference {fd}");
            }
        }
    }
}

#[test]
fn mismatched_buffers_are_refused() {
    let g = gpu();
    let mut reg = Regularizers::new(g.ctx()).unwrap();
    let cases = cases();
    let (_, nb, current, _) = &cases[0];
    let (_, _, other, _) = &cases[1];
    reg.upload(nb).unwrap();
    let params = GaussianBuffers::from_scene(g.ctx(), current).unwrap();
    let wrong = GaussianBuffers::from_scene(g.ctx(), other).unwrap();
    let mut rec = Recorder::new(g.ctx()).unwrap();
    let err = reg.record(&mut rec, &params, &wrong, &Weights::default(), None).unwrap_err();
    assert!(matches!(err, RegularizeError::Shape(_)), "{err}");
    assert!(err.to_string().contains("gradients"), "{err}");
    drop(rec);
}
