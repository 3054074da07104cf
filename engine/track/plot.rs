//! A PNG of trajectories, drawn without text (no font is needed anywhere).
//!
//! Left panel: every trajectory projected on the two world axes along which the points spread
//! most, equal scale on both, a square at each frame-0 position. Right panel: each point's
//! distance from its frame-0 position against the frame index, from 0 (bottom) to the largest
//! displacement (top). One colour per point, the same in both panels.

use super::TrackError;
use crate::io::write_atomically;
use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};
use std::path::Path;

const PANEL: u32 = 600;
const MARGIN: f64 = 30.0;
const BACKGROUND: Rgb<u8> = Rgb([255, 255, 255]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
const FRAME: Rgb<u8> = Rgb([120, 120, 120]);

/// Draws `trajectories[i][t]` (point i in frame t) into a 1200×600 image.
pub fn draw_trajectories(trajectories: &[Vec<DVec3>]) -> RgbImage {
    let mut image = RgbImage::from_pixel(2 * PANEL, PANEL, BACKGROUND);
    let (a, b) = spread_axes(trajectories);
    let projected: Vec<Vec<DVec2>> = trajectories.iter().map(|t| t.iter().map(|p| DVec2::new(p[a], -p[b])).collect()).collect();
    let displacement: Vec<Vec<DVec2>> = trajectories
        .iter()
        .map(|t| t.iter().enumerate().map(|(f, p)| DVec2::new(f as f64, -p.distance(t[0]))).collect())
        .collect();
    draw_panel(&mut image, 0, &projected, true);
    draw_panel(&mut image, PANEL, &displacement, false);
    image
}

/// Draws the plot and writes it as a PNG, atomically.
pub fn write_plot(path: &Path, trajectories: &[Vec<DVec3>]) -> Result<(), TrackError> {
    let image = draw_trajectories(trajectories);
    write_atomically(path, |w| image.write_to(w, image::ImageFormat::Png).map_err(std::io::Error::other))
        .map_err(|error| TrackError::Io { path: path.to_owned(), error })
}

/// The two axes with the largest coordinate range over all points, in axis order.
fn spread_axes(trajectories: &[Vec<DVec3>]) -> (usize, usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in trajectories.iter().flatten() {
        min = min.min(*p);
        max = max.max(*p);
    }
    let range = (max - min).max(DVec3::ZERO);
    let smallest = (0..3).min_by(|&i, &j| range[i].total_cmp(&range[j])).unwrap_or(2);
    match smallest {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// One panel at x offset `left`: frame, grid, one polyline per curve (y grows downwards in
/// the data already). `equal_scale` keeps the aspect ratio; frame-0 points get a marker.
fn draw_panel(image: &mut RgbImage, left: u32, curves: &[Vec<DVec2>], equal_scale: bool) {
    let (lo, hi) = (MARGIN, PANEL as f64 - MARGIN);
    for k in 0..=4 {
        let s = lo + (hi - lo) * k as f64 / 4.0;
        let colour = if k == 0 || k == 4 { FRAME } else { GRID };
        draw_line(image, DVec2::new(left as f64 + lo, s), DVec2::new(left as f64 + hi, s), colour);
        draw_line(image, DVec2::new(left as f64 + s, lo), DVec2::new(left as f64 + s, hi), colour);
    }
    let (mut min, mut max) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for p in curves.iter().flatten().filter(|p| p.is_finite()) {
        min = min.min(*p);
        max = max.max(*p);
    }
    if min.x > max.x {
        return; // No finite point.
    }
    let mut scale = (max - min).max(DVec2::splat(f64::MIN_POSITIVE));
    if equal_scale {
        scale = DVec2::splat(scale.max_element());
    }
    let centre = (min + max) * 0.5;
    let to_pixel = |p: DVec2| DVec2::new(left as f64 + PANEL as f64 * 0.5, PANEL as f64 * 0.5) + (p - centre) / scale * (hi - lo);
    for (i, curve) in curves.iter().enumerate() {
        let colour = palette(i);
        for pair in curve.windows(2) {
            draw_line(image, to_pixel(pair[0]), to_pixel(pair[1]), colour);
        }
        if let (true, Some(&start)) = (equal_scale, curve.first()) {
            let c = to_pixel(start);
            for d in [-2.0, 2.0] {
                draw_line(image, c + DVec2::new(-2.0, d), c + DVec2::new(2.0, d), colour);
                draw_line(image, c + DVec2::new(d, -2.0), c + DVec2::new(d, 2.0), colour);
            }
        }
    }
}

/// A straight line in steps of at most one pixel; pixels outside the image and non-finite
/// ends are skipped.
fn draw_line(image: &mut RgbImage, a: DVec2, b: DVec2, colour: Rgb<u8>) {
    if !a.is_finite() || !b.is_finite() {
        return;
    }
    let steps = (b - a).abs().max_element().ceil().min(1e5) as usize;
    for s in 0..=steps {
        let p = a.lerp(b, if steps == 0 { 0.0 } else { s as f64 / steps as f64 });
        let (x, y) = (p.x.floor(), p.y.floor());
        if x >= 0.0 && y >= 0.0 && x < image.width() as f64 && y < image.height() as f64 {
            image.put_pixel(x as u32, y as u32, colour);
        }
    }
}

/// Well-separated colours: hues a golden-ratio step apart.
fn palette(i: usize) -> Rgb<u8> {
    let hue = (i as f64 * 0.618_033_988_75).fract() * 6.0;
    let (s, v) = (0.85, 0.8);
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let rgb = match hue as u32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    };
    Rgb(rgb.map(|c| (c * 255.0).round() as u8))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_each_curve_in_its_colour_and_survives_degenerate_input() {
        let moving = vec![DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0)];
        let still = vec![DVec3::new(0.5, 0.5, 0.0); 3];
        let image = draw_trajectories(&[moving, still]);
        let count = |c: Rgb<u8>| image.pixels().filter(|&&p| p == c).count();
        assert!(count(palette(0)) > 500, "the moving point's path is drawn in both panels");
        assert!(count(palette(1)) > 0, "the still point is marked");
        // Nothing, one frame, NaN: no panic, and the frame is still drawn.
        for t in [vec![], vec![vec![DVec3::ONE]], vec![vec![DVec3::NAN, DVec3::ONE]]] {
            assert!(draw_trajectories(&t).pixels().any(|&p| p == FRAME));
        }
    }
}
