//! `yarn-ref`: the CPU reference renderer for yarns (issue 18, DESIGN §0, §1.5, §2.5, §4.2
//! of `shared/knit/DESIGN.md`) — the ground truth every fast yarn renderer is scored
//! against.
//!
//! - [`geometry`]: explicit fibers as capsule chains in a binned-SAH BVH, robust ray–capsule
//!   intersection, closest- and any-hit queries, the periodic wrap of a patch and a black
//!   backing plane.
//! - [`camera`], [`light`], [`material`], [`integrator`], [`render`]: a path tracer with the
//!   fiber BCSDFs of `yarn::bcsdf` (or a Lambertian surface), NEE with MIS, Russian
//!   roulette, point/directional/environment lights, pinhole and oblique orthographic
//!   cameras, stratified supersampling with per-pixel seeds and variance.
//! - [`volume`]: a ray marcher over the swept yarn density (`yarn::density`) with the
//!   anisotropic extinction, single scattering with a Kajiya–Kay phase and Monte-Carlo
//!   multiple scattering (the lumislice reference of DESIGN §1.5).
//! - [`patch`] and [`btf`]: the periodic knit patch and the yarn BTF of DESIGN §4.2,
//!   written as an ordinary BTF store.
#![forbid(unsafe_code)]

pub mod btf;
pub mod camera;
pub mod error;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod patch;
pub mod render;
pub mod rng;
pub mod volume;

pub use camera::Camera;
pub use error::{Error, Result};
pub use geometry::{FiberScene, Period, SceneOptions};
pub use integrator::{Background, PathSettings, Scene};
pub use light::{EnvLight, Light};
pub use material::Shading;
pub use render::{Image, PixelSampler, RenderSettings, RenderStats, render, render_with};
