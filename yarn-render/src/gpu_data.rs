//! `YarnBuffers`: the records of [`crate::PackedYarns`] in read-only storage buffers, and
//! bind group 0 that every fiber pass (`shaders/fiber_gen.wgsl`) reads them through.

use crate::pack::PackedYarns;
use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;

/// The packed yarns on the GPU.
pub struct YarnBuffers {
    /// Layout of group 0 (five read-only storage buffers, visible to every stage).
    pub layout: wgpu::BindGroupLayout,
    /// Group 0.
    pub bind_group: wgpu::BindGroup,
    /// Segments on the GPU (the fiber passes' unit of work).
    pub segment_count: u32,
    /// GPU bytes of the five buffers.
    pub bytes: u64,
    _buffers: Vec<wgpu::Buffer>,
}

/// The layout of group 0.
pub fn layout(dev: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE
            | wgpu::ShaderStages::VERTEX
            | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("yarn data"),
        entries: &[entry(0), entry(1), entry(2), entry(3), entry(4)],
    })
}

impl YarnBuffers {
    /// Uploads `packed`. An empty set still gets (one-record) buffers, so passes bind.
    pub fn new(gpu: &Gpu, packed: &PackedYarns) -> Result<Self> {
        let dev = &gpu.device;
        let max = dev.limits().max_storage_buffer_binding_size;
        let mut bytes = 0;
        let mut buffers = Vec::new();
        let mut make = |label: &str, data: &[u8], record: usize| -> Result<()> {
            let padded;
            let data = if data.is_empty() {
                padded = vec![0u8; record];
                &padded[..]
            } else {
                data
            };
            if data.len() as u64 > max {
                return Err(Error::Limit(format!(
                    "the yarns' {label} take {} bytes, above this adapter's storage-buffer \
                     binding limit of {max} bytes; render fewer yarn segments at once",
                    data.len()
                )));
            }
            bytes += data.len() as u64;
            buffers.push(dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: data,
                usage: wgpu::BufferUsages::STORAGE,
            }));
            Ok(())
        };
        make("segments", bytemuck::cast_slice(&packed.segments), 192)?;
        make("curves", bytemuck::cast_slice(&packed.curves), 64)?;
        make("frame samples", bytemuck::cast_slice(&packed.samples), 48)?;
        make("fiber tables", bytemuck::cast_slice(&packed.fibers), 16)?;
        make(
            "yarn params",
            bytemuck::cast_slice(&packed.params),
            size_of::<crate::pack::ParamsRaw>(),
        )?;
        let layout = layout(dev);
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bind_group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("yarn data"),
            layout: &layout,
            entries: &entries,
        });
        Ok(YarnBuffers {
            layout,
            bind_group,
            segment_count: packed.segments.len() as u32,
            bytes,
            _buffers: buffers,
        })
    }
}
