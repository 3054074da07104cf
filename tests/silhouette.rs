//! The long-range silhouette term: its f64 reference against central finite differences, the
//! GPU kernel against the reference (value, and gradients added on top of existing ones), and
//! the hard cases (a NaN position, points behind a camera or far outside the image, a view
//! whose mask is empty), with validation on.

mod common;

use common::{gpu, rng};
use glam::DVec3;
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::{GpuBuffer, GpuContext, Recorder};
use tagsplat::loss::silhouette::reference::silhouette_loss;
use tagsplat::loss::silhouette::{self, SilhouetteTerm, SilhouetteView};

const SIZE: u32 = 48;

/// Three views of a unit disk's silhouette: the mask of a sphere of radius 0.5 at the origin
/// (each view's mask is the sphere's projection), plus `empty` views with an empty mask.
fn views(empty: usize) -> Vec<SilhouetteView> {
    let eyes = [DVec3::new(0.0, -3.0, 0.5), DVec3::new(2.5, 1.0, 1.0), DVec3::new(-2.0, 2.0, -0.5)];
    let f = 40.0;
    let mut out: Vec<SilhouetteView> = eyes
        .iter()
        .map(|&eye| {
            let camera = Camera::look_at(
                SIZE,
                SIZE,
                f,
                f,
                SIZE as f64 / 2.0,
                SIZE as f64 / 2.0,
                eye,
                DVec3::ZERO,
                DVec3::Z,
            )
            .unwrap();
            let mask: Vec<f32> = (0..SIZE * SIZE)
                .map(|p| {
                    let (o, d) = camera.pixel_ray((p % SIZE) as f64 + 0.5, (p / SIZE) as f64 + 0.5);
                    // The ray passes within 0.5 of the origin.
                    let closest = o - d * o.dot(d) / d.length_squared();
                    (closest.length() < 0.5) as u8 as f32
                })
                .collect();
            SilhouetteView::from_mask(camera, &mask)
        })
        .collect();
    for _ in 0..empty {
        let camera = out[0].camera;
        out.push(SilhouetteView::from_mask(camera, &vec![0.0; (SIZE * SIZE) as usize]));
    }
    out
}

/// Points inside and around the sphere, some far outside every view.
fn points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut r = rng(seed);
    (0..n)
        .map(|i| {
            let spread = if i % 5 == 0 { 3.0 } else { 1.2 };
            [
                spread * (r.next_f64() - 0.5),
                spread * (r.next_f64() - 0.5),
                spread * (r.next_f64() - 0.5),
            ]
        })
        .collect()
}

#[test]
fn reference_gradient_matches_central_differences() {
    let views = views(0);
    let pts = points(60, 1);
    let (value, grads) = silhouette_loss(&pts, &views, 2.0, 0.01);
    assert!(value > 0.0);
    let h = 1e-7;
    let mut checked = 0;
    for i in 0..pts.len() {
        for a in 0..3 {
            let at = |delta: f64| {
                let mut p = pts.clone();
                p[i][a] += delta;
                silhouette_loss(&p, &views, 2.0, 0.01).0
            };
            let numeric = (at(h) - at(-h)) / (2.0 * h);
            let scale = grads.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                (numeric - grads[i][a]).abs() < 1e-5 * scale,
                "point {i} axis {a}: {} vs {numeric}",
                grads[i][a]
            );
            checked += (grads[i][a] != 0.0) as usize;
        }
    }
    assert!(checked > 30, "only {checked} non-zero gradient components were checked");
}

#[test]
fn gpu_matches_reference_and_adds_to_gradients() {
    let test = gpu();
    let ctx = test.ctx();
    let views = views(1);
    // One buffer for every field, then a buffer per view (as a device with a small
    // maxStorageBufferRange splits a large capture).
    let field_bytes = (SIZE * SIZE) as u64 * 4;
    for (limit, buffers) in [(u64::MAX, 1), (field_bytes, 3)] {
        let term = SilhouetteTerm::with_buffer_limit(ctx, &views, limit).unwrap();
        assert_eq!(term.field_buffers(), buffers);
        assert_eq!(term.views_without_mask(), &[3]);
        check_against_reference(ctx, &term, &views);
    }
}

