//! The toolkit's one image layer, shared by every crate that reads or writes pictures.
//!
//! - [`envmap`]: [`EnvMap`], the equirectangular environment map (`L_env` of
//!   `[S03 eq. 9–10]`): its convention, `.hdr`/`.exr` loading, EXR writing, solid angles,
//!   `∫ L dω` and the irradiance it gives a surface;
//! - [`color`]: the sRGB transfer function (encode, decode, the 8-bit table) and the one
//!   green → yellow → red error ramp of every heat map (as the difference images of
//!   `[S03 Fig. 6, 13]`);
//! - [`write`]: linear RGB → EXR, linear RGB → sRGB PNG after exposure, 8-bit PNG — all
//!   through `btf_core::fs::write_atomic` (a file is complete or absent), all refusing
//!   non-finite values with the file and pixel named;
//! - [`exr_limits`]: what an EXR header may claim (channels, block bytes) before any
//!   reader allocates for it;
//! - [`heatmap`]: per-pixel error heat maps between two linear images;
//! - [`flip`]: the ꟻLIP perceptual difference map, LDR and HDR (`[A20]`, `[A21]`),
//!   following NVIDIA's reference implementation;
//! - [`compose`]: images side by side and enlarged, for reports and contact sheets;
//! - [`plot`]: line plots drawn straight into images (axes, ticks, legend, log axes) so
//!   reports need no plotting toolchain or system fonts;
//! - [`text`]: labels in an 8×8 bitmap font at integer scales, for plots and strips.
//!
//! Values are linear inside the toolkit; only PNG output is sRGB-encoded (docs/DESIGN.md §3).
//! No GPU code lives here.

pub mod color;
pub mod compose;
pub mod envmap;
pub mod error;
pub mod exr_limits;
pub mod flip;
pub mod heatmap;
pub mod plot;
pub mod text;
pub mod write;

pub use envmap::EnvMap;
pub use error::{Error, Result};
