//! GPU splatting against the f64 CPU reference (`tagsplat::splat::reference`), on lavapipe with
//! validation on: projection and binning, forward images, gradients of every parameter, and
//! the hard cases.

mod common;

use glam::DVec3;
use std::sync::Arc;
use tagsplat::bench::random_scene;
use tagsplat::camera::Camera;
use tagsplat::gpu::{GpuBuffer, GpuContext, Recorder};
use tagsplat::rng::SplitMix64;
use tagsplat::splat::{reference, GaussianBuffers, GaussianScene, RenderSettings, Splatter};

/// A camera at a random direction, 3–4.5 from the origin, looking at it.
fn random_camera(rng: &mut SplitMix64, width: u32, height: u32) -> Camera {
    let mut u = || rng.next_f64();
    let direction = DVec3::new(u() - 0.5, 0.6 * (u() - 0.5), u() - 0.5).normalize();
    let eye = direction * (3.0 + 1.5 * u());
    let f = width.max(height) as f64 * (0.9 + 0.6 * u());
    let (cx, cy) = (width as f64 * (0.4 + 0.2 * u()), height as f64 * (0.4 + 0.2 * u()));
    Camera::look_at(width, height, f, f * (0.95 + 0.1 * u()), cx, cy, eye, DVec3::ZERO, DVec3::Y)
        .unwrap()
}

struct GpuRender {
    rgba: Vec<[f32; 4]>,
    depth: Vec<f32>,
}

fn render(
    ctx: &Arc<GpuContext>,
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
) -> GpuRender {
    let buffers = GaussianBuffers::from_scene(ctx, scene).unwrap();
    let mut splatter = Splatter::new(ctx).unwrap();
    splatter.forward(&buffers, camera, settings).unwrap();
    GpuRender { rgba: splatter.read_rgba().unwrap(), depth: splatter.read_depth().unwrap() }
}

/// Largest |GPU − reference| over colour and alpha; depth compared relative to its value.
fn assert_matches_reference(gpu: &GpuRender, reference: &reference::Image, what: &str) {
    let mut worst = 0.0f64;
    for (p, rgba) in gpu.rgba.iter().enumerate() {
        let expected = [
            reference.color[p][0],
            reference.color[p][1],
            reference.color[p][2],
            reference.alpha[p],
        ];
        for c in 0..4 {
            worst = worst.max((rgba[c] as f64 - expected[c]).abs());
        }
        let depth_error = (gpu.depth[p] as f64 - reference.depth[p]).abs();
        assert!(
            depth_error <= 1e-4 * reference.depth[p].abs().max(1.0),
            "{what}: depth at pixel {p}: {} vs {}",
            gpu.depth[p],
            reference.depth[p]
        );
    }
    assert!(worst <= 1e-4, "{what}: max colour/alpha error {worst:.2e}");
}

#[test]
fn forward_matches_reference() {
    let gpu = common::gpu();
    let mut rng = common::rng(1);
    let sizes = [(67, 33), (16, 16), (40, 57)];
    for (case, &(width, height)) in sizes.iter().enumerate() {
        for degree in 0..=3 {
            let scene = random_scene(60 + 40 * case, degree, rng.next_u64());
            let camera = random_camera(&mut rng, width, height);
            let settings = RenderSettings {
                background: [0.1, 0.5, 0.9],
                sh_degree: degree,
                ..Default::default()
            };
            let what = format!("{width}x{height}, SH degree {degree}");
            assert_matches_reference(
                &render(gpu.ctx(), &scene, &camera, &settings),
                &reference::render(&scene, &camera, &settings),
                &what,
            );
        }
    }
}

#[test]
fn mask_mode_and_lower_active_degree_match_reference() {
    let gpu = common::gpu();
    let mut rng = common::rng(2);
    let scene = random_scene(80, 3, 7);
    let camera = random_camera(&mut rng, 50, 37);
    for settings in [
        RenderSettings { mask_mode: true, ..Default::default() },
        RenderSettings { sh_degree: 1, background: [1.0; 3], ..Default::default() },
    ] {
        let what = format!("{settings:?}");
        assert_matches_reference(
            &render(gpu.ctx(), &scene, &camera, &settings),
            &reference::render(&scene, &camera, &settings),
            &what,
        );
    }
}

