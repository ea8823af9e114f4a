//! `FiberModel`: where fiber `i` of ply `j` of one yarn is, at length coordinate `z`.
//!
//! With the yarn frame `(T, N, B)` at the curve point ([`crate::frame`]):
//! - ply centre [W19 §3.1]: `Δc_ply = d·(cos φ_j N + sin φ_j B)`, `φ_j = 2πj/n_ply + θ_ply`,
//!   `θ_ply = 2πz/α_ply` (DESIGN §2.3 item 1), `d` = `ply_center_distance`;
//! - ply frame: `N̂_ply = cos φ_j N + sin φ_j B` (defined even when `d = 0`, where [W19]'s
//!   `Δc_ply/‖Δc_ply‖` is 0/0), `B̂_ply = T × N̂_ply`;
//! - fiber [W19 eq. 1–2]: `Δc_i = R(z)·(cos ψ e_N N̂_ply + sin ψ e_B B̂_ply)`,
//!   `ψ = θ_i + θ_fib`, `θ_fib = 2πz/α`, and the migration
//!   `R(z) = R_i[ρ_min + (ρ_max − ρ_min)(cos(s·θ_fib + φ_i) + 1)/2]`; in a loop slot
//!   `R(z) += (peak − ρ_max R_i)·sin²(πt)`, `t` the position in the slot — for s > 0 exactly
//!   eq. 2 with `ρ_max` replaced by the loop's `R_max^loop` ([W19 §2.2]), and a smooth bump
//!   when s = 0;
//! - hair [Z16], [H25 eq. 12–13]: from the ply centre outwards,
//!   `r(t) = (r_0 + r_e)(1 − (1 − t)^α)`, angle and `z` linear in `t` (α = 1 is [Z16]'s
//!   straight hair extended back to the centre), mapped through the ply ellipse as the
//!   regular fibers are (`r/√(e_N e_B)` is the normalised radius).
//!
//! **Closed and periodic curves** (our choice; the papers have no periodic yarns). A closed
//! curve of rest length `L` per wrap must carry whole turns or its fibers would not join:
//! [`EffectiveTwist::for_curve`] rounds `L/|α_ply|` and `L/|α|` to the nearest integers
//! (at least 1) and `s·L/|α|` (migration periods per wrap) likewise, and sets
//! `α' = ±L/m`, `s' = m_s/m_f`. The relative change of a pitch is at most `|α|/(2L)`
//! (≈ 3 % for a 3 mm pitch on a 5 cm course); [`EffectiveTwist::max_relative_change`]
//! reports it. Slot indices are reduced modulo the slots per wrap, so flyaways repeat too.

use super::table::{FiberTable, PeriodKind};
use crate::curve::YarnCurve;
use crate::frame::{CurveFrames, Frame};
use crate::params::YarnParams;
use crate::vec3::{self, V3};
use std::f64::consts::{PI, TAU};

/// The pitches a curve actually uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectiveTwist {
    /// Ply pitch α_ply' (signed, metres per turn).
    pub ply_pitch: f64,
    /// Fiber pitch α' (signed).
    pub fiber_pitch: f64,
    /// Migration rate s'.
    pub migration_rate: f64,
    /// Fiber slots per wrap of a closed curve (`None` on open curves).
    pub slots_per_wrap: Option<u64>,
}

impl EffectiveTwist {
    /// The params' own pitches (open curves).
    pub fn nominal(p: &YarnParams) -> Self {
        EffectiveTwist {
            ply_pitch: p.ply_pitch,
            fiber_pitch: p.fiber_pitch,
            migration_rate: p.migration_rate,
            slots_per_wrap: None,
        }
    }

    /// Whole turns per wrap on a closed curve; the nominal pitches on an open one.
    pub fn for_curve(p: &YarnParams, curve: &YarnCurve) -> Self {
        let l = curve.length_wrap;
        if !curve.closed || l <= 0.0 {
            return Self::nominal(p);
        }
        let turns = |pitch: f64| (l / pitch.abs()).round().max(1.0);
        let m_ply = turns(p.ply_pitch);
        let m_fib = turns(p.fiber_pitch);
        let (s, slots) = if p.migration_rate > 0.0 {
            let m_s = (p.migration_rate * m_fib).round().max(1.0);
            (m_s / m_fib, m_s)
        } else {
            (0.0, m_fib)
        };
        EffectiveTwist {
            ply_pitch: p.ply_pitch.signum() * l / m_ply,
            fiber_pitch: p.fiber_pitch.signum() * l / m_fib,
            migration_rate: s,
            slots_per_wrap: Some(slots as u64),
        }
    }

