//! `yarn-render`: fiber-level yarn rendering on wgpu after Wu & Yuksel 2019 ([W19]; issue
//! #19, `shared/knit/DESIGN.md` §2). Fibers are generated on the GPU from yarn control
//! points every frame and never stored ([W19 §5]); wgpu has no tessellation or geometry
//! shaders, so the paper's isoline tessellation and line-to-strip geometry shader become
//! compute passes, storage buffers, indirect draws and vertex pulling (DESIGN §2.4).
//!
//! | module | what it does | paper |
//! |---|---|---|
//! | [`pack`] | `YarnSet` + `YarnParams` → segment, curve, frame-sample and fiber-table records, phases reduced in f64 | [W19 §3.1, §5] |
//! | [`gpu_data`] | those records in storage buffers, bind group 0 of every fiber pass | — |
//! | [`passes::expand`] | `fiber_expand`: fiber points of listed instances into a buffer | [W19 eq. 1–2], DESIGN §2.4 item 4 |
//!
//! The WGSL generator (`shaders/fiber_gen.wgsl`) mirrors `yarn::fiber::FiberModel`
//! function for function; `tests/gpu.rs` holds the two to 1e-5 of the yarn radius.
//! Citation keys: [W19] Wu & Yuksel 2019, [Z16] Zhao, Luan & Bala 2016.
#![forbid(unsafe_code)]
// Citation keys such as `[W19 eq. 4]` are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod error;
pub mod gpu_data;
pub mod pack;
pub mod passes;

pub use error::{Error, Result};
pub use gpu_data::YarnBuffers;
pub use pack::{PackOptions, PackedYarns};

/// The generator WGSL every fiber pass starts with.
pub const FIBER_GEN_WGSL: &str = include_str!("shaders/fiber_gen.wgsl");

/// `FIBER_GEN_WGSL` followed by a pass's own WGSL.
pub fn with_generator(pass: &str) -> String {
    format!("{FIBER_GEN_WGSL}\n{pass}")
}
