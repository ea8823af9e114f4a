//! Baseline 2 of the cost sweep (issue #5): the read bound — a shader making the same
//! number and kind of texture reads per pixel as the BTF pass (`[S03 eq. 2–5]`: one mean
//! read and `3⌈c/4⌉` packed eigentexture reads per view slot, `material/pack.rs`) and
//! merely summing them.
//! The target is the BTF pass within 1.5× of it: everything the reconstruction does beyond
//! its own reads (interpolation weights, the weight buffer, lighting) must be cheap.
//!
//! The BTF pass's read count varies per pixel (1–4 slots; per-vertex blending the union of
//! three vertices' slots), so the bound takes the count measured by the BTF pass's read
//! counters (`RenderOptions::count_reads`) as whole slots: with `s = n / (1 + 3G)` slots on
//! average, `⌊s⌋` slots everywhere and one more on a hashed fraction `s − ⌊s⌋` of the pixels,
//! the same total. Its loops hold no branch and no integer division: lavapipe executes both
//! sides of every branch, so an earlier form (one read per iteration, mean or eigentexture
//! by an `if`) executed two samples per read and timed 1.25–2× its reads.

use super::{BaselinePass, ReadForm, pipeline};
use crate::bind::{self, uniform};
use crate::passes::btf::BtfPass;
use crate::{Error, Gpu, Result};
use wgpu::util::DeviceExt;

/// WGSL of the read bound (shares the plain baseline's vertex stage).
pub const SOURCE: &str = concat!(
    include_str!("../shaders/interp.wgsl"),
    include_str!("plain.wgsl"),
    include_str!("read_bound.wgsl")
);

/// GPU mirror of `ReadBound` in `read_bound.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ReadBoundRaw {
    counts: [u32; 4],
    frac: [f32; 4],
}

/// The read-bound baseline for `reads_per_pixel` reads, on a material of `groups` groups of
/// four components (`3·groups` eigentexture layers per slot) and `views` slots, its reads
/// written in `form`.
pub fn build(
    gpu: &Gpu,
    btf: &BtfPass,
    reads_per_pixel: f64,
    groups: usize,
    views: usize,
    form: ReadForm,
) -> Result<BaselinePass> {
    if !(reads_per_pixel.is_finite() && (0.0..=4096.0).contains(&reads_per_pixel)) {
        return Err(Error::Invalid(format!(
            "read bound: {reads_per_pixel} reads per pixel (expected 0..=4096)"
        )));
    }
    let layout =
        bind::layout_seen_by(&gpu.device, "read bound", wgpu::ShaderStages::FRAGMENT, &[uniform()]);
    let per_slot = 1 + 3 * groups as u32;
    let slots = reads_per_pixel / f64::from(per_slot);
    let floor = slots.floor();
    let raw = ReadBoundRaw {
        counts: [floor as u32, per_slot, (3 * groups * views).max(1) as u32, views.max(1) as u32],
        frac: [(slots - floor) as f32, 0.0, 0.0, 0.0],
    };
    let buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("read bound"),
        contents: bytemuck::bytes_of(&raw),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = bind::group(&gpu.device, "read bound", &layout, &[buffer.as_entire_binding()]);
    Ok(BaselinePass {
        pipeline: pipeline(
            gpu,
            btf,
            SOURCE,
            match form {
                ReadForm::Loop => "fs_read_bound",
                ReadForm::Groups => "fs_read_bound_groups",
            },
            &[("GROUPS", groups as f64)],
            Some(&layout),
        )?,
        group: Some(group),
        name: format!("read bound (baseline, {reads_per_pixel:.1} reads, {form:?})"),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("read_bound.wgsl", super::SOURCE).unwrap();
    }
}