#[test]
fn projection_and_binning_match_reference() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let mut rng = common::rng(3);
    let scene = random_scene(300, 2, 11);
    let camera = random_camera(&mut rng, 93, 71);
    let settings = RenderSettings::default();
    let buffers = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut splatter = Splatter::new(ctx).unwrap();
    splatter.forward(&buffers, &camera, &settings).unwrap();
    let splats = splatter.read_splats().unwrap();
    let mut expected_intersections = 0;
    for (i, splat) in splats.iter().enumerate() {
        let Some(p) = reference::project(&scene, &camera, &settings, i) else {
            assert!(
                splat.touches_no_tile(),
                "Gaussian {i} is culled by the reference but not on the GPU"
            );
            continue;
        };
        let close = |a: f32, b: f64, scale: f64| (a as f64 - b).abs() <= 1e-4 * scale.max(b.abs());
        assert!(
            close(splat.mean[0], p.mean[0], 100.0) && close(splat.mean[1], p.mean[1], 100.0),
            "mean of {i}"
        );
        assert!(
            close(splat.depth, p.depth, 1.0) && close(splat.opacity, p.opacity, 1.0),
            "depth/opacity of {i}"
        );
        let conic_scale = p.conic.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        for c in 0..3 {
            assert!(
                close(splat.conic[c], p.conic[c], conic_scale),
                "conic of {i}: {:?} vs {:?}",
                splat.conic,
                p.conic
            );
            assert!(close(splat.color[c], p.color[c], 1.0), "colour of {i}");
        }
        expected_intersections += reference::tiles_touched(&p, camera.width, camera.height).len();
    }
    assert_eq!(splatter.intersections().unwrap(), expected_intersections);
}

/// The rasterizer's walk order, from 32-bit keys of tile and quantized depth: every visible
/// Gaussian's reference tiles appear once each (and at most 1 in 10 000 more, rounding at a
/// footprint's edge); within a tile, depth order wherever two depths
/// are more than one quantization step apart (1 << shift in float bits, the shift that fits the
/// frame's depth span into 32 − tile bits), and Gaussian index order among equal depths. At
/// 1920 × 1080 over depths 0.02–5000 (18 octaves: the widest span the default near and far
/// allow, and 19 depth bits), with exact duplicates and a pair 2 ulps apart.
#[test]
fn intersections_walk_by_tile_then_depth() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let mut rng = common::rng(17);
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    let add = |scene: &mut GaussianScene, d: f32, x: f32, y: f32| {
        scene.positions.push([x * d, y * d, d]);
        scene.log_scales.push([(0.02 * d).ln(); 3]);
        scene.rotations.push([1.0, 0.0, 0.0, 0.0]);
        scene.opacity_logits.push(1.0);
        scene.sh.extend([0.5, 0.2, -0.3]);
    };
    for _ in 0..3000 {
        let d = (0.02f64 * 250_000f64.powf(rng.next_f64())) as f32;
        let (x, y) = (0.8 * (rng.next_f64() - 0.5), 0.45 * (rng.next_f64() - 0.5));
        add(&mut scene, d, x as f32, y as f32);
    }
    for d in [3.0, 3.0, 3.0, 3.0, 3.0, f32::from_bits(3.0f32.to_bits() + 2)] {
        add(&mut scene, d, 0.01, 0.01);
    }
    let (width, height) = (1920, 1080);
    let f = width as f64;
    let (cx, cy) = (width as f64 / 2.0, height as f64 / 2.0);
    let camera =
        Camera::look_at(width, height, f, f, cx, cy, DVec3::ZERO, DVec3::Z, DVec3::NEG_Y).unwrap();
    let settings = RenderSettings { sh_degree: 0, ..Default::default() };
    let buffers = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut splatter = Splatter::renderer(ctx).unwrap();
    splatter.forward(&buffers, &camera, &settings).unwrap();
    let splats = splatter.read_splats().unwrap();
    let walk = splatter.read_intersections().unwrap();

    let mut expected = Vec::new();
    for i in 0..scene.len() {
        if let Some(p) = reference::project(&scene, &camera, &settings, i) {
            let tiles = reference::tiles_touched(&p, width, height);
            expected.extend(tiles.into_iter().map(|t| [t, i as u32]));
        }
    }
    let mut got = walk.clone();
    got.sort_unstable();
    got.dedup();
    assert_eq!(got.len(), walk.len(), "an intersection walked twice");
    expected.sort_unstable();
    let missing: Vec<_> = expected.iter().filter(|t| got.binary_search(t).is_err()).collect();
    assert!(missing.is_empty(), "reference intersections not walked: {missing:?}");
    // f32 against f64 on the edge of a footprint: the GPU keeps a few tiles the reference drops
    // (6 of 680 000 here).
    assert!(
        got.len() - expected.len() <= expected.len() / 10_000,
        "{} extra",
        got.len() - expected.len()
    );

    let bits = |id: u32| splats[id as usize].depth.to_bits();
    let visible = || walk.iter().map(|&[_, id]| bits(id));
    let span = visible().max().unwrap() - visible().min().unwrap();
    let tiles = width.div_ceil(16) * height.div_ceil(16);
    let depth_bits = 32 - (u32::BITS - tiles.leading_zeros());
    let shift = (u32::BITS - span.leading_zeros()).saturating_sub(depth_bits);
    assert!(span > 1 << 26 && depth_bits == 19 && shift <= 9, "span {span}, shift {shift}");
    for pair in walk.windows(2).filter(|w| w[0][0] == w[1][0]) {
        let ([tile, a], [_, b]) = (pair[0], pair[1]);
        let (da, db) = (bits(a), bits(b));
        assert!(
            da < db + (1 << shift) && (da != db || a < b),
            "tile {tile}: Gaussian {a} (depth {}) walked before {b} (depth {})",
            f32::from_bits(da),
            f32::from_bits(db)
        );
    }
    let twins: Vec<u32> = walk.iter().filter(|w| w[1] >= 3000).map(|w| w[1]).collect();
    assert!(twins.len() >= 6 && twins.windows(2).all(|w| w[0] < w[1] || w[1] == 3000));
}

