//! The fused image loss on the GPU against its f64 reference, the reference against central
//! finite differences, and the SSIM term against the metric (itself checked against
//! scikit-image in tests/eval.rs).

mod common;

use common::{gpu, rng};
use std::sync::Arc;
use tagsplat::eval::ssim;
use tagsplat::gpu::{GpuBuffer, GpuContext, Recorder};
use tagsplat::loss::reference::{image_loss, ReferenceLoss};
use tagsplat::loss::{ImageLoss, LossTarget, LossTerms, ScoredRender};

struct Images {
    width: usize,
    height: usize,
    render: Vec<[f32; 4]>,
    target: Vec<[f32; 4]>,
    weight: Option<Vec<f32>>,
}

fn random_images(width: usize, height: usize, weighted: bool, seed: u64) -> Images {
    let mut r = rng(seed);
    let mut pixel = || [0; 4].map(|_| r.next_f64() as f32);
    let render = (0..width * height).map(|_| pixel()).collect();
    let target = (0..width * height).map(|_| pixel()).collect();
    let mut r = rng(seed + 1);
    let weight =
        weighted.then(|| (0..width * height).map(|_| 0.25 + r.next_f64() as f32).collect());
    Images { width, height, render, target, weight }
}

fn gpu_loss(
    ctx: &Arc<GpuContext>,
    images: &Images,
    lambda: [f32; 4],
) -> (LossTerms, Vec<[f32; 4]>) {
    gpu_losses(ctx, images, &[(&images.render, lambda)]).remove(0)
}

/// One run of the loss over `renders` (each with its λ) against `images`' target and weight.
fn gpu_losses(
    ctx: &Arc<GpuContext>,
    images: &Images,
    renders: &[(&Vec<[f32; 4]>, [f32; 4])],
) -> Vec<(LossTerms, Vec<[f32; 4]>)> {
    gpu_losses_built_for(ctx, images, renders, renders.len())
}

/// [`gpu_losses`] with the loss built for runs of up to `built_for` renders.
fn gpu_losses_built_for(
    ctx: &Arc<GpuContext>,
    images: &Images,
    renders: &[(&Vec<[f32; 4]>, [f32; 4])],
    built_for: usize,
) -> Vec<(LossTerms, Vec<[f32; 4]>)> {
    let pixels = images.width * images.height;
    let mut loss = ImageLoss::new(ctx, built_for).unwrap();
    loss.reserve(pixels).unwrap();
    let upload = |name, data: &[[f32; 4]]| GpuBuffer::from_slice(ctx, name, data).unwrap();
    let target = upload("target", &images.target);
    let weight = images.weight.as_ref().map(|w| GpuBuffer::from_slice(ctx, "weight", w).unwrap());
    let buffers: Vec<_> = renders
        .iter()
        .map(|(render, _)| {
            let gradient = GpuBuffer::<[f32; 4]>::new(ctx, "gradient", pixels).unwrap();
            (upload("render", render), LossTerms::sums(ctx, "terms").unwrap(), gradient)
        })
        .collect();
    let scored: Vec<_> = buffers
        .iter()
        .zip(renders)
        .map(|((image, terms, gradient), &(_, channel_weights))| ScoredRender {
            image,
            channel_weights,
            terms,
            gradient,
        })
        .collect();
    let (width, height) = (images.width as u32, images.height as u32);
    let target = LossTarget { width, height, image: &target, weight: weight.as_ref() };
    let mut rec = Recorder::new(ctx).unwrap();
    buffers.iter().for_each(|(_, terms, _)| terms.clear(&mut rec));
    loss.record(&mut rec, &target, &scored).unwrap();
    rec.submit_and_wait().unwrap();
    buffers
        .iter()
        .map(|(_, terms, gradient)| {
            (LossTerms::from_sums(&terms.read().unwrap()), gradient.read().unwrap())
        })
        .collect()
}

fn reference(images: &Images, lambda: [f32; 4]) -> ReferenceLoss {
    image_loss(
        &images.render,
        &images.target,
        images.weight.as_deref(),
        images.width,
        images.height,
        lambda.map(f64::from),
    )
}

fn max_abs(values: impl Iterator<Item = f64>) -> f64 {
    values.fold(0.0, |m, v| m.max(v.abs()))
}

/// The largest difference between a GPU gradient and the reference's.
fn gradient_error(gpu: &[[f32; 4]], reference: &[[f64; 4]]) -> f64 {
    max_abs(gpu.iter().flatten().zip(reference.iter().flatten()).map(|(&a, &b)| a as f64 - b))
}

