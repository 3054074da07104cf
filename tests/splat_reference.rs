//! The f64 splatting reference: its backward against central finite differences of its own
//! forward for every kind of parameter, hard cases against analytic values and brute force,
//! and the 3DGS PLY form.

use glam::{DMat4, DVec3, DVec4};
use std::path::PathBuf;
use tagsplat::camera::Camera;
use tagsplat::rng::SplitMix64;
use tagsplat::splat::reference::{
    backward, contributions, project, render, tiles_touched, Gradients, Image, Projected,
};
use tagsplat::splat::{
    sh_coefficients, GaussianScene, RenderSettings, ALPHA_MAX, ALPHA_MIN, TRANSMITTANCE_MIN,
};

// ---------------------------------------------------------------------------------------------
// Scenes, cameras and the loss.

fn uniform(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.next_f64()
}

/// A multiple of 2⁻¹² below 2⁸ in magnitude, so `x ± 2⁻¹⁶` is exact in f32: the scene stores
/// f32, and finite differences need steps that the f32 parameters take exactly.
fn grid(x: f64) -> f32 {
    ((x * 4096.0).round() / 4096.0) as f32
}

/// `n` overlapping Gaussians around the origin, anisotropic and rotated, some with opacities
/// above the 0.99 cap at their centre and some colour channels clamped at 0.
fn random_scene(rng: &mut SplitMix64, n: usize, sh_degree: u32) -> GaussianScene {
    let k = sh_coefficients(sh_degree);
    let mut scene = GaussianScene { sh_degree, ..Default::default() };
    for _ in 0..n {
        scene.positions.push([0; 3].map(|_| grid(uniform(rng, -0.8, 0.8))));
        scene.log_scales.push([0; 3].map(|_| grid(uniform(rng, 0.1, 0.45).ln())));
        let rotation = [0; 4].map(|_| uniform(rng, -1.0, 1.0));
        let rotation = if rotation.iter().map(|v| v * v).sum::<f64>() < 0.1 {
            [1.0, 0.2, -0.3, 0.1]
        } else {
            rotation
        };
        scene.rotations.push(rotation.map(grid));
        scene.opacity_logits.push(grid(uniform(rng, -1.5, 6.0)));
        for coefficient in 0..k {
            for _ in 0..3 {
                let value = if coefficient == 0 {
                    uniform(rng, -2.5, 1.5)
                } else {
                    uniform(rng, -0.5, 0.5)
                };
                scene.sh.push(grid(value));
            }
        }
    }
    scene
}

/// World to camera (OpenCV axes) for an eye looking at `target`, rolled by `roll` radians.
fn look_at(eye: DVec3, target: DVec3, roll: f64) -> DMat4 {
    let forward = (target - eye).normalize();
    let helper = if forward.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
    let right0 = forward.cross(helper).normalize();
    let down0 = forward.cross(right0);
    let (right, down) =
        (right0 * roll.cos() + down0 * roll.sin(), down0 * roll.cos() - right0 * roll.sin());
    let rotation = [right, down, forward];
    let row =
        |r: usize| DVec4::new(rotation[r].x, rotation[r].y, rotation[r].z, -rotation[r].dot(eye));
    DMat4::from_cols_array_2d(&[
        row(0).to_array(),
        row(1).to_array(),
        row(2).to_array(),
        [0.0, 0.0, 0.0, 1.0],
    ])
    .transpose()
}

/// A 20×13 camera 3.5 to 4.5 units from the origin, looking near it from a random direction.
fn random_camera(rng: &mut SplitMix64) -> Camera {
    let direction =
        DVec3::new(uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0))
            .normalize();
    let eye = direction * uniform(rng, 3.5, 4.5);
    let target =
        DVec3::new(uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1));
    Camera::new(20, 13, 19.0, 18.0, 10.3, 6.4, look_at(eye, target, uniform(rng, -3.0, 3.0)))
        .unwrap()
}

fn settings(mask_mode: bool, sh_degree: u32) -> RenderSettings {
    RenderSettings { background: [0.3, 0.55, 0.8], near: 0.5, far: 20.0, sh_degree, mask_mode }
}

/// `L = Σ w·colour + Σ w'·alpha + Σ w''·depth` with random weights.
struct Loss {
    color: Vec<[f64; 3]>,
    alpha: Vec<f64>,
    depth: Vec<f64>,
}

impl Loss {
    fn random(rng: &mut SplitMix64, pixels: usize) -> Self {
        Self {
            color: (0..pixels).map(|_| [0; 3].map(|_| uniform(rng, -1.0, 1.0))).collect(),
            alpha: (0..pixels).map(|_| uniform(rng, -1.0, 1.0)).collect(),
            depth: (0..pixels).map(|_| uniform(rng, -1.0, 1.0)).collect(),
        }
    }

    fn value(&self, image: &Image) -> f64 {
        let mut sum = 0.0;
        for p in 0..image.alpha.len() {
            sum += (0..3).map(|ch| self.color[p][ch] * image.color[p][ch]).sum::<f64>();
            sum += self.alpha[p] * image.alpha[p] + self.depth[p] * image.depth[p];
        }
        sum
    }

