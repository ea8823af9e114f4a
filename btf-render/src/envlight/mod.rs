//! Image-based lighting with macroscopic self-shadowing (Sattler et al. 2003, §5,
//! eq. 7–13).
//!
//! - [`hemicube`]: pixel directions, exact solid angles (sum 2π) and the shared table
//!   "pixel → four nearest measured light directions + weights" (eq. 9, §5.2);
//! - [`bvh`], [`visibility`], `raster`: per-vertex visibility maps — the answer of one ray
//!   per hemicube pixel, found by projecting the BVH-culled mesh onto the hemicube and
//!   confirming each covered pixel with the ray test — cached on disk (§5.2);
//! - [`env_cube`]: the environment map (`btf_image::EnvMap`, `L_env`) binned into cube texels;
//! - [`weights`], `gather`: `g_i` per vertex, `γ*` and the weight vector `U` (eq. 10–12);
//! - [`eigenweights`]: the PCA over environment rotations and `U(δ)` (eq. 13);
//! - [`scene_env`]: an environment light of a scene: state, rotation, per-vertex coefficients;

pub mod bvh;
mod camera_basis;
pub mod eigenweights;
pub mod env_cube;
mod gather;
pub mod hemicube;
mod octets;
mod raster;
mod raster_face;
pub mod scene_env;
pub mod visibility;
pub mod weights;

pub use camera_basis::shown_frames;
pub use eigenweights::EigenWeightSets;
pub use env_cube::EnvCube;
pub use hemicube::{Hemicube, LightTable};
pub use scene_env::{EnvironmentParams, SceneEnvironment};
pub use visibility::{HemicubeFrame, VisibilityMaps};
pub use weights::{CoefficientMatrix, GatherInput, WeightSet};
