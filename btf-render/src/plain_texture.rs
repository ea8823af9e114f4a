//! Baseline 1 of the cost sweep (issue #5, "what accuracy costs in time"): plain texture
//! mapping of one mean texture (view slot 0) on the same mesh at the same resolution — one
//! filtered read per pixel and no lighting, the frame a renderer without a BTF would draw.
//! It shares the BTF pass's vertices, bind groups, targets and sampler (so mipmapping and
//! anisotropy match); the BTF frame's cost is reported as a ratio to it, not targeted.
//!
//! Also holds the pipeline builder both baselines use (`plain_texture.wgsl` is the shared
//! vertex stage; `read_bound.rs` adds its fragment stage).

use crate::btf_pass::{BtfPass, color_format, corner_buffer_layout, mesh_depth_state};
use crate::{Gpu, Result};

/// WGSL of the plain-texture baseline (with the `Samplings` block of `interp.wgsl`).
pub const SOURCE: &str = concat!(include_str!("interp.wgsl"), include_str!("plain_texture.wgsl"));

/// Which baseline replaces the BTF shader (`RenderOptions::baseline`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Baseline {
    /// Plain texture mapping of view slot 0's mean texture.
    Plain,
    /// The read bound for the BTF pass's measured reads per pixel.
    ReadBound {
        /// Mean texture reads per shaded pixel of the BTF pass being bounded.
        reads_per_pixel: f64,
        /// How the reads are written (the sweep times both and takes the faster).
        form: ReadForm,
    },
}

/// Two ways to write the read bound's loop over a slot's eigentexture layers; which one
/// llvmpipe runs faster depends on the group count, so the cost sweep times both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadForm {
    /// One read per iteration of a loop whose length is read from a uniform.
    Loop,
    /// Three reads (one group) per iteration of a loop of pipeline-constant length.
    Groups,
}

/// A baseline pipeline ready to replace the BTF pipeline in the frame's colour pass.
pub struct BaselinePass {
    /// Pipeline on the BTF pass's groups 0 and 1 (plus its own group 2, if any).
    pub pipeline: wgpu::RenderPipeline,
    /// Its group 2 (the read bound's counts).
    pub group: Option<wgpu::BindGroup>,
    /// Pass name in the frame statistics.
    pub name: String,
}

/// Builds a baseline pipeline from `source` with fragment entry `fragment` and its override
/// `constants`, on the BTF pass's frame and material layouts and an optional extra group 2.
pub fn pipeline(
    gpu: &Gpu,
    btf: &BtfPass,
    source: &str,
    fragment: &str,
    constants: &[(&str, f64)],
    extra: Option<&wgpu::BindGroupLayout>,
) -> Result<wgpu::RenderPipeline> {
    let dev = &gpu.device;
    gpu.scoped(&format!("building the baseline {fragment}"), || {
        let mut groups = vec![Some(&btf.frame_layout), Some(&btf.material_layout)];
        if let Some(e) = extra {
            groups.push(Some(e));
        }
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(fragment),
            bind_group_layouts: &groups,
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(fragment),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(fragment),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_base"),
                compilation_options: Default::default(),
                buffers: &[Some(corner_buffer_layout())],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(mesh_depth_state(true)),
            multisample: wgpu::MultisampleState { count: btf.key.msaa, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(fragment),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                targets: &[Some(color_format(btf.key.msaa).into())],
            }),
            multiview_mask: None,
            cache: None,
        })
    })
}

/// The plain-texture baseline.
pub fn build(gpu: &Gpu, btf: &BtfPass) -> Result<BaselinePass> {
    Ok(BaselinePass {
        pipeline: pipeline(gpu, btf, SOURCE, "fs_plain", &[], None)?,
        group: None,
        name: "plain texture (baseline)".into(),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("plain_texture.wgsl", super::SOURCE).unwrap();
    }
}