    fn gradients(
        &self,
        scene: &GaussianScene,
        camera: &Camera,
        settings: &RenderSettings,
    ) -> Gradients {
        backward(scene, camera, settings, &self.color, &self.alpha, &self.depth)
    }
}

// ---------------------------------------------------------------------------------------------
// Finite differences.

/// The kinds of stored parameter, SH split by band.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Kind {
    Position,
    LogScale,
    Rotation,
    OpacityLogit,
    ShBand(u32),
}

/// Every stored parameter: its kind, and how to reach it in a scene and in the gradients.
fn parameters(scene: &GaussianScene) -> Vec<(Kind, usize, usize)> {
    let mut out = Vec::new();
    for i in 0..scene.len() {
        out.extend((0..3).map(|a| (Kind::Position, i, a)));
        out.extend((0..3).map(|a| (Kind::LogScale, i, a)));
        out.extend((0..4).map(|a| (Kind::Rotation, i, a)));
        out.push((Kind::OpacityLogit, i, 0));
        for k in 0..scene.coefficients() {
            let band = (k as f64).sqrt() as u32;
            out.extend(
                (0..3).map(|ch| (Kind::ShBand(band), i, (i * scene.coefficients() + k) * 3 + ch)),
            );
        }
    }
    out
}

fn parameter(scene: &mut GaussianScene, (kind, i, a): (Kind, usize, usize)) -> &mut f32 {
    match kind {
        Kind::Position => &mut scene.positions[i][a],
        Kind::LogScale => &mut scene.log_scales[i][a],
        Kind::Rotation => &mut scene.rotations[i][a],
        Kind::OpacityLogit => &mut scene.opacity_logits[i],
        Kind::ShBand(_) => &mut scene.sh[a],
    }
}

fn gradient(g: &Gradients, (kind, i, a): (Kind, usize, usize)) -> f64 {
    match kind {
        Kind::Position => g.positions[i][a],
        Kind::LogScale => g.log_scales[i][a],
        Kind::Rotation => g.rotations[i][a],
        Kind::OpacityLogit => g.opacity_logits[i],
        Kind::ShBand(_) => g.sh[a],
    }
}

/// Everything that makes the render piecewise smooth: per pixel the contributing Gaussians in
/// order with their cap state, and per Gaussian whether it projects and which colour channels
/// sit on the clamp at 0. Equal structures on both sides of a finite-difference step mean the
/// step crossed no discontinuity or kink.
type Structure = (Vec<Vec<(usize, bool)>>, Vec<Option<[bool; 3]>>);

fn structure(scene: &GaussianScene, camera: &Camera, settings: &RenderSettings) -> Structure {
    let pixels = contributions(scene, camera, settings)
        .into_iter()
        .map(|c| c.into_iter().map(|c| (c.gaussian, c.capped)).collect())
        .collect();
    let gaussians = (0..scene.len())
        .map(|i| project(scene, camera, settings, i).map(|p| p.color.map(|c| c == 0.0)))
        .collect();
    (pixels, gaussians)
}

/// Checks the analytic backward against central differences for every parameter, skipping
/// those whose ±step changes the [`structure`] (the derivative does not exist there; the
/// configurations are random, so this is rare). Returns (tested, skipped) per kind.
fn check_gradients(
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
    loss: &Loss,
) -> std::collections::BTreeMap<Kind, (usize, usize)> {
    // 2⁻¹⁶ is exact on the 2⁻¹² grid of the scene values and about 1e-5 of their magnitude;
    // f64 evaluation keeps the rounding error of the difference far below the tolerance.
    let step = 2f64.powi(-16);
    let analytic = loss.gradients(scene, camera, settings);
    let params = parameters(scene);
    let largest = params.iter().map(|&p| gradient(&analytic, p).abs()).fold(0.0, f64::max);
    let base = structure(scene, camera, settings);
    let mut counts = std::collections::BTreeMap::new();
    let mut scene = scene.clone();
    for p in params {
        let original = *parameter(&mut scene, p);
        let mut side = |sign: f64| {
            *parameter(&mut scene, p) = (f64::from(original) + sign * step) as f32;
            assert_eq!(
                f64::from(*parameter(&mut scene, p)),
                f64::from(original) + sign * step,
                "step not exact in f32"
            );
            let value = loss.value(&render(&scene, camera, settings));
            (value, structure(&scene, camera, settings) == base)
        };
        let ((plus, same_plus), (minus, same_minus)) = (side(1.0), side(-1.0));
        *parameter(&mut scene, p) = original;
        let entry = counts.entry(p.0).or_insert((0, 0));
        if !(same_plus && same_minus) {
            entry.1 += 1;
            continue;
        }
        entry.0 += 1;
        let fd = (plus - minus) / (2.0 * step);
        let a = gradient(&analytic, p);
        let tolerance = 1e-3 * a.abs().max(fd.abs()) + 1e-7 * largest + 1e-10;
        assert!(
            (a - fd).abs() <= tolerance,
            "{p:?} (mask {}, degree {}): analytic {a:e}, finite difference {fd:e}",
            settings.mask_mode,
            settings.sh_degree
        );
    }
    counts
}

