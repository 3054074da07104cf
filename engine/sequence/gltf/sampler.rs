//! glTF animation samplers evaluated as the specification's Appendix C says, in f64: STEP,
//! LINEAR (slerp for rotations, the specification's shortest-path formula) and CUBICSPLINE
//! (the Hermite spline with tangents scaled by the key interval; rotations normalised).
//! Before the first key the first value holds, after the last key the last.

pub use gltf::animation::Interpolation;

/// Keyframes of one animated property: `width` values per key (3 for translation and scale, 4
/// for a rotation's x, y, z, w, the target count for morph weights); CUBICSPLINE keys hold
/// (in-tangent, value, out-tangent).
#[derive(Clone, Debug)]
pub struct Sampler {
    interpolation: Interpolation,
    times: Vec<f64>,
    values: Vec<f64>,
    width: usize,
    rotation: bool,
}

impl Sampler {
    /// A sampler, after checking that there is a key, that the times are finite and strictly
    /// increasing, that there are as many values as keys need, and that they are finite.
    pub fn new(
        interpolation: Interpolation,
        times: Vec<f64>,
        values: Vec<f64>,
        width: usize,
        rotation: bool,
    ) -> Result<Self, String> {
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if times.is_empty() {
            return Err("has no keys".into());
        }
        if let Some(k) = times.iter().position(|t| !t.is_finite()) {
            return Err(format!("key {k} has time {}", times[k]));
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "key times do not increase: key {} at {} s follows key {k} at {} s",
                k + 1,
                times[k + 1],
                times[k]
            ));
        }
        if Some(values.len()) != times.len().checked_mul(per_key * width) {
            return Err(format!(
                "{} keys of {interpolation:?} need {} values of {width}, the output holds {}",
                times.len(),
                times.len() * per_key,
                values.len() as f64 / width.max(1) as f64
            ));
        }
        if let Some(v) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("output value {v} is {}", values[v]));
        }
        Ok(Self { interpolation, times, values, width, rotation })
    }

    /// The key times, seconds.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The value at `t` seconds. The key interval holding `t` is found at the file's precision
    /// (`t` rounded to f32, as key times are stored), so that a time computed as k / fps lands
    /// on the key the file wrote as (k / fps) as f32 and STEP does not hold the previous key.
    pub fn sample(&self, t: f64) -> Vec<f64> {
        let n = self.times.len();
        let at = t as f32 as f64;
        if n == 1 || at <= self.times[0] {
            return self.value(0).to_vec();
        }
        if at >= self.times[n - 1] {
            return self.value(n - 1).to_vec();
        }
        let k = self.times.partition_point(|&x| x <= at) - 1;
        let dt = self.times[k + 1] - self.times[k];
        let s = ((t - self.times[k]) / dt).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => self.value(k).to_vec(),
            Interpolation::Linear if self.rotation => slerp(self.value(k), self.value(k + 1), s),
            Interpolation::Linear => {
                let (a, b) = (self.value(k), self.value(k + 1));
                a.iter().zip(b).map(|(a, b)| a + s * (b - a)).collect()
            }
            Interpolation::CubicSpline => {
                let r = self.hermite(k, s, dt);
                if self.rotation {
                    normalised(r)
                } else {
                    r
                }
            }
        }
    }

    /// Part `part` (0 in-tangent, 1 value, 2 out-tangent) of key `k`'s cubic-spline triple.
    fn part(&self, k: usize, part: usize) -> &[f64] {
        let at = (3 * k + part) * self.width;
        &self.values[at..at + self.width]
    }

    /// The value of key `k`.
    fn value(&self, k: usize) -> &[f64] {
        if self.interpolation == Interpolation::CubicSpline {
            self.part(k, 1)
        } else {
            &self.values[k * self.width..(k + 1) * self.width]
        }
    }

    /// p(s) = (2s³ − 3s² + 1)·v_k + td·(s³ − 2s² + s)·b_k + (−2s³ + 3s²)·v_k+1 + td·(s³ − s²)·a_k+1,
    /// b_k the out-tangent of key k, a_k+1 the in-tangent of key k + 1, td the key interval.
    fn hermite(&self, k: usize, s: f64, td: f64) -> Vec<f64> {
        let (s2, s3) = (s * s, s * s * s);
        let (v0, b0) = (self.part(k, 1), self.part(k, 2));
        let (a1, v1) = (self.part(k + 1, 0), self.part(k + 1, 1));
        (0..self.width)
            .map(|i| {
                (2.0 * s3 - 3.0 * s2 + 1.0) * v0[i]
                    + td * (s3 - 2.0 * s2 + s) * b0[i]
                    + (-2.0 * s3 + 3.0 * s2) * v1[i]
                    + td * (s3 - s2) * a1[i]
            })
            .collect()
    }
}

/// The specification's slerp: with d = a·b, angle = acos(|d|), the shorter way round:
/// sin(angle (1 − s)) / sin(angle) · a + sign(d) · sin(angle s) / sin(angle) · b; a plain
/// linear blend when the keys are (numerically) the same rotation.
fn slerp(a: &[f64], b: &[f64], s: f64) -> Vec<f64> {
    let d: f64 = a.iter().zip(b).map(|(a, b)| a * b).sum();
    let sign = if d < 0.0 { -1.0 } else { 1.0 };
    let angle = d.abs().min(1.0).acos();
    let (wa, wb) = if angle.sin() < 1e-12 {
        (1.0 - s, sign * s)
    } else {
        let sin = angle.sin();
        (((1.0 - s) * angle).sin() / sin, sign * (s * angle).sin() / sin)
    };
    a.iter().zip(b).map(|(a, b)| wa * a + wb * b).collect()
}

