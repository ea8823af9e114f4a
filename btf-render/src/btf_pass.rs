//! The BTF pass: draws the mesh with the BTF reconstructed per fragment (eq. 2–5) and lit
//! by up to four point/directional lights, each attenuated by the smooth shadow boundary
//! (eq. 6) and a shadow-volume mask or shadow map, plus an environment light whose
//! per-vertex coefficients (eq. 11) are blended across each triangle. See `btf_pass.wgsl`
//! for the formula.
//!
//! Pipeline variants come from [`BtfPassKey`] (evaluation mode, nearest/four blending,
//! MSAA), the blending choices as WGSL override constants so the unused branch is compiled
//! out. Bind groups are laid out in the order of the WGSL `@binding`s.

use crate::Gpu;
use crate::Result;
use crate::scene::Evaluation;

/// WGSL of the pass (with the shared interpolation functions and the per-vertex evaluation).
pub const SOURCE: &str = concat!(
    include_str!("interp.wgsl"),
    include_str!("btf_pass.wgsl"),
    include_str!("btf_vertex.wgsl")
);

/// Format of the linear HDR colour target: `f32` without MSAA, `f16` (multisample-capable
/// everywhere) with it.
pub fn color_format(msaa: u32) -> wgpu::TextureFormat {
    if msaa > 1 { wgpu::TextureFormat::Rgba16Float } else { wgpu::TextureFormat::Rgba32Float }
}
/// Depth format of the pass.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Format of the corner-id targets of [`BtfPass::corner_ids_pipeline`]: vertex indices as
/// `f32` (exact below 2²⁴), a format every adapter can multisample.
pub const CORNER_ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// What selects a pipeline variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BtfPassKey {
    /// Per-vertex (paper) or per-pixel evaluation.
    pub evaluation: Evaluation,
    /// Four-slot view blending (else nearest slot).
    pub view_four: bool,
    /// Four-light interpolation (else nearest light).
    pub light_four: bool,
    /// Samples per pixel.
    pub msaa: u32,
    /// Count texture reads per fragment into the counter buffer (for tests and stats).
    pub count_reads: bool,
    /// The scene has an environment light (per-vertex coefficients even in per-pixel mode).
    pub environment: bool,
    /// Shadow technique whose visibility code the shader contains: 0 none (no shadowing
    /// light), 1 shadow-volume masks, 2 shadow maps (flat and cube).
    pub shadows: u32,
    /// The smooth shadow boundary (eq. 6) is applied to shadowing lights.
    pub smooth_boundary: bool,
    /// Lights of the scene (`≤ MAX_LIGHTS`; fixed for a renderer's life).
    pub lights: u32,
    /// Groups of four components shared by every material drawn, or 0 when they differ
    /// (the shader then reads each material's own count at run time, which is slower).
    pub groups: u32,
    /// The materials' weights are in the packed `f16` layout (`material.rs`; only with
    /// `groups > 0`).
    pub packed: bool,
    /// Keep the full per-vertex layout even where the separable one applies
    /// (`RenderOptions::full_vertex_layout`).
    pub full_vertex_layout: bool,
}

impl BtfPassKey {
    /// Whether the per-vertex coefficients are in the separable layout (`per_vertex.rs`):
    /// per-vertex mode with only point and directional lights (unless the full layout is
    /// asked for).
    pub fn separable(&self) -> bool {
        self.evaluation == Evaluation::PerVertex && !self.environment && !self.full_vertex_layout
    }

    /// Whether the pass reads per-vertex coefficients (group 2).
    pub fn uses_vertex_coefficients(&self) -> bool {
        self.evaluation == Evaluation::PerVertex || self.environment
    }

    /// The pipeline-overridable constants of the shader for this key.
    fn constants(&self) -> [(&'static str, f64); 9] {
        [
            ("VIEW_FOUR", self.view_four as u32 as f64),
            ("LIGHT_FOUR", self.light_four as u32 as f64),
            ("COUNT_READS", self.count_reads as u32 as f64),
            ("SHADOWS", self.shadows as f64),
            ("SMOOTH_BOUNDARY", self.smooth_boundary as u32 as f64),
            ("N_LIGHTS", self.lights as f64),
            ("GROUPS", self.groups as f64),
            ("PACKED", self.packed as u32 as f64),
            ("SEPARABLE", self.separable() as u32 as f64),
        ]
    }

    fn vertex_entry(&self) -> &'static str {
        if self.uses_vertex_coefficients() { "vs_vertex" } else { "vs_main" }
    }

