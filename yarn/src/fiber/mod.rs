//! The procedural fiber model of [Z16] as [W19 §3.1] places it around a yarn curve, and the
//! explicit fibers the reference renderer traces.
//!
//! - [`table`]: the per-yarn `FiberTable` (`R_i` sampled from p(R) by rejection from the
//!   disk as [Z16] does, `θ_i`, an independent migration phase, sorted by `R_i` so the inner
//!   fibers are core) and the per-period types migration / loop / hair (DESIGN §2.3 items
//!   2–4, 6).
//! - [`model`]: `FiberModel`, the generator of one yarn: yarn centre + ply displacement
//!   [W19 §3.1] + elliptical fiber displacement with migration [W19 eq. 1–2], using the
//!   length coordinate `z` (`θ_ply = 2πz/α_ply`, `θ_fib = 2πz/α`); loops; hair flyaways
//!   [Z16], [H25 eq. 12–13]; and `EffectiveTwist`, the pitch rounding that makes closed and
//!   periodic curves carry whole turns.
//! - [`generate`]: `generate_fibers(&YarnSet, &[YarnParams], &GenOptions) -> Fibers`, flat
//!   f32 arrays for a capsule BVH.

pub mod generate;
pub mod model;
pub mod table;

pub use generate::{FiberKind, Fibers, GenOptions, generate_fibers};
pub use model::{EffectiveTwist, FiberModel, YarnPoint};
pub use table::{FiberRecord, FiberTable, HairShape, PeriodKind};

#[cfg(test)]
mod tests;