/// The term's gradient, added on top of 0.25 everywhere, and value against the f64 reference.
fn check_against_reference(ctx: &Arc<GpuContext>, term: &SilhouetteTerm, views: &[SilhouetteView]) {
    let pts = points(500, 2);
    let flat: Vec<f32> = pts.iter().flatten().map(|&v| v as f32).collect();
    let positions = GpuBuffer::from_slice(ctx, "positions", &flat).unwrap();
    let grads = GpuBuffer::from_slice(ctx, "gradients", &vec![0.25f32; flat.len()]).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    term.record(&mut rec, &positions, &grads, 3.0, 0.01).unwrap();
    rec.submit_and_wait().unwrap();
    let pts32: Vec<[f64; 3]> =
        flat.chunks(3).map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]).collect();
    let (value, expect) = silhouette_loss(&pts32, views, 3.0, 0.01);
    let got = grads.read().unwrap();
    let scale = expect.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, e) in expect.iter().enumerate() {
        for a in 0..3 {
            assert!(
                (got[3 * i + a] as f64 - 0.25 - e[a]).abs() < 1e-4 * scale,
                "point {i} axis {a}: {} vs {}",
                got[3 * i + a] - 0.25,
                e[a]
            );
        }
    }
    let gpu_value = term.take_loss().unwrap() as f64;
    assert!((gpu_value - value).abs() < 1e-4 * value, "{gpu_value} vs {value}");
}

#[test]
fn hard_cases() {
    let test = gpu();
    let ctx = test.ctx();
    let views = views(0);
    let eye = DVec3::new(0.0, -3.0, 0.5);
    let pts = [
        [f32::NAN, 0.0, 0.0],
        // Behind the first camera and far out to the side of the others.
        (eye * 1.5).as_vec3().to_array(),
        // Inside the sphere: inside every mask.
        [0.05, -0.02, 0.1],
        // Far outside the image of every view.
        [40.0, 40.0, 40.0],
    ];
    let positions = GpuBuffer::from_slice(ctx, "positions", &pts.concat()).unwrap();
    let grads = GpuBuffer::from_slice(ctx, "gradients", &[0.0f32; 12]).unwrap();
    let term = SilhouetteTerm::new(ctx, &views).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    term.record(&mut rec, &positions, &grads, 1.0, 0.01).unwrap();
    rec.submit_and_wait().unwrap();
    assert!(term.take_loss().unwrap().is_finite());
    let g = grads.read().unwrap();
    assert!(g.iter().all(|v| v.is_finite()), "{g:?}");
    assert_eq!(&g[0..3], &[0.0; 3], "a NaN position gets no gradient");
    assert_eq!(&g[6..9], &[0.0; 3], "a point inside every mask gets no gradient");
    // The far point is pulled back towards the subject.
    let far = glam::Vec3::from_slice(&g[9..12]);
    assert!(far.dot(glam::Vec3::splat(40.0)) > 0.0, "{far}");
    // No mask anywhere: nothing to record.
    let empty: Vec<SilhouetteView> =
        views.iter().map(|v| SilhouetteView { camera: v.camera, field: None }).collect();
    let term = SilhouetteTerm::new(ctx, &empty).unwrap();
    assert_eq!(term.views_without_mask(), &[0, 1, 2]);
}

