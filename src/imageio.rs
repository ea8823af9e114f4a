//! Image output of the CLI: linear EXR for HDR data, sRGB PNG for viewing, and 8-bit RGB
//! images (plots, heat-maps). Every file is written to a temporary name and renamed, so an
//! interrupted run never leaves half an image.

use anyhow::{Context, Result, bail};
use image::RgbImage;
use std::path::Path;

fn check_rgb(values: &[f32], w: usize, h: usize, path: &Path) -> Result<()> {
    if values.len() != w * h * 3 {
        bail!("{}: {} values for a {w}×{h} RGB image", path.display(), values.len());
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        bail!(
            "{}: refusing to write a non-finite value at texel {} (y={}, x={})",
            path.display(),
            i / 3,
            i / 3 / w,
            i / 3 % w
        );
    }
    Ok(())
}

/// Writes linear RGB (`[y][x][rgb]`) as a 32-bit float EXR.
pub fn write_exr(path: &Path, w: usize, h: usize, rgb: &[f32]) -> Result<()> {
    check_rgb(rgb, w, h, path)?;
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let i = (p.1 * w + p.0) * 3;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_channels((w, h), channels)
        .write()
        .to_buffered(&mut bytes)
        .with_context(|| format!("cannot encode {}", path.display()))?;
    btf_core::fs::write_atomic(path, bytes.get_ref())?;
    Ok(())
}

/// The sRGB transfer function of a linear value in `[0, 1]`.
pub fn srgb_encode(linear: f32) -> u8 {
    let v = linear.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Linear RGB → 8-bit sRGB image, scaled by `exposure` and clipped.
pub fn to_srgb(w: usize, h: usize, rgb: &[f32], exposure: f32) -> RgbImage {
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let i = (y as usize * w + x as usize) * 3;
        image::Rgb([0, 1, 2].map(|c| srgb_encode(rgb[i + c] * exposure)))
    })
}

/// Writes linear RGB as an sRGB PNG with the given exposure.
pub fn write_png_linear(path: &Path, w: usize, h: usize, rgb: &[f32], exposure: f32) -> Result<()> {
    check_rgb(rgb, w, h, path)?;
    write_png(path, &to_srgb(w, h, rgb, exposure))
}

/// Writes an 8-bit RGB image as PNG.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .with_context(|| format!("cannot encode {}", path.display()))?;
    btf_core::fs::write_atomic(path, &bytes)?;
    Ok(())
}

/// An error heat-map: per texel, the length of the RGB error vector divided by `full_scale`,
/// green (0) → yellow → red (≥ 1).
pub fn heatmap(w: usize, h: usize, reference: &[f32], approx: &[f32], full_scale: f32) -> RgbImage {
    RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let i = (y as usize * w + x as usize) * 3;
        let e: f32 = (0..3).map(|c| (reference[i + c] - approx[i + c]).powi(2)).sum::<f32>().sqrt();
        image::Rgb(btf_core::metrics::heat_color((e / full_scale) as f64))
    })
}

/// Places images side by side (top-aligned) with a gap.
pub fn side_by_side(images: &[&RgbImage], gap: u32) -> RgbImage {
    let w: u32 =
        images.iter().map(|i| i.width()).sum::<u32>() + gap * images.len().saturating_sub(1) as u32;
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(w.max(1), h.max(1), image::Rgb([255, 255, 255]));
    let mut x0 = 0;
    for img in images {
        image::imageops::replace(&mut out, *img, x0 as i64, 0);
        x0 += img.width() + gap;
    }
    out
}

/// Nearest-neighbour upscaling so small textures stay visible in reports.
pub fn upscale(img: &RgbImage, min_size: u32) -> RgbImage {
    let f = (min_size / img.width().max(1)).max(1);
    image::imageops::resize(
        img,
        img.width() * f,
        img.height() * f,
        image::imageops::FilterType::Nearest,
    )
}

/// Writes a text file atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    btf_core::fs::write_atomic(path, text.as_bytes())?;
    Ok(())
}