    fn fragment_entry(&self) -> &'static str {
        match (self.evaluation, self.environment) {
            (Evaluation::PerVertex, _) => "fs_vertex",
            (Evaluation::PerPixel, false) => "fs_pixel",
            (Evaluation::PerPixel, true) => "fs_pixel_env",
        }
    }
}

/// One corner of a triangle (the mesh is drawn unindexed so that each corner knows its
/// triangle's three vertices for per-vertex blending).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CornerVertex {
    /// Position (world).
    pub position: [f32; 3],
    /// Vertex normal.
    pub normal: [f32; 3],
    /// Tangent `T` and sign `s` (`B = s · N × T`).
    pub tangent: [f32; 4],
    /// OBJ texture coordinates.
    pub uv: [f32; 2],
    /// The triangle's three vertex indices.
    pub tri: [u32; 3],
    /// Which corner this is (0, 1, 2).
    pub corner: u32,
}

/// Vertex attributes of [`CornerVertex`], in `@location` order.
const CORNER_ATTRS: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2, 4 => Uint32x3, 5 => Uint32];

/// The one vertex buffer every mesh pass reads: the merged mesh's [`CornerVertex`]es.
pub fn corner_buffer_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<CornerVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &CORNER_ATTRS,
    }
}

/// Depth test of the mesh passes (less-than against [`DEPTH_FORMAT`]); `write` is off for
/// blended passes that must not hide what lies behind them.
pub fn mesh_depth_state(write: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// A depth attachment of the mesh passes' depth buffer, cleared to the far plane, stored
/// (`store`: a later pass reads it) or discarded.
pub fn cleared_depth(
    view: &wgpu::TextureView,
    store: bool,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: if store { wgpu::StoreOp::Store } else { wgpu::StoreOp::Discard },
        }),
        stencil_ops: None,
    }
}

/// GPU mirror of one light (`LightRaw` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightRaw {
    /// Position (`w = 1`) or direction towards the light (`w = 0`).
    pub pos: [f32; 4],
    /// RGB power; `w`: 0 unshadowed, 1 volume mask, 2 shadow map.
    pub color: [f32; 4],
    /// Mask/map layer, map texel size, depth bias.
    pub shadow: [f32; 4],
    /// World → light clip space (shadow maps).
    pub view_proj: [[f32; 4]; 4],
}

/// GPU mirror of the per-frame uniform (`FrameRaw` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameRaw {
    /// World → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Eye position; `w = 1` perspective, 0 orthographic.
    pub eye: [f32; 4],
    /// Direction towards the camera (orthographic).
    pub to_camera: [f32; 4],
    /// Number of lights, smooth boundary on.
    pub info: [u32; 4],
    /// `α` in radians.
    pub terminator: [f32; 4],
    /// The lights.
    pub lights: [LightRaw; crate::scene::MAX_LIGHTS],
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
    /// The shader module and pipeline layout (for [`BtfPass::corner_ids_pipeline`]).
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
}

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

fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    let visibility = wgpu::ShaderStages::VERTEX_FRAGMENT;
    wgpu::BindGroupLayoutEntry { binding, visibility, ty, count: None }
}

fn tex(sample_type: wgpu::TextureSampleType, dim: wgpu::TextureViewDimension) -> wgpu::BindingType {
    wgpu::BindingType::Texture { sample_type, view_dimension: dim, multisampled: false }
}

fn buffer(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None }
}

/// A storage-buffer binding type (read-only or read-write).
pub fn storage(read_only: bool) -> wgpu::BindingType {
    buffer(wgpu::BufferBindingType::Storage { read_only })
}

