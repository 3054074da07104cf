//! Masks refined along their outline from the images, against each camera's background plate.
//!
//! A studio's masks are thresholded from a segmentation, and their outline can sit a pixel in
//! or out. When it does so in every camera at once the surface shrinks or grows with it: on
//! fox_walk_capture the masks were the whole gap to the clean benchmark
//! (docs/log/2026-11-28-capture-flaws-oracles.md). A static camera sees the same background
//! in every frame, and that says where the subject ends:
//! 1. [`Plate::from_frames`]: a pixel's background colour is the median, over the frames, of
//!    its colour where it lies more than [`PLATE_MARGIN`] pixels outside the frame's mask;
//!    a pixel never seen so takes the nearest seen pixel's colour;
//! 2. [`refine`]: each pixel near the outline is read as a blend of the plate and the
//!    subject's colour further inside; its share of the subject says on which side of the true
//!    outline it lies. The ring just outside the mask mostly subject means the outline sits a
//!    ring further out; the ring just inside mostly plate, a ring further in. The two rings
//!    either side of the outline so placed take their share as their new mask value, wherever
//!    the two colours differ enough to tell them apart.
//!
//! The refined mask is soft along the outline (a coverage, as a render's alpha is); pixels
//! away from it keep their values.

use crate::io::image::{four_neighbours, Image};
use std::collections::VecDeque;

/// A pixel counts as background in a frame when it lies more than this many pixels (steps
/// to a 4-neighbour) outside the frame's mask: clear of an outline a pixel or two off.
pub const PLATE_MARGIN: u32 = 2;
/// The most frames a plate takes its median over (evenly spread over the capture).
pub const PLATE_FRAMES: usize = 15;
/// The fewest frames a plate is taken from: a camera seen in fewer (a moving camera's
/// sequence) never shows the background behind the subject's outline.
pub const MIN_PLATE_FRAMES: usize = 3;
/// The subject's colour near a pixel: the mean of the pixels at least two rings inside the
/// outline within this radius (7 × 7), which reaches them from both rings decided again.
const WINDOW: i64 = 3;
/// The least distance (RGB, values in [0, 1]) between the plate's and the subject's colour for
/// a pixel's blend to say anything: below it, noise and JPEG decide.
const MIN_CONTRAST: f32 = 0.1;
/// The least distance (RGB, values in [0, 1]) from the plate at which a pixel well outside a
/// mask shows something else than the background ([`off_plate`]): past noise and JPEG.
const OFF_PLATE: f32 = 0.15;
/// How far [`depths`] counts: enough for the rings [`refine`] reads.
const MAX_STEPS: u32 = 5;

/// One camera's background as seen behind the subject, 8 bits a channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Plate {
    width: u32,
    height: u32,
    colour: Vec<[u8; 3]>,
}

impl Plate {
    /// The plate of one camera from its `views` (image and mask of a frame each, all of one
    /// size, masks one value per pixel with > 0.5 subject); a pixel seen clear of the masks
    /// in fewer than `min_seen` frames takes the nearest such pixel's colour. None when no
    /// pixel is seen so (or there is no view). Deterministic: a median and a fill in pixel
    /// order. (Checking a frame's mask against the plate needs `min_seen` 2: where only that
    /// frame's mask leaves a pixel clear, the plate would be what the mask left out.)
    pub fn from_frames(views: &[(&Image, &[f32])], min_seen: usize) -> Option<Plate> {
        let (first, _) = views.first()?;
        let (width, height) = (first.width, first.height);
        let (w, h) = (width as usize, height as usize);
        let outside: Vec<Vec<bool>> = views
            .iter()
            .take(PLATE_FRAMES)
            .map(|(_, mask)| {
                let steps = steps_from(&subject(mask), w, h, PLATE_MARGIN + 1);
                steps.iter().map(|&s| s > PLATE_MARGIN).collect()
            })
            .collect();
        let mut colour = vec![[0u8; 3]; w * h];
        let mut seen = vec![false; w * h];
        let mut values = [[0u8; PLATE_FRAMES]; 3];
        for (p, (colour, seen)) in colour.iter_mut().zip(&mut seen).enumerate() {
            let mut n = 0;
            for ((image, _), _) in views.iter().zip(&outside).filter(|(_, clear)| clear[p]) {
                for (channel, value) in values.iter_mut().zip(rgb(image, p)) {
                    channel[n] = to_u8(value);
                }
                n += 1;
            }
            *seen = n >= min_seen.max(1);
            for (out, channel) in colour.iter_mut().zip(&mut values).filter(|_| *seen) {
                // The lower median: one value of the set, the same whatever the order.
                *out = *channel[..n].select_nth_unstable((n - 1) / 2).1;
            }
        }
        fill_from_nearest(&mut colour, &seen, w, h)?;
        Some(Plate { width, height, colour })
    }