/// Most parameters of every kind were compared (not skipped), so the check cannot pass empty.
fn assert_mostly_tested(counts: &std::collections::BTreeMap<Kind, (usize, usize)>) {
    for (kind, &(tested, skipped)) in counts {
        assert!(
            tested >= 3 && skipped * 5 <= tested + skipped,
            "{kind:?}: {tested} tested, {skipped} skipped"
        );
    }
}

#[test]
fn backward_matches_finite_differences_for_every_parameter_kind() {
    let mut rng = SplitMix64::new(2024);
    let mut total = std::collections::BTreeMap::<Kind, (usize, usize)>::new();
    for round in 0..2 {
        for degree in 0..=3 {
            for mask_mode in [false, true] {
                let n = 3 + (rng.next_u32() % 6) as usize;
                let scene = random_scene(&mut rng, n, degree);
                let camera = random_camera(&mut rng);
                let loss = Loss::random(&mut rng, 20 * 13);
                // Round 1 renders a lower degree than the scene stores: the unused
                // coefficients must get exactly zero, as their differences are.
                let used = if round == 0 { degree } else { degree.saturating_sub(1) };
                let settings = settings(mask_mode, used);
                let covered =
                    render(&scene, &camera, &settings).alpha.iter().filter(|&&a| a > 0.0).count();
                assert!(covered > 20, "degenerate scene: only {covered} pixels covered");
                for (kind, (t, s)) in check_gradients(&scene, &camera, &settings, &loss) {
                    let entry = total.entry(kind).or_insert((0, 0));
                    entry.0 += t;
                    entry.1 += s;
                }
            }
        }
    }
    eprintln!("(tested, skipped) per kind: {total:?}");
    assert_mostly_tested(&total);
    for band in 0..=3 {
        assert!(total.contains_key(&Kind::ShBand(band)), "SH band {band} never tested");
    }
}

/// A large Gaussian whose centre lies beyond the guard band (its Jacobian uses the clamped
/// ray) but whose footprint reaches the image: the clamp passes no gradient to v.x, only v.z.
#[test]
fn backward_matches_finite_differences_beyond_the_guard_band() {
    let mut rng = SplitMix64::new(99);
    let camera = Camera::new(
        20,
        13,
        19.0,
        18.0,
        10.3,
        6.4,
        DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0)),
    )
    .unwrap();
    let mut scene = random_scene(&mut rng, 3, 1);
    // v.x / v.z = 1.1 at depth 4: beyond the limit (20 − 10.3) / 19 + 0.3 · 20 / 19 ≈ 0.84.
    scene.positions[0] = [4.4, 0.25, 0.0];
    scene.log_scales[0] = [grid(1.2f64.ln()), grid(0.9f64.ln()), grid(0.7f64.ln())];
    scene.opacity_logits[0] = 2.0;
    let settings = settings(false, 1);
    let v = camera.to_camera(DVec3::new(4.4, 0.25, 0.0));
    assert!(v.x / v.z > (20.0 - 10.3) / 19.0 + 0.3 * 20.0 / 19.0 + 0.1);
    assert!(
        contributions(&scene, &camera, &settings).iter().flatten().any(|c| c.gaussian == 0),
        "the far Gaussian must reach the image"
    );
    let loss = Loss::random(&mut rng, 20 * 13);
    assert_mostly_tested(&check_gradients(&scene, &camera, &settings, &loss));
}

// ---------------------------------------------------------------------------------------------
// Hard cases.

/// A camera at the origin looking along +z (so view coordinates are world coordinates).
fn origin_camera(width: u32, height: u32, cx: f64, cy: f64) -> Camera {
    Camera::new(width, height, 30.0, 30.0, cx, cy, DMat4::IDENTITY).unwrap()
}

/// One Gaussian of degree 0 with colour `color` (through the DC coefficient).
fn one_gaussian(
    position: [f32; 3],
    log_scales: [f32; 3],
    rotation: [f32; 4],
    logit: f32,
    color: [f32; 3],
) -> GaussianScene {
    const C0: f32 = 0.282_094_8;
    GaussianScene {
        positions: vec![position],
        log_scales: vec![log_scales],
        rotations: vec![rotation],
        opacity_logits: vec![logit],
        sh: color.map(|c| (c - 0.5) / C0).to_vec(),
        sh_degree: 0,
    }
}

fn concat(a: &GaussianScene, b: &GaussianScene) -> GaussianScene {
    assert_eq!(a.sh_degree, b.sh_degree);
    GaussianScene {
        positions: [a.positions.as_slice(), &b.positions].concat(),
        log_scales: [a.log_scales.as_slice(), &b.log_scales].concat(),
        rotations: [a.rotations.as_slice(), &b.rotations].concat(),
        opacity_logits: [a.opacity_logits.as_slice(), &b.opacity_logits].concat(),
        sh: [a.sh.as_slice(), &b.sh].concat(),
        sh_degree: a.sh_degree,
    }
}