/// A 40² view of the sphere with the left half of its mask uncovered by the "render".
fn coverage_case() -> (Camera, Vec<f32>, Vec<f32>, Vec<[f64; 3]>) {
    let view = &views(0)[1];
    let camera = Camera {
        width: 40,
        height: 40,
        fx: view.camera.fx * 40.0 / SIZE as f64,
        fy: view.camera.fy * 40.0 / SIZE as f64,
        cx: 20.0,
        cy: 20.0,
        ..view.camera
    };
    let mask: Vec<f32> = (0..1600)
        .map(|p| (((p % 40) as f64 - 19.5).hypot((p / 40) as f64 - 19.5) < 12.0) as u8 as f32)
        .collect();
    let coverage: Vec<f32> = (0..1600).map(|p| ((p % 40) >= 20) as u8 as f32).collect();
    (camera, mask, coverage, points(300, 7))
}

#[test]
fn coverage_reference_matches_central_differences() {
    let (camera, mask, coverage, pts) = coverage_case();
    let (value, grads) =
        silhouette::reference::coverage_loss(&pts, &camera, (&mask, &coverage), 8, 2.0, 0.01);
    assert!(value > 0.0);
    let scale = grads.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-7;
    let mut checked = 0;
    for i in 0..pts.len() {
        for a in 0..3 {
            let at = |delta: f64| {
                let mut p = pts.clone();
                p[i][a] += delta;
                silhouette::reference::coverage_loss(&p, &camera, (&mask, &coverage), 8, 2.0, 0.01)
                    .0
            };
            let numeric = (at(h) - at(-h)) / (2.0 * h);
            assert!(
                (numeric - grads[i][a]).abs() < 1e-4 * scale,
                "point {i} axis {a}: {} vs {numeric}",
                grads[i][a]
            );
            checked += (grads[i][a] != 0.0) as usize;
        }
    }
    assert!(checked > 20, "only {checked} non-zero gradient components were checked");
}

#[test]
fn coverage_gpu_matches_reference() {
    let test = gpu();
    let ctx = test.ctx();
    let (camera, mask, coverage, pts) = coverage_case();
    let flat: Vec<f32> = pts.iter().flatten().map(|&v| v as f32).collect();
    let pts32: Vec<[f64; 3]> =
        flat.chunks(3).map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]).collect();
    let positions = GpuBuffer::from_slice(ctx, "positions", &flat).unwrap();
    let grads = GpuBuffer::from_slice(ctx, "gradients", &vec![0.5f32; flat.len()]).unwrap();
    let target = GpuBuffer::from_slice(
        ctx,
        "target",
        &mask.iter().map(|&m| [0.0, 0.0, 0.0, m]).collect::<Vec<_>>(),
    )
    .unwrap();
    let render = GpuBuffer::from_slice(
        ctx,
        "render",
        &coverage.iter().map(|&c| [0.0, 0.0, 0.0, c]).collect::<Vec<_>>(),
    )
    .unwrap();
    let term = silhouette::CoverageTerm::new(ctx, pts.len(), 1600, 8).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    term.record(&mut rec, &camera, (&target, &render), &positions, &grads, 2.0, 0.01).unwrap();
    rec.submit_and_wait().unwrap();
    let (value, expect) =
        silhouette::reference::coverage_loss(&pts32, &camera, (&mask, &coverage), 8, 2.0, 0.01);
    let got = grads.read().unwrap();
    let scale = expect.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, e) in expect.iter().enumerate() {
        for a in 0..3 {
            assert!(
                (got[3 * i + a] as f64 - 0.5 - e[a]).abs() < 1e-4 * scale,
                "point {i} axis {a}: {} vs {}",
                got[3 * i + a] - 0.5,
                e[a]
            );
        }
    }
    let gpu_value = term.take_loss().unwrap() as f64;
    assert!((gpu_value - value).abs() < 1e-4 * value, "{gpu_value} vs {value}");
    // A view larger than the buffers is refused, not overrun.
    let big = Camera { width: 41, ..camera };
    let mut rec = Recorder::new(ctx).unwrap();
    assert!(term
        .record(&mut rec, &big, (&target, &render), &positions, &grads, 2.0, 0.01)
        .is_err());
}
