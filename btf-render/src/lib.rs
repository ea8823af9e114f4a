//! wgpu renderer for BTF-textured garments (Sattler, Sarlette, Klein 2003, §4.2–4.3).
//!
//! The BTF is reconstructed in a fragment shader from per-view-slot PCA data (eq. 2–5):
//! `T = E · Σ_m ω_m [(Σ_n τ_n) μ_{j_m} + Σ_k γ_{k,j_m} B_{k,j_m}]`, either per pixel or,
//! as in the paper, per vertex with the three vertices' reconstructions blended across each
//! triangle. Point and directional lights get the smooth shadow boundary of eq. 6 combined
//! with shadow volumes or shadow maps.
//!
//! - [`gpu`]: headless device, error scopes, read-back, WGSL validation;
//! - [`mesh`], [`tangent`]: OBJ loading, normals and the UV tangent frame;
//! - [`scene`]: the plain TOML scene description;
//! - [`material`]: eigen stores packed for the GPU;
//! - [`btf_pass`], [`interp`], [`per_vertex`]: the reconstruction shader, its interpolation
//!   weights, and the paper's per-vertex coefficients;
//! - [`terminator`], [`shadow`], [`shadow_volume`], [`shadow_map`], [`shadow_cube`]: eq. 6
//!   and shadows (cube maps for point lights inside the scene);
//! - [`renderer`], [`frame`], [`timer`]: pass selection, output images, `--stats`;
//! - [`mips`]: mip chains of the PCA textures (exact for the linear reconstruction);
//! - [`plain_texture`], [`read_bound`], [`cost_sweep`]: the cost baselines and the sweep of
//!   components × evaluation × blending against them;
//! - [`transmission`]: thin semi-transparent cloth (front-/back-lit, view-dependent alpha);
//! - [`env_background`]: the environment map drawn behind the scene.

pub mod btf_pass;
pub mod camera_sides;
pub mod cost_sweep;
pub mod env_background;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod interp;
pub mod material;
pub mod math;
pub mod mips;
pub mod per_vertex;
pub mod plain_texture;
pub mod read_bound;
pub mod renderer;
pub mod scene;
pub mod shadow;
pub mod shadow_cube;
pub mod shadow_map;
pub mod shadow_volume;
pub mod terminator;
pub mod timer;
pub mod transmission;

pub use error::{Error, Result};
pub use frame::{Frame, PassStat, Stats};
pub use gpu::Gpu;
pub use plain_texture::{Baseline, ReadForm};
pub use renderer::{RenderOptions, Renderer, render_scene};
pub use scene::Scene;