/// Random per-pixel loss gradients, the same on both sides.
struct LossGradients {
    color: Vec<[f64; 3]>,
    alpha: Vec<f64>,
    depth: Vec<f64>,
}

fn random_loss_gradients(rng: &mut SplitMix64, pixels: usize) -> LossGradients {
    let mut u = || rng.next_f64() - 0.5;
    LossGradients {
        color: (0..pixels).map(|_| [u(), u(), u()]).collect(),
        alpha: (0..pixels).map(|_| u()).collect(),
        depth: (0..pixels).map(|_| 0.1 * u()).collect(),
    }
}

/// GPU gradients as a host scene (every parameter kind in its usual array).
fn gpu_gradients(
    ctx: &Arc<GpuContext>,
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
    loss: &LossGradients,
) -> (GaussianScene, Vec<[f32; 2]>) {
    let buffers = GaussianBuffers::from_scene(ctx, scene).unwrap();
    let grads = GaussianBuffers::shaped_like(ctx, &buffers).unwrap();
    let stats =
        GpuBuffer::from_slice(ctx, "densify stats", &vec![[0.0f32; 2]; scene.len()]).unwrap();
    let rgba: Vec<[f32; 4]> = loss
        .color
        .iter()
        .zip(&loss.alpha)
        .map(|(c, &a)| [c[0] as f32, c[1] as f32, c[2] as f32, a as f32])
        .collect();
    let depth: Vec<f32> = loss.depth.iter().map(|&d| d as f32).collect();
    let grad_rgba = GpuBuffer::from_slice(ctx, "colour gradients", &rgba).unwrap();
    let grad_depth = GpuBuffer::from_slice(ctx, "depth gradients", &depth).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    grads.record_zero(&mut rec);
    rec.submit_and_wait().unwrap();
    let mut splatter = Splatter::new(ctx).unwrap();
    splatter.forward(&buffers, camera, settings).unwrap();
    splatter.backward(&buffers, &grad_rgba, &grad_depth, &grads, &stats).unwrap();
    (grads.to_scene().unwrap(), stats.read().unwrap())
}

/// Compares one parameter kind: |GPU − reference| ≤ 1e-3·|reference| where the reference is not
/// tiny (above 1e-2 of the largest of its kind); the tiny ones, sums of larger terms that
/// cancel in f32, within 5e-5 of that largest.
fn assert_gradients_close(kind: &str, gpu: &[f32], expected: &[f64]) {
    assert_eq!(gpu.len(), expected.len(), "{kind}: lengths");
    let largest = expected.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    assert!(
        largest > 0.0,
        "{kind}: the reference gradient is zero everywhere, the test would prove nothing"
    );
    for (i, (&g, &e)) in gpu.iter().zip(expected).enumerate() {
        let error = (g as f64 - e).abs();
        let allowed = if e.abs() > 1e-2 * largest { 1e-3 * e.abs() } else { 5e-5 * largest };
        assert!(
            error <= allowed,
            "{kind}[{i}]: GPU {g:e} vs reference {e:e} (largest {largest:e})"
        );
    }
}

