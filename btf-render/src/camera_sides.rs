//! Which vertices a fixed camera's frames read, found by rasterising the mesh as the BTF
//! pass does — so that an environment light computes visibility maps (Sattler et al. 2003,
//! §5.2) and gathers `g` (eq. 10) only for the vertex sides the camera shows.
//!
//! A fragment's colour under an environment light blends the per-vertex reconstructions of
//! its triangle's three vertices (eq. 11 per vertex, blended barycentrically as in §4.2),
//! and each vertex contributes the side facing the camera (the frame
//! [`crate::envlight::camera_basis`] picks). So a frame of this camera reads exactly the
//! vertices of the triangles that win the depth test at some sample. The corner-id pass
//! ([`crate::btf_pass::BtfPass::corner_ids_pipeline`]) draws the same corners with the same
//! vertex stage, depth test and sample count as the BTF pass and writes, per sample, the
//! front triangle's three vertex indices; a compute pass marks them. Every vertex that
//! reaches a sample is marked; a vertex hidden at every sample is not, and its weights are
//! never read.

use crate::btf_pass::{BtfPass, CORNER_ID_FORMAT, DEPTH_FORMAT};
use crate::{Error, Gpu, Result};
use wgpu::util::DeviceExt;

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
    let pipeline = d.btf.corner_ids_pipeline(gpu)?;
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
        dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("corner-id per-vertex"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: coef.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: slots.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: coef.as_entire_binding() },
            ],
        })
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
                depth_stencil_attachment: Some(crate::btf_pass::cleared_depth(&depth_view, false)),
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

/// The compute pass that marks every vertex index found in the three id targets.
fn mark_pass(
    gpu: &Gpu,
    samples: u32,
    views: &[wgpu::TextureView],
    seen: &wgpu::Buffer,
) -> Result<(wgpu::ComputePipeline, wgpu::BindGroup)> {
    let source = mark_source(samples);
    let dev = &gpu.device;
    gpu.scoped("building the vertex-marking pass", || {
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mark seen vertices"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let tex = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: samples > 1,
            },
            count: None,
        };
        let bind_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mark seen vertices"),
            entries: &[
                tex(0),
                tex(1),
                tex(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: crate::btf_pass::storage(false),
                    count: None,
                },
            ],
        });
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mark seen vertices"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("mark seen vertices"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let mut entries: Vec<wgpu::BindGroupEntry> = views
            .iter()
            .enumerate()
            .map(|(i, v)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            })
            .collect();
        entries.push(wgpu::BindGroupEntry { binding: 3, resource: seen.as_entire_binding() });
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mark seen vertices"),
            layout: &bind_layout,
            entries: &entries,
        });
        (pipeline, group)
    })
}

/// WGSL of the marking pass for `samples` samples per pixel.
fn mark_source(samples: u32) -> String {
    let (ty, load) = if samples > 1 {
        ("texture_multisampled_2d<f32>", "i32(s)")
    } else {
        ("texture_2d<f32>", "0")
    };
    format!(
        r#"
@group(0) @binding(0) var ids_a: {ty};
@group(0) @binding(1) var ids_b: {ty};
@group(0) @binding(2) var ids_c: {ty};
@group(0) @binding(3) var<storage, read_write> seen: array<atomic<u32>>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) g: vec3<u32>) {{
    let size = textureDimensions(ids_a);
    if (g.x >= size.x || g.y >= size.y) {{
        return;
    }}
    let p = vec2<i32>(g.xy);
    for (var s = 0u; s < {samples}u; s = s + 1u) {{
        let a = textureLoad(ids_a, p, {load}).x;
        if (a >= 0.0) {{
            atomicStore(&seen[u32(a)], 1u);
            atomicStore(&seen[u32(textureLoad(ids_b, p, {load}).x)], 1u);
            atomicStore(&seen[u32(textureLoad(ids_c, p, {load}).x)], 1u);
        }}
    }}
}}
"#
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        for samples in [1, 4] {
            crate::gpu::validate_wgsl("mark seen vertices", &super::mark_source(samples)).unwrap();
        }
    }
}
