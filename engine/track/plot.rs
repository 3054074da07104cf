//! A PNG of trajectories, drawn without text (no font is needed anywhere).
//!
//! Left panel: every trajectory projected on the two world axes along which the points spread
//! most, equal scale on both, a square at each frame-0 position. Right panel: each point's
//! distance from its frame-0 position against the frame index, from 0 (bottom) to the largest
//! displacement (top). One colour per point, the same in both panels.

use super::TrackError;
use crate::io::plot::{draw_panel, write_png_rgb, BACKGROUND, PANEL};
use glam::{DVec2, DVec3};
use image::RgbImage;
use std::path::Path;

/// Draws `trajectories[i][t]` (point i in frame t) into a 1200×600 image.
pub fn draw_trajectories(trajectories: &[Vec<DVec3>]) -> RgbImage {
    let mut image = RgbImage::from_pixel(2 * PANEL, PANEL, BACKGROUND);
    let (a, b) = spread_axes(trajectories);
    let projected: Vec<Vec<DVec2>> =
        trajectories.iter().map(|t| t.iter().map(|p| DVec2::new(p[a], -p[b])).collect()).collect();
    let displacement: Vec<Vec<DVec2>> = trajectories
        .iter()
        .map(|t| {
            t.iter().enumerate().map(|(f, p)| DVec2::new(f as f64, -p.distance(t[0]))).collect()
        })
        .collect();
    draw_panel(&mut image, 0, &projected, true);
    draw_panel(&mut image, PANEL, &displacement, false);
    image
}

/// Draws the plot and writes it as a PNG, atomically.
pub fn write_plot(path: &Path, trajectories: &[Vec<DVec3>]) -> Result<(), TrackError> {
    write_png_rgb(path, &draw_trajectories(trajectories))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::plot::{palette, FRAME};
    use image::Rgb;

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
