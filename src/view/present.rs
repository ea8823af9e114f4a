//! Shows the rendered frame on the window surface: samples the linear HDR texture the
//! renderer encoded the frame into ([`super::state::Shown`], no read-back to the CPU) and
//! draws it with exposure and sRGB encoding (`present.wgsl`), letterboxed into the area
//! the panel leaves free. DESIGN.md §3: values stay linear until this last step, as in the
//! PNG writer.
//!
//! [`Present::upload`] is the former path — a read-back [`Frame`] uploaded as an
//! `Rgba32Float` texture — kept for `btf view --bench`, which times both in one run.

use super::state::Shown;
use btf_render::Frame;
use btf_render::Gpu;
use wgpu::util::DeviceExt;

const SOURCE: &str = include_str!("present.wgsl");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    exposure: f32,
    encode_srgb: u32,
    pad: [f32; 2],
}

/// The presentation pass.
pub struct Present {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    encode_srgb: bool,
    /// The texture drawn: the shown frame's (and its generation), or an uploaded frame's.
    texture: Option<(Source, wgpu::BindGroup)>,
}

/// Where the presented texture comes from.
enum Source {
    /// The renderer's target of this generation.
    Shown(u64),
    /// A frame uploaded from the CPU.
    Uploaded(wgpu::Texture),
}

/// A viewport rectangle in physical pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width.
    pub w: f32,
    /// Height.
    pub h: f32,
}

/// The largest rectangle of aspect `frame_w : frame_h` centred in `area`.
pub fn letterbox(area: Rect, frame_w: u32, frame_h: u32) -> Rect {
    let s = (area.w / frame_w.max(1) as f32).min(area.h / frame_h.max(1) as f32).max(0.0);
    let (w, h) = (frame_w as f32 * s, frame_h as f32 * s);
    Rect { x: area.x + (area.w - w) * 0.5, y: area.y + (area.h - h) * 0.5, w, h }
}

impl Present {
    /// Builds the pass for a surface of `format`.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Present {
        let dev = &gpu.device;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("present.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("present"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("present"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let params = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("present params"),
            contents: bytemuck::bytes_of(&ParamsRaw {
                exposure: 1.0,
                encode_srgb: 0,
                pad: [0.0; 2],
            }),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        Present { pipeline, layout, params, encode_srgb: !format.is_srgb(), texture: None }
    }

    fn bind(&self, gpu: &Gpu, view: &wgpu::TextureView) -> wgpu::BindGroup {
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("present"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry { binding: 1, resource: self.params.as_entire_binding() },
            ],
        })
    }

    /// Presents the renderer's shown texture (rebinding only when it was made anew).
    pub fn show(&mut self, gpu: &Gpu, shown: &Shown) {
        if let Some((Source::Shown(g), _)) = &self.texture
            && *g == shown.generation
        {
            return;
        }
        let group = self.bind(gpu, &shown.view);
        self.texture = Some((Source::Shown(shown.generation), group));
    }

    /// Uploads a read-back `frame` and presents it (re-using the texture while the size
    /// stays): the path the viewer took before it presented the renderer's texture.
    pub fn upload(&mut self, gpu: &Gpu, frame: &Frame) {
        let size =
            wgpu::Extent3d { width: frame.width, height: frame.height, depth_or_array_layers: 1 };
        let fits = matches!(&self.texture, Some((Source::Uploaded(t), _)) if t.size() == size);
        if !fits {
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("shown frame"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            let group = self.bind(gpu, &view);
            self.texture = Some((Source::Uploaded(texture), group));
        }
        let rgba: Vec<f32> =
            frame.rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let Some((Source::Uploaded(texture), _)) = &self.texture else {
            unreachable!("an uploaded texture was just made")
        };
        gpu.queue.write_texture(
            texture.as_image_copy(),
            bytemuck::cast_slice(&rgba),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(frame.width * 16),
                rows_per_image: Some(frame.height),
            },
            size,
        );
    }

    /// Draws the frame into `viewport` of the pass (nothing before one is shown).
    pub fn draw(&self, gpu: &Gpu, pass: &mut wgpu::RenderPass<'_>, exposure: f32, viewport: Rect) {
        let Some((_, group)) = &self.texture else { return };
        if viewport.w < 1.0 || viewport.h < 1.0 {
            return;
        }
        let raw = ParamsRaw { exposure, encode_srgb: self.encode_srgb as u32, pad: [0.0; 2] };
        gpu.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&raw));
        pass.set_viewport(viewport.x, viewport.y, viewport.w, viewport.h, 0.0, 1.0);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shader_validates() {
        btf_render::gpu::validate_wgsl("present.wgsl", SOURCE).unwrap();
    }

    #[test]
    fn letterbox_keeps_aspect_and_centres() {
        let r = letterbox(Rect { x: 10.0, y: 0.0, w: 400.0, h: 300.0 }, 320, 120);
        assert_eq!((r.w, r.h), (400.0, 150.0));
        assert_eq!((r.x, r.y), (10.0, 75.0));
        let r = letterbox(Rect { x: 0.0, y: 0.0, w: 100.0, h: 300.0 }, 200, 200);
        assert_eq!((r.w, r.h, r.y), (100.0, 100.0, 100.0));
    }
}
