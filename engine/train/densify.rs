//! The topology-free 3DGS densification (Kerbl et al. 2023), the baseline of `fit`: Gaussians
//! whose mean view-space gradient passes a threshold are cloned when small and split in two
//! when large; transparent or huge ones are pruned. Works on host arrays; the result carries
//! the remap the optimizer needs.

use crate::optim::NEW_ROW;
use crate::rng::SplitMix64;
use crate::splat::GaussianScene;
use glam::{Quat, Vec3};
use std::cmp::Ordering;

/// Thresholds in scene units (the caller scales the config's extent-relative values).
#[derive(Clone, Copy, Debug)]
pub struct DensifyRules {
    /// Mean 2D gradient norm (NDC units) that selects a Gaussian.
    pub grad_threshold: f32,
    /// Largest scale up to which a selected Gaussian is cloned; above it, split.
    pub clone_max_scale: f32,
    /// Gaussians with a lower opacity are pruned.
    pub prune_opacity: f32,
    /// Gaussians with a larger largest scale are pruned.
    pub prune_max_scale: f32,
    /// Most Gaussians after the step; the largest gradients win when it binds.
    pub budget: usize,
}

/// What one step did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct DensifyCounts {
    /// Gaussians cloned (one new Gaussian each).
    pub cloned: usize,
    /// Gaussians split (each replaced by two).
    pub split: usize,
    /// Gaussians pruned (split ones not counted).
    pub pruned: usize,
}

/// A split makes two Gaussians this much smaller (3DGS).
const SPLIT_SHRINK: f32 = 1.6;

/// Applies one step. `mean_grads[i]` is Gaussian i's mean 2D gradient norm in NDC units (NaN
/// or 0 when never seen). Returns the new scene and, per new row, its old row or `NEW_ROW`
/// (`u32::MAX`: clones and split halves start with fresh optimizer state, as in 3DGS).
pub fn densify_and_prune(
    scene: &GaussianScene,
    mean_grads: &[f32],
    rules: &DensifyRules,
    rng: &mut SplitMix64,
) -> (GaussianScene, Vec<u32>, DensifyCounts) {
    let n = scene.len();
    let max_scale =
        |i: usize| scene.log_scales[i].iter().fold(f32::NEG_INFINITY, |m, &s| m.max(s)).exp();
    // Phrased as positive so NaN statistics select nothing.
    let mut selected: Vec<usize> =
        (0..n).filter(|&i| mean_grads[i] >= rules.grad_threshold).collect();
    selected.sort_by(|&a, &b| mean_grads[b].total_cmp(&mean_grads[a]));
    // A clone adds one Gaussian and a split replaces one by two: each selection adds one.
    selected.truncate(rules.budget.saturating_sub(n));
    let mut split = vec![false; n];
    let mut out = GaussianScene { sh_degree: scene.sh_degree, ..Default::default() };
    let mut counts = DensifyCounts::default();
    for &i in &selected {
        if max_scale(i) <= rules.clone_max_scale {
            push_row(&mut out, scene, i, None);
            counts.cloned += 1;
        } else {
            split[i] = true;
            for _ in 0..2 {
                push_row(&mut out, scene, i, Some(split_offset(scene, i, rng)));
            }
            counts.split += 1;
        }
    }
    // An opacity below the threshold or not comparable with it (NaN) is pruned.
    let pruned = |i: usize| {
        matches!(
            sigmoid(scene.opacity_logits[i]).partial_cmp(&rules.prune_opacity),
            None | Some(Ordering::Less)
        ) || max_scale(i) > rules.prune_max_scale
    };
    let mut kept = GaussianScene { sh_degree: scene.sh_degree, ..Default::default() };
    let mut kept_rows = Vec::with_capacity(n);
    for (i, &was_split) in split.iter().enumerate() {
        if was_split || pruned(i) {
            counts.pruned += (!was_split) as usize;
            continue;
        }
        push_row(&mut kept, scene, i, None);
        kept_rows.push(i as u32);
    }
    // Kept rows first (their order unchanged), new rows after.
    append(&mut kept, &out);
    kept_rows.extend(std::iter::repeat_n(NEW_ROW, out.len()));
    (kept, kept_rows, counts)
}

