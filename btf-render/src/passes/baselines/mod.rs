//! The cost baselines of the sweep (issue #5, "what accuracy costs in time"): passes that
//! replace the BTF shader on the same mesh, targets, bind groups and sampler, so the BTF
//! pass's cost (`[S03 eq. 2–5]` per fragment) can be reported as a ratio — plain texture
//! mapping (`plain.rs`) and the read bound (`read_bound.rs`). This module holds their
//! choice and the pipeline builder both use (`plain.wgsl` is the shared vertex stage).

mod plain;
mod read_bound;

pub use plain::build as plain;
pub use read_bound::build as read_bound;

use crate::passes::btf::BtfPass;
use crate::passes::mesh::{MeshPipeline, color_format};
use crate::{Gpu, Result};

/// Which baseline replaces the BTF shader (`RenderOptions::baseline`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Baseline {
    /// Plain texture mapping of view slot 0's mean texture.
    Plain,
    /// The read bound for the BTF pass's measured reads per pixel.
    ReadBound {
        /// Mean texture reads per shaded pixel of the BTF pass being bounded.
        reads_per_pixel: f64,
        /// How the reads are written (the sweep times both and takes the faster).
        form: ReadForm,
    },
}

/// Two ways to write the read bound's loop over a slot's eigentexture layers; which one
/// llvmpipe runs faster depends on the group count, so the cost sweep times both.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadForm {
    /// One read per iteration of a loop whose length is read from a uniform.
    Loop,
    /// Three reads (one group) per iteration of a loop of pipeline-constant length.
    Groups,
}

/// A baseline pipeline ready to replace the BTF pipeline in the frame's colour pass.
pub struct BaselinePass {
    /// Pipeline on the BTF pass's groups 0 and 1 (plus its own group 2, if any).
    pub pipeline: wgpu::RenderPipeline,
    /// Its group 2 (the read bound's counts).
    pub group: Option<wgpu::BindGroup>,
    /// Pass name in the frame statistics.
    pub name: String,
}

/// Builds a baseline pipeline from `source` with fragment entry `fragment` and its override
/// `constants`, on the BTF pass's frame and material layouts and an optional extra group 2.
pub(crate) fn pipeline(
    gpu: &Gpu,
    btf: &BtfPass,
    source: &str,
    fragment: &str,
    constants: &[(&str, f64)],
    extra: Option<&wgpu::BindGroupLayout>,
) -> Result<wgpu::RenderPipeline> {
    let dev = &gpu.device;
    let (layout, module) = gpu.scoped(&format!("building the baseline {fragment}"), || {
        let mut groups = vec![Some(&btf.frame_layout), Some(&btf.material_layout)];
        if let Some(e) = extra {
            groups.push(Some(e));
        }
        let layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(fragment),
            bind_group_layouts: &groups,
            immediate_size: 0,
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(fragment),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        (layout, module)
    })?;
    MeshPipeline {
        label: fragment,
        layout: &layout,
        module: &module,
        vertex: "vs_base",
        fragment,
        constants,
        targets: &[Some(color_format(btf.key.msaa).into())],
        depth_write: true,
        msaa: btf.key.msaa,
    }
    .build(gpu)
}