fn assert_finite(image: &Image, gradients: &Gradients) {
    let values = image.color.iter().flatten().chain(&image.alpha).chain(&image.depth);
    assert!(values.into_iter().all(|v| v.is_finite()), "non-finite output");
    let g = gradients
        .positions
        .iter()
        .flatten()
        .chain(gradients.log_scales.iter().flatten())
        .chain(gradients.rotations.iter().flatten());
    assert!(
        g.chain(&gradients.opacity_logits).chain(&gradients.sh).all(|v| v.is_finite()),
        "non-finite gradient"
    );
}

/// Renders and back-propagates a random loss; both must be finite.
fn render_and_backward(
    scene: &GaussianScene,
    camera: &Camera,
    settings: &RenderSettings,
) -> (Image, Gradients) {
    let loss = Loss::random(&mut SplitMix64::new(7), (camera.width * camera.height) as usize);
    let image = render(scene, camera, settings);
    let gradients = loss.gradients(scene, camera, settings);
    assert_finite(&image, &gradients);
    (image, gradients)
}

fn is_background(image: &Image, settings: &RenderSettings) -> bool {
    let background = settings.background.map(f64::from);
    image.color.iter().all(|c| *c == background)
        && image.alpha.iter().chain(&image.depth).all(|&v| v == 0.0)
}

#[test]
fn behind_at_and_near_the_near_plane() {
    let camera = origin_camera(67, 33, 33.5, 16.5);
    let settings = settings(false, 0);
    let log_scales = [0.0; 3];
    let at = |z: f32| {
        one_gaussian([0.0, 0.0, z], log_scales, [1.0, 0.0, 0.0, 0.0], 1.0, [0.9, 0.2, 0.1])
    };
    // Behind the camera, at its centre, exactly on the near and far planes: culled.
    for z in [-2.0, 0.0, settings.near, settings.far] {
        assert!(project(&at(z), &camera, &settings, 0).is_none(), "z = {z} not culled");
        let (image, gradients) = render_and_backward(&at(z), &camera, &settings);
        assert!(is_background(&image, &settings));
        assert_eq!(gradients.positions[0], [0.0; 3]);
    }
    // Just past the near plane: a huge footprint, but finite everywhere.
    let just_past = at(settings.near + 2f32.powi(-20));
    let projected =
        project(&just_past, &camera, &settings, 0).expect("just past the near plane projects");
    assert!(projected.conic.iter().all(|v| v.is_finite() && v.abs() < 1.0));
    let (image, _) = render_and_backward(&just_past, &camera, &settings);
    assert!(image.alpha.iter().all(|&a| a > 0.5), "a Gaussian at the near plane covers the image");
}

#[test]
fn far_off_screen_gaussians_touch_no_tile_and_change_nothing() {
    let camera = origin_camera(67, 33, 33.5, 16.5);
    let settings = settings(false, 0);
    let visible =
        one_gaussian([0.0, 0.0, 3.0], [0.3f32.ln(); 3], [1.0, 0.0, 0.0, 0.0], 1.0, [0.9, 0.2, 0.1]);
    for x in [1e3f32, -1e6, 3e30] {
        let far = one_gaussian(
            [x, 0.5, 3.0],
            [0.3f32.ln(); 3],
            [1.0, 0.0, 0.0, 0.0],
            1.0,
            [0.1, 0.2, 0.9],
        );
        if let Some(p) = project(&far, &camera, &settings, 0) {
            assert!(tiles_touched(&p, camera.width, camera.height).is_empty());
        }
        let both = concat(&visible, &far);
        let (image, gradients) = render_and_backward(&both, &camera, &settings);
        assert_eq!(image, render(&visible, &camera, &settings));
        assert_eq!(gradients.positions[1], [0.0; 3]);
    }
}

/// Needles and sheets with scale ratios of 1e6 project to the analytic 2D covariance (the
/// dilation keeps it invertible) and render finitely.
#[test]
fn needles_and_sheets() {
    let camera = origin_camera(67, 33, 33.5, 16.5);
    let settings = settings(false, 0);
    let (long, thin) = (0.5f64, 0.5e-6f64);
    for (scales, rotation) in [
        ([long, thin, thin], [1.0f32, 0.0, 0.0, 0.0]),
        ([long, long, thin], [1.0, 0.0, 0.0, 0.0]),
        ([thin, long, thin], [0.9, 0.1, -0.3, 0.2]),
    ] {
        let scene = one_gaussian(
            [0.0, 0.0, 3.0],
            scales.map(|s| s.ln() as f32),
            rotation,
            2.0,
            [0.5, 0.6, 0.7],
        );
        let p = project(&scene, &camera, &settings, 0).expect("a needle projects");
        render_and_backward(&scene, &camera, &settings);
        if rotation == [1.0, 0.0, 0.0, 0.0] {
            // Σ = diag(s²) at the optical axis: Σ' = diag((f s_x / z)², (f s_y / z)²) + 0.3 I.
            let s = scales.map(|s| f64::from(s.ln() as f32).exp());
            let (a, c) = ((30.0 * s[0] / 3.0).powi(2) + 0.3, (30.0 * s[1] / 3.0).powi(2) + 0.3);
            let expected = [1.0 / a, 0.0, 1.0 / c];
            for k in 0..3 {
                assert!(
                    (p.conic[k] - expected[k]).abs() <= 1e-12 * expected[k].abs().max(1.0),
                    "{:?} vs {expected:?}",
                    p.conic
                );
            }
        }
    }
}