    /// The plate's colour at pixel `p` (row-major), in [0, 1].
    fn at(&self, p: usize) -> [f32; 3] {
        self.colour[p].map(|v| v as f32 / 255.0)
    }
}

/// `mask` (one value per pixel of `image`, > 0.5 subject) with the two rings either side of
/// its outline, moved a ring out or in where the images say so (`Blend::outline_offset`), replaced
/// by their share of subject colour against `plate`, in [0, 1]. A pixel keeps its value where
/// no subject pixel lies in its window or the two colours are closer than `MIN_CONTRAST`
/// (0.1). The mask comes back unchanged when its size or the plate's differs from the image's.
pub fn refine(image: &Image, mask: &[f32], plate: &Plate) -> Vec<f32> {
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = mask.to_vec();
    if mask.len() != w * h || (plate.width, plate.height) != (image.width, image.height) {
        return out;
    }
    let blend = Blend { image, plate, depth: depths(&subject(mask), w, h) };
    let offset = blend.outline_offset();
    for p in (0..w * h).filter(|&p| (offset..=offset + 1).contains(&blend.depth[p])) {
        if let Some(share) = blend.share(p, offset - 2) {
            out[p] = share;
        }
    }
    out
}

/// One image read as a blend of its camera's plate and the subject's colour.
struct Blend<'a> {
    image: &'a Image,
    plate: &'a Plate,
    /// Per pixel, from [`depths`] of the given mask.
    depth: Vec<i32>,
}

impl Blend<'_> {
    /// How many rings out (1) or in (-1) of the mask the true outline lies: the ring just
    /// outside the mask mostly subject means out, the ring just inside mostly plate in; 0
    /// otherwise, and where neither ring can be read. One offset for the whole image, as a
    /// threshold set a little off moves the whole outline.
    fn outline_offset(&self) -> i32 {
        let mean_share = |depth: i32| {
            let shares: Vec<f32> = (0..self.depth.len())
                .filter(|&p| self.depth[p] == depth)
                .filter_map(|p| self.share(p, -2))
                .collect();
            (!shares.is_empty()).then(|| shares.iter().sum::<f32>() / shares.len() as f32)
        };
        if mean_share(1).is_some_and(|s| s > 0.5) {
            1
        } else if mean_share(0).is_some_and(|s| s < 0.5) {
            -1
        } else {
            0
        }
    }

    /// Pixel `p`'s share of subject colour: its colour projected on the segment from the
    /// plate's to the mean colour of the pixels of depth `inner` or less within [`WINDOW`].
    /// None without such a pixel, or where the two colours are closer than `MIN_CONTRAST`.
    fn share(&self, p: usize, inner: i32) -> Option<f32> {
        let subject = self.mean_around(p, inner)?;
        let (pixel, back) = (rgb(self.image, p), self.plate.at(p));
        let d: [f32; 3] = std::array::from_fn(|c| subject[c] - back[c]);
        let contrast = d.iter().map(|v| v * v).sum::<f32>();
        let along: f32 = (0..3).map(|c| (pixel[c] - back[c]) * d[c]).sum();
        (contrast > MIN_CONTRAST * MIN_CONTRAST).then(|| (along / contrast).clamp(0.0, 1.0))
    }

    /// The mean colour of the pixels of depth `inner` or less within [`WINDOW`] of pixel `p`.
    fn mean_around(&self, p: usize, inner: i32) -> Option<[f32; 3]> {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let (x, y) = (p as i64 % w, p as i64 / w);
        let (mut sum, mut n) = ([0.0f32; 3], 0u32);
        for v in (y - WINDOW).max(0)..=(y + WINDOW).min(h - 1) {
            for u in (x - WINDOW).max(0)..=(x + WINDOW).min(w - 1) {
                let q = (v * w + u) as usize;
                if self.depth[q] <= inner {
                    for (s, c) in sum.iter_mut().zip(rgb(self.image, q)) {
                        *s += c;
                    }
                    n += 1;
                }
            }
        }
        (n > 0).then(|| sum.map(|s| s / n as f32))
    }
}

