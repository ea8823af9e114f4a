//! The BTF pass: draws the mesh with the BTF reconstructed per fragment (`[S03 eq. 2–5]`)
//! and lit by up to four point/directional lights, each attenuated by the smooth shadow
//! boundary (`[S03 eq. 6]`, `super::smooth_boundary`) and a shadow-volume mask or shadow map,
//! plus an environment light whose per-vertex coefficients (`[S03 eq. 11]`) are blended
//! across each triangle. The formula is in `btf_pass.wgsl`; the per-vertex evaluation of
//! `[S03 §4.2]` in `btf_vertex.wgsl`.
//!
//! Pipeline variants come from [`BtfPassKey`] (`key.rs`), the blending choices as WGSL
//! override constants so the unused branch is compiled out. Bind groups are built in the
//! order of the WGSL `@binding`s (`crate::bind`): group 0 the frame (uniform, boundary
//! texture, shadow inputs, read counters), group 1 one material, group 2 the per-vertex
//! coefficients.

mod key;

pub use key::BtfPassKey;

use super::mesh::{MeshPipeline, color_format};
use crate::bind::{self, sampler, storage, texture, uniform};
use crate::material::MaterialGpu;
use crate::{Gpu, Result};
use wgpu::{ShaderStages, TextureSampleType as S, TextureViewDimension as D};

/// WGSL of the pass (with the shared interpolation functions and the per-vertex evaluation).
pub const SOURCE: &str = concat!(
    include_str!("../shaders/interp.wgsl"),
    include_str!("btf_pass.wgsl"),
    include_str!("btf_vertex.wgsl")
);

/// Environment variable naming a WGSL file to build the pass from instead of [`SOURCE`]:
/// a knob for timing experiments on the shader (BENCHMARKS.md, issue #5,
/// `benches/shader_variants.py`), never set in normal use.
pub const SHADER_OVERRIDE_VAR: &str = "BTF_PASS_WGSL";

/// The pass's WGSL: [`SOURCE`], or the file named by [`SHADER_OVERRIDE_VAR`].
fn shader_source() -> Result<std::borrow::Cow<'static, str>> {
    let Some(path) = std::env::var_os(SHADER_OVERRIDE_VAR) else {
        return Ok(SOURCE.into());
    };
    let path = std::path::PathBuf::from(path);
    std::fs::read_to_string(&path)
        .map(Into::into)
        .map_err(|source| crate::Error::Io { path, source })
}

/// What the draws of one frame bind besides each material (group 1).
pub struct MeshDraws<'a> {
    /// Group 0: the frame.
    pub frame: &'a wgpu::BindGroup,
    /// Group 2: the per-vertex coefficients, or a baseline's own group.
    pub group2: Option<&'a wgpu::BindGroup>,
    /// The corner buffer.
    pub corners: &'a wgpu::Buffer,
}

/// The pipeline and its bind-group layouts.
pub struct BtfPass {
    /// The render pipeline.
    pub pipeline: wgpu::RenderPipeline,
    /// Group 0: frame uniform, boundary texture, shadow inputs, counters.
    pub frame_layout: wgpu::BindGroupLayout,
    /// Group 1: one material.
    pub material_layout: wgpu::BindGroupLayout,
    /// Group 2: per-vertex coefficients (per-vertex mode or an environment light).
    pub vertex_layout: Option<wgpu::BindGroupLayout>,
    /// The key it was built for.
    pub key: BtfPassKey,
    /// The shader module (the corner-id pass rasterises with its vertex stage).
    pub(crate) module: wgpu::ShaderModule,
    /// The pipeline layout (groups 0–2), shared with the corner-id pass.
    pub(crate) layout: wgpu::PipelineLayout,
}

impl BtfPass {
    /// Builds the pipeline variant for `key`.
    pub fn new(gpu: &Gpu, key: BtfPassKey) -> Result<BtfPass> {
        let source = shader_source()?;
        let dev = &gpu.device;
        let float = S::Float { filterable: true };
        let both = ShaderStages::VERTEX_FRAGMENT;
        let (frame_layout, material_layout, vertex_layout, layout, module) =
            gpu.scoped("building the BTF pass", || {
                let frame_layout = bind::layout(
                    dev,
                    "btf frame",
                    &[
                        (both, uniform()),
                        (both, texture(float, D::D2)),
                        (both, sampler(wgpu::SamplerBindingType::Filtering)),
                        (both, texture(S::Float { filterable: false }, D::D2Array)),
                        (both, texture(S::Depth, D::D2Array)),
                        (both, sampler(wgpu::SamplerBindingType::Comparison)),
                        (ShaderStages::FRAGMENT, storage(false)),
                    ],
                );
                let material_layout = bind::layout_seen_by(
                    dev,
                    "btf material",
                    both,
                    &[
                        uniform(),
                        texture(float, D::D2Array),
                        texture(float, D::D2Array),
                        sampler(wgpu::SamplerBindingType::Filtering),
                        storage(true),
                    ],
                );
                let vertex_layout = key.uses_vertex_coefficients().then(|| {
                    bind::layout_seen_by(
                        dev,
                        "btf per-vertex",
                        both,
                        &[storage(true), storage(true), storage(true)],
                    )
                });
                let mut groups = vec![Some(&frame_layout), Some(&material_layout)];
                if let Some(v) = &vertex_layout {
                    groups.push(Some(v));
                }
                let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("btf"),
                    bind_group_layouts: &groups,
                    immediate_size: 0,
                });
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("btf_pass.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(source),
                });
                (frame_layout, material_layout, vertex_layout, layout, module)
            })?;
        let pipeline = MeshPipeline {
            label: "btf",
            layout: &layout,
            module: &module,
            vertex: key.vertex_entry(),
            fragment: key.fragment_entry(),
            constants: &key.constants(),
            targets: &[Some(color_format(key.msaa).into())],
            depth_write: true,
            msaa: key.msaa,
        }
        .build(gpu)?;
        Ok(BtfPass { pipeline, frame_layout, material_layout, vertex_layout, key, module, layout })
    }

    /// Records the opaque draws of a frame into `pass` with `pipeline` (this pass's, or a
    /// baseline drawn in its place): groups 0 and 2 and the corners once, then per draw its
    /// material (group 1) and corner range.
    pub fn draw<'a>(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        bindings: &MeshDraws,
        draws: impl IntoIterator<Item = (&'a wgpu::BindGroup, std::ops::Range<u32>)>,
    ) {
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bindings.frame, &[]);
        if let Some(g) = bindings.group2 {
            pass.set_bind_group(2, g, &[]);
        }
        pass.set_vertex_buffer(0, bindings.corners.slice(..));
        for (material, corners) in draws {
            pass.set_bind_group(1, material, &[]);
            pass.draw(corners, 0..1);
        }
    }

    /// Bind group of one material: its sampling uniform, textures and weights.
    pub fn material_bind_group(
        &self,
        gpu: &Gpu,
        mat: &MaterialGpu,
        samplings: &wgpu::Buffer,
        sampler: &wgpu::Sampler,
    ) -> wgpu::BindGroup {
        let eigen = mat.eigen.create_view(&Default::default());
        let mean = mat.mean.create_view(&Default::default());
        bind::group(
            &gpu.device,
            "btf material",
            &self.material_layout,
            &[
                samplings.as_entire_binding(),
                wgpu::BindingResource::TextureView(&eigen),
                wgpu::BindingResource::TextureView(&mean),
                wgpu::BindingResource::Sampler(sampler),
                mat.weights.as_entire_binding(),
            ],
        )
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("btf_pass.wgsl", super::SOURCE).unwrap();
    }
}
