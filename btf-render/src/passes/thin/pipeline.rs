//! The thin-cloth pass's pipeline: its WGSL, bind group 3's layout (slab parameters, τ
//! texture, per-vertex environment tables) and the blended render pipeline of
//! `[TC eq. 9]`, `L = L_src + L_dst · alpha_src` with `alpha = e^{−τ₁/μ}`, depth tested
//! without writes; with an environment light the fragment entry `fs_thin_env` and the
//! per-vertex coefficients of the BTF pass as group 2.

use crate::bind::{self, storage, texture, uniform};
use crate::passes::btf::{BtfPass, BtfPassKey};
use crate::passes::mesh::{MeshPipeline, color_format};
use crate::{Gpu, Result};

/// WGSL of the pass: the BTF pass's source (per-vertex part included: the environment term
/// is per vertex) with the thin-cloth fragment shaders appended.
pub const SOURCE: &str = concat!(
    include_str!("../shaders/interp.wgsl"),
    include_str!("../btf/btf_pass.wgsl"),
    include_str!("../btf/btf_vertex.wgsl"),
    include_str!("transmission.wgsl")
);

pub(super) fn thin_layout(dev: &wgpu::Device) -> wgpu::BindGroupLayout {
    let float = wgpu::TextureSampleType::Float { filterable: true };
    bind::layout_seen_by(
        dev,
        "thin material",
        wgpu::ShaderStages::FRAGMENT,
        &[uniform(), texture(float, wgpu::TextureViewDimension::D2), storage(true)],
    )
}

pub(super) fn pipeline(
    gpu: &Gpu,
    btf: &BtfPass,
    thin: &wgpu::BindGroupLayout,
    key: BtfPassKey,
    environment: bool,
) -> Result<wgpu::RenderPipeline> {
    let dev = &gpu.device;
    // group 2: the per-vertex coefficients (the environment's BTF term), which a key with
    // an environment light always has
    let vertex_layout = environment
        .then(|| btf.vertex_layout.as_ref().expect("a pass key with an environment has group 2"));
    let (layout, module) = gpu.scoped("building the thin-cloth pass", || {
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("thin"),
            bind_group_layouts: &[
                Some(&btf.frame_layout),
                Some(&btf.material_layout),
                vertex_layout,
                Some(thin),
            ],
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("transmission.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        (layout, module)
    })?;
    // the material layout of the BTF pass it draws after (its weights may be packed)
    let constants = [
        ("VIEW_FOUR", key.view_four as u32 as f64),
        ("LIGHT_FOUR", key.light_four as u32 as f64),
        ("COUNT_READS", 0.0),
        ("GROUPS", btf.key.groups as f64),
        ("PACKED", btf.key.packed as u32 as f64),
    ];
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
    MeshPipeline {
        label: "thin",
        layout: &layout,
        module: &module,
        // The environment's BTF term blends per-vertex slot sets: `vs_vertex` hands them to
        // the fragments as flat varyings.
        vertex: if environment { "vs_vertex" } else { "vs_main" },
        fragment: if environment { "fs_thin_env" } else { "fs_thin" },
        constants: &constants,
        targets: &[Some(wgpu::ColorTargetState {
            format: color_format(key.msaa),
            blend: Some(blend),
            write_mask: wgpu::ColorWrites::ALL,
        })],
        depth_write: false,
        msaa: key.msaa,
    }
    .build(gpu)
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("transmission.wgsl", super::SOURCE).unwrap();
    }
}
