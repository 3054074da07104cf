//! Whether a capture's images show something behind the subject (a studio's background plate)
//! or were composited over black (a render): `dataset info` says which, so a user knows the
//! masks, not the colours, say what is subject. Over black, lit pixels outside a mask are
//! subject the mask left out (over a background, pixels that are not the camera's plate,
//! `matte::off_plate`): [`Dataset::check`] names the views where that is much of it.

use super::{Dataset, DatasetError};

/// Past this share of lit pixels outside the masks, the images carry a background.
pub const BACKGROUND_SHARE: f64 = 0.05;
/// Mask values at or below this are background.
const OUTSIDE: f32 = 0.05;
/// A background pixel with a channel above this is not black (8 of 255: past JPEG noise).
const NOT_BLACK: f32 = 8.0 / 255.0;

/// The share in [0, 1] of the background pixels (mask ≤ 0.05) of `frame`'s views whose colour
/// is not black, over every view with a mask; 0 when no view has a background pixel.
pub fn background_share(dataset: &Dataset, frame: usize) -> Result<f64, DatasetError> {
    let (mut outside, mut lit) = (0u64, 0u64);
    let views = dataset.frames.get(frame).map_or(0, |f| f.views.len());
    for view in 0..views {
        let (image, mask) = (dataset.image(frame, view)?, dataset.given_mask(frame, view)?);
        let counts = MaskCounts::of(&image.data, image.channels as usize, &mask);
        (outside, lit) = (outside + counts.outside, lit + counts.lit_outside);
    }
    Ok(if outside == 0 { 0.0 } else { lit as f64 / outside as f64 })
}

/// One view's mask against its image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaskCounts {
    /// Pixels the mask calls subject (> 0.5).
    pub inside: u64,
    /// Pixels the mask calls background (≤ 0.05).
    pub outside: u64,
    /// Of the background pixels, those whose colour is not black.
    pub lit_outside: u64,
}

impl MaskCounts {
    /// The counts of an image with `channels` samples a pixel and its mask.
    pub fn of(data: &[f32], channels: usize, mask: &[f32]) -> Self {
        let (outside, lit_outside) = count_lit(data, channels, mask);
        let inside = mask.iter().filter(|&&m| m > 0.5).count() as u64;
        Self { inside, outside, lit_outside }
    }
}

/// (background pixels, of them not black) of one image with `channels` samples a pixel.
fn count_lit(data: &[f32], channels: usize, mask: &[f32]) -> (u64, u64) {
    let pixels = data.chunks_exact(channels.max(1)).zip(mask).filter(|(_, &m)| m <= OUTSIDE);
    pixels.fold((0, 0), |(outside, lit), (colour, _)| {
        (outside + 1, lit + colour.iter().take(3).any(|&c| c > NOT_BLACK) as u64)
    })
}

#[cfg(test)]
mod tests {
    use super::count_lit;

    #[test]
    fn counts_only_lit_pixels_outside_the_mask() {
        // Four RGB pixels: subject, black background, grey background, near-black (JPEG noise).
        let data = [0.9, 0.8, 0.7, 0.0, 0.0, 0.0, 0.4, 0.4, 0.4, 0.02, 0.01, 0.0];
        let mask = [1.0, 0.0, 0.0, 0.0];
        assert_eq!(count_lit(&data, 3, &mask), (3, 1));
        assert_eq!(count_lit(&data, 3, &[1.0; 4]), (0, 0));
    }
}
