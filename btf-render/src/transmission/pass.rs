//! The thin-cloth pass: draws the triangles of transmissive materials after the opaque
//! BTF geometry, sorted back to front every frame, with `L = L_dst · e^{−τ₁/μ} + L_src`
//! (thin-cloth paper eq. 9; the shading is in `transmission.wgsl`).
//!
//! Depth is tested against the opaque geometry but not written, so layers behind a thin
//! sheet stay visible. Bind groups 0 and 1 are the BTF pass's (frame, material); group 3
//! holds the slab parameters and the τ texture of one material.

use super::desc::{TauTexture, TransmissionDesc};
use crate::btf_pass::{
    BtfPass, BtfPassKey, CornerVertex, color_format, corner_buffer_layout, mesh_depth_state,
};
use crate::material::MaterialData;
use crate::renderer::CameraSetup;
use crate::{Error, Gpu, Result};
use half::f16;
use wgpu::util::DeviceExt;

/// WGSL of the pass: the BTF pass's source with the thin-cloth fragment shader appended.
pub const SOURCE: &str = concat!(
    include_str!("../interp.wgsl"),
    include_str!("../btf_pass.wgsl"),
    include_str!("transmission.wgsl")
);

/// GPU mirror of `ThinRaw`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ThinRaw {
    /// `τ₁`, Henyey–Greenstein `g`, τ texture bound (1/0), unused.
    pub params: [f32; 4],
    /// Albedo `ϖ₀` (RGB), unused.
    pub albedo: [f32; 4],
}

/// One material's slab parameters on the GPU.
struct ThinMaterial {
    group: wgpu::BindGroup,
    _uniform: wgpu::Buffer,
    _tau: wgpu::Texture,
}

/// A run of sorted triangles of one material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinDraw {
    /// Material slot of the renderer.
    pub material: usize,
    /// First corner in the sorted buffer.
    pub first: u32,
    /// Corners.
    pub count: u32,
}

/// Pipeline, per-material parameters and the triangles to sort.
pub struct ThinPass {
    pipeline: wgpu::RenderPipeline,
    materials: Vec<Option<ThinMaterial>>,
    /// `(material slot, three corners)` of every thin triangle.
    triangles: Vec<(usize, [CornerVertex; 3])>,
    corners: wgpu::Buffer,
}

impl ThinPass {
    /// Builds the pass for the materials with a `transmission` effect; `descs[slot]` is
    /// the effect of material slot `slot` (`None`: opaque), `corners` the renderer's
    /// corner list with `material_of_triangle` per triangle.
    pub fn new(
        gpu: &Gpu,
        btf: &BtfPass,
        key: BtfPassKey,
        descs: &[(Option<&TransmissionDesc>, &MaterialData, String)],
        corners: &[CornerVertex],
        material_of_triangle: &[usize],
    ) -> Result<ThinPass> {
        if key.msaa == 1 && !gpu.device.features().contains(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err(Error::Unsupported(
                "thin cloth blends into the f32 colour target, which this GPU cannot blend; set effects.msaa = 4 (f16 target)".into(),
            ));
        }
        let layout = thin_layout(&gpu.device);
        let pipeline = pipeline(gpu, btf, &layout, key)?;
        let mut materials = Vec::new();
        for (desc, data, name) in descs {
            materials.push(match desc {
                Some(d) => Some(ThinMaterial::new(gpu, &layout, d, data, name)?),
                None => None,
            });
        }
        let triangles: Vec<(usize, [CornerVertex; 3])> = corners
            .chunks_exact(3)
            .zip(material_of_triangle)
            .filter(|(_, m)| materials[**m].is_some())
            .map(|(c, &m)| (m, [c[0], c[1], c[2]]))
            .collect();
        let corners = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("thin corners (sorted)"),
            size: (triangles.len().max(1) * 3 * std::mem::size_of::<CornerVertex>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(ThinPass { pipeline, materials, triangles, corners })
    }

    /// Whether material slot `m` is drawn by this pass (and not by the opaque one).
    pub fn is_thin(&self, m: usize) -> bool {
        self.materials.get(m).is_some_and(Option::is_some)
    }

    /// Sorts the thin triangles back to front for `camera`, uploads them, and returns
    /// the draws (runs of one material).
    pub fn prepare(&self, gpu: &Gpu, camera: &CameraSetup) -> Vec<ThinDraw> {
        let order = back_to_front(&self.triangles, camera);
        let mut sorted = Vec::with_capacity(order.len() * 3);
        let mut draws: Vec<ThinDraw> = Vec::new();
        for &t in &order {
            let (m, c) = &self.triangles[t];
            match draws.last_mut() {
                Some(d) if d.material == *m => d.count += 3,
                _ => draws.push(ThinDraw { material: *m, first: sorted.len() as u32, count: 3 }),
            }
            sorted.extend_from_slice(c);
        }
        if !sorted.is_empty() {
            gpu.queue.write_buffer(&self.corners, 0, bytemuck::cast_slice(&sorted));
        }
        draws
    }

    /// Records the sorted draws into the BTF render pass (after the opaque geometry).
    pub fn draw<'a>(
        &'a self,
        pass: &mut wgpu::RenderPass<'a>,
        frame_group: &'a wgpu::BindGroup,
        material_group: impl Fn(usize) -> &'a wgpu::BindGroup,
        draws: &[ThinDraw],
    ) {
        if draws.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, frame_group, &[]);
        pass.set_vertex_buffer(0, self.corners.slice(..));
        for d in draws {
            let Some(m) = &self.materials[d.material] else { continue };
            pass.set_bind_group(1, material_group(d.material), &[]);
            pass.set_bind_group(3, &m.group, &[]);
            pass.draw(d.first..d.first + d.count, 0..1);
        }
    }
}

