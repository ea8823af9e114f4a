//! `yarn_tube_shadow` (render, depth only): one shadow map per directional light of the
//! yarns drawn as thick tubes of the yarn radius [W19 §4.1], light-facing strips pulled
//! from the control points like the fibers. The fiber shader reads it at the yarn centre
//! moved towards the light by the tube radius, so a yarn is shadowed by other yarns only;
//! its own fibers' shadows are the self-shadow volume's (`crate::effects`). The tube
//! radius is the yarn radius without flyaways (DESIGN §2.3 item 14).

use crate::gpu_data::YarnBuffers;
use crate::passes::draw::DEPTH;
use crate::view::{FiberCamera, FiberLight, ViewSetup, to_cols};
use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;

const WGSL: &str = include_str!("../shaders/yarn_tube_shadow.wgsl");

/// The pass's WGSL (generator in front).
pub fn source() -> String {
    crate::with_generator(WGSL)
}

/// The most shadowed directional lights per frame.
pub const MAX_SHADOW_MAPS: usize = 4;

/// The uniform of one shadow pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowPassRaw {
    /// Origin-relative world → light clip.
    pub view_proj: [[f32; 4]; 4],
    /// Unit direction towards the light.
    pub to_light: [f32; 4],
    /// Subdivisions per segment.
    pub n: [u32; 4],
}

/// The shadow maps as the fiber shader reads them (uniform).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowViewsRaw {
    /// World → light clip per map.
    pub view_proj: [[[f32; 4]; 4]; MAX_SHADOW_MAPS],
    /// Maps in use.
    pub n: [u32; 4],
    /// The light each map belongs to.
    pub light: [u32; 4],
    /// 1/size, depth bias, unused ×2.
    pub texel: [f32; 4],
}

/// The compiled pass.
pub struct ShadowPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl ShadowPass {
    /// Compiles the pass for `data`'s group-0 layout.
    pub fn new(gpu: &Gpu, data: &YarnBuffers) -> Result<Self> {
        let dev = &gpu.device;
        let layout =
            btf_render::gpu::uniform_layout(dev, "yarn_tube_shadow", wgpu::ShaderStages::VERTEX);
        let src = source();
        let pipeline = gpu
            .scoped("yarn_tube_shadow pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("yarn_tube_shadow.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("yarn_tube_shadow"),
                    bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                    immediate_size: 0,
                });
                dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("yarn_tube_shadow"),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_shadow"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleStrip,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Less),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: None,
                    multiview_mask: None,
                    cache: None,
                })
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        Ok(ShadowPass { pipeline, layout })
    }

    /// Records one map per entry of `passes` into the layers of `maps` (a depth 2-D array
    /// with at least that many layers); with no passes, layer 0 is cleared (a bound map
    /// must have been written).
    pub fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        data: &YarnBuffers,
        maps: &wgpu::Texture,
        passes: &[ShadowPassRaw],
    ) {
        let dev = &gpu.device;
        let begin = |enc: &mut wgpu::CommandEncoder, layer: u32| {
            let view = maps.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            });
            enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("yarn_tube_shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            })
            .forget_lifetime()
        };
        if passes.is_empty() {
            drop(begin(enc, 0));
            return;
        }
        for (layer, raw) in passes.iter().enumerate() {
            let ubuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("yarn_tube_shadow"),
                contents: bytemuck::bytes_of(raw),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bg = dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("yarn_tube_shadow"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: ubuf.as_entire_binding() }],
            });
            let mut pass = begin(enc, layer as u32);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &data.bind_group, &[]);
            pass.set_bind_group(1, &bg, &[]);
            pass.draw(0..2 * (raw.n[0] + 1), 0..data.segment_count);
        }
    }
}

/// One orthographic light view per unit direction of `dirs` (towards the light) for a
/// scene within `radius` of `centre` (origin-relative), side `2·radius`, `size²` texels:
/// the pass uniform and the light-clip depth per metre along the light (PCSS turns depth
/// gaps into metres).
pub fn light_views(
    dirs: &[[f64; 3]],
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    size: u32,
) -> Result<Vec<(ShadowPassRaw, f64)>> {
    let mut out = Vec::new();
    for &dir in dirs {
        let n = (dir.iter().map(|x| x * x).sum::<f64>()).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return Err(Error::Invalid(format!("shadow view: light direction {dir:?}")));
        }
        let d = dir.map(|x| x / n);
        let r = radius;
        let c = [0, 1, 2].map(|a| centre[a] + origin[a]);
        let eye = [0, 1, 2].map(|a| c[a] + d[a] * 2.0 * r);
        let up = if d[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        let cam = FiberCamera::orthographic(eye, c, up, 2.0 * r);
        let setup = ViewSetup::new(&cam, origin, centre, r, (size, size))?;
        let m = &setup.view_proj;
        let depth_per_metre = (m[(2, 0)] * d[0] + m[(2, 1)] * d[1] + m[(2, 2)] * d[2]).abs();
        out.push((
            ShadowPassRaw {
                view_proj: to_cols(m),
                to_light: [d[0] as f32, d[1] as f32, d[2] as f32, 0.0],
                n: [8, 0, 0, 0],
            },
            depth_per_metre,
        ));
    }
    Ok(out)
}

/// The shadow passes of the first [`MAX_SHADOW_MAPS`] directional lights of `lights` for a
/// scene within `radius` of `centre` (origin-relative) ([`light_views`]), with the uniform
/// the fiber shader reads them with and, per map, the light-clip depth per metre.
pub fn directional_views(
    lights: &[FiberLight],
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    size: u32,
) -> Result<(Vec<ShadowPassRaw>, ShadowViewsRaw, Vec<f64>)> {
    let mut views =
        ShadowViewsRaw { texel: [1.0 / size as f32, 2e-3, 0.0, 0.0], ..Default::default() };
    let mut dirs = Vec::new();
    for (i, l) in lights.iter().enumerate() {
        let FiberLight::Directional { to_light, .. } = *l else { continue };
        if dirs.len() == MAX_SHADOW_MAPS {
            break;
        }
        views.light[dirs.len()] = i as u32;
        dirs.push(to_light);
    }
    let v = light_views(&dirs, origin, centre, radius, size)?;
    for (k, (p, _)) in v.iter().enumerate() {
        views.view_proj[k] = p.view_proj;
    }
    views.n[0] = v.len() as u32;
    let depth = v.iter().map(|x| x.1).collect();
    Ok((v.into_iter().map(|x| x.0).collect(), views, depth))
}
