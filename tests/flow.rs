//! The optical-flow term: its f64 reference against central finite differences, the GPU
//! kernel against the reference (value, and gradients added on top of existing ones), and the
//! hard cases (a NaN position or weight, points behind a camera, no targets at all), with
//! validation on.

mod common;

use common::{gpu, rng};
use glam::DVec3;
use tagsplat::camera::Camera;
use tagsplat::gpu::{GpuBuffer, Recorder};
use tagsplat::loss::flow::reference::flow_loss;
use tagsplat::loss::flow::{FlowTarget, FlowTerm, FLOW_TAU_PIXELS};

const SIZE: u32 = 48;
const NEAR: f64 = 0.01;

/// Three views of the origin from about 3 units away.
fn cameras() -> Vec<Camera> {
    [DVec3::new(0.0, -3.0, 0.5), DVec3::new(2.5, 1.0, 1.0), DVec3::new(-2.0, 2.0, -0.5)]
        .iter()
        .map(|&eye| {
            let c = SIZE as f64 / 2.0;
            Camera::look_at(SIZE, SIZE, 40.0, 40.0, c, c, eye, DVec3::ZERO, DVec3::Z).unwrap()
        })
        .collect()
}

/// Points around the origin, and per point and view a target: the point's own pixel moved by
/// up to 8 pixels (near and far beyond τ), a third of them without one (weight 0).
fn case(n: usize, seed: u64) -> (Vec<[f64; 3]>, Vec<FlowTarget>) {
    let (cameras, mut r) = (cameras(), rng(seed));
    let points: Vec<[f64; 3]> =
        (0..n).map(|_| [0.0; 3].map(|_: f64| 1.2 * (r.next_f64() - 0.5))).collect();
    let mut targets = Vec::new();
    for p in &points {
        for camera in &cameras {
            let uv = camera.project(DVec3::from(*p)).unwrap();
            let weight = if r.next_f64() < 0.33 { 0.0 } else { 0.5 + r.next_f64() };
            targets.push(FlowTarget {
                u: (uv.x - 0.5 + 16.0 * (r.next_f64() - 0.5)) as f32,
                v: (uv.y - 0.5 + 16.0 * (r.next_f64() - 0.5)) as f32,
                weight: weight as f32,
                unused: 0.0,
            });
        }
    }
    (points, targets)
}

#[test]
fn reference_gradient_matches_central_differences() {
    let (points, targets) = case(40, 1);
    let cameras = cameras();
    let terms = (2.0, FLOW_TAU_PIXELS as f64, NEAR);
    let (value, grads) = flow_loss(&points, &cameras, &targets, terms);
    assert!(value > 0.0);
    let scale = grads.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-7;
    let mut checked = 0;
    for i in 0..points.len() {
        for a in 0..3 {
            let at = |delta: f64| {
                let mut p = points.clone();
                p[i][a] += delta;
                flow_loss(&p, &cameras, &targets, terms).0
            };
            let numeric = (at(h) - at(-h)) / (2.0 * h);
            assert!(
                (numeric - grads[i][a]).abs() < 1e-5 * scale,
                "point {i} axis {a}: {} vs {numeric}",
                grads[i][a]
            );
            checked += (grads[i][a] != 0.0) as usize;
        }
    }
    assert!(checked > 100, "only {checked} non-zero gradient components were checked");
}

#[test]
fn gpu_matches_reference_and_adds_to_gradients() {
    let test = gpu();
    let ctx = test.ctx();
    let (points, targets) = case(500, 2);
    let cameras = cameras();
    let term = FlowTerm::new(ctx, &cameras, &targets).unwrap();
    assert_eq!(term.pairs(), targets.iter().filter(|t| t.weight > 0.0).count());
    let flat: Vec<f32> = points.iter().flatten().map(|&v| v as f32).collect();
    let positions = GpuBuffer::from_slice(ctx, "positions", &flat).unwrap();
    // Small enough that float32 keeps the added gradients' digits.
    let base = 1e-3f32;
    let grads = GpuBuffer::from_slice(ctx, "gradients", &vec![base; flat.len()]).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    term.record(&mut rec, &positions, &grads, 3.0, NEAR as f32).unwrap();
    rec.submit_and_wait().unwrap();
    let points32: Vec<[f64; 3]> =
        flat.chunks(3).map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]).collect();
    let terms = (3.0, FLOW_TAU_PIXELS as f64, NEAR);
    let (value, expect) = flow_loss(&points32, &cameras, &targets, terms);
    let got = grads.read().unwrap();
    let scale = expect.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, e) in expect.iter().enumerate() {
        for a in 0..3 {
            assert!(
                ((got[3 * i + a] - base) as f64 - e[a]).abs() < 1e-4 * scale,
                "point {i} axis {a}: {} vs {}",
                got[3 * i + a] - base,
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
    let cameras = cameras();
    let eye = DVec3::new(0.0, -3.0, 0.5);
    let points = [
        [f32::NAN, 0.0, 0.0],
        // Behind the first camera.
        (eye * 1.5).as_vec3().to_array(),
        // On its target in every view: no pull.
        [0.1, 0.2, -0.1],
        // A NaN weight and target: skipped.
        [0.3, 0.0, 0.0],
    ];
    let mut targets = vec![FlowTarget { u: 10.0, v: 10.0, weight: 1.0, unused: 0.0 }; 12];
    for (v, camera) in cameras.iter().enumerate() {
        let uv = camera.project(DVec3::new(0.1, 0.2, -0.1)).unwrap();
        targets[6 + v] =
            FlowTarget { u: uv.x as f32 - 0.5, v: uv.y as f32 - 0.5, weight: 1.0, unused: 0.0 };
        targets[9 + v] = FlowTarget { u: f32::NAN, v: f32::NAN, weight: f32::NAN, unused: 0.0 };
    }
    let positions = GpuBuffer::from_slice(ctx, "positions", &points.concat()).unwrap();
    let grads = GpuBuffer::from_slice(ctx, "gradients", &[0.0f32; 12]).unwrap();
    let term = FlowTerm::new(ctx, &cameras, &targets).unwrap();
    assert_eq!(term.pairs(), 9);
    let mut rec = Recorder::new(ctx).unwrap();
    term.record(&mut rec, &positions, &grads, 1.0, NEAR as f32).unwrap();
    rec.submit_and_wait().unwrap();
    assert!(term.take_loss().unwrap().is_finite());
    let g = grads.read().unwrap();
    assert!(g.iter().all(|v| v.is_finite()), "{g:?}");
    assert_eq!(&g[0..3], &[0.0; 3], "a NaN position gets no gradient");
    assert!(g[6..9].iter().all(|v| v.abs() < 1e-6), "on target: {:?}", &g[6..9]);
    assert_eq!(&g[9..12], &[0.0; 3], "a NaN weight is no target");
    // Behind the first camera it is skipped there, pulled by the other two.
    assert!(g[3..6].iter().any(|&v| v != 0.0));
    // No targets, or no views: recording does nothing.
    for (cams, rows) in [(&cameras[..], vec![FlowTarget::default(); 12]), (&[][..], vec![])] {
        let term = FlowTerm::new(ctx, cams, &rows).unwrap();
        assert_eq!(term.pairs(), 0);
        let mut rec = Recorder::new(ctx).unwrap();
        term.record(&mut rec, &positions, &grads, 1.0, NEAR as f32).unwrap();
        rec.submit_and_wait().unwrap();
        assert_eq!(term.take_loss().unwrap(), 0.0);
    }
}