/// Checks one render's GPU terms and gradient against the f64 reference.
fn assert_matches_reference(
    what: &str,
    (terms, gradient): &(LossTerms, Vec<[f32; 4]>),
    expect: &ReferenceLoss,
    lambda: [f32; 4],
) {
    for c in 0..4 {
        let (l1, dssim) = (terms.l1[c] as f64, terms.dssim[c] as f64);
        assert!(
            (l1 - expect.l1[c]).abs() < 1e-5,
            "{what} L1 channel {c}: {l1} vs {}",
            expect.l1[c]
        );
        assert!(
            (dssim - expect.dssim[c]).abs() < 1e-5,
            "{what} SSIM channel {c}: {dssim} vs {}",
            expect.dssim[c]
        );
    }
    assert!((terms.total(lambda) as f64 - expect.total).abs() < 1e-5 * expect.total);
    let scale = max_abs(expect.gradient.iter().flatten().copied());
    let error = gradient_error(gradient, &expect.gradient);
    assert!(error < 1e-4 * scale, "{what}: gradient error {error:e} of max {scale:e}");
}

/// One render per run, and two renders sharing the target (each with its own λ, the second
/// with a channel at λ = 0, which sums no term), on sizes that end in a partial run of 8 pixels
/// along both axes.
#[test]
fn gpu_loss_matches_the_reference() {
    let g = gpu();
    let lambda = [0.3, 0.3, 0.3, 3.0];
    let second_lambda = [1.0, 0.0, 0.25, 2.0];
    for (width, height, weighted) in [(37, 29, false), (23, 41, true), (16, 16, true)] {
        let images = random_images(width, height, weighted, width as u64);
        let single = gpu_loss(g.ctx(), &images, lambda);
        assert_matches_reference(
            &format!("{width}×{height}"),
            &single,
            &reference(&images, lambda),
            lambda,
        );
        let other = random_images(width, height, false, 77).render;
        let pair =
            gpu_losses(g.ctx(), &images, &[(&images.render, lambda), (&other, second_lambda)]);
        assert!(pair[0] == single, "{width}×{height}: the first of two scores as it does alone");
        let second = Images { render: other.clone(), ..images };
        assert_matches_reference(
            &format!("{width}×{height}, second of two"),
            &pair[1],
            &reference(&second, second_lambda),
            second_lambda,
        );
        let left_out = (pair[1].0.l1[1], pair[1].0.dssim[1]);
        assert_eq!(left_out, (0.0, 0.0), "{width}×{height}: a channel at λ = 0 is not summed");
    }
}

#[test]
fn reference_gradient_matches_finite_differences() {
    let lambda = [0.5, 1.0, 0.25, 3.0];
    let images = random_images(15, 13, true, 7);
    let analytic = reference(&images, lambda).gradient;
    let mut r = rng(99);
    let mut checked = 0;
    while checked < 40 {
        let p = (r.next_u32() as usize) % (images.width * images.height);
        let c = (r.next_u32() % 4) as usize;
        // Stay off the L1 kink, where the loss has no derivative.
        if (images.render[p][c] - images.target[p][c]).abs() < 0.02 {
            continue;
        }
        let at = |delta: f32| {
            let mut moved = Images {
                render: images.render.clone(),
                target: images.target.clone(),
                weight: images.weight.clone(),
                ..images
            };
            moved.render[p][c] += delta;
            (
                reference(&moved, lambda).total,
                moved.render[p][c] as f64 - images.render[p][c] as f64,
            )
        };
        let ((plus, dp), (minus, dm)) = (at(5e-3), at(-5e-3));
        let numeric = (plus - minus) / (dp - dm);
        let error = (numeric - analytic[p][c]).abs();
        assert!(
            error < 1e-6 + 1e-4 * analytic[p][c].abs(),
            "pixel {p} channel {c}: analytic {} numeric {numeric}",
            analytic[p][c]
        );
        checked += 1;
    }
}

