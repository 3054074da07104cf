//! Image files as float arrays (docs/conventions.md): 8- and 16-bit PNG read as values in [0, 1]
//! without gamma conversion, EXR read as linear float; PNG written 8-bit, EXR written as
//! 32-bit float. Every error names the file.

use image::{DynamicImage, ExtendedColorType, ImageEncoder};
use std::path::{Path, PathBuf};

/// Interleaved `height × width × channels` values (1 = grey, 2 = grey + alpha, 3 = RGB,
/// 4 = RGBA).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Channels per pixel, 1 to 4.
    pub channels: u8,
    /// The values, interleaved, row-major (read from PNG: in [0, 1]).
    pub data: Vec<f32>,
}

/// An image file that cannot be opened, decoded or written; names the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct ImageError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub problem: String,
}

fn fail(path: &Path, problem: impl std::fmt::Display) -> ImageError {
    ImageError { path: path.to_owned(), problem: problem.to_string() }
}

impl Image {
    /// Channel `c` of pixel (x, y).
    #[inline]
    pub fn at(&self, x: u32, y: u32, c: u8) -> f32 {
        self.data[((y * self.width + x) * self.channels as u32 + c as u32) as usize]
    }

    /// The alpha channel (last of 2 or 4 channels), if there is one.
    pub fn alpha(&self) -> Option<Vec<f32>> {
        matches!(self.channels, 2 | 4).then(|| {
            self.data.chunks_exact(self.channels as usize).map(|p| p[p.len() - 1]).collect()
        })
    }

    /// The first channel of every pixel (a mask stored as grey or as any colour).
    pub fn first_channel(&self) -> Vec<f32> {
        self.data.chunks_exact(self.channels as usize).map(|p| p[0]).collect()
    }
}

/// The 4-neighbours of pixel `p` (row-major) inside a `width × height` image: left, right,
/// up, down, those that exist.
pub fn four_neighbours(p: usize, width: usize, height: usize) -> impl Iterator<Item = usize> {
    let (x, y) = (p % width, p / width);
    [
        (x > 0).then(|| p - 1),
        (x + 1 < width).then(|| p + 1),
        (y > 0).then(|| p - width),
        (y + 1 < height).then(|| p + width),
    ]
    .into_iter()
    .flatten()
}

/// Reads a PNG (8 or 16 bit, grey / grey+alpha / RGB / RGBA) or an EXR.
pub fn read_image(path: &Path) -> Result<Image, ImageError> {
    let reader =
        image::ImageReader::open(path).map_err(|e| fail(path, format!("cannot open: {e}")))?;
    let reader =
        reader.with_guessed_format().map_err(|e| fail(path, format!("cannot read: {e}")))?;
    let decoded = reader.decode().map_err(|e| fail(path, format!("cannot decode: {e}")))?;
    let (width, height) = (decoded.width(), decoded.height());
    let channels = decoded.color().channel_count();
    let unit8 = |v: &[u8]| v.iter().map(|&x| x as f32 / 255.0).collect::<Vec<f32>>();
    let unit16 = |v: &[u16]| v.iter().map(|&x| x as f32 / 65535.0).collect::<Vec<f32>>();
    let data = match &decoded {
        DynamicImage::ImageLuma8(b) => unit8(b.as_raw()),
        DynamicImage::ImageLumaA8(b) => unit8(b.as_raw()),
        DynamicImage::ImageRgb8(b) => unit8(b.as_raw()),
        DynamicImage::ImageRgba8(b) => unit8(b.as_raw()),
        DynamicImage::ImageLuma16(b) => unit16(b.as_raw()),
        DynamicImage::ImageLumaA16(b) => unit16(b.as_raw()),
        DynamicImage::ImageRgb16(b) => unit16(b.as_raw()),
        DynamicImage::ImageRgba16(b) => unit16(b.as_raw()),
        DynamicImage::ImageRgb32F(b) => b.as_raw().clone(),
        DynamicImage::ImageRgba32F(b) => b.as_raw().clone(),
        other => return Err(fail(path, format!("unsupported pixel format {:?}", other.color()))),
    };
    Ok(Image { width, height, channels, data })
}

/// Width and height from the file header, without decoding the pixels.
pub fn image_size(path: &Path) -> Result<(u32, u32), ImageError> {
    image::image_dimensions(path)
        .map_err(|e| fail(path, format!("cannot read the image header: {e}")))
}

