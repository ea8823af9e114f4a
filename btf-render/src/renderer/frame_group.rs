//! Group 0 of the mesh passes: the frame uniform (camera, lights, `α` of `[S03 eq. 6]`),
//! the smooth boundary's step texture, the shadow inputs (volume masks or maps) and the
//! read counters. The buffers live as long as the renderer and are rewritten each frame
//! with `queue.write_buffer`; the bind group is rebuilt only when the shadow pass is (a
//! light moved).

use crate::Gpu;
use crate::bind;
use crate::passes::btf::BtfPass;
use crate::passes::shadow::{ShadowInputs, Shadowing};
use crate::passes::smooth_boundary;
use crate::uniforms::FrameRaw;

/// The frame uniform, counters and group 0.
pub(crate) struct FrameGroup {
    /// `FrameRaw`, written every frame.
    pub uniform: wgpu::Buffer,
    /// Texture reads and shaded pixels (`RenderOptions::count_reads`), zeroed every frame.
    pub counters: wgpu::Buffer,
    /// Group 0.
    pub group: wgpu::BindGroup,
}

impl FrameGroup {
    /// Buffers and group 0 for `btf`, with the inputs of `shadowing` (placeholders without
    /// one) and a boundary texture blurred by `blur` texels.
    pub fn new(gpu: &Gpu, btf: &BtfPass, shadowing: Option<&Shadowing>, blur: u32) -> FrameGroup {
        let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read counters"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = Self::bind(gpu, btf, &uniform, &counters, shadowing, blur);
        FrameGroup { uniform, counters, group }
    }

    /// Rebuilds group 0 for a new shadow pass.
    pub fn rebind(&mut self, gpu: &Gpu, btf: &BtfPass, shadowing: Option<&Shadowing>, blur: u32) {
        self.group = Self::bind(gpu, btf, &self.uniform, &self.counters, shadowing, blur);
    }

    fn bind(
        gpu: &Gpu,
        btf: &BtfPass,
        uniform: &wgpu::Buffer,
        counters: &wgpu::Buffer,
        shadowing: Option<&Shadowing>,
        blur: u32,
    ) -> wgpu::BindGroup {
        use wgpu::BindingResource::{Sampler, TextureView};
        let shadow = match shadowing {
            Some(s) => s.inputs(gpu),
            None => ShadowInputs::dummy(gpu),
        };
        // 1 KiB placeholder without a shadowing light (never sampled)
        let blur = if shadowing.is_some() { blur } else { 0 };
        let boundary = smooth_boundary::texture(gpu, blur);
        let boundary_view = boundary.create_view(&Default::default());
        let clamp = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear clamp"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        bind::group(
            &gpu.device,
            "btf frame",
            &btf.frame_layout,
            &[
                uniform.as_entire_binding(),
                TextureView(&boundary_view),
                Sampler(&clamp),
                TextureView(&shadow.masks),
                TextureView(&shadow.maps),
                Sampler(&shadow.compare),
                counters.as_entire_binding(),
            ],
        )
    }
}
