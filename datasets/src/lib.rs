//! Synthetic data with known ground truth: mesostructure BTF materials, a virtual
//! gonioreflectometer, HDR environments and garment meshes (DESIGN.md §5).
//!
//! - [`material`]: height-field materials rendered into BTF stores (`btf synth material`);
//! - [`capture`]: the virtual gonioreflectometer (raw images of the sample on its plate);
//! - [`env`]: procedural equirectangular HDR environments (sky, studio, interior);
//! - [`mesh`]: plane, sphere, curtain, simulated drape and garments as OBJ;
//! - [`noise`], [`vec3`]: deterministic noise and small vector helpers.

pub mod capture;
pub mod env;
pub mod error;
pub mod garment;
pub mod material;
pub mod mesh;
pub mod noise;
pub mod sim;
pub mod vec3;

pub use env::{EnvKind, EnvParams, synth_env};
pub use error::{Error, Result};
pub use material::{
    GenerateOptions, GenerateReport, Material, MaterialKind, MaterialParams, MaterialSpec, generate,
};
pub use mesh::{Mesh, MeshKind, Resolution, read_obj, synth_mesh, write_obj, write_obj_material};
