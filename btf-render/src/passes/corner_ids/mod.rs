//! The corner-id pass (was `camera_sides.rs`): which vertices a fixed camera's frames read,
//! found by rasterising the mesh as the BTF pass does — so that an environment light
//! computes visibility maps (`[S03 §5.2]`) and gathers `g` (`[S03 eq. 10]`) only for the
//! vertex sides the camera shows.
//!
//! A fragment's colour under an environment light blends the per-vertex reconstructions of
//! its triangle's three vertices (`[S03 eq. 11]` per vertex, blended barycentrically as in
//! `[S03 §4.2]`), and each vertex contributes the side facing the camera (the frame
//! `btf_light::env_coefficients` picks). So a frame of this camera reads exactly the
//! vertices of the triangles that win the depth test at some sample. The corner-id pass
//! draws the same corners with the BTF pass's shader module, vertex stage, constants,
//! layout, depth test and sample count, and writes, per sample, the front triangle's three
//! vertex indices (`fs_corner_ids`); a compute pass (`mark.wgsl`) marks them. Every vertex that
//! reaches a sample is marked; a vertex hidden at every sample is not, and its weights are
//! never read.

use crate::bind::{self, storage};
use crate::passes::btf::BtfPass;
use crate::passes::mesh::{DEPTH_FORMAT, MeshPipeline, cleared_depth};
use crate::{Error, Gpu, Result};
use wgpu::util::DeviceExt;

/// WGSL of the marking pass.
pub const MARK_SOURCE: &str = include_str!("mark.wgsl");

/// Format of the corner-id targets: vertex indices as `f32` (exact below 2²⁴), a format
/// every adapter can multisample.
pub const CORNER_ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// Vertex indices the `f32` targets hold exactly.
pub const MAX_VERTICES: usize = 1 << 24;

/// What the corner-id pass draws.
pub struct CornerDraws<'a> {
    /// The BTF pass (its module, layout and key).
    pub btf: &'a BtfPass,
    /// The corner buffer of the BTF pass.
    pub corners: &'a wgpu::Buffer,
    /// Group 0 of the BTF pass (its frame uniform must hold this camera).
    pub frame_group: &'a wgpu::BindGroup,
    /// Group 1 per draw: `(material bind group, first corner, corners)`.
    pub draws: Vec<(&'a wgpu::BindGroup, u32, u32)>,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Frame size.
    pub width: u32,
    /// Frame height.
    pub height: u32,
}

