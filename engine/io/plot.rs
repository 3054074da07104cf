//! Plots drawn without text (no font is needed anywhere): square panels with a grid and one
//! polyline per curve in well-separated colours. Files that carry the numbers go beside them.

use super::write_atomically;
use glam::DVec2;
use image::{Rgb, RgbImage};
use std::path::Path;

/// Side of one panel, pixels.
pub const PANEL: u32 = 600;
const MARGIN: f64 = 30.0;
pub const BACKGROUND: Rgb<u8> = Rgb([255, 255, 255]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
pub(crate) const FRAME: Rgb<u8> = Rgb([120, 120, 120]);

/// One panel of curves (y grows downwards: negate values that should rise) as a PNG.
pub fn write_line_plot(path: &Path, curves: &[Vec<DVec2>]) -> std::io::Result<()> {
    let mut image = RgbImage::from_pixel(PANEL, PANEL, BACKGROUND);
    draw_panel(&mut image, 0, curves, false);
    write_png_rgb(path, &image)
}

/// Writes an RGB image as a PNG, atomically.
pub fn write_png_rgb(path: &Path, image: &RgbImage) -> std::io::Result<()> {
    write_atomically(path, |w| {
        image.write_to(w, image::ImageFormat::Png).map_err(std::io::Error::other)
    })
}

/// One panel at x offset `left`: frame, grid, one polyline per curve (y grows downwards in
/// the data already). `equal_scale` keeps the aspect ratio; frame-0 points get a marker.
pub fn draw_panel(image: &mut RgbImage, left: u32, curves: &[Vec<DVec2>], equal_scale: bool) {
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
    let to_pixel = |p: DVec2| {
        DVec2::new(left as f64 + PANEL as f64 * 0.5, PANEL as f64 * 0.5)
            + (p - centre) / scale * (hi - lo)
    };
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
pub(crate) fn palette(i: usize) -> Rgb<u8> {
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