/// Two counts of `image` against its `mask` and its camera's `plate`: (pixels `mask` calls
/// subject, pixels more than [`PLATE_MARGIN`] outside it whose colour is not `plate`'s): over
/// a background, a mask that cuts the subject off leaves the second count large against the
/// first. `(0, 0)` when the sizes differ.
pub fn off_plate(image: &Image, mask: &[f32], plate: &Plate) -> (u64, u64) {
    let (w, h) = (image.width as usize, image.height as usize);
    if mask.len() != w * h || (plate.width, plate.height) != (image.width, image.height) {
        return (0, 0);
    }
    let inside = subject(mask);
    let steps = steps_from(&inside, w, h, PLATE_MARGIN + 1);
    let differs = |p: usize| {
        let (a, b) = (rgb(image, p), plate.at(p));
        (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f32>().sqrt() > OFF_PLATE
    };
    let off = (0..w * h).filter(|&p| steps[p] > PLATE_MARGIN && differs(p)).count();
    (inside.iter().filter(|&&s| s).count() as u64, off as u64)
}

/// Pixel `p`'s colour (a grey image's one value three times).
fn rgb(image: &Image, p: usize) -> [f32; 3] {
    let channels = image.channels.max(1) as usize;
    std::array::from_fn(|c| image.data[p * channels + c.min(channels - 1)])
}

fn subject(mask: &[f32]) -> Vec<bool> {
    mask.iter().map(|&m| m > 0.5).collect()
}

fn complement(set: &[bool]) -> Vec<bool> {
    set.iter().map(|&s| !s).collect()
}

fn to_u8(value: f32) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Per pixel, 4-neighbour steps to the nearest pixel of `set` (`w × h`, row-major): 0 on the
/// set, at most `cap` (further pixels, and every pixel when the set is empty, read `cap`).
fn steps_from(set: &[bool], w: usize, h: usize, cap: u32) -> Vec<u32> {
    let mut steps: Vec<u32> = set.iter().map(|&s| if s { 0 } else { cap }).collect();
    let mut queue: VecDeque<usize> = (0..w * h).filter(|&p| set[p]).collect();
    while let Some(p) = queue.pop_front() {
        let next = steps[p] + 1;
        for q in four_neighbours(p, w, h) {
            if next < steps[q] {
                steps[q] = next;
                queue.push_back(q);
            }
        }
    }
    steps
}

/// Per pixel, which ring of the outline of `subject` it lies on: 1, 2, … outside (steps to
/// the subject), 0, -1, … inside (one less than the steps to a pixel outside); the outline
/// lies between 0 and 1. Counted to [`MAX_STEPS`].
fn depths(subject: &[bool], w: usize, h: usize) -> Vec<i32> {
    let outside = steps_from(subject, w, h, MAX_STEPS);
    let inside = steps_from(&complement(subject), w, h, MAX_STEPS);
    (0..w * h).map(|p| if subject[p] { 1 - inside[p] as i32 } else { outside[p] as i32 }).collect()
}

/// Gives every pixel not `seen` the colour of the nearest seen one (4-neighbour steps, ties to
/// the one reached first from the seen pixels in index order). None when none is seen.
fn fill_from_nearest(colour: &mut [[u8; 3]], seen: &[bool], w: usize, h: usize) -> Option<()> {
    let mut queue: VecDeque<usize> = (0..w * h).filter(|&p| seen[p]).collect();
    if queue.is_empty() {
        return None;
    }
    let mut reached = seen.to_vec();
    while let Some(p) = queue.pop_front() {
        for q in four_neighbours(p, w, h) {
            if !reached[q] {
                reached[q] = true;
                colour[q] = colour[p];
                queue.push_back(q);
            }
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × w` RGB image: `back` everywhere, `front` on the pixels whose centre lies left of
    /// `edge` (x + 0.5 < edge), and the pixel the edge crosses blended by its share.
    fn edge_image(w: u32, edge: f32, back: [f32; 3], front: [f32; 3]) -> (Image, Vec<f32>) {
        let cover = |x: u32| (edge - x as f32).clamp(0.0, 1.0);
        let mut data = Vec::new();
        let mut coverage = Vec::new();
        for _ in 0..w {
            for x in 0..w {
                let a = cover(x);
                data.extend((0..3).map(|c| front[c] * a + back[c] * (1.0 - a)));
                coverage.push(a);
            }
        }
        (Image { width: w, height: w, channels: 3, data }, coverage)
    }

    #[test]
    fn a_mask_a_pixel_off_comes_back_to_the_images_outline() {
        let (back, front) = ([0.2, 0.5, 0.3], [0.9, 0.6, 0.1]);
        // The plate is seen in frames whose subject stops well left of the pixels it covers.
        let frames: Vec<(Image, Vec<f32>)> =
            [4.0, 6.0, 12.4, 12.6].iter().map(|&e| edge_image(24, e, back, front)).collect();
        let views: Vec<(&Image, &[f32])> = frames.iter().map(|(i, m)| (i, m.as_slice())).collect();
        let plate = Plate::from_frames(&views, 1).unwrap();
        for p in [30, 24 * 24 - 1] {
            assert_eq!(plate.at(p).map(|v| (v * 255.0).round()), back.map(|v| (v * 255.0).round()));
        }
        // Column 12 is covered 0.6 in frame 3, whose thresholded mask (columns 0-12) is eroded
        // by one, and 0.4 in frame 2, whose thresholded mask (columns 0-11) is dilated by one.
        // Frame 2's mask thresholded as it should be (columns 0-11) stays where it is.
        for (frame, wrong_edge) in [(3, 12.0), (2, 13.0), (2, 12.0)] {
            let (image, truth) = &frames[frame];
            let mask: Vec<f32> =
                (0..24 * 24).map(|p| ((p % 24) as f32 + 0.5 < wrong_edge) as u8 as f32).collect();
            let refined = refine(image, &mask, &plate);
            let error = |m: &[f32]| m.iter().zip(truth).map(|(a, b)| (a - b).abs()).sum::<f32>();
            assert!(
                error(&refined) < 0.05 * error(&mask),
                "{} of {}",
                error(&refined),
                error(&mask)
            );
        }
    }

    #[test]
    fn pixels_the_colours_cannot_tell_apart_keep_the_mask() {
        let (back, front) = ([0.4, 0.4, 0.4], [0.43, 0.42, 0.41]);
        let frames: Vec<(Image, Vec<f32>)> =
            [4.0, 12.0].iter().map(|&e| edge_image(16, e, back, front)).collect();
        let views: Vec<(&Image, &[f32])> = frames.iter().map(|(i, m)| (i, m.as_slice())).collect();
        let plate = Plate::from_frames(&views, 1).unwrap();
        let mask: Vec<f32> = (0..16 * 16).map(|p| ((p % 16) < 13) as u8 as f32).collect();
        assert_eq!(refine(&frames[1].0, &mask, &plate), mask);
    }

    #[test]
    fn no_plate_without_a_pixel_clear_of_the_masks() {
        let (image, _) = edge_image(8, 8.0, [0.0; 3], [1.0; 3]);
        let all = vec![1.0; 64];
        assert_eq!(Plate::from_frames(&[(&image, all.as_slice())], 1), None);
        assert_eq!(Plate::from_frames(&[], 1), None);
    }

    #[test]
    fn unseen_pixels_take_the_nearest_seen_colour() {
        let mut colour =
            vec![[0, 0, 0], [10, 10, 10], [0, 0, 0], [0, 0, 0], [0, 0, 0], [90, 90, 90]];
        let seen = [false, true, false, false, false, true];
        fill_from_nearest(&mut colour, &seen, 3, 2).unwrap();
        assert_eq!(colour.iter().map(|c| c[0]).collect::<Vec<_>>(), [10, 10, 10, 10, 10, 90]);
    }
}