/// `q` scaled to unit length (unchanged when it is zero).
fn normalised(q: Vec<f64>) -> Vec<f64> {
    let length = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if length > 0.0 {
        q.into_iter().map(|x| x / length).collect()
    } else {
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(
        interpolation: Interpolation,
        values: Vec<f64>,
        width: usize,
        rotation: bool,
    ) -> Sampler {
        Sampler::new(interpolation, vec![1.0, 2.0, 4.0], values, width, rotation).unwrap()
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-12)
    }

    #[test]
    fn step_and_linear_hold_outside_the_keys_and_blend_inside() {
        let step = sampler(Interpolation::Step, vec![0.0, 10.0, 30.0], 1, false);
        let linear = sampler(Interpolation::Linear, vec![0.0, 10.0, 30.0], 1, false);
        for (t, held, blended) in [
            (0.0, 0.0, 0.0),
            (1.5, 0.0, 5.0),
            (2.0, 10.0, 10.0),
            (3.0, 10.0, 20.0),
            (9.0, 30.0, 30.0),
        ] {
            assert_eq!(step.sample(t), [held], "STEP at {t}");
            assert!(close(&linear.sample(t), &[blended]), "LINEAR at {t}");
        }
    }

    #[test]
    fn linear_rotations_follow_the_great_circle_the_short_way() {
        // 0°, 90° and −270° (the same as 90°, as the antipodal quaternion) about z.
        let z = |degrees: f64| {
            let h = degrees.to_radians() / 2.0;
            [0.0, 0.0, h.sin(), h.cos()]
        };
        let flipped = z(90.0).map(|c| -c);
        let values = [z(0.0), z(90.0), flipped].concat();
        let rotation = sampler(Interpolation::Linear, values, 4, true);
        // A quarter of the way from 0° to 90° (t = 1.25) is 22.5°.
        assert!(close(&rotation.sample(1.25), &z(22.5)), "{:?}", rotation.sample(1.25));
        // 90° to its antipode: the same rotation all the way (a sign flip, no turn).
        let mid = rotation.sample(3.0);
        assert!(close(&mid, &z(90.0)) || close(&mid, &flipped), "{mid:?}");
    }

    #[test]
    fn cubic_splines_are_the_specifications_hermite_with_scaled_tangents() {
        // Keys (in, value, out): (0, 0, 2), (−1, 1, 1), (0, 0, 0) at 1 s, 2 s and 4 s.
        let values = vec![0.0, 0.0, 2.0, -1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
        let cubic = sampler(Interpolation::CubicSpline, values, 1, false);
        let hermite = |s: f64, v0: f64, b0: f64, v1: f64, a1: f64, td: f64| {
            (2.0 * s * s * s - 3.0 * s * s + 1.0) * v0
                + td * (s * s * s - 2.0 * s * s + s) * b0
                + (-2.0 * s * s * s + 3.0 * s * s) * v1
                + td * (s * s * s - s * s) * a1
        };
        for s in [0.0, 0.3, 0.5, 0.9] {
            let first = hermite(s, 0.0, 2.0, 1.0, -1.0, 1.0);
            assert!(close(&cubic.sample(1.0 + s), &[first]), "s = {s}");
            // Over the 2-second interval the tangents count twice.
            let second = hermite(s, 1.0, 1.0, 0.0, 0.0, 2.0);
            assert!(close(&cubic.sample(2.0 + 2.0 * s), &[second]), "s = {s}");
        }
        assert!(close(&cubic.sample(3.0), &[0.75]));
    }

    #[test]
    fn keys_at_f32_times_are_found_from_f64_frame_times() {
        // Keys at (k / 30) as f32, as a writer stores them; sampled at k / 30 in f64.
        let times: Vec<f64> = (0..40).map(|k| (k as f64 / 30.0) as f32 as f64).collect();
        let values: Vec<f64> = (0..40).map(f64::from).collect();
        let step = Sampler::new(Interpolation::Step, times, values, 1, false).unwrap();
        for k in 0..40 {
            assert_eq!(step.sample(k as f64 / 30.0), [k as f64]);
        }
    }

    #[test]
    fn bad_keys_are_refused() {
        let new = |times: Vec<f64>, values: Vec<f64>| {
            Sampler::new(Interpolation::Linear, times, values, 1, false).unwrap_err()
        };
        assert!(new(vec![], vec![]).contains("no keys"));
        assert!(new(vec![0.0, f64::NAN], vec![0.0, 1.0]).contains("key 1 has time NaN"));
        assert!(new(vec![0.0, 0.0], vec![0.0, 1.0]).contains("do not increase"));
        assert!(new(vec![0.0, 1.0], vec![0.0]).contains("need 2 values"));
        assert!(new(vec![0.0, 1.0], vec![0.0, f64::INFINITY]).contains("output value 1 is inf"));
    }
}
