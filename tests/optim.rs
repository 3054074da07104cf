//! Fused Adam against an f64 reference, across a remap of the Gaussian set.

mod common;

use common::{gpu, rng};
use std::sync::Arc;
use tagsplat::gpu::{Batch, GpuContext, Recorder, Replay};
use tagsplat::optim::{Adam, AdamParams, LearningRates, NEW_ROW};
use tagsplat::splat::{sh_coefficients, GaussianBuffers, GaussianScene};

const RATES: LearningRates = LearningRates {
    positions: 1e-3,
    log_scales: 5e-3,
    rotations: 1e-3,
    opacity_logits: 5e-2,
    sh_dc: 2.5e-3,
    sh_rest: 1.25e-4,
};

fn random_scene(n: usize, degree: u32, seed: u64) -> GaussianScene {
    let mut r = rng(seed);
    let mut v = || r.next_f64() as f32 * 2.0 - 1.0;
    GaussianScene {
        positions: (0..n).map(|_| [v(), v(), v()]).collect(),
        log_scales: (0..n).map(|_| [v(), v(), v()]).collect(),
        rotations: (0..n).map(|_| [v(), v(), v(), v()]).collect(),
        opacity_logits: (0..n).map(|_| v()).collect(),
        sh: (0..n * 3 * sh_coefficients(degree)).map(|_| v()).collect(),
        sh_degree: degree,
    }
}

/// Flat parameter arrays in buffer order, each with its learning rate per float.
fn flat(scene: &GaussianScene) -> Vec<Vec<f64>> {
    let rows = |r: &[[f32; 3]]| r.iter().flatten().map(|&v| v as f64).collect::<Vec<_>>();
    vec![
        rows(&scene.positions),
        rows(&scene.log_scales),
        scene.rotations.iter().flatten().map(|&v| v as f64).collect(),
        scene.opacity_logits.iter().map(|&v| v as f64).collect(),
        scene.sh.iter().map(|&v| v as f64).collect(),
    ]
}

fn rate(buffer: usize, index: usize, coefficients: usize) -> f64 {
    let r = RATES;
    (match buffer {
        0 => r.positions,
        1 => r.log_scales,
        2 => r.rotations,
        3 => r.opacity_logits,
        _ if (index / 3).is_multiple_of(coefficients) => r.sh_dc,
        _ => r.sh_rest,
    }) as f64
}

/// The reference: parameters, moments (m, v) per float, one step.
fn reference_step(
    params: &mut [Vec<f64>],
    moments: &mut [Vec<[f64; 2]>],
    grads: &[Vec<f64>],
    step: i32,
    coefficients: usize,
) {
    let (b1, b2) = (0.9f64, 0.999f64);
    for k in 0..5 {
        for i in 0..params[k].len() {
            let g = grads[k][i];
            let [m, v] = moments[k][i];
            let (m, v) = (b1 * m + (1.0 - b1) * g, b2 * v + (1.0 - b2) * g * g);
            moments[k][i] = [m, v];
            let (m_hat, v_hat) = (m / (1.0 - b1.powi(step)), v / (1.0 - b2.powi(step)));
            params[k][i] -= rate(k, i, coefficients) * m_hat / (v_hat.sqrt() + 1e-15);
        }
    }
}

fn gpu_step(
    ctx: &Arc<GpuContext>,
    adam: &Adam,
    params: &GaussianBuffers,
    grads: &GaussianBuffers,
    step: u32,
) {
    let mut rec = Recorder::new(ctx).unwrap();
    adam.record_step(
        &mut rec,
        params,
        grads,
        &AdamParams::new(&RATES, step, params.len(), params.sh_degree()),
    )
    .unwrap();
    rec.submit_and_wait().unwrap();
}

fn assert_close(gpu: &[Vec<f64>], reference: &[Vec<f64>], what: &str) {
    for (k, (a, b)) in gpu.iter().zip(reference).enumerate() {
        assert_eq!(a.len(), b.len());
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-6 * y.abs().max(1e-2),
                "{what}: buffer {k} float {i}: {x} vs {y}"
            );
        }
    }
}

fn moments_f64(adam: &Adam) -> Vec<Vec<[f64; 2]>> {
    adam.read_moments()
        .unwrap()
        .iter()
        .map(|m| m.iter().map(|&[a, b]| [a as f64, b as f64]).collect())
        .collect()
}

