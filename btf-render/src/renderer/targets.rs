//! The render targets and read-back buffers of a frame, made once per frame size and
//! sample count and kept (wgpu's examples make them on resize, not per frame): the MSAA
//! colour target, the depth buffer, the timestamp query set with its resolve and read
//! buffers, the read counters' read buffer, and — only once [`super::Renderer::render`] is
//! used — the renderer's own colour target and its read-back buffer. No equation here.

use crate::Gpu;
use crate::passes::mesh::{DEPTH_FORMAT, color_format};
use crate::timer::MAX_TIMED_PASSES;

/// Timestamp queries of a frame and where they are resolved and read.
pub(crate) struct Timestamps {
    /// Two queries per pass.
    pub query: wgpu::QuerySet,
    /// Resolve target.
    pub resolve: wgpu::Buffer,
    /// Mappable copy.
    pub read: wgpu::Buffer,
}

/// The colour target `render` draws into and its read-back buffer (rows padded to
/// `COPY_BYTES_PER_ROW_ALIGNMENT`).
pub(crate) struct OwnTarget {
    /// `color_format(msaa)`, `width × height`.
    pub texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
    /// Read-back buffer.
    pub readback: wgpu::Buffer,
    /// Bytes per padded row.
    pub padded_row: u32,
}

/// A frame's cached targets.
pub(crate) struct FrameTargets {
    size: (u32, u32),
    msaa: u32,
    /// Multisampled colour target (resolved into the frame's target), with `msaa > 1`.
    pub color_ms: Option<wgpu::TextureView>,
    /// Depth buffer at `msaa` samples.
    pub depth: wgpu::TextureView,
    /// Timestamps, when the adapter has them.
    pub timestamps: Option<Timestamps>,
    /// Mappable copy of the read counters.
    pub counters_read: wgpu::Buffer,
    /// The renderer's own target (first `render`).
    pub own: Option<OwnTarget>,
}

fn buffer(gpu: &Gpu, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

impl FrameTargets {
    /// The targets for `size` at `msaa` samples: `slot`'s when they fit, else new ones.
    pub fn ensure<'a>(
        slot: &'a mut Option<FrameTargets>,
        gpu: &Gpu,
        size: (u32, u32),
        msaa: u32,
    ) -> &'a mut FrameTargets {
        if slot.as_ref().is_none_or(|t| t.size != size || t.msaa != msaa) {
            *slot = Some(FrameTargets::new(gpu, size, msaa));
        }
        slot.as_mut().expect("just made")
    }

    fn new(gpu: &Gpu, size: (u32, u32), msaa: u32) -> FrameTargets {
        let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let view = |t: wgpu::Texture| t.create_view(&Default::default());
        let color_ms = (msaa > 1)
            .then(|| view(gpu.target("btf target (msaa)", size, msaa, color_format(msaa), att)));
        let depth = view(gpu.target("btf depth", size, msaa, DEPTH_FORMAT, att));
        let use_ = wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC;
        let read_use = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ;
        let timestamps = gpu.timestamps.then(|| {
            let bytes = 16 * MAX_TIMED_PASSES as u64;
            Timestamps {
                query: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2 * MAX_TIMED_PASSES,
                }),
                resolve: buffer(gpu, "timestamps", bytes, use_),
                read: buffer(gpu, "timestamps readback", bytes, read_use),
            }
        });
        FrameTargets {
            size,
            msaa,
            color_ms,
            depth,
            timestamps,
            counters_read: buffer(gpu, "read counters readback", 16, read_use),
            own: None,
        }
    }

    /// The renderer's own colour target and read-back buffer, made on first use.
    pub fn own(&mut self, gpu: &Gpu) -> &OwnTarget {
        let (size, msaa) = (self.size, self.msaa);
        self.own.get_or_insert_with(|| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST;
            let texture = gpu.target("btf target", size, 1, color_format(msaa), usage);
            let view = texture.create_view(&Default::default());
            let texel = color_format(msaa).block_copy_size(None).expect("a colour format");
            let padded_row = (size.0 * texel).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let readback = buffer(
                gpu,
                "frame readback",
                padded_row as u64 * size.1 as u64,
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            );
            OwnTarget { texture, view, readback, padded_row }
        })
    }
}