#[test]
fn ssim_term_is_one_minus_the_metric() {
    let g = gpu();
    let images = random_images(31, 24, false, 3);
    let (terms, _) = gpu_loss(g.ctx(), &images, [1.0; 4]);
    let channel = |img: &[[f32; 4]], c: usize| img.iter().map(|p| p[c]).collect::<Vec<f32>>();
    for c in 0..4 {
        let metric =
            ssim(&channel(&images.render, c), &channel(&images.target, c), 31, 24, 1).unwrap();
        assert!(
            (1.0 - terms.dssim[c] as f64 - metric).abs() < 2e-6,
            "channel {c}: {} vs {metric}",
            1.0 - terms.dssim[c]
        );
    }
    // Constant images have no variance: S = (2ab + C1) / (a² + b² + C1) exactly. In f32 the
    // variance E[x²] − μ² cancels to within ~1e-7, which C2 = 9e-4 magnifies to ~1e-4 in S:
    // the price of single-pass moments, and harmless where the image is flat.
    let constant = |v: f32| vec![[v; 4]; 12 * 12];
    let flat = Images {
        width: 12,
        height: 12,
        render: constant(0.25),
        target: constant(0.75),
        weight: None,
    };
    let (terms, _) = gpu_loss(g.ctx(), &flat, [1.0; 4]);
    let s = (2.0 * 0.25 * 0.75 + 1e-4) / (0.25 * 0.25 + 0.75 * 0.75 + 1e-4);
    assert!((terms.dssim[0] as f64 - (1.0 - s)).abs() < 3e-4, "{} vs {}", terms.dssim[0], 1.0 - s);
    assert!((terms.l1[0] - 0.5).abs() < 1e-6);
}

#[test]
fn hard_cases() {
    let g = gpu();
    // Identical images: zero loss, zero gradient (S is at its maximum).
    let mut same = random_images(20, 20, false, 11);
    same.target = same.render.clone();
    let (terms, gradient) = gpu_loss(g.ctx(), &same, [1.0; 4]);
    assert!(terms.total([1.0; 4]).abs() < 1e-6);
    assert!(max_abs(gradient.iter().flatten().map(|&v| v as f64)) < 1e-6);
    // Smaller than the window: L1 only, and still its exact gradient.
    let small = random_images(7, 9, false, 12);
    let (terms, gradient) = gpu_loss(g.ctx(), &small, [1.0; 4]);
    let expect = reference(&small, [1.0; 4]);
    assert_eq!(terms.dssim, [0.0; 4]);
    assert!(gradient_error(&gradient, &expect.gradient) < 1e-7);
    // An empty image records nothing and scores nothing.
    let empty = Images { width: 0, height: 0, render: vec![], target: vec![], weight: None };
    assert_eq!(gpu_loss(g.ctx(), &empty, [1.0; 4]).0, LossTerms::default());
    // A NaN in the render reaches the loss value, where the training loop looks for it.
    let mut nan = random_images(16, 16, false, 13);
    nan.render[100][1] = f32::NAN;
    let (terms, _) = gpu_loss(g.ctx(), &nan, [1.0; 4]);
    assert!(!terms.total([1.0; 4]).is_finite());
}

/// A loss built for two renders a run (a trainer with a second render) scores one render as
/// the one-render loss does, bit for bit: the runs share the scratch, not the kernels.
#[test]
fn a_two_render_loss_scores_one_render_as_the_one_render_loss() {
    let g = gpu();
    let images = random_images(37, 29, true, 21);
    let lambda = [0.3, 0.5, 0.7, 2.0];
    let one = gpu_losses_built_for(g.ctx(), &images, &[(&images.render, lambda)], 1);
    let two = gpu_losses_built_for(g.ctx(), &images, &[(&images.render, lambda)], 2);
    assert_eq!(one[0].0, two[0].0);
    assert_eq!(one[0].1, two[0].1);
}

#[test]
fn short_buffers_are_refused_by_name() {
    let g = gpu();
    let ctx = g.ctx();
    let mut loss = ImageLoss::new(ctx, 1).unwrap();
    loss.reserve(100).unwrap();
    let render = GpuBuffer::<[f32; 4]>::new(ctx, "render", 100).unwrap();
    let short = GpuBuffer::<[f32; 4]>::new(ctx, "target of view 3", 99).unwrap();
    let terms = LossTerms::sums(ctx, "terms").unwrap();
    let scored = ScoredRender {
        image: &render,
        channel_weights: [1.0; 4],
        terms: &terms,
        gradient: &render,
    };
    let target = LossTarget { width: 10, height: 10, image: &short, weight: None };
    let mut rec = Recorder::new(ctx).unwrap();
    let error = loss.record(&mut rec, &target, &[scored]).unwrap_err().to_string();
    assert!(error.contains("target of view 3"), "{error}");
    // A run scores at most as many renders as the kernels were built for.
    let target = LossTarget { image: &render, ..target };
    let error = loss.record(&mut rec, &target, &[scored, scored]).unwrap_err().to_string();
    assert!(error.contains("renders per run"), "{error}");
    let error = ImageLoss::new(ctx, 3).err().expect("three renders are refused").to_string();
    assert!(error.contains("1 or 2"), "{error}");
    drop(rec);
}

