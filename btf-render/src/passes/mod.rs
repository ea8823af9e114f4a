//! The GPU passes, one folder or file per pass with its WGSL beside it. Each builds its
//! pipelines from a description or a key and encodes itself; the renderer only decides
//! which passes a scene needs and in what order they run.
//!
//! - [`mesh`]: the corner vertex, formats, depth test and the mesh pipeline builder every
//!   pass below shares;
//! - [`shaders`]: `interp.wgsl` (`[S03 eq. 3, 5]` on the GPU) and its probe;
//! - [`btf`]: the BTF pass, `[S03 eq. 2–5]` per pixel or per vertex, `[S03 eq. 11]` blended;
//! - [`smooth_boundary`]: the step texture of `[S03 eq. 6]`;
//! - [`shadow`]: shadow volumes, shadow maps and cube maps (`[S03 §4.3]`);
//! - [`thin`]: thin semi-transparent cloth (`[TC eq. 7–9]`), sorted and blended;
//! - [`corner_ids`]: which vertex sides a camera shows (for `[S03 §5.2]` visibility);
//! - [`background`]: the environment map behind the scene;
//! - [`baselines`]: plain texturing and the read bound, the cost sweep's yardsticks.

pub mod background;
pub mod baselines;
pub mod btf;
pub mod corner_ids;
pub mod mesh;
pub mod shaders;
pub mod shadow;
pub mod smooth_boundary;
pub mod thin;
