//! `fiber_expand` (compute): every instance `(segment, ply << 16 | fiber)` of a list
//! evaluated at `n_sub + 1` uniform parameters of its segment by the WGSL generator
//! ([W19 eq. 1–2] with the choices of DESIGN §2.3 items 1–3), written as `vec4` points
//! relative to [`crate::PackedYarns::origin`]. DESIGN §2.4 item 4: the compute alternative
//! to vertex pulling, worth it when several passes reuse the geometry; here also the
//! read-back that proves the GPU generator equals `yarn::fiber::FiberModel`.

use crate::gpu_data::YarnBuffers;
use crate::pack::PackedYarns;
use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;

const WGSL: &str = include_str!("../shaders/fiber_expand.wgsl");

/// The pass's WGSL with the generator in front.
pub fn source() -> String {
    crate::with_generator(WGSL)
}

/// Every fiber of every segment of `packed` (all plies, all fibers, core included), as
/// `[segment, ply << 16 | fiber]` instance records.
pub fn all_instances(packed: &PackedYarns) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    for (s, seg) in packed.segments.iter().enumerate() {
        let curve = &packed.curves[seg.ids[0] as usize];
        let p = &packed.params[curve.ids[0] as usize];
        for ply in 0..p.d[0] {
            for f in 0..p.d[1] {
                out.push([s as u32, (ply << 16) | f]);
            }
        }
    }
    out
}

/// The compiled pass.
pub struct ExpandPass {
    /// What to write: 0 fiber points (default); probes for tests: 1 `(N, z − z_1)` of the
    /// yarn frame, 2 `(R, ψ, φ_ply)` of the fiber.
    pub probe: u32,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl ExpandPass {
    /// Compiles the pass for `data`'s group-0 layout.
    pub fn new(gpu: &Gpu, data: &YarnBuffers) -> Result<Self> {
        let dev = &gpu.device;
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fiber_expand"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, false),
            ],
        });
        let src = source();
        let pipeline = gpu.scoped("fiber_expand pipeline", || {
            let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("fiber_expand.wgsl"),
                source: wgpu::ShaderSource::Wgsl(src.into()),
            });
            let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("fiber_expand"),
                bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                immediate_size: 0,
            });
            dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("fiber_expand"),
                layout: Some(&pl),
                module: &module,
                entry_point: Some("expand"),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        Ok(ExpandPass { probe: 0, pipeline, layout })
    }

    /// Expands `instances` at `n_sub ≥ 1` subdivisions; returns the points buffer
    /// (`instances.len() · (n_sub + 1)` `vec4`s, usable as storage and copy source).
    pub fn run(
        &self,
        gpu: &Gpu,
        data: &YarnBuffers,
        instances: &[[u32; 2]],
        n_sub: u32,
        loops: bool,
    ) -> Result<wgpu::Buffer> {
        if n_sub == 0 || n_sub > 1024 {
            return Err(Error::Invalid(format!("fiber_expand: n_sub {n_sub} (must be 1..=1024)")));
        }
        let dev = &gpu.device;
        let per = n_sub as u64 + 1;
        let total = instances.len() as u64 * per;
        let bytes = total.max(1) * 16;
        if bytes > dev.limits().max_storage_buffer_binding_size {
            return Err(Error::Limit(format!(
                "fiber_expand: {} instances × {per} points need {bytes} bytes, above the \
                 storage-buffer binding limit",
                instances.len()
            )));
        }
        let params = [instances.len() as u32, per as u32, loops as u32, self.probe];
        let ubuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("fiber_expand params"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let list: &[[u32; 2]] = if instances.is_empty() { &[[0, 0]] } else { instances };
        let ibuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("fiber instances"),
            contents: bytemuck::cast_slice(list),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let out = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fiber points"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bg = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fiber_expand"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: ubuf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: ibuf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: out.as_entire_binding() },
            ],
        });
        gpu.scoped("fiber_expand", || {
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &data.bind_group, &[]);
                pass.set_bind_group(1, &bg, &[]);
                let (x, y) = super::dispatch_size(total, 64);
                pass.dispatch_workgroups(x, y, 1);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        Ok(out)
    }

    /// Runs [`Self::run`] and reads the points back (xyz relative to the origin, w = 1).
    pub fn read(
        &self,
        gpu: &Gpu,
        data: &YarnBuffers,
        instances: &[[u32; 2]],
        n_sub: u32,
        loops: bool,
    ) -> Result<Vec<[f32; 4]>> {
        let out = self.run(gpu, data, instances, n_sub, loops)?;
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fiber points read-back"),
            size: out.size(),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&out, 0, &staging, 0, out.size());
        gpu.queue.submit([enc.finish()]);
        let raw = gpu.read_buffer(&staging)?;
        let v: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        let n = instances.len() * (n_sub as usize + 1);
        Ok(v[..n].to_vec())
    }
}
