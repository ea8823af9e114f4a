//! A packed material on the GPU (`[S03 eq. 2–5]` read by the BTF pass): its eigentexture
//! and mean layers as texture arrays with mip chains (`crate::mips`), its weights as a
//! storage buffer, and the `Samplings` uniform that tells the shaders the rings of its view
//! and light samplings (`passes/shaders/interp.wgsl`).

use super::pack::{MAX_RINGS, MaterialData};
use crate::{Error, Result};
use btf_core::Sampling;
use btf_core::eigen::Quantization;
use half::f16;

/// GPU mirror of the `Samplings` uniform: rings `(θ°, count, φ offset°, first index)`, view
/// rings at `0..16`, light rings at `16..32`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SamplingsRaw {
    /// Rings of both samplings.
    pub rings: [[f32; 4]; 2 * MAX_RINGS],
    /// Ring counts: view, light.
    pub n_rings: [u32; 4],
    /// `G`, light directions, view slots, unused.
    pub info: [u32; 4],
    /// UV scale, unused ×3.
    pub params: [f32; 4],
}

impl SamplingsRaw {
    /// The rings of a view and a light sampling, nothing else (the interpolation probe).
    pub fn of_samplings(view: &Sampling, light: &Sampling) -> SamplingsRaw {
        let mut raw: SamplingsRaw = bytemuck::Zeroable::zeroed();
        for (which, s) in [view, light].into_iter().enumerate() {
            for (r, ring) in s.rings.iter().enumerate() {
                raw.rings[which * MAX_RINGS + r] = [
                    ring.theta_deg as f32,
                    ring.count as f32,
                    ring.phi_offset_deg as f32,
                    s.ring_start(r) as f32,
                ];
            }
            raw.n_rings[which] = s.rings.len() as u32;
        }
        raw
    }

    /// The uniform block of `material` drawn with `uv_scale` repetitions per UV unit.
    pub fn of_material(material: &MaterialData, uv_scale: f32) -> SamplingsRaw {
        let mut raw = SamplingsRaw::of_samplings(&material.view_sampling, &material.light_sampling);
        raw.info = [
            material.groups as u32,
            material.light_sampling.len() as u32,
            material.view_sampling.len() as u32,
            0,
        ];
        raw.params = [uv_scale, 0.0, 0.0, 0.0];
        raw
    }
}

/// A material uploaded to the GPU.
pub struct MaterialGpu {
    /// Packed eigentextures, `n_views · 3G` layers.
    pub eigen: wgpu::Texture,
    /// Means, `n_views` layers.
    pub mean: wgpu::Texture,
    /// Scaled weights and biases.
    pub weights: wgpu::Buffer,
    /// Bytes uploaded (textures + weights).
    pub bytes: u64,
}

impl MaterialGpu {
    /// Uploads `data` with full mip chains (`mips.rs`), checking the device's limits first.
    pub fn upload(gpu: &crate::Gpu, data: &MaterialData, name: &str) -> Result<MaterialGpu> {
        Self::upload_with(gpu, data, name, true, None)
    }

    /// Uploads `data`, with mip chains or the base level only, and its weights as `f32` rows
    /// or as `packed` (`MaterialData::packed_weights`).
    pub fn upload_with(
        gpu: &crate::Gpu,
        data: &MaterialData,
        name: &str,
        mipmaps: bool,
        packed: Option<&[[u32; 4]]>,
    ) -> Result<MaterialGpu> {
        use wgpu::util::DeviceExt;
        let limits = gpu.device.limits();
        let n_v = data.view_sampling.len() as u32;
        let layers = n_v * 3 * data.groups as u32;
        if layers > limits.max_texture_array_layers
            || data.width.max(data.height) > limits.max_texture_dimension_2d
        {
            return Err(Error::Limit(format!(
                "{name}: {layers} eigentexture layers of {}×{} exceed the GPU's limits ({} layers, {} texels); use fewer components",
                data.width,
                data.height,
                limits.max_texture_array_layers,
                limits.max_texture_dimension_2d
            )));
        }
        let format = match data.quantization {
            Quantization::F16 => wgpu::TextureFormat::Rgba16Float,
            Quantization::U8 => wgpu::TextureFormat::Rgba8Unorm,
        };
        let levels = if mipmaps { crate::mips::level_count(data.width, data.height) } else { 1 };
        let (w, h) = (data.width as usize, data.height as usize);
        use std::borrow::Cow;
        let mean_layers: Cow<[f16]> = if levels > 1 {
            Cow::Owned(crate::mips::chain_f16(&data.mean_layers, w, h, n_v as usize))
        } else {
            Cow::Borrowed(&data.mean_layers)
        };
        let eigen_layers: Cow<[u8]> = match (levels > 1, data.quantization) {
            (false, _) => Cow::Borrowed(&data.eigen_layers),
            (true, Quantization::U8) => {
                Cow::Owned(crate::mips::chain_u8(&data.eigen_layers, w, h, layers as usize))
            }
            (true, Quantization::F16) => {
                let halves: Vec<f16> = data
                    .eigen_layers
                    .chunks_exact(2)
                    .map(|b| f16::from_le_bytes([b[0], b[1]]))
                    .collect();
                let chain = crate::mips::chain_f16(&halves, w, h, layers as usize);
                Cow::Owned(chain.iter().flat_map(|v| v.to_le_bytes()).collect())
            }
        };
        let tex = |label: &str, format, layers: u32, bytes: &[u8]| {
            gpu.device.create_texture_with_data(
                &gpu.queue,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: data.width,
                        height: data.height,
                        depth_or_array_layers: layers,
                    },
                    mip_level_count: levels,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                bytes,
            )
        };
        gpu.scoped(&format!("uploading material {name}"), || {
            let eigen = tex("eigentextures", format, layers, &eigen_layers);
            let mean = tex(
                "means",
                wgpu::TextureFormat::Rgba16Float,
                n_v,
                bytemuck::cast_slice(&mean_layers),
            );
            let weight_bytes: &[u8] = match packed {
                Some(p) => bytemuck::cast_slice(p),
                None => bytemuck::cast_slice(&data.weights),
            };
            let weights = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("weights"),
                contents: weight_bytes,
                usage: wgpu::BufferUsages::STORAGE,
            });
            let bytes = (eigen_layers.len() + mean_layers.len() * 2 + weight_bytes.len()) as u64;
            MaterialGpu { eigen, mean, weights, bytes }
        })
    }
}
