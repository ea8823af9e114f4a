//! The thin-cloth pass's pipeline: bind group 3's layout (slab parameters, τ texture,
//! per-vertex environment tables) and the blended render pipeline of eq. 9,
//! `L = L_src + L_dst · alpha_src` with `alpha = e^{−τ₁/μ}` (thin-cloth paper), depth
//! tested without writes; with an environment light the fragment entry `fs_thin_env` and
//! the per-vertex coefficients of the BTF pass as group 2.

use super::pass::SOURCE;
use crate::btf_pass::{BtfPass, BtfPassKey, color_format, corner_buffer_layout, mesh_depth_state};
use crate::{Error, Gpu, Result};

pub(super) fn thin_layout(dev: &wgpu::Device) -> wgpu::BindGroupLayout {
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
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: vis,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    })
}

pub(super) fn pipeline(
    gpu: &Gpu,
    btf: &BtfPass,
    thin: &wgpu::BindGroupLayout,
    key: BtfPassKey,
    environment: bool,
) -> Result<wgpu::RenderPipeline> {
    let dev = &gpu.device;
    let vertex_layout = match (environment, &btf.vertex_layout) {
        (false, _) => None,
        (true, Some(l)) => Some(l),
        (true, None) => {
            return Err(Error::Gpu(
                "thin cloth: the environment's per-vertex layout is missing".into(),
            ));
        }
    };
    gpu.scoped("building the thin-cloth pass", || {
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("thin"),
            bind_group_layouts: &[
                Some(&btf.frame_layout),
                Some(&btf.material_layout),
                vertex_layout, // group 2: per-vertex coefficients (the environment's BTF term)
                Some(thin),
            ],
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("transmission.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        // the material layout of the BTF pass it draws after (its weights may be packed)
        let constants = [
            ("VIEW_FOUR", key.view_four as u32 as f64),
            ("LIGHT_FOUR", key.light_four as u32 as f64),
            ("COUNT_READS", 0.0),
            ("GROUPS", btf.key.groups as f64),
            ("PACKED", btf.key.packed as u32 as f64),
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
                // The environment's BTF term blends per-vertex slot sets: `vs_vertex` hands
                // them to the fragments as flat varyings.
                entry_point: Some(if environment { "vs_vertex" } else { "vs_main" }),
                compilation_options: options.clone(),
                buffers: &[Some(corner_buffer_layout())],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(mesh_depth_state(false)),
            multisample: wgpu::MultisampleState { count: key.msaa, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(if environment { "fs_thin_env" } else { "fs_thin" }),
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
