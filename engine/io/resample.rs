//! Area resampling: each output pixel is the mean of the input over its footprint, input
//! pixels weighted by how much of them it covers. For a downscale this is the box filter a
//! camera with larger pixels would have integrated; it keeps the image's mean.

use super::image::Image;

/// `image` resampled to `width` × `height` (each at least 1), every channel alike. The
/// footprint of output pixel x is [x, x + 1) × (input width / `width`) in input pixels, so
/// continuous image coordinates scale by `width` / input width (pixel centres at half-integers
/// stay at half-integers).
pub fn resample_area(image: &Image, width: u32, height: u32) -> Image {
    let (width, height) = (width.max(1), height.max(1));
    let columns = footprints(image.width, width);
    let rows = footprints(image.height, height);
    let c = image.channels as usize;
    // Columns first, into a width × input-height buffer, then rows.
    let mut narrow = vec![0f32; width as usize * image.height as usize * c];
    for y in 0..image.height as usize {
        let row = &image.data[y * image.width as usize * c..][..image.width as usize * c];
        for (x, weights) in columns.iter().enumerate() {
            let out = &mut narrow[(y * width as usize + x) * c..][..c];
            for &(i, w) in weights {
                out.iter_mut().zip(&row[i * c..][..c]).for_each(|(o, v)| *o += w * v);
            }
        }
    }
    let mut data = vec![0f32; width as usize * height as usize * c];
    for (y, weights) in rows.iter().enumerate() {
        let out = &mut data[y * width as usize * c..][..width as usize * c];
        for &(i, w) in weights {
            let row = &narrow[i * width as usize * c..][..width as usize * c];
            out.iter_mut().zip(row).for_each(|(o, v)| *o += w * v);
        }
    }
    Image { width, height, channels: image.channels, data }
}

/// For each of `outputs` pixels along an axis of `inputs` pixels: the input pixels its
/// footprint covers and their weights (the covered length over the footprint's, summing to 1).
fn footprints(inputs: u32, outputs: u32) -> Vec<Vec<(usize, f32)>> {
    let step = inputs as f64 / outputs as f64;
    (0..outputs)
        .map(|o| {
            let (start, end) = (o as f64 * step, ((o + 1) as f64 * step).min(inputs as f64));
            let first = start.floor() as usize;
            let last = (end.ceil() as usize).min(inputs as usize).max(first + 1);
            (first..last)
                .map(|i| {
                    let covered = (end.min(i as f64 + 1.0) - start.max(i as f64)).max(0.0);
                    (i, (covered / (end - start)) as f32)
                })
                .filter(|&(_, w)| w > 0.0)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, channels: u8, f: impl Fn(u32, u32, u8) -> f32) -> Image {
        let mut data = Vec::new();
        for y in 0..height {
            for x in 0..width {
                (0..channels).for_each(|c| data.push(f(x, y, c)));
            }
        }
        Image { width, height, channels, data }
    }

    #[test]
    fn halving_averages_two_by_two_blocks() {
        let input = image(4, 2, 2, |x, y, c| (x + 4 * y) as f32 + 100.0 * c as f32);
        let out = resample_area(&input, 2, 1);
        assert_eq!((out.width, out.height, out.channels), (2, 1, 2));
        assert_eq!(out.data, vec![2.5, 102.5, 4.5, 104.5]);
    }

    #[test]
    fn a_fractional_scale_keeps_constants_and_the_mean() {
        let flat = resample_area(&image(7, 5, 1, |_, _, _| 0.25), 3, 2);
        assert!(flat.data.iter().all(|&v| (v - 0.25).abs() < 1e-6), "{:?}", flat.data);
        // A ramp along x: each output pixel is the mean of its footprint, exactly.
        let ramp = resample_area(&image(10, 1, 1, |x, _, _| x as f32), 4, 1);
        // Footprints of 2.5 pixels: [0, 2.5) → (0 + 1 + 0.5·2) / 2.5 = 0.8, and so on.
        let expected = [0.8, 3.2, 5.8, 8.2];
        for (v, e) in ramp.data.iter().zip(expected) {
            assert!((v - e).abs() < 1e-5, "{:?}", ramp.data);
        }
        let mean = |i: &Image| i.data.iter().sum::<f32>() / i.data.len() as f32;
        assert!((mean(&ramp) - 4.5).abs() < 1e-5);
    }

    #[test]
    fn the_same_size_is_the_identity() {
        let input = image(5, 3, 3, |x, y, c| (x * 7 + y * 3 + c as u32) as f32);
        assert_eq!(resample_area(&input, 5, 3).data, input.data);
    }
}