/// The loss totals are order-independent fixed-point sums with a dropped count per sum: a NaN
/// in one pixel's red channel and a value past the sums' range in another pixel's alpha make
/// exactly those channels' terms NaN (the training loop then names them), and leave green and
/// blue equal to the f64 reference.
#[test]
fn a_bad_pixel_makes_only_its_channel_nan() {
    let g = gpu();
    let mut images = random_images(32, 24, false, 9);
    let clean = reference(&images, [1.0; 4]);
    images.render[100][0] = f32::NAN;
    images.render[400][3] = 1e30;
    let (terms, _) = gpu_loss(g.ctx(), &images, [1.0; 4]);
    assert!(terms.l1[0].is_nan() && terms.dssim[0].is_nan(), "{terms:?}");
    assert!(terms.l1[3].is_nan(), "{terms:?}");
    for c in 1..3 {
        assert!((terms.l1[c] as f64 - clean.l1[c]).abs() < 1e-5, "{terms:?}");
        assert!((terms.dssim[c] as f64 - clean.dssim[c]).abs() < 1e-5, "{terms:?}");
    }
}

// ---- The camera colour maps (loss::colour_map) ----

use tagsplat::loss::colour_map::affine::{fix_gauge, IDENTITY};
use tagsplat::loss::colour_map::{
    reference as colour_reference, CameraColour, ColourMap, MappedRender,
};

/// A gain and offset per channel, different for each camera.
fn camera_map(camera: usize) -> ColourMap {
    let g = |k: usize| 0.85 + 0.07 * ((camera * 3 + k) % 5) as f32;
    let o = |k: usize| 0.02 * ((camera + k) % 3) as f32 - 0.02;
    [[g(0), 0.0, 0.0, o(0)], [0.0, g(1), 0.0, o(1)], [0.0, 0.0, g(2), o(2)]]
}

/// Renders over `background`: premultiplied colours in [0, α], some pixels empty.
fn renders_over(pixels: usize, background: [f32; 3], seed: u64) -> Vec<[f32; 4]> {
    let mut r = rng(seed);
    (0..pixels)
        .map(|i| {
            let alpha = match i % 7 {
                0 => 0.0,
                1..=3 => 1.0,
                _ => (0.2 + r.next_f64()).min(1.0) as f32,
            };
            let p = [0; 3].map(|_| alpha * r.next_f64() as f32);
            [0, 1, 2]
                .map(|k| p[k] + (1.0 - alpha) * background[k])
                .into_iter()
                .chain([alpha])
                .collect::<Vec<_>>()
                .try_into()
                .unwrap()
        })
        .collect()
}

fn to_f64(p: [f32; 4]) -> [f64; 4] {
    p.map(f64::from)
}

#[test]
fn colour_maps_see_renders_as_the_reference_and_carry_the_gradient_back() {
    let test = gpu();
    let ctx = test.ctx();
    // Not a multiple of a workgroup's pixels, so the tail and empty invocations are exercised.
    let (pixels, background) = (37 * 23, [0.2f32, 0.5, 0.1]);
    let maps: Vec<ColourMap> = (0..3).map(camera_map).collect();
    let colour = CameraColour::new(ctx, &maps, 1, pixels).unwrap();
    let render = renders_over(pixels, background, 11);
    let target = renders_over(pixels, background, 12);
    let seen_gradient = renders_over(pixels, [0.0; 3], 13);
    let upload = |name, data: &[[f32; 4]]| GpuBuffer::from_slice(ctx, name, data).unwrap();
    let (render_buf, target_buf) = (upload("render", &render), upload("target", &target));
    let gradient = GpuBuffer::<[f32; 4]>::new(ctx, "gradient", pixels).unwrap();
    let seen_gradient_buf = upload("seen gradient", &seen_gradient);
    let mapped = MappedRender {
        camera: 2,
        render: &render_buf,
        slot: 0,
        fit_against: Some(&target_buf),
        pixels,
        background,
    };
    let mut rec = Recorder::new(ctx).unwrap();
    rec.copy_buffer(&seen_gradient_buf, colour.seen_gradient(0), pixels);
    colour.record_forward(&mut rec, &mapped).unwrap();
    colour.record_backward(&mut rec, &mapped, &gradient).unwrap();
    rec.submit_and_wait().unwrap();

    let bg = background.map(f64::from);
    let seen = colour.seen(0).read().unwrap();
    let expect: Vec<[f64; 4]> =
        render.iter().map(|&c| colour_reference::seen(&maps[2], to_f64(c), bg)).collect();
    assert!(gradient_error(&seen, &expect) < 1e-6, "seen: {}", gradient_error(&seen, &expect));
    let expect: Vec<[f64; 4]> = seen_gradient
        .iter()
        .map(|&g| colour_reference::seen_backward(&maps[2], to_f64(g), bg))
        .collect();
    let back = gradient.read().unwrap();
    assert!(gradient_error(&back, &expect) < 1e-6, "backward: {}", gradient_error(&back, &expect));

    let moments = colour.take_moments().unwrap();
    let (c64, t64): (Vec<_>, Vec<_>) =
        render.iter().zip(&target).map(|(&c, &t)| (to_f64(c), to_f64(t))).unzip();
    let want = colour_reference::moments(&c64, &t64, bg);
    let (camera_2, others) = (&moments[44..66], [&moments[..44], &moments[66..]].concat());
    for (m, (got, want)) in camera_2.iter().zip(&want).enumerate() {
        assert!(
            (got - want).abs() <= 1e-5 * want.abs().max(1.0),
            "moment {m}: {got} against {want}"
        );
    }
    assert!(others.iter().all(|&m| m == 0.0), "only the camera's own moments are summed");
}

