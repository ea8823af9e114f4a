//! Baseline 1 of the cost sweep (issue #5): plain texture mapping of one mean texture
//! (view slot 0) on the same mesh at the same resolution — one filtered read per pixel and
//! no lighting, the frame a renderer without a BTF would draw. It shares the BTF pass's
//! vertices, bind groups, targets and sampler (so mipmapping and anisotropy match); the BTF
//! frame's cost (`[S03 eq. 2–5]`) is reported as a ratio to it, not targeted.

use super::{BaselinePass, pipeline};
use crate::passes::btf::BtfPass;
use crate::{Gpu, Result};

/// WGSL of the plain-texture baseline (with the `Samplings` block of `interp.wgsl`).
pub const SOURCE: &str =
    concat!(include_str!("../shaders/interp.wgsl"), include_str!("plain.wgsl"));

/// The plain-texture baseline.
pub fn build(gpu: &Gpu, btf: &BtfPass) -> Result<BaselinePass> {
    Ok(BaselinePass {
        pipeline: pipeline(gpu, btf, SOURCE, "fs_plain", &[], None)?,
        group: None,
        name: "plain texture (baseline)".into(),
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("plain.wgsl", super::SOURCE).unwrap();
    }
}