    /// Largest relative change of α_ply, α or s against the params.
    pub fn max_relative_change(&self, p: &YarnParams) -> f64 {
        let rel = |a: f64, b: f64| if b != 0.0 { (a / b - 1.0).abs() } else { a.abs() };
        rel(self.ply_pitch, p.ply_pitch)
            .max(rel(self.fiber_pitch, p.fiber_pitch))
            .max(rel(self.migration_rate, p.migration_rate))
    }
}

/// The yarn centre, its frame and its length coordinate at one curve parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YarnPoint {
    /// Centre-line point (metres).
    pub position: V3,
    /// Frame (T, N, B).
    pub frame: Frame,
    /// Length coordinate z (metres).
    pub z: f64,
}

impl YarnPoint {
    /// The point of `curve` at parameter `u`.
    pub fn at(curve: &YarnCurve, frames: &CurveFrames, u: f64) -> Self {
        YarnPoint {
            position: curve.point(u),
            frame: frames.frame_at(curve, u),
            z: curve.length_coord(u),
        }
    }

    /// `position + a·N + b·B`.
    #[inline]
    pub fn offset(&self, ab: [f64; 2]) -> V3 {
        let f = &self.frame;
        vec3::add_scaled(vec3::add_scaled(self.position, f.n, ab[0]), f.b, ab[1])
    }
}

/// The fiber generator of one yarn (see the module documentation).
#[derive(Debug, Clone, Copy)]
pub struct FiberModel<'a> {
    /// The yarn description.
    pub params: &'a YarnParams,
    /// The yarn's fiber table.
    pub table: &'a FiberTable,
    /// The pitches in use.
    pub twist: EffectiveTwist,
}

