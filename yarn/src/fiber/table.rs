//! `FiberTable`: the cross-section of one yarn, and the random type of every (fiber,
//! period) slot.
//!
//! **Sampling** ([Z16], as its code does): per fiber, a radius `R_i = R_max·√u₁` uniform on
//! the disk, accepted when `u₂ < p(R_i)` (p ≤ 1, so this is exact rejection sampling of the
//! area density p); the sampled radii therefore follow `R·p(R)` (normalised) — the KS test
//! checks that CDF. `θ_i` and the migration phase `φ_i` are independent uniform angles
//! (DESIGN §2.3 item 2: [W19 eq. 2] reuses θ_i, which the fitted parameters do not assume).
//! Each ply's fibers are then sorted by `R_i` (ties by draw order) and the first
//! `round(core_fraction·n)` are core fibers ([W19 §5]: fibers are skipped from the ply
//! centre outwards; DESIGN items 6–7).
//!
//! **Periods** (DESIGN items 3–4). A fiber's slot coordinate is
//! `σ(z) = (s·θ_fib(z) + φ_i − π)/2π` (with s replaced by 1 when s = 0: one slot per turn),
//! so slot boundaries fall on the migration minima `R = ρ_min·R_i`. Each slot is a loop with
//! chance `p_loop`, carries a hair with chance `p_hair`, and is plain migration otherwise.
//! Every random number comes from a hash of `(seed, yarn, ply, fiber, slot, stream)`
//! ([`crate::hash`]), so any slot's type is known without generating the ones before it,
//! and a periodic curve reduces the slot index modulo its slots per period.
//!
//! **Flyaway shapes** ([Z16]'s code): loops peak at `r₁ ~ N(μ, 0.5σ)` from the ply centre,
//! at least 1.05 × the migration peak; hairs draw `z_e, r_0, r_e, p_e ~ N(μ, 0.75σ)` (those
//! σ scales are [Z16]'s), start at a uniform angle and at a uniform point of the slot, and
//! are extended back to the ply centre as [Z16]'s code does (so no hair ends inside the
//! ply). Negative draws of `r_0` are clamped to 0 and `r_e` to at least 5 % of the ply
//! reach, where [Z16] would divide by a non-positive extent.

use crate::hash::KeyRng;
use crate::params::YarnParams;

const STREAM_FIBER: u64 = 1;
const STREAM_SLOT: u64 = 2;

/// One fiber of the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberRecord {
    /// Normalised distance to the ply centre `R_i ∈ [0, R_max]`.
    pub r: f64,
    /// Initial angle `θ_i` (radians).
    pub theta: f64,
    /// Migration phase `φ_i` (radians).
    pub migration_phase: f64,
    /// Inner (core) fiber.
    pub core: bool,
}

/// A hair flyaway of one slot (lengths in metres, angles in radians; `r` measured from the
/// ply centre in the ply's circular space of radius `√(e_N·e_B)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HairShape {
    /// Position of the hair's crossing of `r_0` inside its slot, in `[0, 1)`.
    pub slot_fraction: f64,
    /// Length-coordinate extent `z_e` of the visible part (signed).
    pub ze: f64,
    /// Radius where the visible part starts.
    pub r0: f64,
    /// Radial extent of the visible part.
    pub re: f64,
    /// Angle at `r_0` in the ply frame.
    pub p0: f64,
    /// Angular extent of the visible part.
    pub pe: f64,
}

/// The type of one (fiber, period) slot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodKind {
    /// A plain migration period ([W19 eq. 2]).
    Migration,
    /// A loop: the normalised radius peaks at `peak` (instead of `ρ_max·R_i`).
    Loop {
        /// Normalised peak radius.
        peak: f64,
    },
    /// A migration period that also emits a hair flyaway.
    Hair(HairShape),
}

