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
//! | [`passes::lod`] | `fiber_lod`: conservative culling, λ, instance list, indirect arguments | [W19 eq. 4], DESIGN §2.3 items 7–8 |
//! | [`passes::draw`] | `fiber_draw`: vertex-pulled camera-facing strips, fiber BCSDF, MSAA | [W19 §5, eq. 5–6], [H25 eq. 7] |
//! | [`passes::shadow`] | `yarn_tube_shadow`: shadow maps of the yarns as tubes | [W19 §4.1] |
//! | [`passes::fiber_shadow`] | fiber shadow maps fitted to the seen part of the yarns | [W19 §4.1] (ours: every fiber casts) |
//! | [`effects`] | self-shadow volume, AO, ambient term: precomputed data packed | [W19 §4, eq. 7–8] |
//! | [`bcsdf`] | `yarn::bcsdf::FiberBcsdf` lobes packed for the shader | [W19 eq. 5–6] |
//! | [`view`] | camera, lights, frustum planes in f64 about the origin | — |
//! | [`btf`] | the yarn BTF of DESIGN §4.2 rendered with fibers (`--method fibers`) | DESIGN §4.2 |
//! | [`renderer`] | `FiberRenderer`: the passes of one frame, stats | [W19 §3.3, §5] |
//! | [`strips`] | `StripRenderer`: fiber-textured yarn strips (bake, Ψ·ξ factors, PCSS) | [H25 §4.3, §5.2, eq. 9–11] |
//! | [`lumislice`] | `LumisliceRenderer`: ray-marched lumislice pieces, centre-line shadow maps (eq. 10), back-to-front "over" | [C03 §5, eq. 9–11] |
//! | [`scene`] | a btf-render scene's `[[yarns]]`: chart on the mesh's UVs, skeleton, pack; drawn into its frame | [C03 §3], [W19 §5] |
//!
//! The WGSL generator (`shaders/fiber_gen.wgsl`) mirrors `yarn::fiber::FiberModel`
//! function for function; `tests/gpu.rs` holds the two to 1e-5 of the yarn radius.
//! Citation keys: [W19] Wu & Yuksel 2019, [Z16] Zhao, Luan & Bala 2016.
#![forbid(unsafe_code)]
// Citation keys such as `[W19 eq. 4]` are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod bcsdf;
pub mod btf;
pub mod effects;
pub mod error;
pub mod gpu_data;
pub mod knot;
pub mod lumislice;
pub mod pack;
pub mod passes;
pub mod renderer;
pub mod scene;
pub mod strips;
pub mod view;

pub use effects::{AoMode, FiberEffects};
pub use error::{Error, Result};
pub use gpu_data::YarnBuffers;
pub use lumislice::{LumisliceRenderSettings, LumisliceRenderer};
pub use pack::{PackOptions, PackedYarns};
pub use renderer::{FiberImage, FiberRenderer, FiberSettings, FiberStats, MAX_SUPERSAMPLE};
pub use strips::{StripRenderer, StripSettings};
pub use view::{FiberCamera, FiberLight};

/// The generator WGSL every fiber pass starts with.
pub const FIBER_GEN_WGSL: &str = include_str!("shaders/fiber_gen.wgsl");

/// The frame's view (camera, LoD settings, lights) the LoD and draw passes share.
pub const FIBER_VIEW_WGSL: &str = include_str!("shaders/fiber_view.wgsl");

/// Every WGSL program of the crate, assembled as the passes compile it: `(name, source)`.
pub fn wgsl_programs() -> Vec<(&'static str, String)> {
    vec![
        ("fiber_expand", passes::expand::source()),
        ("fiber_lod", passes::lod::source()),
        ("fiber_draw", passes::draw::source()),
        ("yarn_tube_shadow", passes::shadow::source()),
        ("strip_regular", strips::source()),
        ("lumislice_march", lumislice::source()),
        ("lumislice_centerline", lumislice::centerline_source()),
        ("knot_solve", knot::source()),
    ]
}

/// `FIBER_GEN_WGSL` followed by a pass's own WGSL.
pub fn with_generator(pass: &str) -> String {
    format!("{FIBER_GEN_WGSL}\n{pass}")
}
