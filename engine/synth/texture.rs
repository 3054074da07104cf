//! The coloured procedural texture painted on every synthetic subject: a smooth function of the
//! rest-pose position, so a surface point keeps its colour through the animation. Frequencies
//! are relative to the subject's size (scale-free): about five colour bands and a 20-cell
//! checker modulation across the bounding sphere.

use glam::DVec3;

/// The procedural texture of a subject, fitted to its rest pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texture {
    /// Centre and radius of the rest pose's bounding sphere (about the box centre).
    pub center: DVec3,
    /// Radius of that sphere, scene units (1 when the rest pose has no extent).
    pub radius: f64,
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
        Self { center, radius: if radius > 0.0 { radius } else { 1.0 } }
    }

    /// Linear RGB in [0.05, 0.95] at rest-pose position `p`.
    #[inline]
    pub fn color(&self, p: DVec3) -> [f32; 3] {
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
