//! GPU splatting against the f64 CPU reference (tagsplat::splat::reference), on lavapipe with
//! validation on.

mod common;

use glam::{DMat4, DVec3};
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuBuffer;
use tagsplat::splat::{GaussianBuffers, GaussianScene, RenderSettings, Splatter};

fn camera(width: u32, height: u32) -> Camera {
    Camera::new(width, height, 50.0, 50.0, width as f64 / 2.0, height as f64 / 2.0, DMat4::from_translation(DVec3::new(0.0, 0.0, 4.0))).unwrap()
}

#[test]
fn one_gaussian_smoke() {
    let gpu = common::gpu();
    let ctx = gpu.ctx();
    let scene = GaussianScene {
        positions: vec![[0.0, 0.0, 0.0]],
        log_scales: vec![[-2.0; 3]],
        rotations: vec![[1.0, 0.0, 0.0, 0.0]],
        opacity_logits: vec![2.0],
        sh: vec![1.0, 0.0, -1.0],
        sh_degree: 0,
    };
    let buffers = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut splatter = Splatter::new(ctx).unwrap();
    let cam = camera(40, 30);
    let settings = RenderSettings { background: [0.2, 0.2, 0.2], ..Default::default() };
    let times = splatter.forward(&buffers, &cam, &settings).unwrap();
    let rgba = splatter.read_rgba().unwrap();
    let o = 1.0 / (1.0 + (-2.0f32).exp());
    // Pixel (20, 15) has its centre 0.5 px off the mean on each axis.
    let sigma2d = (0.135335f32 * 50.0 / 4.0).powi(2) + 0.3;
    let alpha = o * (-0.25 / sigma2d).exp();
    let c0 = 0.5 + 0.28209479 * 1.0;
    let px = rgba[15 * 40 + 20];
    eprintln!("{px:?} alpha {alpha} times {:?}", times.passes);
    assert!((px[3] - alpha).abs() < 1e-4, "{px:?} vs {alpha}");
    assert!((px[0] - (c0 * alpha + 0.2 * (1.0 - alpha))).abs() < 1e-4);
    let grad_rgba = GpuBuffer::from_slice(ctx, "grad", &vec![[1.0f32, 0.0, 0.0, 0.0]; 40 * 30]).unwrap();
    let grad_depth = GpuBuffer::from_slice(ctx, "grad depth", &vec![0.0f32; 40 * 30]).unwrap();
    let grads = GaussianBuffers::shaped_like(ctx, &buffers).unwrap();
    let stats = GpuBuffer::from_slice(ctx, "stats", &[[0.0f32; 2]]).unwrap();
    let mut rec = tagsplat::gpu::Recorder::new(ctx).unwrap();
    grads.record_zero(&mut rec);
    rec.submit_and_wait().unwrap();
    splatter.backward(&buffers, &grad_rgba, &grad_depth, &grads, &stats).unwrap();
    let g = grads.to_scene().unwrap();
    eprintln!("{g:?} {:?}", stats.read().unwrap());
}
