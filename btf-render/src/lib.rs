//! wgpu renderer for BTF-textured garments (Sattler, Sarlette, Klein 2003, §4.2–4.3).
//!
//! The BTF is reconstructed in a fragment shader from per-view-slot PCA data
//! (`[S03 eq. 2–5]`): `T = E · Σ_m ω_m [(Σ_n τ_n) μ_{j_m} + Σ_k γ_{k,j_m} B_{k,j_m}]`,
//! either per pixel or, as in the paper, per vertex with the three vertices'
//! reconstructions blended across each triangle. Point and directional lights get the
//! smooth shadow boundary of `[S03 eq. 6]` combined with shadow volumes or shadow maps.
//! The CPU light transport (visibility, gathers, eigenweightsets) is `btf-light`.
//!
//! - [`gpu`], [`bind`]: headless device, error scopes, read-back, WGSL validation; the
//!   sequential bind-group helper;
//! - [`scene`]: the plain TOML scene description; [`camera`], [`uniforms`]: its camera and
//!   lights as the shaders read them;
//! - [`material`]: eigen stores packed for the GPU; [`mips`]: their mip chains;
//! - [`per_vertex`]: the paper's per-vertex coefficients;
//! - [`passes`]: one module per GPU pass with its WGSL;
//! - [`renderer`], [`frame`], [`timer`]: pass selection, output images, `--stats`;
//! - [`cost_sweep`]: components × evaluation × blending against the baselines.

pub(crate) mod bind;
pub mod camera;
pub mod cost_sweep;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod material;
pub mod math;
pub(crate) mod mips;
pub(crate) mod passes;
pub mod per_vertex;
pub mod renderer;
pub mod scene;
pub(crate) mod timer;
pub(crate) mod uniforms;

pub use error::{Error, Result};
pub use frame::{Frame, PassStat, Stats};
pub use gpu::Gpu;
pub use passes::baselines::{Baseline, ReadForm};
pub use passes::btf::BtfPassKey;
pub use renderer::{RenderOptions, Renderer, render_scene};
pub use scene::Scene;