fn check_gradients(
    ctx: &Arc<GpuContext>,
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
    rng: &mut SplitMix64,
) {
    let pixels = (camera.width * camera.height) as usize;
    let loss = random_loss_gradients(rng, pixels);
    let (gpu, stats) = gpu_gradients(ctx, scene, camera, settings, &loss);
    let expected =
        reference::backward(scene, camera, settings, &loss.color, &loss.alpha, &loss.depth);
    let flat3 = |rows: &[[f64; 3]]| rows.iter().flatten().copied().collect::<Vec<f64>>();
    assert_gradients_close("positions", &gpu.positions.concat(), &flat3(&expected.positions));
    assert_gradients_close("log_scales", &gpu.log_scales.concat(), &flat3(&expected.log_scales));
    assert_gradients_close("rotations", &gpu.rotations.concat(), &expected.rotations.concat());
    if !settings.mask_mode {
        assert_gradients_close("opacity_logits", &gpu.opacity_logits, &expected.opacity_logits);
        let active = tagsplat::splat::sh_coefficients(settings.sh_degree.min(scene.sh_degree)) * 3;
        let per = scene.coefficients() * 3;
        let pick = |all: Vec<f64>| {
            all.chunks(per).flat_map(|c| c[..active].to_vec()).collect::<Vec<f64>>()
        };
        let gpu_sh: Vec<f64> = gpu.sh.iter().map(|&g| g as f64).collect();
        let gpu_sh: Vec<f32> = pick(gpu_sh).into_iter().map(|g| g as f32).collect();
        assert_gradients_close("sh", &gpu_sh, &pick(expected.sh.clone()));
    }
    // Every Gaussian with any positional gradient was on screen at least once.
    for (i, s) in stats.iter().enumerate() {
        assert!(s[1] <= 1.0 && s[0].is_finite(), "stats of {i}: {s:?}");
    }
}

#[test]
fn gradients_match_reference() {
    let gpu = common::gpu();
    let mut rng = common::rng(4);
    for degree in [0, 1, 3] {
        let scene = random_scene(40, degree, rng.next_u64());
        let camera = random_camera(&mut rng, 47, 35);
        let settings =
            RenderSettings { background: [0.3, 0.2, 0.7], sh_degree: degree, ..Default::default() };
        check_gradients(gpu.ctx(), &scene, &camera, &settings, &mut rng);
    }
    let scene = random_scene(40, 2, 99);
    let camera = random_camera(&mut rng, 33, 40);
    check_gradients(
        gpu.ctx(),
        &scene,
        &camera,
        &RenderSettings { mask_mode: true, ..Default::default() },
        &mut rng,
    );
}

/// A single Gaussian scene with default parameters, to be edited by each hard case.
fn one_gaussian(position: [f32; 3], log_scale: [f32; 3]) -> GaussianScene {
    GaussianScene {
        positions: vec![position],
        log_scales: vec![log_scale],
        rotations: vec![[1.0, 0.0, 0.0, 0.0]],
        opacity_logits: vec![3.0],
        sh: vec![0.5, -0.2, 0.1],
        sh_degree: 0,
    }
}

fn front_camera(width: u32, height: u32) -> Camera {
    let f = 1.2 * width as f64;
    Camera::look_at(
        width,
        height,
        f,
        f,
        width as f64 / 2.0,
        height as f64 / 2.0,
        DVec3::new(0.0, 0.0, -4.0),
        DVec3::ZERO,
        DVec3::Y,
    )
    .unwrap()
}

#[test]
fn empty_and_single_gaussian_scenes() {
    let gpu = common::gpu();
    let camera = front_camera(67, 33);
    let settings = RenderSettings { background: [0.25, 0.5, 0.75], ..Default::default() };
    let empty = GaussianScene::default();
    let image = render(gpu.ctx(), &empty, &camera, &settings);
    assert!(
        image.rgba.iter().all(|p| *p == [0.25, 0.5, 0.75, 0.0])
            && image.depth.iter().all(|&d| d == 0.0)
    );
    let single = one_gaussian([0.1, -0.05, 0.2], [-1.5; 3]);
    assert_matches_reference(
        &render(gpu.ctx(), &single, &camera, &settings),
        &reference::render(&single, &camera, &settings),
        "one Gaussian",
    );
}