#[test]
fn steps_match_the_reference_across_a_remap() {
    let g = gpu();
    let ctx = g.ctx();
    // Odd counts: every buffer but the rotations ends in a partial four-float chunk.
    let (n, degree) = (301, 2);
    let coefficients = sh_coefficients(degree);
    let scene = random_scene(n, degree, 1);
    let params = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut adam = Adam::new(ctx, &params).unwrap();
    let mut expect = flat(&scene);
    let mut moments: Vec<Vec<[f64; 2]>> = expect.iter().map(|p| vec![[0.0; 2]; p.len()]).collect();
    for step in 1..=3 {
        let grad_scene = random_scene(n, degree, 10 + step as u64);
        let grads = GaussianBuffers::from_scene(ctx, &grad_scene).unwrap();
        gpu_step(ctx, &adam, &params, &grads, step);
        reference_step(&mut expect, &mut moments, &flat(&grad_scene), step as i32, coefficients);
    }
    assert_close(&flat(&params.to_scene().unwrap()), &expect, "after 3 steps");

    // Remap: drop some rows, permute, add new ones; kept rows keep their moments.
    let old_of_new: Vec<u32> =
        (0..n as u32).rev().filter(|i| i % 3 != 0).chain([NEW_ROW, NEW_ROW]).collect();
    adam.remap(&old_of_new).unwrap();
    let widths = [3, 3, 4, 1, 3 * coefficients];
    let old_moments = &moments;
    let remapped: Vec<Vec<[f64; 2]>> = (0..5)
        .map(|k| {
            old_of_new
                .iter()
                .flat_map(|&o| {
                    (0..widths[k]).map(move |j| {
                        if o == NEW_ROW {
                            [0.0; 2]
                        } else {
                            old_moments[k][o as usize * widths[k] + j]
                        }
                    })
                })
                .collect()
        })
        .collect();
    // m sums gradients of both signs, so its error is relative to the array's scale.
    let gpu_moments = moments_f64(&adam);
    for k in 0..5 {
        for lane in 0..2 {
            let scale = remapped[k].iter().fold(0.0f64, |s, m| s.max(m[lane].abs()));
            for (i, (a, b)) in gpu_moments[k].iter().zip(&remapped[k]).enumerate() {
                assert!(
                    (a[lane] - b[lane]).abs() <= 1e-6 * scale,
                    "moment {lane} of buffer {k} float {i} after remap: {} vs {}",
                    a[lane],
                    b[lane]
                );
            }
        }
    }

    // One more step on the new set, from the remapped parameters.
    let mut new_scene = random_scene(old_of_new.len(), degree, 50);
    let gathered = params.to_scene().unwrap();
    for (i, &o) in old_of_new.iter().enumerate().filter(|(_, &o)| o != NEW_ROW) {
        let o = o as usize;
        new_scene.positions[i] = gathered.positions[o];
        new_scene.log_scales[i] = gathered.log_scales[o];
        new_scene.rotations[i] = gathered.rotations[o];
        new_scene.opacity_logits[i] = gathered.opacity_logits[o];
        new_scene.sh[i * 3 * coefficients..(i + 1) * 3 * coefficients]
            .copy_from_slice(&gathered.sh[o * 3 * coefficients..(o + 1) * 3 * coefficients]);
    }
    let params = GaussianBuffers::from_scene(ctx, &new_scene).unwrap();
    let grad_scene = random_scene(old_of_new.len(), degree, 60);
    let grads = GaussianBuffers::from_scene(ctx, &grad_scene).unwrap();
    gpu_step(ctx, &adam, &params, &grads, 4);
    let mut expect = flat(&new_scene);
    let mut moments = remapped;
    reference_step(&mut expect, &mut moments, &flat(&grad_scene), 4, coefficients);
    assert_close(&flat(&params.to_scene().unwrap()), &expect, "step after remap");
}

#[test]
fn mismatched_shapes_and_empty_sets() {
    let g = gpu();
    let ctx = g.ctx();
    let params = GaussianBuffers::from_scene(ctx, &random_scene(10, 0, 2)).unwrap();
    let other = GaussianBuffers::from_scene(ctx, &random_scene(11, 0, 3)).unwrap();
    let mut adam = Adam::new(ctx, &params).unwrap();
    let mut rec = Recorder::new(ctx).unwrap();
    assert!(adam
        .record_step(&mut rec, &params, &other, &AdamParams::new(&RATES, 1, 10, 0))
        .is_err());
    drop(rec);
    adam.remap(&[]).unwrap();
    assert!(adam.is_empty());
    adam.remap(&[NEW_ROW, 5]).unwrap();
    assert_eq!(moments_f64(&adam)[4], vec![[0.0; 2]; 6]);
}

