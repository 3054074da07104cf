//! The coloured procedural texture painted on every synthetic subject: a smooth function of the
//! rest-pose position, so a surface point keeps its colour through the animation. Frequencies
//! are relative to the subject's size (scale-free): about five colour bands and a 20-cell
//! checker modulation across the bounding sphere. [`Pattern::Bands`] prints high-contrast
//! bands over it, as fox_walk_banded's printed cloth: a slide of a band's width shows there.

use glam::DVec3;

/// Dark bands per bounding-sphere radius along the bands' normal (about 1.5 radii⁻¹ of it per
/// unit of `x + y + z / 2`): at 96² a dark band is 1–6 pixels across a row, 3 at the median.
const BANDS_PER_RADIUS: f64 = 2.0;

/// The share of each band period that is dark.
const DARK_SHARE: f64 = 0.4;

/// What a dark band leaves of the colour under it (a real print's contrast).
const DARK_FACTOR: f64 = 0.25;

/// What a speckle adds to the colour under it, × that colour.
const SPECKLE_GAIN: f64 = 0.3;

/// What is printed on a subject.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pattern {
    /// The smooth bands and soft checker alone.
    #[default]
    Smooth,
    /// Dark diagonal bands with distorted edges and a light speckle multiplied over them.
    Bands,
}

impl Pattern {
    /// `smooth` or `bands` (for the CLI).
    pub fn from_name(name: &str) -> Result<Self, String> {
        match name {
            "smooth" => Ok(Self::Smooth),
            "bands" => Ok(Self::Bands),
            other => Err(format!("unknown pattern {other:?} (smooth or bands)")),
        }
    }
}

/// The procedural texture of a subject, fitted to its rest pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texture {
    /// Centre and radius of the rest pose's bounding sphere (about the box centre).
    pub center: DVec3,
    /// Radius of that sphere, scene units (1 when the rest pose has no extent).
    pub radius: f64,
    /// What is printed over the smooth colours.
    pub pattern: Pattern,
}

impl Texture {
    /// Fitted to the rest-pose positions (a non-empty set).
    pub fn fit(rest: &[[f32; 3]]) -> Self {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in rest {
            let p = DVec3::from(p.map(f64::from));
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let center = 0.5 * (lo + hi);
        let radius =
            rest.iter().map(|p| DVec3::from(p.map(f64::from)).distance(center)).fold(0.0, f64::max);
        let radius = if radius > 0.0 { radius } else { 1.0 };
        Self { center, radius, pattern: Pattern::Smooth }
    }

    /// The same texture with `pattern` printed over it.
    pub fn with_pattern(self, pattern: Pattern) -> Self {
        Self { pattern, ..self }
    }

    /// Linear RGB at rest-pose position `p`: in [0.05, 0.95] for [`Pattern::Smooth`], in
    /// [0.01, 0.95] with the bands.
    #[inline]
    pub fn color(&self, p: DVec3) -> [f32; 3] {
        let smooth = self.smooth_color(p);
        match self.pattern {
            Pattern::Smooth => smooth,
            Pattern::Bands => {
                let print = self.print(p);
                smooth.map(|c| (c as f64 * print).min(0.95) as f32)
            }
        }
    }

    /// The factor [`Pattern::Bands`] multiplies the colour at `p` by: 0.25 in a band, 1
    /// between them, 1.3 on a speckle (`DARK_FACTOR`, `SPECKLE_GAIN`).
    pub fn print(&self, p: DVec3) -> f64 {
        let q = (p - self.center) / self.radius;
        let across = (q.x + q.y + 0.5 * q.z) * BANDS_PER_RADIUS;
        let wobble = 0.2 * (7.0 * q.z).sin() + 0.12 * (11.0 * q.x + 1.0).sin();
        let band = if (across + wobble).rem_euclid(1.0) < DARK_SHARE { DARK_FACTOR } else { 1.0 };
        let speckle =
            (53.0 * q.x + 1.0).sin() * (59.0 * q.y + 2.0).sin() * (61.0 * q.z + 3.0).sin();
        band * if speckle > 0.6 { 1.0 + SPECKLE_GAIN } else { 1.0 }
    }

    /// The smooth colour bands and checker.
    fn smooth_color(&self, p: DVec3) -> [f32; 3] {
        let q = 2.5 * (p - self.center) / self.radius;
        let band = |a: f64, b: f64, shift: f64| {
            0.5 + 0.3 * (2.0 * a + shift + 0.8 * (1.3 * b).sin()).sin()
        };
        let checker = ((9.0 * q.x).sin() * (9.0 * q.y).sin() * (9.0 * q.z).sin() * 6.0).tanh();
        let m = 0.78 + 0.17 * checker;
        [band(q.x, q.y, 0.0) * m, band(q.y, q.z, 2.1) * m, band(q.z, q.x, 4.2) * m]
            .map(|c| c as f32)
    }

    /// 8-bit vertex colours for rest positions.
    pub fn vertex_colors(&self, rest: &[[f32; 3]]) -> Vec<[u8; 3]> {
        rest.iter()
            .map(|p| self.color(DVec3::from(p.map(f64::from))).map(|c| (c * 255.0).round() as u8))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_alternate_across_the_subject_and_leave_the_smooth_colours_between_them() {
        let smooth = Texture::fit(&[[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]);
        let banded = smooth.with_pattern(Pattern::Bands);
        // Along the bands' normal through the centre, one radius: dark runs start about
        // 1.5 × BANDS_PER_RADIUS times (the wobble moves the edges, not the count).
        let normal = DVec3::new(1.0, 1.0, 0.5).normalize() * smooth.radius;
        let dark: Vec<bool> =
            (0..=2000).map(|i| banded.print(normal * (i as f64 / 2000.0)) < 0.5).collect();
        let starts = dark.windows(2).filter(|w| !w[0] && w[1]).count();
        assert!((2..=4).contains(&starts), "{starts} dark bands in one radius");
        let share = dark.iter().filter(|&&d| d).count() as f64 / dark.len() as f64;
        assert!((share - DARK_SHARE).abs() < 0.15, "dark share {share}");
        for i in 0..500 {
            let p = normal * (i as f64 / 250.0 - 1.0);
            let (a, b) = (smooth.color(p), banded.color(p));
            let factor = banded.print(p);
            for k in 0..3 {
                let expect = (a[k] as f64 * factor).min(0.95);
                assert!((b[k] as f64 - expect).abs() < 1e-6 && (0.01..=0.95).contains(&b[k]));
            }
        }
        assert_eq!(Pattern::from_name("bands"), Ok(Pattern::Bands));
        assert!(Pattern::from_name("stripes").unwrap_err().contains("smooth or bands"));
    }
}