/// Triangle indices ordered from the farthest to the nearest centroid (perspective:
/// distance to the eye; orthographic: depth along the view direction). Exact for layers
/// that do not interpenetrate; ties keep mesh order.
pub fn back_to_front(triangles: &[(usize, [CornerVertex; 3])], camera: &CameraSetup) -> Vec<usize> {
    let depth: Vec<f32> = triangles
        .iter()
        .map(|(_, c)| {
            let p =
                [0, 1, 2].map(|a| (c[0].position[a] + c[1].position[a] + c[2].position[a]) / 3.0);
            match camera.ortho_to_camera {
                Some(d) => -(p[0] * d.x + p[1] * d.y + p[2] * d.z),
                None => {
                    let e = camera.eye;
                    (p[0] - e.x).powi(2) + (p[1] - e.y).powi(2) + (p[2] - e.z).powi(2)
                }
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..triangles.len()).collect();
    order.sort_by(|&a, &b| depth[b].total_cmp(&depth[a]));
    order
}

fn thin_layout(dev: &wgpu::Device) -> wgpu::BindGroupLayout {
    let vis = wgpu::ShaderStages::FRAGMENT;
    dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("thin material"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: vis,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: vis,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
        ],
    })
}

fn pipeline(
    gpu: &Gpu,
    btf: &BtfPass,
    thin: &wgpu::BindGroupLayout,
    key: BtfPassKey,
) -> Result<wgpu::RenderPipeline> {
    let dev = &gpu.device;
    gpu.scoped("building the thin-cloth pass", || {
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("thin"),
            bind_group_layouts: &[
                Some(&btf.frame_layout),
                Some(&btf.material_layout),
                None, // group 2: per-vertex coefficients of the opaque pass, unused here
                Some(thin),
            ],
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("transmission.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        let constants = [
            ("VIEW_FOUR", key.view_four as u32 as f64),
            ("LIGHT_FOUR", key.light_four as u32 as f64),
            ("COUNT_READS", 0.0),
        ];
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            zero_initialize_workgroup_memory: true,
        };
        // L = L_src · 1 + L_dst · alpha_src; the target's alpha is left as it is.
        let blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::SrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        };
        dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("thin"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: options.clone(),
                buffers: &[Some(corner_buffer_layout())],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(mesh_depth_state(false)),
            multisample: wgpu::MultisampleState { count: key.msaa, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_thin"),
                compilation_options: options,
                targets: &[Some(wgpu::ColorTargetState {
                    format: color_format(key.msaa),
                    blend: Some(blend),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    })
}

impl ThinMaterial {
    fn new(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        desc: &TransmissionDesc,
        data: &MaterialData,
        name: &str,
    ) -> Result<ThinMaterial> {
        let (w, h, texels) = match &desc.tau_texture {
            None => (1, 1, vec![f16::ONE]),
            Some(TauTexture::BtfMean) => btf_mean_thickness(data),
            Some(TauTexture::Image(p)) => image_thickness(p)?,
        };
        let a = desc.albedo.rgb();
        let raw = ThinRaw {
            params: [desc.tau, desc.phase.g(), desc.tau_texture.is_some() as u32 as f32, 0.0],
            albedo: [a[0], a[1], a[2], 0.0],
        };
        gpu.scoped(&format!("uploading the transmission of {name}"), || {
            let uniform = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("thin params"),
                contents: bytemuck::bytes_of(&raw),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let tau = gpu.device.create_texture_with_data(
                &gpu.queue,
                &wgpu::TextureDescriptor {
                    label: Some("tau"),
                    size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::R16Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                bytemuck::cast_slice(&texels),
            );
            let view = tau.create_view(&Default::default());
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("thin material"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&view),
                    },
                ],
            });
            ThinMaterial { group, _uniform: uniform, _tau: tau }
        })
    }
}

/// Luminance of the frontal view slot's mean texture, divided by its average (all ones
/// for a black mean).
pub fn btf_mean_thickness(data: &MaterialData) -> (u32, u32, Vec<f16>) {
    let n = (data.width * data.height) as usize;
    let lum: Vec<f32> = data.mean_layers[..n * 4]
        .chunks_exact(4)
        .map(|p| 0.2126 * p[0].to_f32() + 0.7152 * p[1].to_f32() + 0.0722 * p[2].to_f32())
        .map(|l| l.max(0.0))
        .collect();
    let avg = lum.iter().map(|&l| l as f64).sum::<f64>() / n.max(1) as f64;
    let texels = if avg > 0.0 {
        lum.iter().map(|&l| f16::from_f32((l as f64 / avg) as f32)).collect()
    } else {
        vec![f16::ONE; n]
    };
    (data.width, data.height, texels)
}

/// A grey image's values in `[0, 1]` (8/16-bit: `v / max`; float: as stored, refused
/// outside `[0, 1]` or non-finite).
pub fn image_thickness(path: &std::path::Path) -> Result<(u32, u32, Vec<f16>)> {
    let img = image::open(path)
        .map_err(|e| Error::Invalid(format!("{}: tau_texture: {e}", path.display())))?;
    let grey = img.to_luma32f();
    if let Some((i, v)) =
        grey.iter().enumerate().find(|(_, v)| !(v.is_finite() && (0.0..=1.0).contains(*v)))
    {
        return Err(Error::Invalid(format!(
            "{}: tau_texture pixel x={}, y={} is {v}; values must be in [0, 1]",
            path.display(),
            i as u32 % grey.width(),
            i as u32 / grey.width()
        )));
    }
    Ok((grey.width(), grey.height(), grey.iter().map(|&v| f16::from_f32(v)).collect()))
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("transmission.wgsl", super::SOURCE).unwrap();
        assert_eq!(std::mem::size_of::<super::ThinRaw>(), 32);
    }
}
