//! `fiber_lod` (compute, one invocation per yarn segment): conservative culling against
//! the hull of the segment's Bézier points inflated by the fiber reach (DESIGN §2.3 item
//! 8), the level of detail λ of [W19 eq. 4] from the projected fiber and ply widths at the
//! segment midpoint, `n = max(1, round(λ²·n_max))` fibers per ply (the outermost by `R_i`,
//! [W19 §5]) and `max(2, ceil(λ²·n_sub))` subdivisions (DESIGN §2.3 item 7, the count
//! formula the paper omits). Instances are appended to a list and counted into an indirect
//! draw's `instance_count` with `atomicAdd`; a list that would overflow its capacity is
//! cut there and the overflow counted (never drawn half-written).
//!
//! **Hair flyaways** (ours; [W19 §3.1] converts part of a period into a hair but draws it
//! only through the tessellated fiber): each segment hashes the slots all its fibers pass
//! through with the keys of `yarn::fiber::FiberTable::period_kind` and lists the hairs
//! whose crossing of `r_0` lies on it, as one more instance (bit 31 of the segment word,
//! the slot in bits 25–30), with the segment's subdivisions. LoD thins them (ours): the
//! hairs of the outermost `ceil(φ·n_fib)` fibers of each ply are listed, `φ = max(λ,
//! ω_f/ω_min)` (`ω_min` the narrowest strip, 1 px) — all of them at full detail, with or
//! without core strips — and `fiber_draw` divides a kept hair's coverage `ω_f/ω_min` by the
//! fraction kept, which `φ ≥ ω_f/ω_min` keeps within one pixel's samples (stochastic
//! simplification: the expected fuzz stays). Thinned as the regular fibers (λ², and none
//! once the ply is below ω^LoD and λ = 0) the fuzz would fade with distance: that variant,
//! measured once and not kept, made the 4-px-LoD patch of `tests/gpu/lod.rs` lose 8 % of
//! its radiance. Keeping every hair at every λ (commit d43a08d) was measured first: a
//! cotton segment has ~10 hairs against 2 listed fibers in a far view, and the whole
//! 22 × 22-stitch patch took 3.4× the frame time without hairs (`benches/hairs.rs` at that
//! commit). The segment test is one comparison the two
//! segments of a boundary compute identically, so each hair is listed once; a hair spans
//! more than its segment, so it is culled only when every segment it crosses, inflated by
//! its own reach, is outside the frustum.

use crate::gpu_data::YarnBuffers;
use crate::{Error, Result};
use btf_render::Gpu;

const WGSL: &str = include_str!("../shaders/fiber_lod.wgsl");

/// The pass's WGSL (generator and view in front).
pub fn source() -> String {
    format!("{}\n{}\n{WGSL}", crate::FIBER_GEN_WGSL, crate::FIBER_VIEW_WGSL)
}

/// [W19 eq. 4]: λ from the projected fiber width `w_fiber`, ply width `w_ply` and the
/// threshold `w_lod` (pixels; `w_lod ≤ 0` turns LoD off). 1 when the fiber is at least
/// `w_lod` wide, 0 when the ply is at most, `(w_f/w_L)(w_p − w_L)/(w_p − w_f)` between —
/// continuous at both thresholds (the middle branch is 1 at `w_L = w_f` and 0 at
/// `w_L = w_p`). The WGSL `lod_lambda` is this function.
pub fn lambda(w_fiber: f64, w_ply: f64, w_lod: f64) -> f64 {
    if w_lod <= 0.0 || w_lod <= w_fiber {
        return 1.0;
    }
    if w_ply <= w_lod {
        return 0.0;
    }
    ((w_fiber / w_lod) * (w_ply - w_lod) / (w_ply - w_fiber)).clamp(0.0, 1.0)
}

/// Fibers per ply and subdivisions at λ (DESIGN §2.3 item 7).
pub fn counts(lambda: f64, n_max: u32, n_sub: u32) -> (u32, u32) {
    let l2 = lambda * lambda;
    let n = ((l2 * n_max as f64).round() as u32).clamp(1, n_max.max(1));
    let s = ((l2 * n_sub as f64).ceil() as u32).clamp(2, n_sub.max(2));
    (n, s)
}

/// The indirect draw arguments and counters the pass writes (28 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DrawArgsRaw {
    /// Vertices per instance: `2·(n_sub + 1)`.
    pub vertex_count: u32,
    /// Instances listed.
    pub instance_count: u32,
    /// 0.
    pub first_vertex: u32,
    /// 0.
    pub first_instance: u32,
    /// Instances beyond the capacity (dropped).
    pub overflow: u32,
    /// Segments culled.
    pub culled: u32,
    /// Hair flyaways listed.
    pub hairs: u32,
}

/// The compiled pass.
pub struct LodPass {
    lod: wgpu::ComputePipeline,
    clamp: wgpu::ComputePipeline,
    /// Layout of group 1 (view uniform, instance list, draw arguments).
    pub layout: wgpu::BindGroupLayout,
}

impl LodPass {
    /// Compiles the pass for `data`'s group-0 layout.
    pub fn new(gpu: &Gpu, data: &YarnBuffers) -> Result<Self> {
        let dev = &gpu.device;
        let buf = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fiber_lod"),
            entries: &[
                buf(0, wgpu::BufferBindingType::Uniform),
                buf(1, wgpu::BufferBindingType::Storage { read_only: false }),
                buf(2, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        let src = source();
        let (lod, clamp) = gpu
            .scoped("fiber_lod pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("fiber_lod.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("fiber_lod"),
                    bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                    immediate_size: 0,
                });
                let make = |entry: &str| {
                    dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pl),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                };
                (make("lod"), make("clamp_count"))
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        Ok(LodPass { lod, clamp, layout })
    }

    /// Records the pass: resets `args` (vertex count `2·(n_sub + 1)`), then culls and
    /// lists `segments` segments.
    pub fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        data: &YarnBuffers,
        group1: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        n_sub: u32,
    ) {
        let reset = DrawArgsRaw { vertex_count: 2 * (n_sub + 1), ..Default::default() };
        gpu.queue.write_buffer(args, 0, bytemuck::bytes_of(&reset));
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("fiber_lod"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.lod);
        pass.set_bind_group(0, &data.bind_group, &[]);
        pass.set_bind_group(1, group1, &[]);
        let (x, y) = super::dispatch_size(data.segment_count as u64, 64);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.clamp);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