/// The parameters of step `step`: the rates scaled per step, so a step that read another
/// step's slot would show.
fn params_of_step(step: u32, params: &GaussianBuffers) -> AdamParams {
    let s = 1.0 + step as f32 * 0.25;
    let rates = LearningRates { positions: RATES.positions * s, sh_dc: RATES.sh_dc / s, ..RATES };
    AdamParams::new(&rates, step, params.len(), params.sh_degree())
}

#[test]
fn replayed_steps_in_flight_match_fresh_recordings() {
    let g = gpu();
    let ctx = g.ctx();
    let (n, degree, steps) = (301, 1, 7u32);
    let scene = random_scene(n, degree, 5);
    let grads = GaussianBuffers::from_scene(ctx, &random_scene(n, degree, 6)).unwrap();

    // Fresh: one recording per step, each waited for.
    let fresh = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let adam = Adam::new(ctx, &fresh).unwrap();
    for step in 1..=steps {
        let mut rec = Recorder::new(ctx).unwrap();
        adam.record_step(&mut rec, &fresh, &grads, &params_of_step(step, &fresh)).unwrap();
        rec.submit_and_wait().unwrap();
    }

    // Replayed: one recording per ring slot, two steps on the queue at a time, each step's
    // parameters written into its slot before its submit.
    let replayed = GaussianBuffers::from_scene(ctx, &scene).unwrap();
    let mut adam = Adam::new(ctx, &replayed).unwrap();
    adam.reserve_slots(2).unwrap();
    let replays: Vec<Replay> = (0..2)
        .map(|slot| {
            let mut rec = Recorder::reusable(ctx).unwrap();
            adam.record_step_from(&mut rec, &replayed, &grads, slot).unwrap();
            rec.finish().unwrap()
        })
        .collect();
    let mut batches: Vec<Batch> = (0..2).map(|_| Batch::new(ctx).unwrap()).collect();
    for step in 1..=steps {
        let slot = step as usize % 2;
        batches[slot].wait(&[&replays[slot]]).unwrap();
        adam.set_step(slot, &params_of_step(step, &replayed));
        batches[slot].submit(&[&replays[slot]]).unwrap();
        assert!(replays[slot].is_pending());
    }
    for (batch, replay) in batches.iter_mut().zip(&replays) {
        batch.wait(&[replay]).unwrap();
    }
    let (a, b) = (fresh.to_scene().unwrap(), replayed.to_scene().unwrap());
    assert_eq!(flat(&a), flat(&b), "replayed steps differ from fresh ones");
    assert_ne!(flat(&a), flat(&scene), "the steps moved nothing");
}

#[test]
fn a_batch_refuses_pending_and_stale_replays() {
    let g = gpu();
    let ctx = g.ctx();
    let params = GaussianBuffers::from_scene(ctx, &random_scene(10, 0, 7)).unwrap();
    let grads = GaussianBuffers::from_scene(ctx, &random_scene(10, 0, 8)).unwrap();
    let adam = Adam::new(ctx, &params).unwrap();
    adam.set_step(0, &params_of_step(1, &params));
    let mut rec = Recorder::reusable(ctx).unwrap();
    adam.record_step_from(&mut rec, &params, &grads, 0).unwrap();
    let replay = rec.finish().unwrap();
    let (mut first, mut second) = (Batch::new(ctx).unwrap(), Batch::new(ctx).unwrap());
    first.submit(&[&replay]).unwrap();
    let pending = second.submit(&[&replay]).unwrap_err().to_string();
    assert!(pending.contains("still on the queue"), "{pending}");
    let again = first.submit(&[&replay]).unwrap_err().to_string();
    assert!(again.contains("the batch is still on the queue"), "{again}");
    first.wait(&[&replay]).unwrap();
    // A buffer destroyed since the recording (any: the replay cannot tell which it names).
    drop(GaussianBuffers::from_scene(ctx, &random_scene(3, 0, 9)).unwrap());
    assert!(!replay.is_current());
    let stale = first.submit(&[&replay]).unwrap_err().to_string();
    assert!(stale.contains("destroyed since it was recorded"), "{stale}");
    // A slot past the ring is refused at recording.
    let mut rec = Recorder::reusable(ctx).unwrap();
    assert!(adam.record_step_from(&mut rec, &params, &grads, 1).is_err());
}