/// A render-only splatter renders what a training one does, bit for bit, and refuses a
/// backward with an error rather than touching buffers it never allocated.
#[test]
fn a_renderer_renders_the_same_and_refuses_a_backward() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let scene = random_scene(200, 1, 4);
    let camera = front_camera(40, 24);
    let settings = RenderSettings { sh_degree: 1, ..Default::default() };
    let buffers = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut renderer = Splatter::renderer(ctx).unwrap();
    renderer.forward(&buffers, &camera, &settings).unwrap();
    let trained = render(ctx, &scene, &camera, &settings);
    assert_eq!(renderer.read_rgba().unwrap(), trained.rgba);
    let grads = GaussianBuffers::shaped_like(ctx, &buffers).unwrap();
    let pixels = camera.width as usize * camera.height as usize;
    let grad_rgba = GpuBuffer::from_slice(ctx, "grad rgba", &vec![[0.0f32; 4]; pixels]).unwrap();
    let grad_depth = GpuBuffer::from_slice(ctx, "grad depth", &vec![0.0f32; pixels]).unwrap();
    let stats = GpuBuffer::from_slice(ctx, "stats", &vec![[0.0f32; 2]; scene.len()]).unwrap();
    let refused = renderer.backward(&buffers, &grad_rgba, &grad_depth, &grads, &stats);
    assert!(matches!(refused, Err(tagsplat::splat::SplatError::RenderOnly)), "{refused:?}");
}

/// Hard cases: each scene renders finite pixels that match the reference, and gradients stay
/// finite.
#[test]
fn hard_cases_stay_finite_and_match_reference() {
    let gpu = common::gpu();
    let mut rng = common::rng(5);
    let camera = front_camera(48, 40);
    let settings = RenderSettings::default();
    let near = settings.near;
    // The camera sits at z = -4, so view depth is z + 4.
    let cases: Vec<(&str, GaussianScene)> = vec![
        ("behind the camera", one_gaussian([0.0, 0.0, -5.0], [-1.0; 3])),
        ("exactly on the near plane", one_gaussian([0.0, 0.0, -4.0 + near], [-1.0; 3])),
        ("just past the near plane", one_gaussian([0.0, 0.0, -4.0 + near * 1.001], [-3.0; 3])),
        ("far off screen", one_gaussian([1e4, -3e4, 5.0], [-1.0; 3])),
        ("needle 1e6", one_gaussian([0.0, 0.0, 0.0], [0.0, -13.8, -13.8])),
        ("sheet 1e6", one_gaussian([0.2, 0.1, 0.0], [0.0, 0.0, -13.8])),
        ("sub-pixel", one_gaussian([0.01, 0.02, 0.0], [-9.0; 3])),
        ("covers the whole image", one_gaussian([0.0, 0.0, 0.0], [3.0; 3])),
        (
            "zero quaternion",
            GaussianScene { rotations: vec![[0.0; 4]], ..one_gaussian([0.0; 3], [-1.0; 3]) },
        ),
        (
            "denormal quaternion",
            GaussianScene {
                rotations: vec![[1e-40, 0.0, 1e-41, 0.0]],
                ..one_gaussian([0.0; 3], [-1.0; 3])
            },
        ),
        (
            "tiny normal quaternion",
            GaussianScene {
                rotations: vec![[3e-30, 1e-30, 0.0, 2e-30]],
                ..one_gaussian([0.0; 3], [-1.0; 3])
            },
        ),
        (
            "opacity logit +50",
            GaussianScene { opacity_logits: vec![50.0], ..one_gaussian([0.0; 3], [-1.0; 3]) },
        ),
        (
            "opacity logit -50",
            GaussianScene { opacity_logits: vec![-50.0], ..one_gaussian([0.0; 3], [-1.0; 3]) },
        ),
    ];
    for (what, scene) in cases {
        let image = render(gpu.ctx(), &scene, &camera, &settings);
        assert!(
            image.rgba.iter().flatten().chain(&image.depth).all(|v| v.is_finite()),
            "{what}: non-finite output"
        );
        assert_matches_reference(&image, &reference::render(&scene, &camera, &settings), what);
        let pixels = (camera.width * camera.height) as usize;
        let loss = random_loss_gradients(&mut rng, pixels);
        let (grads, _) = gpu_gradients(gpu.ctx(), &scene, &camera, &settings, &loss);
        let all = grads
            .positions
            .concat()
            .into_iter()
            .chain(grads.log_scales.concat())
            .chain(grads.rotations.concat())
            .chain(grads.opacity_logits)
            .chain(grads.sh);
        assert!(all.into_iter().all(f32::is_finite), "{what}: non-finite gradient");
    }
}

