//! Raw images in sensor units: 8/16-bit PNG or TIFF holding `bits`-bit values stored
//! left-aligned (`DN << (container bits − bits)`), or EXR holding linear DN directly. All
//! bits are kept (the paper kept the central 8 of 12; we keep the full 12 as `f32`), and
//! nothing is gamma-decoded: raw sensor values are linear.

use crate::{Error, Result};
use std::path::Path;

/// One raw image: linear RGB in DN (`0 ..= 2^bits − 1`), row-major from the top-left.
#[derive(Debug, Clone)]
pub struct RawImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// RGB values in DN.
    pub rgb: Vec<[f32; 3]>,
}

impl RawImage {
    /// Mean of the three channels at pixel `(c, r)`.
    pub fn luminance(&self, c: usize, r: usize) -> f32 {
        let p = self.rgb[r * self.width + c];
        (p[0] + p[1] + p[2]) / 3.0
    }
}

fn image_err(path: &Path, what: impl ToString) -> Error {
    Error::Image { file: path.display().to_string(), what: what.to_string() }
}

/// The size of an image from its header, without decoding it.
pub fn dimensions(path: &Path) -> Result<(usize, usize)> {
    if is_exr(path) {
        let img = read(path, 16)?;
        return Ok((img.width, img.height));
    }
    let (w, h) = image::image_dimensions(path).map_err(|e| match e {
        image::ImageError::IoError(io) => Error::io(path, io),
        other => image_err(path, other),
    })?;
    Ok((w as usize, h as usize))
}

fn is_exr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Reads a raw image; `bits` is the sensor's bit depth from `capture.toml`.
pub fn read(path: &Path, bits: u32) -> Result<RawImage> {
    if is_exr(path) {
        return read_exr(path);
    }
    let img = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?
        .decode()
        .map_err(|e| image_err(path, e))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let rgb = match img {
        image::DynamicImage::ImageRgb16(_)
        | image::DynamicImage::ImageRgba16(_)
        | image::DynamicImage::ImageLuma16(_)
        | image::DynamicImage::ImageLumaA16(_) => {
            let scale = 1.0 / (1u32 << 16u32.saturating_sub(bits)) as f32;
            let buf = img.to_rgb16();
            buf.pixels().map(|p| p.0.map(|v| v as f32 * scale)).collect()
        }
        image::DynamicImage::ImageRgb8(_)
        | image::DynamicImage::ImageRgba8(_)
        | image::DynamicImage::ImageLuma8(_)
        | image::DynamicImage::ImageLumaA8(_) => {
            let scale = (1u64 << bits.saturating_sub(8)) as f32;
            let buf = img.to_rgb8();
            buf.pixels().map(|p| p.0.map(|v| v as f32 * scale)).collect()
        }
        other => {
            return Err(Error::unsupported(
                &path.display().to_string(),
                format!("pixel format {:?} (use 8/16-bit PNG/TIFF or EXR)", other.color()),
            ));
        }
    };
    Ok(RawImage { width, height, rgb })
}

fn read_exr(path: &Path) -> Result<RawImage> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            let (w, h) = (res.width(), res.height());
            (w, vec![[0f32; 3]; w * h])
        },
        |(w, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| image_err(path, e))?;
    let size = img.layer_data.size;
    let (_, rgb) = img.layer_data.channel_data.pixels;
    if rgb.iter().flatten().any(|v| !v.is_finite()) {
        return Err(image_err(path, "NaN or infinite values"));
    }
    Ok(RawImage { width: size.width(), height: size.height(), rgb })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bit_png_keeps_all_twelve_bits() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        let dn: [u16; 3] = [1, 2049, 4095];
        let data: Vec<u16> = (0..4).flat_map(|_| dn.map(|v| v << 4)).collect();
        image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(2, 2, data)
            .unwrap()
            .save(&path)
            .unwrap();
        let img = read(&path, 12).unwrap();
        assert_eq!((img.width, img.height), (2, 2));
        assert_eq!(img.rgb[3], [1.0, 2049.0, 4095.0]);
        assert_eq!(dimensions(&path).unwrap(), (2, 2));
    }

    #[test]
    fn unreadable_file_names_itself() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("broken.png");
        std::fs::write(&path, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let e = read(&path, 12).unwrap_err().to_string();
        assert!(e.contains("broken.png"), "{e}");
    }
}