/// A sub-pixel Gaussian centred on a pixel: alpha there is o exactly, and its neighbours get
/// `o exp(−½ / (0.3 + (f s / z)²))` (the dilation dominates).
#[test]
fn sub_pixel_gaussian_matches_the_analytic_footprint() {
    let camera = origin_camera(20, 13, 10.5, 5.5);
    let settings = settings(false, 0);
    let color = [0.25f32, 0.5, 0.75];
    let scene = one_gaussian([0.0, 0.0, 2.0], [1e-5f32.ln(); 3], [1.0, 0.0, 0.0, 0.0], 0.5, color);
    let (image, _) = render_and_backward(&scene, &camera, &settings);
    let o = 1.0 / (1.0 + (-0.5f64).exp());
    let s = f64::from(1e-5f32.ln()).exp();
    let variance = 0.3 + (30.0 * s / 2.0).powi(2);
    let c = color.map(|c| f64::from((c - 0.5) / 0.282_094_8) * 0.28209479177387814 + 0.5);
    for (x, y, distance2) in [(10, 5, 0.0), (11, 5, 1.0), (10, 4, 1.0), (9, 6, 2.0)] {
        let alpha = o * (-0.5 * distance2 / variance).exp();
        let pixel = y * 20 + x;
        assert!(
            (image.alpha[pixel] - alpha).abs() < 1e-12,
            "pixel ({x}, {y}): {} vs {alpha}",
            image.alpha[pixel]
        );
        let expected: [f64; 3] = std::array::from_fn(|ch| {
            c[ch] * alpha + (1.0 - alpha) * f64::from(settings.background[ch])
        });
        assert!(
            (0..3).all(|ch| (image.color[pixel][ch] - expected[ch]).abs() < 1e-12),
            "{:?} vs {expected:?}",
            image.color[pixel]
        );
        assert!((image.depth[pixel] - 2.0).abs() < 1e-12);
    }
    assert_eq!(image.alpha[0], 0.0, "a pixel 10 away is beyond the footprint");
}

/// One isotropic Gaussian covering the whole 67×33 image (not a multiple of 16): every tile,
/// and alpha `min(0.99, o exp(−|u − m|² / 2 (f² s² / z² + 0.3)))` at every pixel.
#[test]
fn one_gaussian_covering_the_image_matches_the_analytic_image() {
    let camera = origin_camera(67, 33, 33.5, 16.5);
    let settings = settings(false, 0);
    for logit in [1.5f32, 50.0] {
        let scene = one_gaussian(
            [0.0, 0.0, 3.0],
            [1.5f32.ln(); 3],
            [1.0, 0.0, 0.0, 0.0],
            logit,
            [0.8, 0.4, 0.2],
        );
        let p = project(&scene, &camera, &settings, 0).unwrap();
        assert_eq!(tiles_touched(&p, 67, 33), (0..15).collect::<Vec<u32>>());
        let (image, _) = render_and_backward(&scene, &camera, &settings);
        let o = 1.0 / (1.0 + (-f64::from(logit)).exp());
        let variance = (30.0 * f64::from(1.5f32.ln()).exp() / 3.0).powi(2) + 0.3;
        for y in 0..33 {
            for x in 0..67 {
                let d2 = (x as f64 + 0.5 - 33.5).powi(2) + (y as f64 + 0.5 - 16.5).powi(2);
                let alpha = (o * (-0.5 * d2 / variance).exp()).min(ALPHA_MAX);
                assert!(alpha >= ALPHA_MIN, "the footprint covers the corners");
                assert!((image.alpha[y * 67 + x] - alpha).abs() < 1e-12, "({x}, {y})");
            }
        }
        // At logit 50, o = 1: the centre pixels sit on the 0.99 cap.
        assert_eq!(image.alpha[16 * 67 + 33] == ALPHA_MAX, logit == 50.0);
    }
}

/// Equal depths composite in index order: at the shared centre pixel (G = 1) the colour is
/// `c0 o0 + c1 o1 (1 − o0) + bg (1 − o0)(1 − o1)`, and swapping the rows swaps the layers.
#[test]
fn equal_depths_composite_in_index_order() {
    let camera = origin_camera(20, 13, 10.5, 5.5);
    let settings = settings(false, 0);
    let (red, blue) = ([0.9f32, 0.1, 0.1], [0.1f32, 0.1, 0.9]);
    let layer = |color: [f32; 3], logit: f32| {
        one_gaussian([0.0, 0.0, 2.0], [0.1f32.ln(); 3], [1.0, 0.0, 0.0, 0.0], logit, color)
    };
    let o = |logit: f64| 1.0 / (1.0 + (-logit).exp());
    let decoded =
        |c: [f32; 3]| c.map(|c| f64::from((c - 0.5) / 0.282_094_8) * 0.28209479177387814 + 0.5);
    for (front, back) in [((red, 0.5f32), (blue, 1.0f32)), ((blue, 1.0), (red, 0.5))] {
        let scene = concat(&layer(front.0, front.1), &layer(back.0, back.1));
        let pixel = render(&scene, &camera, &settings).color[5 * 20 + 10];
        let (o0, o1) = (o(f64::from(front.1)), o(f64::from(back.1)));
        let (c0, c1) = (decoded(front.0), decoded(back.0));
        for ch in [0, 2] {
            let expected = c0[ch] * o0
                + c1[ch] * o1 * (1.0 - o0)
                + f64::from(settings.background[ch]) * (1.0 - o0) * (1.0 - o1);
            assert!(
                (pixel[ch] - expected).abs() < 1e-12,
                "channel {ch}: {} vs {expected}",
                pixel[ch]
            );
        }
    }
}