#[test]
fn colour_map_backward_matches_central_differences() {
    // L = Σ w · seen(c) over a pixel; its gradient in c is the backward of w.
    let (map, background) = (camera_map(4), [0.3, 0.1, 0.6]);
    let (c, w) = ([0.4, 0.2, 0.5, 0.7], [0.9, -0.4, 0.3, 1.2]);
    let loss = |c: [f64; 4]| -> f64 {
        let s = colour_reference::seen(&map, c, background);
        (0..4).map(|k| w[k] * s[k]).sum()
    };
    let analytic = colour_reference::seen_backward(&map, w, background);
    let h = 1e-6;
    for i in 0..4 {
        let (mut up, mut down) = (c, c);
        up[i] += h;
        down[i] -= h;
        let numeric = (loss(up) - loss(down)) / (2.0 * h);
        assert!(
            (numeric - analytic[i]).abs() < 1e-8,
            "channel {i}: {numeric} against {}",
            analytic[i]
        );
    }
}

#[test]
fn a_refit_recovers_each_cameras_gains_up_to_the_shared_gauge() {
    let test = gpu();
    let ctx = test.ctx();
    let (pixels, background, cameras) = (40 * 30, [0.0f32; 3], 4);
    // The fit is a gain per channel (affine::fit_map): the truth has no offset.
    let gains_only = |mut m: ColourMap| {
        m.iter_mut().for_each(|row| row[3] = 0.0);
        m
    };
    let truth: Vec<ColourMap> = (0..cameras).map(|c| gains_only(camera_map(c))).collect();
    let mut colour = CameraColour::new(ctx, &vec![IDENTITY; cameras], 1, pixels).unwrap();
    let bg = background.map(f64::from);
    let mut buffers = Vec::new();
    for (camera, map) in truth.iter().enumerate() {
        let render = renders_over(pixels, background, 20 + camera as u64);
        let target: Vec<[f32; 4]> = render
            .iter()
            .map(|&c| colour_reference::seen(map, to_f64(c), bg).map(|v| v as f32))
            .collect();
        buffers.push((
            GpuBuffer::from_slice(ctx, "render", &render).unwrap(),
            GpuBuffer::from_slice(ctx, "target", &target).unwrap(),
        ));
    }
    let mut rec = Recorder::new(ctx).unwrap();
    for (camera, (render, target)) in buffers.iter().enumerate() {
        let mapped =
            MappedRender { camera, render, slot: 0, fit_against: Some(target), pixels, background };
        colour.record_forward(&mut rec, &mapped).unwrap();
    }
    rec.submit_and_wait().unwrap();
    let fitted = colour.refit(1e-9).unwrap();
    assert_eq!(fitted, colour.maps().unwrap());
    let want = fix_gauge(&truth);
    for (got, want) in fitted.iter().flatten().flatten().zip(want.iter().flatten().flatten()) {
        assert!((got - want).abs() < 1e-4, "{fitted:?} against {want:?}");
    }
    // The moments restarted: a refit with nothing summed keeps every map.
    assert_eq!(colour.refit(1e-9).unwrap(), fitted);
}