/// A Gaussian with a NaN or an infinity is skipped: its neighbours' pixels and gradients are
/// exactly those of the scene without it.
#[test]
fn non_finite_gaussian_never_poisons_neighbours() {
    let gpu = common::gpu();
    let mut rng = common::rng(6);
    let camera = front_camera(40, 32);
    let settings = RenderSettings::default();
    let clean = random_scene(30, 1, 5);
    let loss = random_loss_gradients(&mut rng, 40 * 32);
    let clean_image = render(gpu.ctx(), &clean, &camera, &settings);
    let (clean_grads, _) = gpu_gradients(gpu.ctx(), &clean, &camera, &settings, &loss);
    type Poison = fn(&mut GaussianScene, usize);
    let poisons: [(&str, Poison); 5] = [
        ("NaN position", |s, i| s.positions[i][1] = f32::NAN),
        ("infinite log-scale", |s, i| s.log_scales[i][0] = f32::INFINITY),
        ("NaN rotation", |s, i| s.rotations[i][3] = f32::NAN),
        ("NaN opacity", |s, i| s.opacity_logits[i] = f32::NAN),
        ("infinite SH", |s, i| s.sh[i * 12 + 2] = f32::NEG_INFINITY),
    ];
    for (what, poison) in poisons {
        // A copy of Gaussian 3, appended (so the clean ones keep their indices), then poisoned.
        let mut scene = clean.clone();
        scene.positions.push(clean.positions[3]);
        scene.log_scales.push(clean.log_scales[3]);
        scene.rotations.push(clean.rotations[3]);
        scene.opacity_logits.push(4.0);
        scene.sh.extend_from_slice(&clean.sh[3 * 12..4 * 12]);
        let last = clean.len();
        poison(&mut scene, last);
        let image = render(gpu.ctx(), &scene, &camera, &settings);
        assert_eq!(image.rgba, clean_image.rgba, "{what}: pixels changed");
        let (grads, _) = gpu_gradients(gpu.ctx(), &scene, &camera, &settings, &loss);
        // Float atomics add in any order, so equal up to rounding.
        let same = |a: &[f32], b: &[f32]| {
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-5 * (1.0 + y.abs()))
        };
        assert!(
            same(&grads.positions[..last].concat(), &clean_grads.positions.concat()),
            "{what}: gradients changed"
        );
        assert!(same(&grads.sh[..clean.sh.len()], &clean_grads.sh), "{what}: SH gradients changed");
        assert!(
            grads.positions[last].iter().all(|&g| g == 0.0),
            "{what}: the skipped Gaussian got a gradient"
        );
    }
}

#[test]
fn tens_of_thousands_stacked_in_one_tile() {
    let gpu = common::gpu();
    let camera = front_camera(32, 32);
    let n = 30_000;
    let mut rng = common::rng(7);
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    for i in 0..n {
        let jitter = (rng.next_f64() as f32 - 0.5) * 0.01;
        scene.positions.push([-0.3 + jitter, -0.3 - jitter, 1.0 - i as f32 * 1e-5]);
        scene.log_scales.push([-4.5; 3]);
        scene.rotations.push([1.0, 0.0, 0.0, 0.0]);
        scene.opacity_logits.push(-4.0); // o ≈ 0.018: thousands are needed before T runs out
        scene.sh.extend_from_slice(&[0.3, (i % 7) as f32 * 0.1, -0.1]);
    }
    let settings = RenderSettings::default();
    let image = render(gpu.ctx(), &scene, &camera, &settings);
    assert_matches_reference(
        &image,
        &reference::render(&scene, &camera, &settings),
        "30 000 stacked Gaussians",
    );
}

/// More Gaussians in one tile than lavapipe lets one loop walk one at a time (65 535
/// iterations per invocation, then loops end silently), none saturating its pixel: each
/// sub-pixel Gaussian sits on one pixel centre, 200–310 per pixel at opacity 0.006, so every
/// pixel walks the whole tile. 48 000 is the longest walk the backward takes one Gaussian per
/// iteration on lavapipe (6000 chunks of 8; 52 400 failed), 80 000 takes the unrolled walk. The forward and
/// the gradients must match the reference all the same.
#[test]
fn past_the_loop_limit_in_one_tile() {
    for n in [48_000, 80_000] {
        check_one_deep_tile(n);
    }
}