fn check_shape(path: &Path, image: &Image) -> Result<(), ImageError> {
    let expect = image.width as usize * image.height as usize * image.channels as usize;
    if image.data.len() != expect
        || !(1..=4).contains(&image.channels)
        || image.width == 0
        || image.height == 0
    {
        return Err(fail(
            path,
            format!(
                "cannot write {} values as a {}×{}×{} image",
                image.data.len(),
                image.width,
                image.height,
                image.channels
            ),
        ));
    }
    Ok(())
}

/// Writes an 8-bit PNG (values clamped to [0, 1], rounded), atomically.
pub fn write_png(path: &Path, image: &Image) -> Result<(), ImageError> {
    check_shape(path, image)?;
    super::write_atomically(path, |w| encode_png(image, w))
        .map_err(|e| fail(path, format!("cannot write: {e}")))
}

/// Encodes an image of 1 to 4 channels (values clamped to [0, 1], 8 bits) as PNG into `out`.
/// A shape that does not fit (the encoder would panic on it) is an error.
pub fn encode_png(image: &Image, out: impl std::io::Write) -> std::io::Result<()> {
    let expect = image.width as usize * image.height as usize * image.channels as usize;
    if !(1..=4).contains(&image.channels) || image.data.len() != expect {
        let shape = format!("{}×{}×{}", image.width, image.height, image.channels);
        let problem = format!("{} values do not make a {shape} PNG", image.data.len());
        return Err(std::io::Error::other(problem));
    }
    let bytes: Vec<u8> =
        image.data.iter().map(|&v| (v.clamp(0.0, 1.0) * 255.0).round() as u8).collect();
    let color = [
        ExtendedColorType::L8,
        ExtendedColorType::La8,
        ExtendedColorType::Rgb8,
        ExtendedColorType::Rgba8,
    ][image.channels as usize - 1];
    image::codecs::png::PngEncoder::new(out)
        .write_image(&bytes, image.width, image.height, color)
        .map_err(std::io::Error::other)
}

/// Writes a 32-bit float EXR of an RGB or RGBA image, atomically.
pub fn write_exr(path: &Path, image: &Image) -> Result<(), ImageError> {
    check_shape(path, image)?;
    let color = match image.channels {
        3 => ExtendedColorType::Rgb32F,
        4 => ExtendedColorType::Rgba32F,
        n => return Err(fail(path, format!("EXR output takes 3 or 4 channels, not {n}"))),
    };
    super::write_atomically(path, |w| {
        image::codecs::openexr::OpenExrEncoder::new(w)
            .write_image(bytemuck::cast_slice(&image.data), image.width, image.height, color)
            .map_err(std::io::Error::other)
    })
    .map_err(|e| fail(path, format!("cannot write: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_and_exr_round_trip_and_corrupt_files_are_named() {
        let dir = std::env::temp_dir().join(format!("tagsplat-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for channels in 1..=4u8 {
            let data: Vec<f32> =
                (0..5 * 3 * channels as usize).map(|i| (i * 17 % 256) as f32 / 255.0).collect();
            let img = Image { width: 5, height: 3, channels, data };
            let path = dir.join(format!("c{channels}.png"));
            write_png(&path, &img).unwrap();
            assert_eq!(read_image(&path).unwrap(), img);
            assert_eq!(image_size(&path).unwrap(), (5, 3));
        }
        let hdr = Image {
            width: 2,
            height: 2,
            channels: 3,
            data: vec![0.0, 1.5, 1e-3, 7.0, -0.25, 2.0, 0.5, 0.5, 0.5, 100.0, 0.0, 3.0],
        };
        write_exr(&dir.join("a.exr"), &hdr).unwrap();
        assert_eq!(read_image(&dir.join("a.exr")).unwrap(), hdr);
        std::fs::write(dir.join("bad.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let e = read_image(&dir.join("bad.png")).unwrap_err();
        assert!(e.to_string().contains("bad.png"), "{e}");
        assert!(read_image(&dir.join("missing.png"))
            .unwrap_err()
            .to_string()
            .contains("missing.png"));
        assert!(write_png(
            &dir.join("x.png"),
            &Image { width: 2, height: 2, channels: 3, data: vec![0.0; 3] }
        )
        .is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
