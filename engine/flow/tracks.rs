//! Image tracks: points of a camera's first frame followed through its later frames, one
//! Lucas–Kanade step per frame (small changes of shape and shading between neighbours, so a
//! step is precise), each step checked forward and backward, and then pulled back to the first
//! frame's pixel where the first image still matches (so the small errors of the steps do not
//! add up). A point whose step fails its check (a limb passed in front of it, a view lost the
//! subject) is lost until [`ImageTracks::revive`] finds its first-frame pixel again near a
//! guess: a track restarts only where the first image matches, so it carries what the images
//! say, not the guess.

use super::{GrayImage, LucasKanade, Warp, IDENTITY};

/// Largest forward-backward round trip of a kept step, pixels.
const MAX_STEP_ROUND_TRIP: f32 = 0.5;

/// Largest forward-backward round trip of a match against the first frame, pixels.
const MAX_ANCHOR_ROUND_TRIP: f32 = 1.0;

/// A match against the first frame replaces the chained position only this close to it,
/// pixels: further away it is more likely a similar patch elsewhere than removed drift.
const MAX_ANCHOR_SHIFT: f32 = 1.5;

/// The tracks of one camera's points.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTracks {
    /// Each point's pixel in the first frame (index coordinates: pixel centres at integers),
    /// None for a point the track never had (hidden, outside the image).
    pub first: Vec<Option<[f32; 2]>>,
    /// Where each point is in the latest frame, None once lost.
    pub now: Vec<Option<[f32; 2]>>,
    /// Steps taken since the first frame.
    pub steps: usize,
}

impl ImageTracks {
    /// Tracks starting at `first` in the first frame.
    pub fn new(first: Vec<Option<[f32; 2]>>) -> Self {
        Self { now: first.clone(), first, steps: 0 }
    }

    /// Points still followed (for the tests).
    #[cfg(test)]
    pub fn live(&self) -> usize {
        self.now.iter().flatten().count()
    }

    /// Follows every live point from `previous` (the frame its positions are in) to `next`,
    /// then matches it against `first` (the first frame's image) from where the step put it,
    /// its first-frame window mapped by its warp in `warps` (first frame to `next`; a point
    /// past the slice's end is matched unwarped). All images must share one size; otherwise
    /// every point is lost.
    pub fn advance(
        &mut self,
        lk: &LucasKanade,
        [first, previous, next]: [GrayImage; 3],
        warps: &[Warp],
    ) {
        let (live, points): (Vec<usize>, Vec<[f32; 2]>) =
            self.now.iter().enumerate().filter_map(|(i, p)| Some((i, (*p)?))).unzip();
        let stepped = lk.track_consistent(previous, next, &points, &points, MAX_STEP_ROUND_TRIP);
        let sources: Vec<[f32; 2]> =
            live.iter().map(|&i| self.first[i].unwrap_or([f32::NAN; 2])).collect();
        let guesses: Vec<[f32; 2]> = stepped.iter().map(|p| p.unwrap_or([f32::NAN; 2])).collect();
        let anchored = lk.track_warped(
            first,
            next,
            &sources,
            &guesses,
            &warps_of(&live, warps),
            MAX_ANCHOR_ROUND_TRIP,
        );
        for ((&i, step), anchor) in live.iter().zip(stepped).zip(anchored) {
            self.now[i] = step.map(|s| match anchor {
                Some(a) if (a[0] - s[0]).hypot(a[1] - s[1]) <= MAX_ANCHOR_SHIFT => a,
                _ => s,
            });
        }
        self.steps += 1;
    }

    /// Searches every lost point with a guess (where it is expected in `next`, the latest
    /// frame) for its first-frame pixel: matched from `first` to `next` from the guess and kept
    /// where the backward match returns within a pixel. `guesses` has one entry per point;
    /// `warps` as in [`Self::advance`].
    pub fn revive(
        &mut self,
        lk: &LucasKanade,
        [first, next]: [GrayImage; 2],
        guesses: &[Option<[f32; 2]>],
        warps: &[Warp],
    ) {
        // (point, its first-frame pixel, its guess) of every lost point with both.
        let lost: Vec<(usize, [f32; 2], [f32; 2])> = (0..self.now.len())
            .filter(|&i| self.now[i].is_none())
            .filter_map(|i| Some((i, self.first[i]?, guesses.get(i).copied()??)))
            .collect();
        let sources: Vec<[f32; 2]> = lost.iter().map(|l| l.1).collect();
        let near: Vec<[f32; 2]> = lost.iter().map(|l| l.2).collect();
        let points: Vec<usize> = lost.iter().map(|l| l.0).collect();
        let warps = warps_of(&points, warps);
        let found = lk.track_warped(first, next, &sources, &near, &warps, MAX_ANCHOR_ROUND_TRIP);
        for ((i, _, _), p) in lost.into_iter().zip(found) {
            self.now[i] = p;
        }
    }
}

