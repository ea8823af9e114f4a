//! Yarn and knit foundation of the BTF toolkit (issue 18; `shared/knit/DESIGN.md` §0): the
//! data and numerics every knit and yarn renderer stands on. CPU only, no GPU code, no
//! image codecs.
//!
//! | module | what it holds | papers |
//! |---|---|---|
//! | [`params`] | `YarnParams`: the procedural yarn, presets, Zhao-config import, TOML | [Z16], [W19 §2.2, §3.1] |
//! | [`curve`] | `YarnCurve` (uniform Catmull–Rom, rest length coordinate), `YarnSet` | [W19 §5], [C03 §3] |
//! | [`frame`] | surface-anchored frames with a rotation-minimising fallback | DESIGN §0, [W19 §3.1] |
//! | [`fiber`] | `FiberTable`, `FiberModel`, `generate_fibers` → flat f32 `Fibers` | [W19 eq. 1–2], [Z16], [H25 eq. 12–13] |
//! | [`density`] | fiber-centre density n_A and extinction `2 r_f n_A` | [C03 §5.1], DESIGN §1.3 item 10 |
//! | [`bcsdf`] | `Bcsdf` trait; simple, Khungurn R+TT, Huang R+TT+D; ambient tables | [W19 eq. 5–10], [H25 eq. 7] |
//! | [`io`] | BCC read/write, `.pyp` read, Mitsuba curve text and OBJ lines | DESIGN §2.6 |
//! | [`knit`] | charts, stitch meshes, Chen skeleton, Crane's curve | [C03 §3], DESIGN §1.6, §3.6 |
//! | [`quad`], [`special`], [`stats`], [`hash`], [`vec3`] | quadrature, special functions, KS/χ² tests, keyed random numbers, vectors | — |
//!
//! Citation keys: [C03] Chen et al. 2003 (knitwear, lumislice), [W19] Wu & Yuksel 2019
//! (fiber-level cloth), [H25] Huang et al. 2025 (knit deformation), [Z16] Zhao, Luan & Bala
//! 2016 (procedural yarn model). Conventions (shared `DESIGN.md` §3): z-up world, metres,
//! radians, linear radiometry. Dependencies point one way inside the crate: `params`,
//! `curve` ← `frame` ← `fiber` ← `density`; `bcsdf` and `io` stand beside them; `knit`
//! builds `YarnSet`s from charts. Every file the crate writes goes through
//! `btf_core::fs::write_atomic*`.
#![forbid(unsafe_code)]
// Citation keys such as `[Z16]` or `[W19 eq. 2]` are written in square brackets, as in the
// design documents; they are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod bcsdf;
pub mod curve;
pub mod density;
pub mod error;
pub mod fiber;
pub mod frame;
pub mod hash;
pub mod io;
pub mod knit;
pub mod params;
pub mod quad;
pub mod special;
pub mod stats;
pub mod vec3;

pub use bcsdf::{Bcsdf, FiberBcsdf, FiberDir};
pub use curve::{YarnCurve, YarnSet};
pub use density::CrossSectionDensity;
pub use error::{Error, Result};
pub use fiber::{Fibers, GenOptions, generate_fibers};
pub use frame::{CurveFrames, Frame};
pub use params::{Gaussian, YarnParams};