#[test]
fn zero_and_denormal_quaternions_are_culled_tiny_normal_ones_are_not() {
    let camera = origin_camera(20, 13, 10.5, 5.5);
    let settings = settings(false, 0);
    let with = |rotation: [f32; 4]| {
        one_gaussian(
            [0.1, 0.0, 2.0],
            [0.3f32.ln(), 0.1f32.ln(), 0.2f32.ln()],
            rotation,
            1.0,
            [0.5; 3],
        )
    };
    let denormal = f32::MIN_POSITIVE / 4.0;
    for rotation in [[0.0; 4], [denormal, 0.0, -denormal, 0.0], [-0.0, 0.0, 0.0, 0.0]] {
        assert!(project(&with(rotation), &camera, &settings, 0).is_none(), "{rotation:?}");
        assert!(is_background(
            &render_and_backward(&with(rotation), &camera, &settings).0,
            &settings
        ));
    }
    // A quaternion with a smallest-normal component normalises like a unit one.
    let unit = [0.6f32, 0.0, 0.8, 0.0];
    let tiny = unit.map(|v| v * 2.0 * f32::MIN_POSITIVE);
    let (a, b) = (
        project(&with(unit), &camera, &settings, 0).unwrap(),
        project(&with(tiny), &camera, &settings, 0).unwrap(),
    );
    for k in 0..3 {
        assert!((a.conic[k] - b.conic[k]).abs() < 1e-12 * a.conic[k].abs().max(1.0));
    }
    render_and_backward(&with(tiny), &camera, &settings);
}

#[test]
fn extreme_opacity_logits() {
    let camera = origin_camera(20, 13, 10.5, 5.5);
    let settings = settings(false, 0);
    let with = |logit: f32| {
        one_gaussian([0.0, 0.0, 2.0], [0.1f32.ln(); 3], [1.0, 0.0, 0.0, 0.0], logit, [0.5; 3])
    };
    assert!(project(&with(-50.0), &camera, &settings, 0).is_none());
    assert!(is_background(&render(&with(-50.0), &camera, &settings), &settings));
    let (image, gradients) = render_and_backward(&with(50.0), &camera, &settings);
    assert_eq!(image.alpha[5 * 20 + 10], ALPHA_MAX);
    assert_eq!(gradients.opacity_logits[0], 0.0, "sigmoid saturates to exactly 1 in f64");
}

/// A Gaussian with one NaN or infinite parameter is culled: the image and every other
/// Gaussian's gradients are exactly those of the scene without it, its own are zero.
#[test]
fn non_finite_gaussians_never_poison_their_neighbours() {
    let mut rng = SplitMix64::new(31);
    let camera = random_camera(&mut rng);
    let scene = random_scene(&mut rng, 6, 2);
    let settings = settings(false, 2);
    let loss = Loss::random(&mut rng, 20 * 13);
    let reference_image = render(&scene, &camera, &settings);
    let reference_gradients = loss.gradients(&scene, &camera, &settings);
    let bad_row = 2;
    for value in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        // A copy of Gaussian 1 (which overlaps the others) at row 2, with one bad value.
        for target in [
            Kind::Position,
            Kind::LogScale,
            Kind::Rotation,
            Kind::OpacityLogit,
            Kind::ShBand(0),
            Kind::ShBand(2),
        ] {
            let mut bad = scene.clone();
            let insert_row = |v: &mut Vec<_>, row| v.insert(bad_row, row);
            insert_row(&mut bad.positions, scene.positions[1]);
            insert_row(&mut bad.log_scales, scene.log_scales[1]);
            bad.rotations.insert(bad_row, scene.rotations[1]);
            bad.opacity_logits.insert(bad_row, scene.opacity_logits[1]);
            let k3 = scene.coefficients() * 3;
            let copied = scene.sh[k3..2 * k3].to_vec();
            bad.sh.splice(bad_row * k3..bad_row * k3, copied);
            let sh_index =
                |band: u32| (bad_row * scene.coefficients() + (band * band) as usize) * 3 + 1;
            let at = match target {
                Kind::ShBand(band) => (target, bad_row, sh_index(band)),
                _ => (target, bad_row, 0),
            };
            *parameter(&mut bad, at) = value;
            assert!(
                project(&bad, &camera, &settings, bad_row).is_none(),
                "{target:?} = {value} not culled"
            );
            let (image, gradients) =
                (render(&bad, &camera, &settings), loss.gradients(&bad, &camera, &settings));
            assert_eq!(image, reference_image, "{target:?} = {value}");
            let mut without = gradients.clone();
            without.positions.remove(bad_row);
            without.log_scales.remove(bad_row);
            without.rotations.remove(bad_row);
            without.opacity_logits.remove(bad_row);
            without.sh.drain(bad_row * k3..(bad_row + 1) * k3);
            assert_eq!(without, reference_gradients, "{target:?} = {value}");
            assert_eq!(gradients.positions[bad_row], [0.0; 3]);
            assert!(gradients.sh[bad_row * k3..(bad_row + 1) * k3].iter().all(|&g| g == 0.0));
        }
    }
}

