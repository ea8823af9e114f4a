//! A rendered frame: linear HDR RGB read back from the GPU, its pass statistics, and its
//! output as linear EXR or as sRGB PNG after exposure (DESIGN.md §3: values stay linear
//! inside the toolkit; only the PNG is gamma-encoded).

use crate::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// Cost of one pass.
#[derive(Debug, Clone, Serialize)]
pub struct PassStat {
    /// Pass name, e.g. `btf (per-pixel)`.
    pub name: String,
    /// Milliseconds (GPU timestamps when available, else CPU time around submit + wait).
    pub ms: f64,
}

/// What ran and what it cost.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Stats {
    /// Passes in execution order.
    pub passes: Vec<PassStat>,
    /// Wall-clock time of the frame (per-frame CPU work, encoding, GPU execution), ms.
    pub frame_ms: f64,
    /// How pass times were measured: `gpu-timestamps` or `cpu`.
    pub timing: String,
    /// One-off costs of preparing the scene (environment visibility, gathers,
    /// eigenweightsets), not part of `frame_ms`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub setup: Vec<PassStat>,
    /// Texture reads per covered pixel in the BTF pass (when counted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reads_per_pixel: Option<f64>,
    /// Pixels the BTF pass shaded (when counted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shaded_pixels: Option<u64>,
}

impl Stats {
    /// Total of the named pass (0 when it did not run).
    pub fn ms_of(&self, name_prefix: &str) -> f64 {
        self.passes.iter().filter(|p| p.name.starts_with(name_prefix)).map(|p| p.ms).sum()
    }
    /// Whether a pass whose name starts with `name_prefix` ran.
    pub fn ran(&self, name_prefix: &str) -> bool {
        self.passes.iter().any(|p| p.name.starts_with(name_prefix))
    }
}

/// A linear HDR image.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major linear RGB radiance, top row first.
    pub rgb: Vec<f32>,
    /// Passes and timings.
    pub stats: Stats,
}

/// sRGB transfer function of a linear value in `[0, 1]`.
pub fn srgb_encode(linear: f32) -> f32 {
    if linear.is_nan() || linear <= 0.0 {
        return 0.0;
    }
    if linear >= 1.0 {
        return 1.0;
    }
    if linear <= 0.003_130_8 { 12.92 * linear } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

impl Frame {
    /// Pixel `(x, y)` as linear RGB.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        let i = ((y * self.width + x) * 3) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// 8-bit sRGB after multiplying by `exposure`.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.rgb.iter().map(|v| (srgb_encode(v * exposure) * 255.0).round() as u8).collect()
    }

    /// Writes an sRGB PNG (exposure applied, values clipped to `[0, 1]`).
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        let img = image::RgbImage::from_raw(self.width, self.height, self.to_srgb8(exposure))
            .ok_or_else(|| Error::Image {
                path: path.into(),
                what: "buffer size mismatch".into(),
            })?;
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| Error::Image { path: path.into(), what: e.to_string() })?;
        Ok(btf_core::fs::write_atomic(path, &png)?)
    }

    /// Writes a linear float EXR (no exposure).
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
        let (w, h) = (self.width as usize, self.height as usize);
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
            let v = self.pixel(p.0 as u32, p.1 as u32);
            (v[0], v[1], v[2])
        });
        let mut bytes = std::io::Cursor::new(Vec::new());
        Image::from_channels((w, h), channels)
            .write()
            .to_buffered(&mut bytes)
            .map_err(|e| Error::Image { path: path.into(), what: e.to_string() })?;
        Ok(btf_core::fs::write_atomic(path, bytes.get_ref())?)
    }

    /// True when every value is finite.
    pub fn all_finite(&self) -> bool {
        self.rgb.iter().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_midpoint() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.2140) - 0.5).abs() < 1e-3);
        assert_eq!(srgb_encode(7.0), 1.0);
        assert_eq!(srgb_encode(f32::NAN), 0.0);
    }

    #[test]
    fn exr_round_trip_is_linear() {
        let dir = tempfile::tempdir().unwrap();
        let f = Frame {
            width: 2,
            height: 1,
            rgb: vec![0.5, 2.0, 1e-3, 100.0, 0.0, 0.25],
            stats: Stats::default(),
        };
        let p = dir.path().join("a.exr");
        f.write_exr(&p).unwrap();
        let img = exr::prelude::read_first_rgba_layer_from_file(
            &p,
            |r, _| vec![[0f32; 3]; r.width() * r.height()],
            |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * 2 + pos.x()] = [r, g, b]
            },
        )
        .unwrap();
        assert_eq!(img.layer_data.channel_data.pixels[1], [100.0, 0.0, 0.25]);
        f.write_png(&dir.path().join("a.png"), 1.0).unwrap();
    }
}
