//! Pictures of the eigenweightset error (Sattler et al. 2003, §5.4, Fig. 12–13): error
//! heat maps that go from green (no error) to red (the chosen maximum), as the paper's
//! Fig. 13, and a small line plot of the coefficients `o_k(δ)` over the rotation, as its
//! Fig. 12. Written as 8-bit PNGs with the `image` crate, atomically.

use crate::{Error, Result};
use std::path::Path;

/// Green → red colour of `t ∈ [0, 1]` (non-finite values are drawn red).
pub fn green_red(t: f32) -> [u8; 3] {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 1.0 };
    [(255.0 * t).round() as u8, (255.0 * (1.0 - t)).round() as u8, 0]
}

/// Per pixel, the length of the RGB difference of two linear images, mapped green → red
/// over `[0, max_error]`; pixels where both are background (0) are drawn black.
pub fn error_heatmap(reference: &[f32], actual: &[f32], max_error: f32) -> Vec<u8> {
    reference
        .chunks_exact(3)
        .zip(actual.chunks_exact(3))
        .flat_map(|(r, a)| {
            if r.iter().chain(a).all(|&x| x == 0.0) {
                return [0, 0, 0];
            }
            let d = ((r[0] - a[0]).powi(2) + (r[1] - a[1]).powi(2) + (r[2] - a[2]).powi(2)).sqrt();
            green_red(d / max_error.max(f32::MIN_POSITIVE))
        })
        .collect()
}

/// Writes 8-bit RGB pixels as a PNG (temporary file, then rename).
pub fn write_rgb8(path: &Path, width: u32, height: u32, rgb: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(width, height, rgb).ok_or_else(|| Error::Image {
        path: path.into(),
        what: "pixel count does not match the size".into(),
    })?;
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| Error::Image { path: path.into(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic(path, &bytes)?)
}

/// Line plot of `curves` (each sampled at equal steps over `[0°, 360°)`) on a white
/// `width × height` canvas with a zero line; distinct colours per curve.
pub fn line_plot(curves: &[Vec<f64>], width: u32, height: u32) -> Vec<u8> {
    const COLOURS: [[u8; 3]; 8] = [
        [31, 119, 180],
        [255, 127, 14],
        [44, 160, 44],
        [214, 39, 40],
        [148, 103, 189],
        [140, 86, 75],
        [227, 119, 194],
        [127, 127, 127],
    ];
    let (w, h) = (width as usize, height as usize);
    let mut px = vec![255u8; w * h * 3];
    let max =
        curves.iter().flatten().filter(|v| v.is_finite()).fold(1e-30f64, |m, v| m.max(v.abs()));
    let y_of = |v: f64| {
        ((0.5 - 0.45 * v / max) * (h - 1) as f64).round().clamp(0.0, (h - 1) as f64) as usize
    };
    let mut put = |x: usize, y: usize, c: [u8; 3]| px[(y * w + x) * 3..][..3].copy_from_slice(&c);
    for x in 0..w {
        put(x, y_of(0.0), [200, 200, 200]);
    }
    for (k, curve) in curves.iter().enumerate() {
        let n = curve.len().max(1);
        let c = COLOURS[k % COLOURS.len()];
        let mut last: Option<usize> = None;
        for x in 0..w {
            // Periodic linear interpolation between the samples.
            let s = x as f64 / w as f64 * n as f64;
            let (i, t) = (s.floor() as usize % n, s.fract());
            let v = curve.get(i).copied().unwrap_or(0.0) * (1.0 - t)
                + curve.get((i + 1) % n).copied().unwrap_or(0.0) * t;
            let y = y_of(if v.is_finite() { v } else { 0.0 });
            let (a, b) = last.map_or((y, y), |l| (l.min(y), l.max(y)));
            (a..=b).for_each(|yy| put(x, yy, c));
            last = Some(y);
        }
    }
    px
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_plot() {
        assert_eq!(green_red(0.0), [0, 255, 0]);
        assert_eq!(green_red(1.0), [255, 0, 0]);
        assert_eq!(green_red(f32::NAN), [255, 0, 0]);
        let h =
            error_heatmap(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &[0.0, 0.0, 0.0, 1.0, 1.0, 1.5], 1.0);
        assert_eq!(h, vec![0, 0, 0, 128, 128, 0]);
        let p = line_plot(&[vec![1.0, -1.0, 0.5]], 30, 20);
        assert_eq!(p.len(), 30 * 20 * 3);
        assert!(p.chunks(3).any(|c| c == [31, 119, 180]));
    }
}
