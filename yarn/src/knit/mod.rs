//! Knit test data: stitch charts ([`chart`]), stitch meshes on flat periodic patches, under
//! affine test maps and on garment surfaces through their UVs ([`stitch_mesh`],
//! [`uv_lookup`]), the Chen et al. key-point skeleton ([`skeleton`], [C03 §3]) and Keenan
//! Crane's closed-form plain-knit curve as an independent check ([`crane`]), and the
//! knot-based deformation of the yarns with the stitch mesh ([`knot`], [H25 §3, §5]).
//!
//! Data flow: `Chart` → `StitchMesh` (cells with a stitch kind and 3-D corners) →
//! `chen_skeleton` → `YarnSet` (one curve per course) → [`crate::fiber`] or [`crate::io`].

pub mod chart;
pub mod crane;
pub mod knot;
pub mod skeleton;
pub mod stitch_mesh;
pub mod uv_lookup;

pub use chart::{Chart, Stitch};
pub use crane::CraneKnit;
pub use knot::{KnotFrame, KnotModel, KnotParams};
pub use skeleton::{SkeletonParams, chen_skeleton};
pub use stitch_mesh::{StitchCell, StitchMesh, UvLayout};
pub use uv_lookup::{SurfaceMesh, UvLocator};