/// The warps of `points` (indices into `warps`), unwarped past its end.
fn warps_of(points: &[usize], warps: &[Warp]) -> Vec<Warp> {
    points.iter().map(|&i| warps.get(i).copied().unwrap_or(IDENTITY)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth random texture, sampled at (x − shift).
    fn image(width: usize, height: usize, shift: [f32; 2]) -> Vec<f32> {
        let at = |x: f32, y: f32| {
            0.5 + 0.2 * (0.31 * x + 0.17 * y).sin() * (0.23 * y - 0.11 * x).cos()
                + 0.15 * (0.47 * x - 0.29 * y + 1.0).sin()
                + 0.1 * (0.13 * x * 0.9 + 0.41 * y).cos()
        };
        (0..width * height)
            .map(|i| at((i % width) as f32 - shift[0], (i / width) as f32 - shift[1]))
            .collect()
    }

    fn gray(pixels: &[f32], width: usize) -> GrayImage<'_> {
        GrayImage { pixels, width, height: pixels.len() / width }
    }

    #[test]
    fn a_drifting_motion_is_followed_without_the_steps_error_adding_up() {
        let (w, h) = (96, 96);
        // Ten frames moving 2.3 px right and 1.1 px down each: the points end 25 px away.
        let frames: Vec<Vec<f32>> =
            (0..=10).map(|t| image(w, h, [2.3 * t as f32, 1.1 * t as f32])).collect();
        let first: Vec<Option<[f32; 2]>> = (0..25)
            .map(|k| Some([20.0 + 6.0 * (k % 5) as f32, 20.0 + 6.0 * (k / 5) as f32]))
            .chain([None])
            .collect();
        let mut tracks = ImageTracks::new(first.clone());
        let lk = LucasKanade::default();
        for t in 1..frames.len() {
            let (f0, prev, next) = (&frames[0], &frames[t - 1], &frames[t]);
            tracks.advance(&lk, [gray(f0, w), gray(prev, w), gray(next, w)], &[]);
        }
        assert_eq!(tracks.steps, 10);
        assert_eq!(tracks.now[25], None, "a point the track never had stays without one");
        assert!(tracks.live() >= 24, "{} of 25 followed", tracks.live());
        for (start, now) in first.iter().zip(&tracks.now).filter_map(|(s, n)| Some(((*s)?, (*n)?)))
        {
            let error = (now[0] - start[0] - 23.0).hypot(now[1] - start[1] - 11.0);
            assert!(error < 0.05, "{start:?} -> {now:?}: {error} px off");
        }
    }

    #[test]
    fn a_point_whose_step_fails_is_lost_for_good() {
        let (w, h) = (64, 64);
        let textured = image(w, h, [0.0; 2]);
        let flat = vec![0.5; w * h];
        let mut tracks = ImageTracks::new(vec![Some([32.0, 32.0])]);
        let lk = LucasKanade::default();
        tracks.advance(&lk, [gray(&textured, w), gray(&textured, w), gray(&flat, w)], &[]);
        assert_eq!(tracks.now, vec![None]);
        // The texture back: the lost point is not found again by stepping...
        tracks.advance(&lk, [gray(&textured, w), gray(&flat, w), gray(&textured, w)], &[]);
        assert_eq!((tracks.now.clone(), tracks.live()), (vec![None], 0));
        // ...but from a guess three pixels off, where the first image matches again.
        let moved = image(w, h, [2.0, -1.0]);
        tracks.revive(&lk, [gray(&textured, w), gray(&moved, w)], &[Some([31.0, 34.0])], &[]);
        let now = tracks.now[0].expect("revived");
        assert!((now[0] - 34.0).hypot(now[1] - 31.0) < 0.05, "{now:?}");
        // Not where the image holds no texture, nor without a guess.
        let mut lost = ImageTracks::new(vec![Some([32.0, 32.0])]);
        lost.now = vec![None];
        lost.revive(&lk, [gray(&textured, w), gray(&flat, w)], &[Some([32.0, 32.0])], &[]);
        lost.revive(&lk, [gray(&textured, w), gray(&moved, w)], &[None], &[]);
        assert_eq!(lost.now, vec![None]);
        // Images of another size lose every point.
        let mut tracks = ImageTracks::new(vec![Some([10.0, 10.0])]);
        let small = image(32, 32, [0.0; 2]);
        tracks.advance(&lk, [gray(&textured, w), gray(&textured, w), gray(&small, 32)], &[]);
        assert_eq!(tracks.now, vec![None]);
    }
}
