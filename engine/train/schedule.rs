//! The schedule every training loop shares (`fit`, the pipeline's frames, the deformation
//! graph): which view each iteration trains on, when the SH degree rises, when densification
//! runs, and how colour and mask weights spread over a render's four channels.

use crate::rng::SplitMix64;

/// Views in a fresh random order on every pass over them (3DGS's camera stack): each view once
/// per pass, the order fixed by the generator's seed.
#[derive(Default)]
pub struct ViewCycle {
    order: Vec<usize>,
}

impl ViewCycle {
    /// The next of `views` views (0 when there are none).
    pub fn next(&mut self, views: usize, rng: &mut SplitMix64) -> usize {
        if self.order.is_empty() {
            self.order = shuffled(views, rng);
        }
        self.order.pop().unwrap_or(0)
    }
}

/// 0..n in a Fisher–Yates order.
fn shuffled(n: usize, rng: &mut SplitMix64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    order
}

/// The SH degree at 1-based iteration `it`: one band more every `increase_every` iterations,
/// up to `max`.
#[inline]
pub fn sh_degree_at(max: u32, increase_every: u32, it: u32) -> u32 {
    max.min((it - 1) / increase_every)
}

/// When densification runs: every `every` iterations after `from` up to `until`, leaving the
/// last `every` iterations of the run to settle what the last densification made.
#[derive(Clone, Copy, Debug)]
pub struct DensifyWindow {
    /// Densification runs only after this iteration.
    pub from: u32,
    /// Densification runs at no iteration after this one.
    pub until: u32,
    /// Iterations between runs (and the run's last iterations kept free of them).
    pub every: u32,
}

impl DensifyWindow {
    /// Whether densification runs at 1-based iteration `it` of a run of `iterations`.
    #[inline]
    pub fn due(&self, it: u32, iterations: u32) -> bool {
        it > self.from
            && it <= self.until.min(iterations.saturating_sub(self.every))
            && it.is_multiple_of(self.every)
    }
}

/// Per-channel weights of an RGBA render's loss: colour shared by the three colour channels,
/// mask on alpha.
#[inline]
pub fn channel_weights(color: f32, mask: f32) -> [f32; 4] {
    [color / 3.0, color / 3.0, color / 3.0, mask]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_view_once_per_pass_and_the_same_for_the_same_seed() {
        let draw = |seed| {
            let (mut cycle, mut rng) = (ViewCycle::default(), SplitMix64::new(seed));
            (0..10).map(|_| cycle.next(5, &mut rng)).collect::<Vec<_>>()
        };
        let views = draw(3);
        for pass in views.chunks(5) {
            let mut sorted = pass.to_vec();
            sorted.sort_unstable();
            assert_eq!(sorted, [0, 1, 2, 3, 4]);
        }
        assert_eq!(views, draw(3));
        assert_eq!(ViewCycle::default().next(0, &mut SplitMix64::new(1)), 0);
    }

    #[test]
    fn sh_ramp_densify_window_and_channel_weights() {
        assert_eq!(
            [1, 1000, 1001, 3001, 9000].map(|it| sh_degree_at(3, 1000, it)),
            [0, 0, 1, 3, 3]
        );
        let window = DensifyWindow { from: 100, until: 1000, every: 100 };
        let due: Vec<u32> = (1..=1000).filter(|&it| window.due(it, 1000)).collect();
        assert_eq!(due, [200, 300, 400, 500, 600, 700, 800, 900]);
        assert_eq!(channel_weights(3.0, 2.0), [1.0, 1.0, 1.0, 2.0]);
    }
}
