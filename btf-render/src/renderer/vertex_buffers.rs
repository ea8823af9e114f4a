//! Group 2 of the BTF pass: the per-vertex coefficients (`[S03 eq. 3–5]` folded per vertex,
//! plus an environment light's `[S03 eq. 11]`), their view slots and, in the separable
//! layout, the irradiance per vertex and light (`crate::per_vertex`). Three storage
//! buffers that live as long as the renderer, rewritten each frame with
//! `queue.write_buffer` and re-created (with the bind group) only when their size changes.

use crate::Gpu;
use crate::bind;

/// The buffers and bind group of group 2.
pub(crate) struct VertexBuffers {
    buffers: [wgpu::Buffer; 3],
    group: wgpu::BindGroup,
}

/// Bytes a storage buffer holding `bytes` needs (never empty, 4-byte multiples).
fn size_of(bytes: &[u8]) -> u64 {
    (bytes.len().max(16) as u64).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
}

impl VertexBuffers {
    /// Group 2 over the buffers.
    pub fn group(&self) -> &wgpu::BindGroup {
        &self.group
    }

    /// Writes `[coefficients, slots, irradiance]` into `slot`'s buffers (creating them, or
    /// re-creating those whose size changed) and returns group 2.
    pub fn write<'a>(
        slot: &'a mut Option<VertexBuffers>,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        contents: [&[u8]; 3],
    ) -> &'a wgpu::BindGroup {
        let fits = slot
            .as_ref()
            .is_some_and(|v| v.buffers.iter().zip(&contents).all(|(b, c)| b.size() == size_of(c)));
        if !fits {
            let labels = ["vertex coefficients", "vertex slots", "vertex irradiance"];
            let buffers = [0, 1, 2].map(|k| {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(labels[k]),
                    size: size_of(contents[k]),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            });
            let resources = [0, 1, 2].map(|k| buffers[k].as_entire_binding());
            let group = bind::group(&gpu.device, "per-vertex", layout, &resources);
            *slot = Some(VertexBuffers { buffers, group });
        }
        let v = slot.as_ref().expect("just made");
        for (b, c) in v.buffers.iter().zip(contents) {
            if !c.is_empty() {
                gpu.queue.write_buffer(b, 0, c);
            }
        }
        &v.group
    }
}