/// `seen[v]`: vertex `v` belongs to a triangle that is in front at some sample of the frame.
pub fn seen_vertices(gpu: &Gpu, d: &CornerDraws) -> Result<Vec<bool>> {
    if d.vertices >= MAX_VERTICES {
        return Err(Error::Unsupported(format!(
            "{} vertices: the corner-id pass holds indices below {MAX_VERTICES}",
            d.vertices
        )));
    }
    let samples = d.btf.key.msaa;
    let dev = &gpu.device;
    let pipeline = corner_ids_pipeline(gpu, d.btf)?;
    let target =
        |format, usage| gpu.target("corner ids", (d.width, d.height), samples, format, usage);
    let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let ids: Vec<wgpu::Texture> = (0..3)
        .map(|_| target(CORNER_ID_FORMAT, att | wgpu::TextureUsages::TEXTURE_BINDING))
        .collect();
    let views: Vec<wgpu::TextureView> =
        ids.iter().map(|t| t.create_view(&Default::default())).collect();
    let depth = target(DEPTH_FORMAT, att);
    let depth_view = depth.create_view(&Default::default());
    // Group 2 of the vertex stage: the slots it loads do not move a vertex (zeros suffice).
    let layout = d.btf.vertex_layout.as_ref();
    let zeros = |label, bytes: usize| {
        dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &vec![0u8; bytes.max(16)],
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let (coef, slots) = (zeros("corner-id coef", 16), zeros("corner-id slots", 16 * d.vertices));
    let vertex_group = layout.map(|layout| {
        let resources =
            [coef.as_entire_binding(), slots.as_entire_binding(), coef.as_entire_binding()];
        bind::group(dev, "corner-id per-vertex", layout, &resources)
    });
    let seen_bytes = 4 * d.vertices.max(1) as u64;
    let seen = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("seen vertices"),
        contents: &vec![0u8; seen_bytes as usize],
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let (mark, mark_group) = mark_pass(gpu, samples, &views, &seen)?;
    let read = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("seen vertices readback"),
        size: seen_bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    gpu.scoped("corner-id pass", || {
        let mut enc = dev.create_command_encoder(&Default::default());
        {
            let clear = wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r: -1.0, g: -1.0, b: -1.0, a: 1.0 }),
                store: wgpu::StoreOp::Store,
            };
            let color: Vec<Option<wgpu::RenderPassColorAttachment>> = views
                .iter()
                .map(|view| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: clear,
                    })
                })
                .collect();
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("corner ids"),
                color_attachments: &color,
                depth_stencil_attachment: Some(cleared_depth(&depth_view, false)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, d.frame_group, &[]);
            if let Some(g) = &vertex_group {
                pass.set_bind_group(2, g, &[]);
            }
            pass.set_vertex_buffer(0, d.corners.slice(..));
            for &(group, first, count) in &d.draws {
                pass.set_bind_group(1, group, &[]);
                pass.draw(first..first + count, 0..1);
            }
        }
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&mark);
            pass.set_bind_group(0, &mark_group, &[]);
            pass.dispatch_workgroups(d.width.div_ceil(8), d.height.div_ceil(8), 1);
        }
        enc.copy_buffer_to_buffer(&seen, 0, &read, 0, seen_bytes);
        gpu.queue.submit([enc.finish()]);
    })?;
    let raw = gpu.read_buffer(&read)?;
    let flags: &[u32] = bytemuck::cast_slice(&raw);
    Ok(flags[..d.vertices].iter().map(|&f| f != 0).collect())
}

/// A pipeline that rasterises exactly as the BTF pass does — the same module, vertex entry
/// point, constants, layout, depth test and sample count — but writes, per sample, the three
/// vertex indices of the triangle in front (as `f32`, one [`CORNER_ID_FORMAT`] target each).
fn corner_ids_pipeline(gpu: &Gpu, btf: &BtfPass) -> Result<wgpu::RenderPipeline> {
    let target = Some(wgpu::ColorTargetState::from(CORNER_ID_FORMAT));
    MeshPipeline {
        label: "corner ids",
        layout: &btf.layout,
        module: &btf.module,
        vertex: btf.key.vertex_entry(),
        fragment: "fs_corner_ids",
        constants: &btf.key.constants(),
        targets: &[target.clone(), target.clone(), target],
        depth_write: true,
        msaa: btf.key.msaa,
    }
    .build(gpu)
}

/// The compute pass that marks every vertex index found in the three id targets.
fn mark_pass(
    gpu: &Gpu,
    samples: u32,
    views: &[wgpu::TextureView],
    seen: &wgpu::Buffer,
) -> Result<(wgpu::ComputePipeline, wgpu::BindGroup)> {
    let dev = &gpu.device;
    gpu.scoped("building the vertex-marking pass", || {
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mark.wgsl"),
            source: wgpu::ShaderSource::Wgsl(MARK_SOURCE.into()),
        });
        let ids = wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: samples > 1,
        };
        let bind_layout = bind::layout_seen_by(
            dev,
            "mark seen vertices",
            wgpu::ShaderStages::COMPUTE,
            &[ids, ids, ids, storage(false)],
        );
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mark seen vertices"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let constants = [("SAMPLES", samples as f64)];
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("mark seen vertices"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(if samples > 1 { "mark_multisampled" } else { "mark" }),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: if samples > 1 { &constants } else { &[] },
                zero_initialize_workgroup_memory: true,
            },
            cache: None,
        });
        let mut resources: Vec<wgpu::BindingResource> =
            views.iter().map(wgpu::BindingResource::TextureView).collect();
        resources.push(seen.as_entire_binding());
        let group = bind::group(dev, "mark seen vertices", &bind_layout, &resources);
        (pipeline, group)
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("mark.wgsl", super::MARK_SOURCE).unwrap();
    }
}