#[inline]
fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// A sample of Gaussian i's own distribution (the new centre of a split half), relative.
fn split_offset(scene: &GaussianScene, i: usize, rng: &mut SplitMix64) -> Vec3 {
    let [w, x, y, z] = scene.rotations[i];
    let rotation = Quat::from_xyzw(x, y, z, w).normalize();
    let scale = Vec3::from_array(scene.log_scales[i].map(f32::exp));
    rotation * (scale * Vec3::new(gaussian(rng), gaussian(rng), gaussian(rng)))
}

/// A standard normal sample (Box–Muller).
fn gaussian(rng: &mut SplitMix64) -> f32 {
    let u = rng.next_f64().max(f64::MIN_POSITIVE);
    let v = rng.next_f64();
    ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
}

/// Appends row i of `scene`; `split_offset` moves it and shrinks it as a split half.
fn push_row(out: &mut GaussianScene, scene: &GaussianScene, i: usize, split_offset: Option<Vec3>) {
    let width = scene.sh.len() / scene.len().max(1);
    let mut position = scene.positions[i];
    let mut log_scales = scene.log_scales[i];
    if let Some(offset) = split_offset {
        position = (Vec3::from_array(position) + offset).to_array();
        log_scales = log_scales.map(|s| s - SPLIT_SHRINK.ln());
    }
    out.positions.push(position);
    out.log_scales.push(log_scales);
    out.rotations.push(scene.rotations[i]);
    out.opacity_logits.push(scene.opacity_logits[i]);
    out.sh.extend_from_slice(&scene.sh[i * width..(i + 1) * width]);
}

fn append(to: &mut GaussianScene, from: &GaussianScene) {
    to.positions.extend_from_slice(&from.positions);
    to.log_scales.extend_from_slice(&from.log_scales);
    to.rotations.extend_from_slice(&from.rotations);
    to.opacity_logits.extend_from_slice(&from.opacity_logits);
    to.sh.extend_from_slice(&from.sh);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::init::{gaussians_at_points, logit};

    fn scene() -> GaussianScene {
        let mut s = gaussians_at_points(
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            None,
            1,
        );
        s.log_scales[1] = [0.5f32.ln(); 3]; // large: split
        s.log_scales[2] = [0.01f32.ln(); 3]; // small: clone
        s.opacity_logits[3] = logit(0.001); // transparent: pruned
        for (i, p) in s.sh.chunks_mut(12).enumerate() {
            p[0] = i as f32; // row identity
        }
        s
    }

    const RULES: DensifyRules = DensifyRules {
        grad_threshold: 1.0,
        clone_max_scale: 0.1,
        prune_opacity: 0.005,
        prune_max_scale: 10.0,
        budget: 100,
    };

    #[test]
    fn clones_splits_prunes_and_remaps() {
        let (out, old_of_new, counts) = densify_and_prune(
            &scene(),
            &[0.0, 2.0, 2.0, f32::NAN],
            &RULES,
            &mut SplitMix64::new(1),
        );
        out.check().unwrap();
        assert_eq!(counts, DensifyCounts { cloned: 1, split: 1, pruned: 1 });
        // Kept: 0 and 2; new: the two halves of 1 (largest gradient first: a tie, stable order), the clone of 2.
        assert_eq!(old_of_new, vec![0, 2, NEW_ROW, NEW_ROW, NEW_ROW]);
        let ids: Vec<f32> = out.sh.chunks(12).map(|p| p[0]).collect();
        assert_eq!(ids, vec![0.0, 2.0, 1.0, 1.0, 2.0]);
        assert!((out.log_scales[2][0] - (0.5f32 / 1.6).ln()).abs() < 1e-6);
        assert_ne!(out.positions[2], out.positions[3], "split halves are sampled apart");
    }

    #[test]
    fn the_budget_binds_on_the_largest_gradients() {
        let rules = DensifyRules { budget: 5, ..RULES };
        let (out, _, counts) =
            densify_and_prune(&scene(), &[0.0, 2.0, 3.0, 0.0], &rules, &mut SplitMix64::new(1));
        assert_eq!(
            (counts.cloned, counts.split),
            (1, 0),
            "room for one: the larger gradient (Gaussian 2)"
        );
        assert_eq!(out.len(), 4);
    }
}