fn check_one_deep_tile(n: usize) {
    let gpu = common::gpu();
    let camera = front_camera(16, 16);
    let mut rng = common::rng(8);
    let mut scene = GaussianScene { sh_degree: 0, ..Default::default() };
    let opacity: f64 = 0.006;
    for i in 0..n {
        let pixel = i % 256;
        let (origin, direction) =
            camera.pixel_ray((pixel % 16) as f64 + 0.5, (pixel / 16) as f64 + 0.5);
        let position = origin + direction * (3.0 + 2.0 * rng.next_f64());
        scene.positions.push(position.as_vec3().to_array());
        scene.log_scales.push([(0.002f32).ln(); 3]);
        scene.rotations.push([1.0, 0.0, 0.0, 0.0]);
        scene.opacity_logits.push((opacity / (1.0 - opacity)).ln() as f32);
        scene.sh.extend_from_slice(&[rng.next_f64() as f32 - 0.5, 0.2, (i % 5) as f32 * 0.1 - 0.2]);
    }
    let settings = RenderSettings::default();
    let image = render(gpu.ctx(), &scene, &camera, &settings);
    let what = format!("{n} unsaturated Gaussians in one tile");
    assert_matches_reference(&image, &reference::render(&scene, &camera, &settings), &what);

    let loss = random_loss_gradients(&mut rng, 16 * 16);
    let (grads, _) = gpu_gradients(gpu.ctx(), &scene, &camera, &settings, &loss);
    let expected =
        reference::backward(&scene, &camera, &settings, &loss.color, &loss.alpha, &loss.depth);
    let flat3 = |rows: &[[f64; 3]]| rows.iter().flatten().copied().collect::<Vec<f64>>();
    // f32 compositing 310 deep (transmittance recovered by division) leaves errors near 1e-4
    // of the largest gradient; a Gaussian the walk never reached is off by its whole gradient.
    // Log-scales and rotations of these isotropic sub-pixel Gaussians are rounding noise.
    let kinds = [
        ("positions", grads.positions.concat(), flat3(&expected.positions)),
        ("opacity_logits", grads.opacity_logits, expected.opacity_logits),
        ("sh", grads.sh, expected.sh),
    ];
    for (kind, gpu, expected) in kinds {
        let largest = expected.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        let worst =
            gpu.iter().zip(&expected).fold(0.0f64, |m, (&g, e)| m.max((g as f64 - e).abs()));
        assert!(
            largest > 0.0 && worst <= 1e-3 * largest,
            "{what}: {kind}: worst error {worst:e}, largest gradient {largest:e}"
        );
    }
}

/// The forward sizes its intersection buffers before counting; a scene that outgrows the
/// guess (a few screen-filling Gaussians: over a thousand intersections from 12 Gaussians) is
/// rendered again with room, and still matches the reference, count included.
#[test]
fn intersections_past_the_capacity_guess_render_again() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let camera = front_camera(256, 256);
    let settings = RenderSettings::default();
    let mut splatter = Splatter::new(ctx).unwrap();
    let small = one_gaussian([0.0; 3], [-3.0; 3]);
    splatter
        .forward(&GaussianBuffers::from_scene(ctx, &small).unwrap(), &camera, &settings)
        .unwrap();
    let mut big = GaussianScene { sh_degree: 0, ..Default::default() };
    for i in 0..12 {
        let one = one_gaussian([0.05 * i as f32 - 0.3, 0.0, -1.0 + 0.1 * i as f32], [0.7; 3]);
        big.positions.extend(one.positions);
        big.log_scales.extend(one.log_scales);
        big.rotations.extend(one.rotations);
        big.opacity_logits.extend(one.opacity_logits);
        big.sh.extend(one.sh);
    }
    let buffers = GaussianBuffers::from_scene(ctx, &big).unwrap();
    splatter.forward(&buffers, &camera, &settings).unwrap();
    let expected: usize = (0..big.len())
        .filter_map(|i| reference::project(&big, &camera, &settings, i))
        .map(|p| reference::tiles_touched(&p, 256, 256).len())
        .sum();
    assert!(
        expected > 1024,
        "the scene must outgrow the smallest capacity ({expected} intersections)"
    );
    assert_eq!(splatter.intersections().unwrap(), expected);
    let image =
        GpuRender { rgba: splatter.read_rgba().unwrap(), depth: splatter.read_depth().unwrap() };
    assert_matches_reference(
        &image,
        &reference::render(&big, &camera, &settings),
        "12 screen-filling Gaussians",
    );
}

