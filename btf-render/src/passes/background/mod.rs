//! The environment map drawn behind the scene (`[output] show_environment = true`): per
//! pixel, the radiance `f · L_env(R_{−δ} ω)` of the camera ray's world direction `ω`, with
//! the environment light's rotation `δ` about `+z` and exposure `f` — the same map, turned
//! the same way, that lights the scene (DESIGN.md §3; `f` is `[S03 eq. 11]`'s). Thin cloth
//! (`[TC eq. 9]`) then shows it through with its view-dependent alpha, as the paper's flag
//! shows the sky.
//!
//! A full-screen pass (as wgpu's skybox example draws the sky) into the frame's colour
//! target — the multisampled one with MSAA, which the BTF pass then loads and resolves —
//! before the mesh passes; `background.wgsl` filters the equirectangular map bilinearly
//! itself (rows `θ` from `+z`, columns `φ` from `+x` towards `+y`, wrapping in `φ`).

use crate::bind::{self, texture, uniform};
use crate::camera::CameraSetup;
use crate::math::{self, Mat4};
use crate::passes::mesh::color_format;
use crate::timer::PassTimer;
use crate::{Error, Gpu, Result};
use btf_image::EnvMap;
use wgpu::util::DeviceExt;

/// WGSL of the pass.
pub const SOURCE: &str = include_str!("background.wgsl");

/// GPU mirror of `Background` in `background.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BackgroundRaw {
    inv_view_proj: [[f32; 4]; 4],
    frame: [f32; 4],
    rotation: [f32; 4],
}

/// The pipeline, the map as a texture and the uniform of the view.
pub struct BackgroundPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    group: wgpu::BindGroup,
    _map: wgpu::Texture,
}

/// What one frame's background is drawn for.
pub struct BackgroundView<'a> {
    /// The camera.
    pub camera: &'a CameraSetup,
    /// Frame size in pixels.
    pub size: (u32, u32),
    /// The environment's rotation `δ` about `+z`, degrees.
    pub rotation_deg: f64,
    /// Its exposure `f`.
    pub exposure: f32,
}

impl BackgroundPass {
    /// Builds the pass for frames of `msaa` samples and uploads `map`.
    pub fn new(gpu: &Gpu, map: &EnvMap, msaa: u32) -> Result<BackgroundPass> {
        let dev = &gpu.device;
        let layout = bind::layout_seen_by(
            dev,
            "background",
            wgpu::ShaderStages::FRAGMENT,
            &[
                uniform(),
                texture(
                    wgpu::TextureSampleType::Float { filterable: false },
                    wgpu::TextureViewDimension::D2,
                ),
            ],
        );
        let pipeline = gpu.scoped("building the background pass", || {
            let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("background.wgsl"),
                source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
            });
            let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("background"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("background"),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_fullscreen"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState { count: msaa, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_background"),
                    compilation_options: Default::default(),
                    targets: &[Some(color_format(msaa).into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        })?;
        let uniform = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("background"),
            size: std::mem::size_of::<BackgroundRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (map_texture, group) = Self::upload(gpu, &layout, &uniform, map)?;
        Ok(BackgroundPass { pipeline, layout, uniform, group, _map: map_texture })
    }

    fn upload(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        uniform: &wgpu::Buffer,
        map: &EnvMap,
    ) -> Result<(wgpu::Texture, wgpu::BindGroup)> {
        let side = gpu.device.limits().max_texture_dimension_2d;
        let (w, h) = (map.width as u32, map.height as u32);
        if w > side || h > side {
            return Err(Error::Limit(format!(
                "a {w} × {h} environment map exceeds this adapter's max_texture_dimension_2d \
                 ({side}) for the background; use a smaller map"
            )));
        }
        let rgba: Vec<[f32; 4]> = map.pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let texture = gpu.device.create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("environment map"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&rgba),
        );
        let view = texture.create_view(&Default::default());
        let resources = [uniform.as_entire_binding(), wgpu::BindingResource::TextureView(&view)];
        let group = bind::group(&gpu.device, "background", layout, &resources);
        Ok((texture, group))
    }

    /// Replaces the map.
    pub fn set_map(&mut self, gpu: &Gpu, map: &EnvMap) -> Result<()> {
        let (texture, group) = Self::upload(gpu, &self.layout, &self.uniform, map)?;
        (self._map, self.group) = (texture, group);
        Ok(())
    }

    /// Encodes the pass into `target` (the multisampled colour target with MSAA), writing
    /// the view's uniform first.
    pub fn encode(
        &self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        target: &wgpu::TextureView,
        view: &BackgroundView,
    ) -> Result<()> {
        let inv = view.camera.view_proj.try_inverse().unwrap_or_else(Mat4::identity);
        let (sin, cos) = view.rotation_deg.to_radians().sin_cos();
        let raw = BackgroundRaw {
            inv_view_proj: math::to_cols(&inv),
            frame: [view.size.0 as f32, view.size.1 as f32, view.exposure, 0.0],
            rotation: [cos as f32, sin as f32, 0.0, 0.0],
        };
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&raw));
        gpu.scoped("environment background", || {
            timer.pass("environment background", |enc, ts| {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("environment background"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.group, &[]);
                pass.draw(0..3, 0..1);
            })
        })?
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("background.wgsl", super::SOURCE).unwrap();
        assert_eq!(std::mem::size_of::<super::BackgroundRaw>(), 96);
    }
}
