//! `fiber_draw` (render, vertex pulling, one indirect draw): the instances `fiber_lod`
//! listed, each a camera-facing triangle strip evaluated by the WGSL generator ([W19 §5]'s
//! tessellation + geometry shaders, DESIGN §2.4 item 2), shaded with the fiber BCSDF of
//! `yarn::bcsdf` under point and directional lights, into a linear `Rgba32Float` target
//! (`Rgba16Float` under MSAA) with MSAA; strips narrower than the minimum width keep their coverage fraction of the
//! samples through a hashed sample mask (see the WGSL). With fiber shadows a second
//! pipeline of the same module draws the fiber shadow maps (`vs_main` with the light as
//! the camera, `fs_shadow`: far-side depth and fiber key, `crate::passes::fiber_shadow`).

use crate::gpu_data::YarnBuffers;
use crate::{Error, Result};
use btf_render::Gpu;

const WGSL: &str = include_str!("../shaders/fiber_draw.wgsl");
/// The fiber BCSDF, view direction and sample masks `fiber_draw` and `strip_regular` share.
pub const SHADING_WGSL: &str = include_str!("../shaders/fiber_shading.wgsl");

/// The colour target format at `samples` per pixel: `Rgba32Float`, or `Rgba16Float` under
/// MSAA (WebGPU guarantees multisampling of the 16-bit format only; btf-render does the
/// same).
pub fn color_format(samples: u32) -> wgpu::TextureFormat {
    if samples > 1 { wgpu::TextureFormat::Rgba16Float } else { wgpu::TextureFormat::Rgba32Float }
}
/// The depth format.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The fiber shadow maps' fiber keys.
pub const SHADOW_IDS: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// The pass's WGSL (generator and view in front).
pub fn source() -> String {
    format!("{}\n{}\n{SHADING_WGSL}\n{WGSL}", crate::FIBER_GEN_WGSL, crate::FIBER_VIEW_WGSL)
}

/// The compiled pass.
pub struct DrawPass {
    pipeline: wgpu::RenderPipeline,
    /// The fiber shadow maps' pipeline (`vs_main` with the light's view, `fs_shadow`, depth
    /// only, one sample), compiled only when a renderer draws them.
    shadow: Option<wgpu::RenderPipeline>,
    /// Layout of group 1 (view, instances, lobes, q nodes, effect headers and data, tube
    /// shadow maps, their comparison sampler and views).
    pub layout: wgpu::BindGroupLayout,
    /// MSAA samples.
    pub samples: u32,
}

impl DrawPass {
    /// Compiles the pass at `samples` per pixel (1 or 4), with the fiber shadow maps'
    /// pipeline when `shadows`.
    pub fn new(gpu: &Gpu, data: &YarnBuffers, samples: u32, shadows: bool) -> Result<Self> {
        if samples != 1 && samples != 4 {
            return Err(Error::Invalid(format!("fiber_draw: MSAA {samples} (1 or 4)")));
        }
        let dev = &gpu.device;
        let buf = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let fs = wgpu::ShaderStages::FRAGMENT;
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fiber_draw"),
            entries: &[
                buf(0, vf, wgpu::BufferBindingType::Uniform),
                buf(1, wgpu::ShaderStages::VERTEX, ro),
                buf(2, fs, ro),
                buf(3, fs, ro),
                buf(4, vf, ro),
                buf(5, vf, ro),
                wgpu::BindGroupLayoutEntry {
                    binding: 6,
                    visibility: fs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 7,
                    visibility: fs,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                buf(8, fs, wgpu::BufferBindingType::Uniform),
                buf(9, fs, ro),
                wgpu::BindGroupLayoutEntry {
                    binding: 10,
                    visibility: fs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let src = source();
        let (pipeline, shadow) = gpu
            .scoped("fiber_draw pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("fiber_draw.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("fiber_draw"),
                    bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                    immediate_size: 0,
                });
                let strip = wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleStrip,
                    cull_mode: None,
                    ..Default::default()
                };
                let depth = wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                };
                let shadow = shadows.then(|| {
                    dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("fiber_draw shadow"),
                        layout: Some(&pl),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some("vs_main"),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: strip,
                        depth_stencil: Some(depth.clone()),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some("fs_shadow"),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format: SHADOW_IDS,
                                blend: None,
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                });
                let main = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("fiber_draw"),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: strip,
                    depth_stencil: Some(depth),
                    multisample: wgpu::MultisampleState {
                        count: samples,
                        mask: !0,
                        alpha_to_coverage_enabled: false,
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_main"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: color_format(samples),
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                (main, shadow)
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        Ok(DrawPass { pipeline, shadow, layout, samples })
    }

    /// The pull = expand probe (tests, DESIGN §2.5): `vs_probe`/`fs_probe` of the same
    /// module and layouts, a point per strip vertex into an `Rgba32Float` target (see the
    /// WGSL).
    pub fn probe_pipeline(&self, gpu: &Gpu, data: &YarnBuffers) -> Result<wgpu::RenderPipeline> {
        let dev = &gpu.device;
        gpu.scoped("fiber_draw probe pipeline", || {
            let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("fiber_draw.wgsl (probe)"),
                source: wgpu::ShaderSource::Wgsl(source().into()),
            });
            let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("fiber_draw probe"),
                bind_group_layouts: &[Some(&data.layout), Some(&self.layout)],
                immediate_size: 0,
            });
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("fiber_draw probe"),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_probe"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::PointList,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_probe"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: wgpu::TextureFormat::Rgba32Float,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
        .map_err(|e| Error::Gpu(e.to_string()))
    }

    /// Records the draw into `color`/`depth`, cleared to `clear` (depth discarded after) or,
    /// with `None`, loaded — another renderer's targets, whose depth the strips test against
    /// and keep — reading the instance count from `args` at offset 0.
    pub fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        data: &YarnBuffers,
        group1: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        targets: (&wgpu::TextureView, Option<&wgpu::TextureView>, &wgpu::TextureView),
        clear: Option<[f64; 4]>,
    ) {
        let (color, resolve, depth) = targets;
        let (color_load, depth_load, depth_store) = match clear {
            Some(c) => (
                wgpu::LoadOp::Clear(wgpu::Color { r: c[0], g: c[1], b: c[2], a: c[3] }),
                wgpu::LoadOp::Clear(1.0),
                wgpu::StoreOp::Discard,
            ),
            None => (wgpu::LoadOp::Load, wgpu::LoadOp::Load, wgpu::StoreOp::Store),
        };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("fiber_draw"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations { load: color_load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: depth_load, store: depth_store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &data.bind_group, &[]);
        pass.set_bind_group(1, group1, &[]);
        pass.draw_indirect(args, 0);
    }
}

