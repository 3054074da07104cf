//! When an optimisation stops (`fit`, a frame's per-vertex stage, a graph level): its loss,
//! averaged over one pass through the training views (every view once, so passes compare like
//! with like), improved on the pass before by less than a tolerance, once the minimum is done;
//! or at the cap. With the minimum at the cap it runs a fixed count, checking every `window`.

use std::cmp::Ordering;

/// Why a stage stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The loss stopped improving (relative change below the tolerance).
    Converged,
    /// The iteration cap came first.
    MaxIterations,
    /// Nothing to fit: no training view of the frame shows the subject (the frame keeps the
    /// extrapolated pose).
    NoViews,
}

/// The stopping test of one stage.
#[derive(Clone, Debug)]
pub struct Plateau {
    min: u32,
    max: u32,
    window: u32,
    tolerance: f64,
    last_pass: Option<f64>,
}

impl Plateau {
    /// `window`: iterations per pass through the views (at least 1).
    pub fn new(min: u32, max: u32, window: usize, tolerance: f32) -> Self {
        Self {
            min,
            max,
            window: (window as u32).max(1),
            tolerance: tolerance as f64,
            last_pass: None,
        }
    }

    /// Whether iteration `it` (from 1) ends a pass, after which [`Self::check`] wants its loss.
    pub fn pass_ends(&self, it: u32) -> bool {
        it.is_multiple_of(self.window) || it >= self.max
    }

    /// After iteration `it`: with `pass_loss` the mean loss of the pass that just ended (when
    /// one did), whether to stop and why. Never stops before `min`; always at `max`.
    pub fn check(&mut self, it: u32, pass_loss: Option<f64>) -> Option<StopReason> {
        if it >= self.max {
            return Some(StopReason::MaxIterations);
        }
        let loss = pass_loss?;
        let previous = self.last_pass.replace(loss);
        let improved = previous.map(|p| (p - loss) / p.abs().max(f64::MIN_POSITIVE));
        // "Not above": a NaN change, comparable with nothing, stops too (the caller reports it).
        let not_above =
            |change: f64| change.partial_cmp(&self.tolerance) != Some(Ordering::Greater);
        match improved {
            Some(change) if it >= self.min && not_above(change) => Some(StopReason::Converged),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_at_plateau_after_minimum_and_at_cap() {
        let mut p = Plateau::new(30, 100, 10, 0.01);
        assert!(!p.pass_ends(9) && p.pass_ends(10) && p.pass_ends(100));
        assert_eq!(p.check(10, Some(1.0)), None);
        // A plateau before the minimum does not stop.
        assert_eq!(p.check(20, Some(0.999)), None);
        assert_eq!(p.check(25, None), None);
        assert_eq!(p.check(30, Some(0.9)), None);
        assert_eq!(p.check(40, Some(0.8995)), Some(StopReason::Converged));
        let mut capped = Plateau::new(0, 25, 10, 0.01);
        assert_eq!(capped.check(25, None), Some(StopReason::MaxIterations));
        // Zero tolerance: runs while the loss still falls at all.
        let mut strict = Plateau::new(0, 50, 10, 0.0);
        assert_eq!(strict.check(10, Some(1.0)), None);
        assert_eq!(strict.check(20, Some(0.999)), None);
        assert_eq!(strict.check(30, Some(0.999)), Some(StopReason::Converged));
        let mut nan = Plateau::new(0, 50, 10, 0.01);
        assert_eq!(nan.check(10, Some(1.0)), None);
        assert_eq!(nan.check(20, Some(f64::NAN)), Some(StopReason::Converged));
    }
}
