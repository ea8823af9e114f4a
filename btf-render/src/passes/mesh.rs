//! What every pass that draws the mesh shares: the corner vertex (the mesh drawn
//! unindexed, each corner knowing its triangle's three vertices for the per-vertex blending
//! of `[S03 §4.2]`), its vertex layouts, the colour and depth formats of a frame, the depth
//! test, and one builder for the mesh pipelines (the BTF pass, the corner-id pass, the thin
//! pass and the baselines differ only in entry points, constants and targets).

use crate::Gpu;
use crate::Result;

/// Format of the linear HDR colour target: `f32` without MSAA, `f16` (multisample-capable
/// everywhere) with it.
pub fn color_format(msaa: u32) -> wgpu::TextureFormat {
    if msaa > 1 { wgpu::TextureFormat::Rgba16Float } else { wgpu::TextureFormat::Rgba32Float }
}

/// Depth format of the mesh passes.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

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

/// The corner buffer read for the position alone (the depth-only passes of the shadows).
pub fn position_only_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<CornerVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRS,
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

/// A render pipeline over the corner buffer: two-sided triangles, the mesh depth test,
/// `msaa` samples, the same override `constants` for both stages.
pub struct MeshPipeline<'a> {
    /// Label (also names the error scope).
    pub label: &'a str,
    /// Pipeline layout.
    pub layout: &'a wgpu::PipelineLayout,
    /// Shader module holding both entry points.
    pub module: &'a wgpu::ShaderModule,
    /// Vertex entry point.
    pub vertex: &'a str,
    /// Fragment entry point.
    pub fragment: &'a str,
    /// Override constants.
    pub constants: &'a [(&'a str, f64)],
    /// Colour targets.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// Write depth (off for blended passes).
    pub depth_write: bool,
    /// Samples per pixel.
    pub msaa: u32,
}

impl MeshPipeline<'_> {
    /// Builds the pipeline inside an error scope named after its label.
    pub fn build(&self, gpu: &Gpu) -> Result<wgpu::RenderPipeline> {
        let options = wgpu::PipelineCompilationOptions {
            constants: self.constants,
            zero_initialize_workgroup_memory: true,
        };
        gpu.scoped(&format!("building the {} pipeline", self.label), || {
            gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(self.label),
                layout: Some(self.layout),
                vertex: wgpu::VertexState {
                    module: self.module,
                    entry_point: Some(self.vertex),
                    compilation_options: options.clone(),
                    buffers: &[Some(corner_buffer_layout())],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(mesh_depth_state(self.depth_write)),
                multisample: wgpu::MultisampleState { count: self.msaa, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module: self.module,
                    entry_point: Some(self.fragment),
                    compilation_options: options,
                    targets: self.targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }
}
