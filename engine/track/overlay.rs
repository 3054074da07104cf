//! Tracked points drawn over a camera's footage, so an animator can see where each one sits.
//!
//! A point the camera sees is a filled disk; one hidden by the frame's surface is a ring of the
//! same size, so an occluded point stays findable without looking seen. Colours follow the
//! trajectory plot's, point by point.

use crate::io::image::Image;
use crate::io::plot::colour_rgb;

/// One point to draw: its pixel position (the centre of pixel (i, j) is (i + 0.5, j + 0.5)),
/// whether the camera sees it, and its colour in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    /// Horizontal pixel coordinate.
    pub u: f64,
    /// Vertical pixel coordinate (y down).
    pub v: f64,
    /// Seen (a disk) or hidden (a ring).
    pub visible: bool,
    /// RGB in [0, 1].
    pub rgb: [f32; 3],
}

/// The plot's colour of point `i` (its place in the track report), as RGB in [0, 1].
pub fn mark_colour(i: usize) -> [f32; 3] {
    colour_rgb(i).map(|c| c as f32 / 255.0)
}

/// The marks' radius in pixels for an image of this size: a hundredth of its smaller side,
/// at least 2 pixels.
pub fn mark_radius(width: u32, height: u32) -> f64 {
    (width.min(height) as f64 / 100.0).max(2.0)
}

/// The RGB part of `image`: grey repeated into three channels, alpha dropped.
pub fn rgb_of(image: &Image) -> Image {
    let c = image.channels as usize;
    let data = image
        .data
        .chunks_exact(c)
        .flat_map(|p| if c < 3 { [p[0]; 3] } else { [p[0], p[1], p[2]] })
        .collect();
    Image { width: image.width, height: image.height, channels: 3, data }
}

/// Draws `marks` into `image` (RGB, see [`rgb_of`]), later marks over earlier ones. Pixel
/// (i, j) takes a visible mark's colour when its centre lies within `radius` of the mark, a
/// hidden mark's when it lies within half a pixel of the circle of that radius. Only what
/// falls inside the image is drawn; a mark with a non-finite coordinate draws nothing.
pub fn draw_marks(image: &mut Image, marks: &[Mark], radius: f64) {
    assert_eq!(image.channels, 3, "draw_marks takes an RGB image");
    let (width, height) = (image.width as i64, image.height as i64);
    let reach = radius + 0.5;
    for mark in marks.iter().filter(|m| m.u.is_finite() && m.v.is_finite()) {
        let span = |centre: f64, size: i64| {
            let lo = ((centre - reach).floor() as i64).clamp(0, size);
            (lo, ((centre + reach).ceil() as i64).clamp(0, size))
        };
        let ((x0, x1), (y0, y1)) = (span(mark.u, width), span(mark.v, height));
        for y in y0..y1 {
            for x in x0..x1 {
                let d = (x as f64 + 0.5 - mark.u).hypot(y as f64 + 0.5 - mark.v);
                let covered = if mark.visible { d <= radius } else { (d - radius).abs() <= 0.5 };
                if covered {
                    let at = 3 * (y * width + x) as usize;
                    image.data[at..at + 3].copy_from_slice(&mark.rgb);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RED: [f32; 3] = [1.0, 0.0, 0.0];

    fn grey(width: u32, height: u32) -> Image {
        Image { width, height, channels: 3, data: vec![0.5; (3 * width * height) as usize] }
    }

    fn pixel(image: &Image, x: u32, y: u32) -> [f32; 3] {
        [0, 1, 2].map(|c| image.at(x, y, c))
    }

    fn mark(u: f64, v: f64, visible: bool) -> Mark {
        Mark { u, v, visible, rgb: RED }
    }

    #[test]
    fn a_seen_point_is_a_disk_and_a_hidden_one_a_ring() {
        let mut image = grey(20, 20);
        draw_marks(&mut image, &[mark(5.5, 5.5, true), mark(14.5, 14.5, false)], 3.0);
        // The disk: its centre pixel and one 3 pixels away are drawn, one 4 away is not.
        assert_eq!(pixel(&image, 5, 5), RED);
        assert_eq!(pixel(&image, 8, 5), RED);
        assert_eq!(pixel(&image, 9, 5), [0.5; 3]);
        // The ring: its centre is left as it was, the circle is drawn.
        assert_eq!(pixel(&image, 14, 14), [0.5; 3]);
        assert_eq!(pixel(&image, 17, 14), RED);
        assert_eq!(pixel(&image, 14, 11), RED);
        let drawn = image.data.chunks_exact(3).filter(|p| p == &RED).count();
        // A disk of radius 3 covers 29 pixel centres; the ring about 2π·3 ≈ 19 pixels.
        assert!((29 + 12..=29 + 28).contains(&drawn), "{drawn} pixels drawn");
    }

    #[test]
    fn marks_off_the_image_or_not_finite_draw_only_what_is_inside() {
        let mut image = grey(8, 8);
        let marks = [
            mark(-0.5, 3.5, true),
            mark(f64::NAN, 2.0, true),
            mark(2.0, f64::INFINITY, false),
            mark(1e300, -1e300, true),
        ];
        draw_marks(&mut image, &marks, 2.0);
        // Only the first mark reaches the image: its right half, in column 0 and 1.
        assert_eq!(pixel(&image, 0, 3), RED);
        assert_eq!(pixel(&image, 1, 3), RED);
        assert_eq!(pixel(&image, 2, 3), [0.5; 3]);
        assert!(image.data.chunks_exact(3).skip(8 * 6).all(|p| p == [0.5; 3]));
    }

    #[test]
    fn grey_and_rgba_images_become_rgb() {
        let grey = Image { width: 2, height: 1, channels: 1, data: vec![0.25, 0.75] };
        assert_eq!(rgb_of(&grey).data, vec![0.25, 0.25, 0.25, 0.75, 0.75, 0.75]);
        let rgba = Image { width: 1, height: 1, channels: 4, data: vec![0.1, 0.2, 0.3, 0.0] };
        assert_eq!(rgb_of(&rgba).data, vec![0.1, 0.2, 0.3]);
    }
}
