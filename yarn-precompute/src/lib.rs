//! `yarn-precompute`: the CPU precomputation of Wu & Yuksel's real-time fiber-level cloth
//! [W19] for the GPU fiber renderer (issue 19; `shared/knit/DESIGN.md` §2.3–§2.5). CPU only,
//! no GPU code: every bake ray-casts or ray-marches on the CPU (rayon).
//!
//! | module | what it holds | paper |
//! |---|---|---|
//! | [`core_texture`] | `CoreTexture`: the core fibers of one ply through one twist | [W19 §3.2, eq. 3] |
//! | [`self_shadow`] | `SelfShadowVolume`: optical depth toward the light, per relative angle | [W19 §4.1] |
//! | [`ao`] | `AoTexture` (stratified 2-D Monte Carlo) and `AoCubic` (distance fit) | [W19 §4.2] |
//! | [`cache`] | `Precomputed`: all of the above + the ambient tables, cached on disk | [W19 eq. 8–10] |
//! | [`sigma`] | `SigmaField`: extinction `2 r_f n_A` of the cross-section | DESIGN §2.3 item 10 |
//! | [`settings`] | `BakeSettings`: sizes and their limits | DESIGN §2.4 |
//! | [`srbf`] | `SrbfFit` (NNLS on a Fibonacci set) and the `I_M` table of the strips' environment light | [H25 eq. 14–17] |
//! | [`flyaway`] | `FlyawayBake`: hair-flyaway coverage and direction textures of the strips' overlay | [H25 §4.4, eq. 12–13] |
//! | [`lumislice`] | `Lumislice`: the 32 × 21-direction scattering table per voxel of the yarn cross-section, its LoD pyramid, the yarn shadow table | [C03 §5, eq. 4–11] |
//! | [`strip_bake`] | `StripBake`: coverage, tangent, AO, factorised Ψ^Fiber and ξ of yarn strips | [H25 §4.3, §5.1, eq. 9–11] |
//!
//! Citation keys: [W19] Wu & Yuksel 2019, [C03] Chen et al. 2003, [H25] Huang et al. 2025,
//! [Z16] Zhao, Luan & Bala 2016. Lengths in metres, angles in radians (DESIGN §0).
#![forbid(unsafe_code)]
// Citation keys such as `[W19 eq. 3]` are written in square brackets, as in the design
// documents; they are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod ao;
pub mod cache;
pub mod core_texture;
pub mod error;
pub mod flyaway;
pub mod lumislice;
pub mod self_shadow;
pub mod settings;
pub mod sigma;
pub mod srbf;
pub mod strip_bake;

pub use ao::{AoCubic, AoTexture};
pub use cache::{BakeTimes, Precomputed};
pub use core_texture::{CoreTexcoord, CoreTexel, CoreTexture};
pub use error::{Error, Result};
pub use flyaway::FlyawayBake;
pub use lumislice::{Lumislice, LumisliceSettings, YarnShadowLut};
pub use self_shadow::SelfShadowVolume;
pub use settings::{
    AoSettings, BakeSettings, CoreMigration, CoreSettings, ShadingModel, ShadowSettings,
};
pub use sigma::SigmaField;
pub use srbf::{ImTable, SrbfFit};
pub use strip_bake::{StripBake, StripBakeSettings};
