//! CPU light transport for BTF-textured garments (Sattler, Sarlette, Klein 2003, §5, and
//! the thin-cloth paper's environment terms): everything about lighting a mesh that needs
//! no GPU. The renderer (`btf-render`) depends on it; batch jobs and reference renderers
//! can use it without linking wgpu.
//!
//! Equation index (`[S03 …]` Sattler et al. 2003, `[TC …]` the thin-cloth paper):
//! - `[S03 eq. 7–9]` — hemicube discretisation, exact solid angles and the shared
//!   pixel → light table: [`hemicube`];
//! - `[S03 §5.2]`, the `V` of eq. 9 — visibility maps (BVH, rasteriser, ray lanes,
//!   cache): [`visibility`];
//! - `L_env` — the environment binned into cube texels: [`env_cube`];
//! - `[S03 eq. 10]` — the gathered radiances `g_i` (reference and fast): [`gather`];
//! - `[S03 eq. 10–12]` — the coefficient matrix `P`, `γ*` and `U = G P`: [`coefficients`];
//! - `[S03 eq. 13]` — eigenweightsets (PCA over rotations): [`eigenweights`];
//! - `[S03 eq. 11]` — per-vertex coefficients `f · ω · γ*` for a camera:
//!   [`env_coefficients`];
//! - the scene's environment light at run time (state, rotation, timings): [`environment`];
//! - `[TC eq. 7–8]` under an environment — per-vertex thin-cloth tables: [`thin_tables`];
//! - meshes (OBJ) and the UV tangent frame: [`mesh`], [`tangent`], [`math`];
//! - which vector code the ray lanes and gathers run (`BTF_SIMD`): [`simd`].

pub mod coefficients;
pub mod eigenweights;
pub mod env_coefficients;
pub mod env_cube;
pub mod environment;
pub mod error;
pub mod gather;
pub mod hemicube;
pub mod math;
pub mod mesh;
pub mod simd;
pub mod tangent;
pub mod thin_tables;
pub mod visibility;

pub use coefficients::CoefficientMatrix;
pub use eigenweights::EigenWeightSets;
pub use env_coefficients::{EnvCoefficients, Slots, ViewInput, shown_frames};
pub use env_cube::EnvCube;
pub use environment::{EnvMesh, EnvironmentParams, SceneEnvironment};
pub use error::{Error, Result};
pub use gather::{GatherInput, Radiances};
pub use hemicube::{Hemicube, HemicubeFrame, LightTable};
pub use visibility::VisibilityMaps;
