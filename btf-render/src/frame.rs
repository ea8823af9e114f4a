//! A rendered frame: linear HDR RGB read back from the GPU, its pass statistics, and its
//! output as linear EXR or as sRGB PNG after exposure (DESIGN.md §3: values stay linear
//! inside the toolkit; only the PNG is gamma-encoded).

use crate::{Error, Gpu, Result};
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

impl Frame {
    /// Reads back a frame a renderer encoded into `texture` (linear RGBA, `Rgba32Float` or
    /// `Rgba16Float`, as [`crate::Renderer::target_format`] gives), with its `stats`: the
    /// read-back a viewer that presents the texture itself makes only for screenshots.
    pub fn read(gpu: &Gpu, texture: &wgpu::Texture, stats: Stats) -> Result<Frame> {
        let (width, height, format) = (texture.width(), texture.height(), texture.format());
        let texel = format.block_copy_size(None).unwrap_or(0);
        let mut rgb = Vec::with_capacity((width * height * 3) as usize);
        let raw = gpu.read_texture(texture, texel)?;
        if !push_linear_rgb(&mut rgb, &raw, format) {
            return Err(Error::Invalid(format!("Frame::read: {format:?} is not a frame")));
        }
        Ok(Frame { width, height, rgb, stats })
    }

    /// Pixel `(x, y)` as linear RGB.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        let i = ((y * self.width + x) * 3) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// 8-bit sRGB after multiplying by `exposure`.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        btf_image::write::to_srgb8(&self.rgb, exposure)
    }

    /// Writes an sRGB PNG (exposure applied, values clipped to `[0, 1]`); refuses a frame
    /// with a non-finite value.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        let (w, h) = (self.width as usize, self.height as usize);
        Ok(btf_image::write::write_png_linear(path, w, h, &self.rgb, exposure)?)
    }

    /// Writes a linear float EXR (no exposure); refuses a frame with a non-finite value.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        let (w, h) = (self.width as usize, self.height as usize);
        Ok(btf_image::write::write_exr_rgb(path, w, h, &self.rgb)?)
    }

    /// True when every value is finite.
    pub fn all_finite(&self) -> bool {
        self.rgb.iter().all(|v| v.is_finite())
    }
}

/// Appends the RGB of linear RGBA `texels` (`Rgba32Float` or `Rgba16Float`) to `rgb`;
/// false for another format.
pub(crate) fn push_linear_rgb(
    rgb: &mut Vec<f32>,
    texels: &[u8],
    format: wgpu::TextureFormat,
) -> bool {
    match format {
        wgpu::TextureFormat::Rgba32Float => {
            let f: &[f32] = bytemuck::cast_slice(texels);
            rgb.extend(f.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]));
        }
        wgpu::TextureFormat::Rgba16Float => {
            let h: &[half::f16] = bytemuck::cast_slice(texels);
            rgb.extend(h.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]].map(half::f16::to_f32)));
        }
        _ => return false,
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

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