impl DrawPass {
    /// Records one fiber shadow map into `map` (a depth view) and `ids` (its fiber keys),
    /// both cleared: the instances `fiber_lod` listed for the light's view in `group1`,
    /// their count in `args`. Nothing when the pass was compiled without the shadow
    /// pipeline.
    pub fn encode_shadow(
        &self,
        enc: &mut wgpu::CommandEncoder,
        data: &YarnBuffers,
        group1: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        (map, ids): (&wgpu::TextureView, &wgpu::TextureView),
    ) {
        let Some(pipeline) = &self.shadow else { return };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("fiber_draw shadow"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: ids,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: map,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &data.bind_group, &[]);
        pass.set_bind_group(1, group1, &[]);
        pass.draw_indirect(args, 0);
    }
}

/// Checks that another renderer's `(colour, resolve, depth)` targets fit a `size` frame at
/// `samples` per pixel (formats, sizes, sample counts, a resolve target exactly under
/// MSAA); `what` names the caller in the error.
pub fn check_targets(
    what: &str,
    (color, resolve, depth): (&wgpu::TextureView, Option<&wgpu::TextureView>, &wgpu::TextureView),
    size: (u32, u32),
    samples: u32,
) -> Result<()> {
    let (c, d) = (color.texture(), depth.texture());
    let fits = |t: &wgpu::Texture, format| {
        (t.width(), t.height()) == size && t.sample_count() == samples && t.format() == format
    };
    if fits(c, color_format(samples)) && fits(d, DEPTH) && (samples > 1) == resolve.is_some() {
        return Ok(());
    }
    Err(crate::Error::Invalid(format!(
        "{what} encode_into: targets {:?} {}×{} ×{} and {:?} ×{} for a {}×{} frame of {:?}/{:?} at {samples} samples",
        c.format(),
        c.width(),
        c.height(),
        c.sample_count(),
        d.format(),
        d.sample_count(),
        size.0,
        size.1,
        color_format(samples),
        DEPTH
    )))
}

/// The colour (resolved, and multisampled under MSAA) and depth targets of one offscreen
/// frame, as the fiber and strip renderers draw into them.
pub struct FrameTargets {
    resolved: wgpu::Texture,
    msaa: Option<wgpu::Texture>,
    depth: wgpu::Texture,
    samples: u32,
}

impl FrameTargets {
    /// Targets of `size` at `samples` per pixel (`what` names them in GPU errors).
    pub fn new(gpu: &Gpu, what: &str, size: (u32, u32), samples: u32) -> Result<Self> {
        gpu.check_frame(size.0, size.1, samples)?;
        let format = color_format(samples);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        Ok(FrameTargets {
            resolved: gpu.target(&format!("{what} colour"), size, 1, format, usage),
            msaa: (samples > 1)
                .then(|| gpu.target(&format!("{what} colour msaa"), size, samples, format, attach)),
            depth: gpu.target(&format!("{what} depth"), size, samples, DEPTH, attach),
            samples,
        })
    }

    /// Views `(colour, resolve, depth)` as the passes take them.
    pub fn views(&self) -> (wgpu::TextureView, Option<wgpu::TextureView>, wgpu::TextureView) {
        let rv = self.resolved.create_view(&Default::default());
        let dv = self.depth.create_view(&Default::default());
        match &self.msaa {
            Some(m) => (m.create_view(&Default::default()), Some(rv), dv),
            None => (rv, None, dv),
        }
    }

    /// The resolved frame as linear RGBA, rows top to bottom.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<[f32; 4]>> {
        Ok(if self.samples > 1 {
            let bytes = gpu.read_texture(&self.resolved, 8)?;
            bytemuck::cast_slice::<u8, [half::f16; 4]>(&bytes)
                .iter()
                .map(|p| p.map(f32::from))
                .collect()
        } else {
            let bytes = gpu.read_texture(&self.resolved, 16)?;
            bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec()
        })
    }
}
