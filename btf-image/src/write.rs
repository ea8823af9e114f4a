//! Image writers: linear RGB as 32-bit float EXR, linear RGB as sRGB PNG after an
//! exposure, and 8-bit RGB as PNG. Every file goes through `btf_core::fs::write_atomic`
//! (temporary name, checked writes, `fsync`, rename): a failure leaves the previous file
//! as it was. Linear data with a non-finite value is refused, naming the file and pixel —
//! no command writes a NaN.

use crate::color::srgb_encode8;
use crate::{Error, Result};
use image::RgbImage;
use std::path::Path;

/// Refuses a buffer of the wrong length or with a non-finite value, naming the pixel.
pub fn check_rgb(path: &Path, w: usize, h: usize, rgb: &[f32]) -> Result<()> {
    if w.checked_mul(h).and_then(|n| n.checked_mul(3)) != Some(rgb.len()) {
        return Err(Error::Invalid(format!(
            "{}: {} values for a {w}×{h} RGB image",
            path.display(),
            rgb.len()
        )));
    }
    if let Some(i) = rgb.iter().position(|v| !v.is_finite()) {
        return Err(Error::Invalid(format!(
            "{}: refusing to write a non-finite value at pixel x={}, y={} ({})",
            path.display(),
            i / 3 % w,
            i / 3 / w,
            ["R", "G", "B"][i % 3]
        )));
    }
    Ok(())
}

/// Writes linear RGB (`[y][x][rgb]`, top row first) as a 32-bit float EXR.
pub fn write_exr_rgb(path: &Path, w: usize, h: usize, rgb: &[f32]) -> Result<()> {
    check_rgb(path, w, h, rgb)?;
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let i = (p.1 * w + p.0) * 3;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_channels((w, h), channels)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| Error::Image { path: path.to_owned(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic(path, bytes.get_ref())?)
}

/// Writes several linear RGB images of one size (`[y][x][rgb]` each) as one single-part
/// 32-bit float EXR whose channels are `NAME.R`, `NAME.G`, `NAME.B` per image — the
/// OpenEXR layer naming inside one part, so a reader of single-part files (OpenEXR's
/// `InputFile`, OpenImageIO, imageio) sees every image, not only the first part.
pub fn write_exr_named_rgb(
    path: &Path,
    w: usize,
    h: usize,
    images: &[(&str, &[f32])],
) -> Result<()> {
    use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::prelude::{LayerAttributes, WritableImage};
    let mut channels = Vec::with_capacity(images.len() * 3);
    for (name, rgb) in images {
        check_rgb(path, w, h, rgb)?;
        for (c, ch) in ["R", "G", "B"].iter().enumerate() {
            let samples = rgb.iter().skip(c).step_by(3).copied().collect();
            channels
                .push(AnyChannel::new(format!("{name}.{ch}").as_str(), FlatSamples::F32(samples)));
        }
    }
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| Error::Image { path: path.to_owned(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic(path, bytes.get_ref())?)
}

/// Linear RGB → 8-bit sRGB codes after multiplying by `exposure` (clipped to `[0, 1]`).
pub fn to_srgb8(rgb: &[f32], exposure: f32) -> Vec<u8> {
    rgb.iter().map(|v| srgb_encode8(v * exposure)).collect()
}

/// Linear RGB → an 8-bit sRGB image after `exposure`.
pub fn to_srgb_image(w: usize, h: usize, rgb: &[f32], exposure: f32) -> RgbImage {
    RgbImage::from_raw(w as u32, h as u32, to_srgb8(rgb, exposure))
        .expect("an RGB buffer of w × h × 3 values")
}

/// Writes linear RGB as an sRGB PNG after `exposure` (values clipped to `[0, 1]`).
pub fn write_png_linear(path: &Path, w: usize, h: usize, rgb: &[f32], exposure: f32) -> Result<()> {
    check_rgb(path, w, h, rgb)?;
    write_png(path, &to_srgb_image(w, h, rgb, exposure))
}

/// Writes 8-bit RGB pixels (`[y][x][rgb]`) as a PNG.
pub fn write_png_rgb8(path: &Path, w: usize, h: usize, rgb8: Vec<u8>) -> Result<()> {
    let img = RgbImage::from_raw(w as u32, h as u32, rgb8).ok_or_else(|| {
        Error::Invalid(format!("{}: pixel count does not match {w}×{h}", path.display()))
    })?;
    write_png(path, &img)
}

/// Writes an 8-bit RGB image as a PNG.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| Error::Image { path: path.to_owned(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic(path, &bytes)?)
}

/// Writes a text file atomically (reports, CSV, Markdown).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    Ok(btf_core::fs::write_atomic(path, text.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_is_linear_png_is_srgb_and_nan_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let rgb = [0.5, 2.0, 1e-3, 100.0, 0.0, 0.25];
        let p = dir.path().join("a.exr");
        write_exr_rgb(&p, 2, 1, &rgb).unwrap();
        let img = exr::prelude::read_first_rgba_layer_from_file(
            &p,
            |r, _| vec![[0f32; 3]; r.width() * r.height()],
            |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * 2 + pos.x()] = [r, g, b]
            },
        )
        .unwrap();
        assert_eq!(img.layer_data.channel_data.pixels[1], [100.0, 0.0, 0.25]);
        let png = dir.path().join("a.png");
        write_png_linear(&png, 2, 1, &rgb, 1.0).unwrap();
        let back = image::open(&png).unwrap().into_rgb8();
        assert_eq!(back.get_pixel(0, 0).0, [188, 255, 3]);
        let mut bad = rgb;
        bad[4] = f32::NAN;
        let e = write_exr_rgb(&dir.path().join("b.exr"), 2, 1, &bad).unwrap_err().to_string();
        assert!(e.contains("b.exr") && e.contains("x=1, y=0") && e.contains("(G)"), "{e}");
        assert!(!dir.path().join("b.exr").exists());
        assert!(write_png_linear(&dir.path().join("c.png"), 3, 1, &rgb, 1.0).is_err());
    }
}