/// SH coefficients the render does not read (above the active degree, or any in mask mode)
/// do not cull a Gaussian even when non-finite.
#[test]
fn unread_non_finite_coefficients_are_harmless() {
    let mut rng = SplitMix64::new(32);
    let camera = random_camera(&mut rng);
    let scene = random_scene(&mut rng, 4, 3);
    let mut bad = scene.clone();
    bad.sh[(16 + 12) * 3] = f32::NAN; // Gaussian 1, coefficient 12 (band 3), red.
    for settings in [settings(false, 2), settings(true, 3)] {
        assert_eq!(render(&bad, &camera, &settings), render(&scene, &camera, &settings));
    }
}

#[test]
fn no_gaussians_render_the_background() {
    let camera = origin_camera(67, 33, 33.5, 16.5);
    let scene = GaussianScene { sh_degree: 1, ..Default::default() };
    for mask_mode in [false, true] {
        let settings = settings(mask_mode, 1);
        let (image, gradients) = render_and_backward(&scene, &camera, &settings);
        assert!(is_background(&image, &settings));
        assert_eq!((image.width, image.height, image.alpha.len()), (67, 33, 67 * 33));
        assert!(gradients.positions.is_empty() && gradients.sh.is_empty());
    }
}

/// On a 67×33 image (partial tiles at the right and bottom), binning loses nothing: the
/// render equals brute-force compositing of every projected Gaussian at every pixel, and the
/// contributions stop where transmittance would fall below 1e-4.
#[test]
fn binned_render_equals_brute_force_on_a_partial_tile_image() {
    let mut rng = SplitMix64::new(67);
    let scene = random_scene(&mut rng, 60, 1);
    let mut scene = scene;
    scene.positions.iter_mut().for_each(|p| *p = p.map(|v| v * 2.5));
    let camera = Camera::new(
        67,
        33,
        40.0,
        40.0,
        31.0,
        17.0,
        look_at(DVec3::new(0.5, -1.0, -5.0), DVec3::ZERO, 0.4),
    )
    .unwrap();
    for mask_mode in [false, true] {
        let settings = settings(mask_mode, 1);
        let (image, _) = render_and_backward(&scene, &camera, &settings);
        let projected: Vec<(usize, Projected)> = (0..scene.len())
            .filter_map(|i| project(&scene, &camera, &settings, i).map(|p| (i, p)))
            .collect();
        let mut order = projected.clone();
        order.sort_by(|a, b| (a.1.depth as f32).total_cmp(&(b.1.depth as f32)).then(a.0.cmp(&b.0)));
        let mut stopped = 0;
        for y in 0..33 {
            for x in 0..67 {
                let u = [x as f64 + 0.5, y as f64 + 0.5];
                let (mut color, mut depth, mut t) = ([0.0; 3], 0.0, 1.0);
                for (_, p) in &order {
                    let alpha = (p.opacity * (-p.sigma(u)).exp()).min(ALPHA_MAX);
                    if alpha < ALPHA_MIN {
                        continue;
                    }
                    if t * (1.0 - alpha) < TRANSMITTANCE_MIN {
                        stopped += 1;
                        break;
                    }
                    for (sum, c) in color.iter_mut().zip(p.color) {
                        *sum += c * alpha * t;
                    }
                    depth += p.depth * alpha * t;
                    t *= 1.0 - alpha;
                }
                let pixel = y * 67 + x;
                assert!((image.alpha[pixel] - (1.0 - t)).abs() < 1e-12, "({x}, {y})");
                let expected: [f64; 3] =
                    std::array::from_fn(|ch| color[ch] + t * f64::from(settings.background[ch]));
                assert!(
                    (0..3).all(|ch| (image.color[pixel][ch] - expected[ch]).abs() < 1e-12),
                    "({x}, {y})"
                );
                let expected_depth = if 1.0 - t < 1e-6 { 0.0 } else { depth / (1.0 - t) };
                assert!((image.depth[pixel] - expected_depth).abs() < 1e-9, "({x}, {y})");
            }
        }
        assert!(
            image.alpha[32 * 67 + 66] > 0.0 || image.alpha[0] > 0.0,
            "the scene reaches the partial tiles"
        );
        if mask_mode {
            assert!(stopped > 0, "opaque mask renders must hit the transmittance stop somewhere");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// PLY.

fn temporary(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("tagsplat-splat-{}-{name}", std::process::id()))
}

#[test]
fn ply_round_trip_is_bit_exact_for_every_degree() {
    let mut rng = SplitMix64::new(12);
    let camera = random_camera(&mut rng);
    for degree in 0..=3 {
        let mut scene = random_scene(&mut rng, 7, degree);
        scene.positions[3][1] = -0.0;
        scene.sh[4] = f32::MIN_POSITIVE / 8.0;
        let path = temporary(&format!("round-{degree}.ply"));
        scene.write_ply(&path).unwrap();
        let back = GaussianScene::read_ply(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        let bits = |s: &GaussianScene| {
            let rows = s
                .positions
                .iter()
                .flatten()
                .chain(s.log_scales.iter().flatten())
                .chain(s.rotations.iter().flatten());
            (
                rows.chain(&s.opacity_logits).chain(&s.sh).map(|v| v.to_bits()).collect::<Vec<_>>(),
                s.sh_degree,
            )
        };
        assert_eq!(bits(&back), bits(&scene));
        let settings = settings(false, degree);
        assert_eq!(render(&back, &camera, &settings), render(&scene, &camera, &settings));
    }
}

/// The file follows the 3DGS layout: property order, normals 0, channel-major `f_rest`.
#[test]
fn ply_layout_is_the_3dgs_one() {
    let scene = random_scene(&mut SplitMix64::new(13), 3, 2);
    let path = temporary("layout.ply");
    scene.write_ply(&path).unwrap();
    let ply = tagsplat::io::ply::Ply::read(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    let vertex = ply.element("vertex").unwrap();
    let names: Vec<&str> = vertex.properties.iter().map(|p| p.name.as_str()).collect();
    let mut expected: Vec<String> =
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"].map(String::from).to_vec();
    expected.extend((0..24).map(|k| format!("f_rest_{k}")));
    expected.extend(
        ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
            .map(String::from),
    );
    assert_eq!(names, expected);
    assert_eq!(vertex.column_f32("ny").unwrap(), vec![0.0; 3]);
    // Coefficient 5 of the green channel of Gaussian 2 is f_rest_{1·8 + 4}.
    assert_eq!(vertex.column_f32("f_rest_12").unwrap()[2], scene.sh[(2 * 9 + 5) * 3 + 1]);
    assert_eq!(vertex.column_f32("f_dc_2").unwrap()[1], scene.sh[9 * 3 + 2]);
    assert_eq!(vertex.column_f32("rot_0").unwrap()[0], scene.rotations[0][0]);
}

#[test]
fn ascii_3dgs_ply_reads() {
    let path = temporary("ascii.ply");
    let header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
        property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float opacity\n\
        property float scale_0\nproperty float scale_1\nproperty float scale_2\n\
        property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float rot_3\nend_header\n";
    std::fs::write(
        &path,
        format!(
            "{header}1 2 3 0.1 0.2 0.3 -1 -2 -3 -4 1 0 0 0\n4 5 6 0.4 0.5 0.6 2 -1 -1 -1 0 1 0 0\n"
        ),
    )
    .unwrap();
    let scene = GaussianScene::read_ply(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(scene.sh_degree, 0);
    assert_eq!(scene.positions, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(scene.sh, vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
    assert_eq!(scene.opacity_logits, vec![-1.0, 2.0]);
    assert_eq!(scene.log_scales[0], [-2.0, -3.0, -4.0]);
    assert_eq!(scene.rotations[1], [0.0, 1.0, 0.0, 0.0]);
}

#[test]
fn bad_ply_files_name_the_file_and_the_problem() {
    use tagsplat::io::ply::{write_ply, ColumnOut, ElementOut};
    let scene = random_scene(&mut SplitMix64::new(14), 4, 1);
    let path = temporary("bad.ply");
    let expect_error = |expected: &str| {
        let message = GaussianScene::read_ply(&path).unwrap_err().to_string();
        assert!(
            message.starts_with(&path.display().to_string()) && message.contains(expected),
            "{message}"
        );
    };
    // Truncated body.
    scene.write_ply(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 10]).unwrap();
    expect_error("truncated");
    // A missing property, a count of f_rest of no degree, no vertex element.
    let column = || ColumnOut::F32(vec![0.5; 2]);
    let mut element = ElementOut::new("vertex");
    for name in [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2",
    ] {
        element = element.with(name, column());
    }
    write_ply(&path, &[], &[element]).unwrap();
    expect_error("rot_3");
    let mut element = ElementOut::new("vertex").with("rot_3", column());
    for name in [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2",
    ] {
        element = element.with(name, column());
    }
    for k in 0..5 {
        element = element.with(&format!("f_rest_{k}"), column());
    }
    write_ply(&path, &[], &[element]).unwrap();
    expect_error("5 'f_rest_*' properties");
    write_ply(&path, &[], &[ElementOut::new("face").with("x", column())]).unwrap();
    expect_error("no 'vertex' element");
    std::fs::write(&path, b"not a ply at all").unwrap();
    expect_error("not a PLY file");
    std::fs::remove_file(&path).unwrap();
    // Missing file; an invalid scene is refused on writing.
    expect_error("cannot read");
    let mut invalid = scene.clone();
    invalid.sh.pop();
    let message = invalid.write_ply(&path).unwrap_err().to_string();
    assert!(
        message.contains(&path.display().to_string()) && message.contains("SH values"),
        "{message}"
    );
    assert!(!path.exists());
}