/// The cross-section of one yarn (see the module documentation).
#[derive(Debug, Clone)]
pub struct FiberTable {
    seed: u64,
    yarn: u64,
    fibers_per_ply: usize,
    /// Fibers of all plies, ply-major, each ply sorted by `R_i`.
    pub fibers: Vec<FiberRecord>,
}

impl FiberTable {
    /// Samples the table of yarn number `yarn` with `seed`.
    pub fn new(params: &YarnParams, seed: u64, yarn: u64) -> Self {
        let n = params.fibers_per_ply as usize;
        let core = (params.core_fraction * n as f64).round() as usize;
        let mut fibers = Vec::with_capacity(n * params.ply_count as usize);
        for ply in 0..params.ply_count as u64 {
            let mut ply_fibers: Vec<(FiberRecord, usize)> = (0..n)
                .map(|i| {
                    let mut rng = KeyRng::new(&[seed, yarn, ply, i as u64, STREAM_FIBER]);
                    // p(0) ≥ 1/2, so acceptance never vanishes; the cap only bounds the loop.
                    let mut r = 0.0;
                    for _ in 0..1_000_000 {
                        r = params.r_max * rng.uniform().sqrt();
                        if rng.uniform() < params.density_p(r) {
                            break;
                        }
                    }
                    let theta = std::f64::consts::TAU * rng.uniform();
                    let migration_phase = std::f64::consts::TAU * rng.uniform();
                    (FiberRecord { r, theta, migration_phase, core: false }, i)
                })
                .collect();
            ply_fibers.sort_by(|a, b| a.0.r.total_cmp(&b.0.r).then(a.1.cmp(&b.1)));
            for (k, (mut f, _)) in ply_fibers.into_iter().enumerate() {
                f.core = k < core;
                fibers.push(f);
            }
        }
        FiberTable { seed, yarn, fibers_per_ply: n, fibers }
    }

    /// The record of fiber `fiber` (sorted index) of ply `ply`.
    #[inline]
    pub fn fiber(&self, ply: usize, fiber: usize) -> &FiberRecord {
        &self.fibers[ply * self.fibers_per_ply + fiber]
    }

    /// Fibers per ply.
    pub fn fibers_per_ply(&self) -> usize {
        self.fibers_per_ply
    }

    /// The type of slot `slot` of fiber `fiber` of ply `ply` (a periodic curve passes the
    /// slot index reduced modulo its slots per period).
    pub fn period_kind(
        &self,
        params: &YarnParams,
        ply: usize,
        fiber: usize,
        slot: i64,
    ) -> PeriodKind {
        let (p_loop, p_hair) = (params.loop_chance(), params.hair_chance());
        if p_loop <= 0.0 && p_hair <= 0.0 {
            return PeriodKind::Migration;
        }
        let keys = [self.seed, self.yarn, ply as u64, fiber as u64, slot as u64, STREAM_SLOT];
        let mut rng = KeyRng::new(&keys);
        let u = rng.uniform();
        let ply_scale = (params.ply_ellipse_n * params.ply_ellipse_b).sqrt();
        if u < p_loop {
            let r1 = params.loop_r1.mean + 0.5 * params.loop_r1.sigma * rng.normal();
            let mig_peak = params.rho_max * self.fiber(ply, fiber).r;
            PeriodKind::Loop { peak: (r1 / ply_scale).max(1.05 * mig_peak) }
        } else if u < p_loop + p_hair {
            let mut g =
                |gauss: crate::params::Gaussian| gauss.mean + 0.75 * gauss.sigma * rng.normal();
            let ze = g(params.hair_ze);
            let r0 = g(params.hair_r0).max(0.0);
            let re = g(params.hair_re).max(0.05 * params.ply_reach());
            let pe = g(params.hair_pe);
            let p0 = std::f64::consts::TAU * rng.uniform();
            let slot_fraction = rng.uniform();
            PeriodKind::Hair(HairShape { slot_fraction, ze, r0, re, p0, pe })
        } else {
            PeriodKind::Migration
        }
    }
}
