//! Synthetic data with known ground truth: mesostructure BTF materials, a virtual
//! gonioreflectometer, HDR environments and garment meshes (DESIGN.md §5).
//!
//! - [`material`]: height-field materials rendered into BTF stores (`btf synth material`);
//! - [`noise`], [`vec3`]: deterministic noise and small vector helpers.

pub mod error;
pub mod material;
pub mod noise;
pub mod vec3;

pub use error::{Error, Result};
pub use material::{
    GenerateOptions, GenerateReport, Material, MaterialKind, MaterialParams, MaterialSpec, generate,
};
