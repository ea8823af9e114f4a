//! Bind-group layouts and bind groups built in sequence, so that the order of the Rust
//! entries *is* the WGSL `@binding` order (the idea of Bevy's
//! `BindGroupLayoutEntries::sequential`): no binding number is written by hand, and a list
//! reordered on one side only fails validation instead of binding a buffer to a texture's
//! slot. No equation lives here.

use wgpu::{BindingType, ShaderStages};

/// A layout whose `k`-th entry is `@binding(k)`, each with its own shader stages.
pub(crate) fn layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[(ShaderStages, BindingType)],
) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = entries
        .iter()
        .enumerate()
        .map(|(k, &(visibility, ty))| wgpu::BindGroupLayoutEntry {
            binding: k as u32,
            visibility,
            ty,
            count: None,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// A layout whose `k`-th entry is `@binding(k)`, all seen by `visibility`.
pub(crate) fn layout_seen_by(
    device: &wgpu::Device,
    label: &str,
    visibility: ShaderStages,
    types: &[BindingType],
) -> wgpu::BindGroupLayout {
    let entries: Vec<(ShaderStages, BindingType)> =
        types.iter().map(|&t| (visibility, t)).collect();
    layout(device, label, &entries)
}

/// A bind group whose `k`-th resource is `@binding(k)` of `layout`.
pub(crate) fn group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource<'_>],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .iter()
        .enumerate()
        .map(|(k, r)| wgpu::BindGroupEntry { binding: k as u32, resource: r.clone() })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A uniform buffer.
pub(crate) fn uniform() -> BindingType {
    BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A storage buffer, read-only or read-write.
pub(crate) fn storage(read_only: bool) -> BindingType {
    BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A single-sampled texture.
pub(crate) fn texture(
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
) -> BindingType {
    BindingType::Texture { sample_type, view_dimension, multisampled: false }
}

/// A sampler.
pub(crate) fn sampler(ty: wgpu::SamplerBindingType) -> BindingType {
    BindingType::Sampler(ty)
}
