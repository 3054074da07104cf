//! Learning-rate schedules.

/// Log-linear interpolation from `start` at step 0 to `end` at `steps` (held after): the
/// exponential decay 3DGS uses for positions. `start` when `steps` is 0.
pub fn exponential_decay(start: f64, end: f64, step: u64, steps: u64) -> f64 {
    if steps == 0 || start <= 0.0 || end <= 0.0 {
        return start;
    }
    let t = (step as f64 / steps as f64).min(1.0);
    (start.ln() * (1.0 - t) + end.ln() * t).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decays_geometrically_and_holds() {
        assert!((exponential_decay(1e-2, 1e-4, 0, 100) - 1e-2).abs() < 1e-15);
        assert!((exponential_decay(1e-2, 1e-4, 50, 100) - 1e-3).abs() < 1e-15);
        assert!((exponential_decay(1e-2, 1e-4, 100, 100) - 1e-4).abs() < 1e-17);
        assert!((exponential_decay(1e-2, 1e-4, 500, 100) - 1e-4).abs() < 1e-17);
        assert_eq!(exponential_decay(1e-2, 1e-4, 5, 0), 1e-2);
    }
}