#[test]
fn ply_round_trip_renders_identically() {
    let gpu = common::gpu();
    let mut rng = common::rng(8);
    let scene = random_scene(50, 3, 3);
    let path = std::env::temp_dir().join(format!("tagsplat-splat-{}.ply", std::process::id()));
    scene.write_ply(&path).unwrap();
    let back = GaussianScene::read_ply(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(back, scene);
    let camera = random_camera(&mut rng, 40, 30);
    let settings = RenderSettings::default();
    assert_eq!(
        render(gpu.ctx(), &back, &camera, &settings).rgba,
        render(gpu.ctx(), &scene, &camera, &settings).rgba
    );
}

/// `tagsplat render` writes the PNG, alpha and depth it is asked for (the depth equal to the
/// library's render of the same scene), with no validation message (the CLI fails on any),
/// and bad inputs get an error naming the file instead of a panic.
#[test]
fn render_cli_outputs_and_bad_inputs() {
    let gpu = common::gpu();
    let dir = std::env::temp_dir().join(format!("tagsplat-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (splats, camera, out) = (dir.join("scene.ply"), dir.join("cam.json"), dir.join("out.png"));
    random_scene(200, 3, 21).write_ply(&splats).unwrap();
    front_camera(61, 45).save_json(&camera).unwrap();
    let run = |args: &[&std::path::Path]| {
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"));
        command.arg("render").env("TAGSPLAT_VALIDATION", "1");
        let names = ["--splats", "--camera", "--out", "--depth", "--alpha"];
        for (name, path) in names.iter().zip(args) {
            command.arg(name).arg(path);
        }
        command.output().unwrap()
    };
    let (depth, alpha) = (dir.join("depth.exr"), dir.join("alpha.png"));
    let output = run(&[&splats, &camera, &out, &depth, &alpha]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let rgb = image::open(&out).unwrap().to_rgb8();
    assert_eq!(rgb.dimensions(), (61, 45));
    assert!(rgb.pixels().any(|p| p.0 != [0, 0, 0]), "nothing drawn");
    assert_eq!(image::open(&alpha).unwrap().to_luma8().dimensions(), (61, 45));
    let expected = render(
        gpu.ctx(),
        &GaussianScene::read_ply(&splats).unwrap(),
        &front_camera(61, 45),
        &RenderSettings::default(),
    );
    assert_eq!(read_depth_exr(&depth), expected.depth);
    assert!(expected.depth.iter().any(|&d| d > 0.0), "no depth drawn");

    // With the best-practices checks on, the layer has things to say: the CLI must fail.
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_tagsplat"));
    command.arg("render").env("TAGSPLAT_VALIDATION", "1");
    command.env("VK_LAYER_ENABLES", "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT");
    let output = command
        .args([
            "--splats".as_ref(),
            splats.as_os_str(),
            "--camera".as_ref(),
            camera.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("the Vulkan validation layer reported"), "{stderr}");

    let truncated = dir.join("truncated.ply");
    let bytes = std::fs::read(&splats).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let bent = dir.join("bent.json");
    std::fs::write(&bent, r#"{"width": 8, "height": 8, "fx": 8, "fy": 8, "cx": 4, "cy": 4, "world_to_camera": [1,0,0,0, 0.5,1,0,0, 0,0,1,4, 0,0,0,1]}"#).unwrap();
    for (args, named) in [([&truncated, &camera], &truncated), ([&splats, &bent], &bent)] {
        let output = run(&[args[0], args[1], &dir.join("never.png")]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains(&named.display().to_string()) && !stderr.contains("panicked"),
            "{stderr}"
        );
        assert!(!dir.join("never.png").exists());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The single "Z" channel of a depth EXR written by `tagsplat render`, in row order.
fn read_depth_exr(path: &std::path::Path) -> Vec<f32> {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path).unwrap();
    let channels = &image.layer_data.channel_data.list;
    assert_eq!(channels.len(), 1, "{}: one channel", path.display());
    channels[0].sample_data.values_as_f32().collect()
}

/// The walked-pair count `bench splat` measures the backward by. Gaussians that cover the whole
/// 64² image, each contributing at every pixel but too faint to use up the transmittance: every
/// pixel walks all of them, so there are 256 pairs per (tile, Gaussian) intersection and 40 × 16
/// intersections. Opaque ones stop each pixel early: fewer pairs.
#[test]
fn walked_pairs_count_each_pixel_of_each_intersection() {
    let g = common::gpu();
    let ctx = g.ctx();
    let camera = front_camera(64, 64);
    let settings = RenderSettings::default();
    for (opacity_logit, faint) in [(-3.0, true), (4.0, false)] {
        let mut scene = random_scene(40, 0, 3);
        scene.opacity_logits.iter_mut().for_each(|o| *o = opacity_logit);
        scene.log_scales.iter_mut().for_each(|s| *s = [3f32.ln(); 3]);
        let buffers = GaussianBuffers::from_scene(ctx, &scene).unwrap();
        let mut splatter = Splatter::new(ctx).unwrap();
        splatter.forward(&buffers, &camera, &settings).unwrap();
        let (pairs, intersections) =
            (splatter.walked_pairs().unwrap(), splatter.intersections().unwrap() as u64);
        assert_eq!(intersections, 40 * 16, "every Gaussian covers every tile");
        if faint {
            assert_eq!(pairs, 256 * intersections, "faint Gaussians: every pixel walks all");
        } else {
            assert!(
                pairs < 256 * intersections / 4,
                "{pairs} pairs, {intersections} intersections"
            );
        }
    }
}