impl FiberModel<'_> {
    /// `φ_j` of ply `ply` at `z`.
    #[inline]
    pub fn ply_angle(&self, z: f64, ply: usize) -> f64 {
        TAU * ply as f64 / self.params.ply_count as f64 + TAU * z / self.twist.ply_pitch
    }

    /// `θ_fib(z) = 2πz/α'`.
    #[inline]
    pub fn fiber_turn(&self, z: f64) -> f64 {
        TAU * z / self.twist.fiber_pitch
    }

    fn slot_rate(&self) -> f64 {
        if self.twist.migration_rate > 0.0 { self.twist.migration_rate } else { 1.0 }
    }

    /// The slot coordinate σ(z) of a fiber (integer part: slot index; module docs of
    /// [`super::table`]).
    pub fn slot_coord(&self, z: f64, ply: usize, fiber: usize) -> f64 {
        let f = self.table.fiber(ply, fiber);
        (self.slot_rate() * self.fiber_turn(z) + f.migration_phase - PI) / TAU
    }

    /// The length coordinate where a fiber's slot coordinate is `sigma`.
    pub fn z_of_slot_coord(&self, sigma: f64, ply: usize, fiber: usize) -> f64 {
        let f = self.table.fiber(ply, fiber);
        (TAU * sigma - f.migration_phase + PI) * self.twist.fiber_pitch / (TAU * self.slot_rate())
    }

    /// The key a slot's random draws use (reduced modulo the slots per wrap).
    #[inline]
    pub fn slot_key(&self, slot: i64) -> i64 {
        match self.twist.slots_per_wrap {
            Some(m) if m > 0 => slot.rem_euclid(m as i64),
            _ => slot,
        }
    }

    /// The type of a fiber's slot `slot`.
    pub fn period_kind(&self, ply: usize, fiber: usize, slot: i64) -> PeriodKind {
        self.table.period_kind(self.params, ply, fiber, self.slot_key(slot))
    }

    /// The migration radius `R(z)` of [W19 eq. 2] (normalised; no loops).
    pub fn migration_radius(&self, z: f64, ply: usize, fiber: usize) -> f64 {
        let p = self.params;
        let f = self.table.fiber(ply, fiber);
        let c = (self.twist.migration_rate * self.fiber_turn(z) + f.migration_phase).cos();
        f.r * (p.rho_min + (p.rho_max - p.rho_min) * 0.5 * (c + 1.0))
    }

    /// The normalised radius with loops, given the slot's type.
    pub fn radius_in(
        &self,
        z: f64,
        ply: usize,
        fiber: usize,
        sigma: f64,
        kind: &PeriodKind,
    ) -> f64 {
        let base = self.migration_radius(z, ply, fiber);
        match kind {
            PeriodKind::Loop { peak } => {
                let t = sigma - sigma.floor();
                let s = (PI * t).sin();
                base + (peak - self.params.rho_max * self.table.fiber(ply, fiber).r) * s * s
            }
            _ => base,
        }
    }

    /// The normalised radius at `z` (migration and loops).
    pub fn radius(&self, z: f64, ply: usize, fiber: usize) -> f64 {
        let sigma = self.slot_coord(z, ply, fiber);
        let kind = self.period_kind(ply, fiber, sigma.floor() as i64);
        self.radius_in(z, ply, fiber, sigma, &kind)
    }

    /// `Δc_ply` in the yarn frame: coefficients of `(N, B)`.
    #[inline]
    pub fn ply_offset(&self, z: f64, ply: usize) -> [f64; 2] {
        let (s, c) = self.ply_angle(z, ply).sin_cos();
        let d = self.params.ply_center_distance;
        [d * c, d * s]
    }

    /// `Δc_ply + Δc` for a point at normalised radius `r` and ply-frame angle `psi`.
    #[inline]
    pub fn ellipse_offset(&self, z: f64, ply: usize, r: f64, psi: f64) -> [f64; 2] {
        let (sp, cp) = self.ply_angle(z, ply).sin_cos();
        let (sf, cf) = psi.sin_cos();
        let d = self.params.ply_center_distance;
        let a = r * self.params.ply_ellipse_n * cf; // along N̂_ply
        let b = r * self.params.ply_ellipse_b * sf; // along B̂_ply = (−sin φ, cos φ)
        [d * cp + a * cp - b * sp, d * sp + a * sp + b * cp]
    }

    /// A regular fiber's offset from the yarn centre at `z`, coefficients of `(N, B)`.
    pub fn fiber_offset(&self, z: f64, ply: usize, fiber: usize) -> [f64; 2] {
        let psi = self.table.fiber(ply, fiber).theta + self.fiber_turn(z);
        self.ellipse_offset(z, ply, self.radius(z, ply, fiber), psi)
    }

    /// The fiber point at a yarn point.
    pub fn point(&self, yp: &YarnPoint, ply: usize, fiber: usize) -> V3 {
        yp.offset(self.fiber_offset(yp.z, ply, fiber))
    }

    /// `fiber_point(curve, frame, fiber, u)` of DESIGN §2.7: the point of fiber `fiber` of ply
    /// `ply` at curve parameter `u` (the CPU reference a GPU fiber pass is tested against).
    pub fn fiber_point(
        &self,
        curve: &YarnCurve,
        frames: &CurveFrames,
        ply: usize,
        fiber: usize,
        u: f64,
    ) -> V3 {
        self.point(&YarnPoint::at(curve, frames, u), ply, fiber)
    }

    /// A hair's offset at its parameter `t ∈ [0, 1]`: `(z, [a, b])`, the length coordinate
    /// and the `(N, B)` coefficients at that z. `sigma0` is the slot coordinate of the
    /// hair's crossing of `r_0`.
    pub fn hair_offset(
        &self,
        shape: &super::table::HairShape,
        ply: usize,
        fiber: usize,
        sigma0: f64,
        t: f64,
    ) -> (f64, [f64; 2]) {
        let k = shape.r0 / shape.re;
        let z_cross = self.z_of_slot_coord(sigma0, ply, fiber);
        let z = z_cross - shape.ze * k + shape.ze * (1.0 + k) * t;
        let p = shape.p0 - shape.pe * k + shape.pe * (1.0 + k) * t;
        let r = (shape.r0 + shape.re) * (1.0 - (1.0 - t).powf(self.params.hair_curvature));
        let scale = (self.params.ply_ellipse_n * self.params.ply_ellipse_b).sqrt();
        (z, self.ellipse_offset(z, ply, r / scale, p))
    }
}