impl BtfPass {
    /// Builds the pipeline variant for `key`.
    pub fn new(gpu: &Gpu, key: BtfPassKey) -> Result<BtfPass> {
        use wgpu::{BindingType as B, TextureSampleType as S, TextureViewDimension as D};
        let source = shader_source()?;
        let dev = &gpu.device;
        let float = S::Float { filterable: true };
        gpu.scoped("building the BTF pass", || {
            let frame_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("btf frame"),
                entries: &[
                    entry(0, buffer(wgpu::BufferBindingType::Uniform)),
                    entry(1, tex(float, D::D2)),
                    entry(2, B::Sampler(wgpu::SamplerBindingType::Filtering)),
                    entry(3, tex(S::Float { filterable: false }, D::D2Array)),
                    entry(4, tex(S::Depth, D::D2Array)),
                    entry(5, B::Sampler(wgpu::SamplerBindingType::Comparison)),
                    wgpu::BindGroupLayoutEntry {
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ..entry(6, storage(false))
                    },
                ],
            });
            let material_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("btf material"),
                entries: &[
                    entry(0, buffer(wgpu::BufferBindingType::Uniform)),
                    entry(1, tex(float, D::D2Array)),
                    entry(2, tex(float, D::D2Array)),
                    entry(3, B::Sampler(wgpu::SamplerBindingType::Filtering)),
                    entry(4, storage(true)),
                ],
            });
            let vertex_layout = key.uses_vertex_coefficients().then(|| {
                dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("btf per-vertex"),
                    entries: &[
                        entry(0, storage(true)),
                        entry(1, storage(true)),
                        entry(2, storage(true)),
                    ],
                })
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
            let constants = key.constants();
            let options = wgpu::PipelineCompilationOptions {
                constants: &constants,
                zero_initialize_workgroup_memory: true,
            };
            let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("btf"),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(key.vertex_entry()),
                    compilation_options: options.clone(),
                    buffers: &[Some(corner_buffer_layout())],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(mesh_depth_state(true)),
                multisample: wgpu::MultisampleState { count: key.msaa, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(key.fragment_entry()),
                    compilation_options: options,
                    targets: &[Some(color_format(key.msaa).into())],
                }),
                multiview_mask: None,
                cache: None,
            });
            BtfPass { pipeline, frame_layout, material_layout, vertex_layout, key, module, layout }
        })
    }

    /// A pipeline that rasterises exactly as [`BtfPass::pipeline`] does — the same module,
    /// vertex entry point, constants, layout, depth test and sample count — but writes, per
    /// sample, the three vertex indices of the triangle in front (as `f32`, one
    /// [`CORNER_ID_FORMAT`] target each): which vertices a frame of this camera reads.
    pub fn corner_ids_pipeline(&self, gpu: &Gpu) -> Result<wgpu::RenderPipeline> {
        let constants = self.key.constants();
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            zero_initialize_workgroup_memory: true,
        };
        let target = Some(wgpu::ColorTargetState::from(CORNER_ID_FORMAT));
        gpu.scoped("building the corner-id pass", || {
            gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("corner ids"),
                layout: Some(&self.layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some(self.key.vertex_entry()),
                    compilation_options: options.clone(),
                    buffers: &[Some(corner_buffer_layout())],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(mesh_depth_state(true)),
                multisample: wgpu::MultisampleState { count: self.key.msaa, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some("fs_corner_ids"),
                    compilation_options: options,
                    targets: &[target.clone(), target.clone(), target],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }

    /// Bind group of one material: its sampling uniform, textures and weights.
    pub fn material_bind_group(
        &self,
        gpu: &Gpu,
        mat: &crate::material::MaterialGpu,
        samplings: &wgpu::Buffer,
        sampler: &wgpu::Sampler,
    ) -> wgpu::BindGroup {
        let eigen = mat.eigen.create_view(&Default::default());
        let mean = mat.mean.create_view(&Default::default());
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("btf material"),
            layout: &self.material_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: samplings.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&eigen),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&mean),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
                wgpu::BindGroupEntry { binding: 4, resource: mat.weights.as_entire_binding() },
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("btf_pass.wgsl", super::SOURCE).unwrap();
        assert_eq!(std::mem::size_of::<super::FrameRaw>(), 64 + 4 * 16 + 4 * (48 + 64));
    }
}
