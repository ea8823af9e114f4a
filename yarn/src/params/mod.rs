//! `YarnParams`: the procedural yarn of Zhao et al. [Z16] in the notation of Wu & Yuksel
//! [W19 §2.2, §3.1], with the choices of DESIGN §0 and §2.3 items 1–4, 6 and 13.
//!
//! - **Geometry.** `ply_count` plies whose centres sit `ply_center_distance` from the yarn
//!   axis ([W19 §3.1] writes this `R^ply/2`; [Z16]'s `yarn_radius/2`). Each ply is an
//!   ellipse with semi-axes `ply_ellipse_n` along `N̂_ply` (from the yarn axis towards the
//!   ply centre) and `ply_ellipse_b` along `B̂_ply` ([W19 §3.1]'s `e_N`, `e_B`; [Z16]'s
//!   `ellipse_short` and `ellipse_long`: the short axis points at the yarn centre).
//! - **Twist.** `ply_pitch` (α_ply) and `fiber_pitch` (α) are lengths per full turn along
//!   the length coordinate z, **signed**: the sign is the handedness (DESIGN §2.3 item 1;
//!   [Z16]'s `*_clock_wise` flags become a negative pitch). The paper's one θ for both
//!   rotations is replaced by `θ_ply = 2πz/α_ply` and `θ_fib = 2πz/α`.
//! - **Cross-section.** Fiber centres have the area density
//!   `p(R) = (1−2ε)((e − e^{R/R_max})/(e−1))^β + ε` on the normalised disk `R ≤ R_max`
//!   [Z16]; migration `R(z) = R_i[ρ_min + (ρ_max−ρ_min)(cos(s·θ_fib + φ_i)+1)/2]`
//!   ([W19 eq. 2] with an independent phase φ_i, DESIGN §2.3 item 2); period `α/s`
//!   (item 3). `s = 0` (no migration) and `ρ_min = ρ_max` are allowed.
//! - **Flyaways.** Hair and loop densities are counts per metre of yarn *per ply*, as
//!   [Z16]'s code uses them; hair shape from [Z16]'s Gaussians `z_e, r_0, r_e, p_e`
//!   (lengths in metres, `p_e` in radians) bent by [H25 eq. 13] (`hair_curvature`, 1 =
//!   [Z16]'s straight hair); loops reach `r_1` (metres, from the ply centre) at their peak
//!   ([W19 §2.2]'s `R_max^loop`). Per migration period the chance of a loop is
//!   `loop_density·(α/s)/fibers_per_ply` (DESIGN §2.3 item 4), likewise for hair.
//! - **Fiber radius** `fiber_radius` (r_f, metres) is explicit (DESIGN §2.3 item 13:
//!   [W19] never gives it). `core_fraction` of each ply's fibers, the innermost by `R_i`,
//!   are core fibers (items 6–7).
//!
//! Every length is in metres and every angle in radians (DESIGN §0). [`presets`] holds our
//! own presets; [`zhao`] imports a fitted `config_step2.txt` with an explicit unit.

pub mod presets;
pub mod zhao;

use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// A normal distribution `(mean, sigma)`, as [Z16]'s config files give their flyaway
/// parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gaussian {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (≥ 0).
    pub sigma: f64,
}

impl Gaussian {
    /// `N(mean, sigma)`.
    pub const fn new(mean: f64, sigma: f64) -> Self {
        Gaussian { mean, sigma }
    }
}

/// The procedural yarn description (see the module documentation for every symbol).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YarnParams {
    /// A name for messages and presets.
    pub name: String,
    /// Number of plies `n_ply` (≥ 1).
    pub ply_count: u32,
    /// Fibers per ply (≥ 1).
    pub fibers_per_ply: u32,
    /// Distance from the yarn axis to each ply centre, metres (`R^ply/2` of [W19]).
    pub ply_center_distance: f64,
    /// Ply ellipse semi-axis along `N̂_ply`, metres (`e_N`).
    pub ply_ellipse_n: f64,
    /// Ply ellipse semi-axis along `B̂_ply`, metres (`e_B`).
    pub ply_ellipse_b: f64,
    /// Ply pitch α_ply: metres of length coordinate per turn of the plies, signed.
    pub ply_pitch: f64,
    /// Fiber pitch α: metres per turn of a fiber about its ply centre, signed.
    pub fiber_pitch: f64,
    /// ε of p(R), in `[0, 0.5]`.
    pub density_epsilon: f64,
    /// β of p(R), in `[0, 100]`.
    pub density_beta: f64,
    /// R_max of p(R) (normalised radius; 1 in all of [Z16]'s fits), > 0.
    pub r_max: f64,
    /// ρ_min of the migration, ≥ 0.
    pub rho_min: f64,
    /// ρ_max of the migration, ≥ ρ_min.
    pub rho_max: f64,
    /// Migration rate s (periods of R per fiber turn), ≥ 0; 0 = no migration.
    pub migration_rate: f64,
    /// Fiber radius r_f, metres, ≥ 0 (0: fibers of no thickness, no extinction).
    pub fiber_radius: f64,
    /// Hair flyaways per metre of yarn per ply, ≥ 0.
    pub hair_density: f64,
    /// Hair extent along the yarn `z_e`, metres (signed mean).
    pub hair_ze: Gaussian,
    /// Hair start radius from the ply centre `r_0`, metres.
    pub hair_r0: Gaussian,
    /// Hair radial extent `r_e`, metres.
    pub hair_re: Gaussian,
    /// Hair angular extent `p_e` (θ_e of [H25 eq. 12]), radians.
    pub hair_pe: Gaussian,
    /// Hair curvature exponent α of [H25 eq. 13] (> 0; 1 = straight).
    pub hair_curvature: f64,
    /// Loop flyaways per metre of yarn per ply, ≥ 0.
    pub loop_density: f64,
    /// Loop peak distance from the ply centre `r_1`, metres.
    pub loop_r1: Gaussian,
    /// Fraction of each ply's fibers (the innermost) that are core fibers, in `[0, 1]`.
    pub core_fraction: f64,
}

/// Upper bounds on counts (a params file claiming 10⁹ fibers is refused, not allocated).
pub const MAX_PLIES: u32 = 64;
/// Upper bound on fibers per ply.
pub const MAX_FIBERS_PER_PLY: u32 = 100_000;

impl YarnParams {
    /// Checks every field; the error names the yarn and the field.
    pub fn validate(&self) -> Result<()> {
        let name = &self.name;
        let bad = |field: &str, v: f64, rule: &str| {
            Err(Error::Invalid(format!("yarn params '{name}': {field} = {v} ({rule})")))
        };
        if self.ply_count == 0 {
            return bad("ply_count", 0.0, "a yarn needs at least one ply");
        }
        if self.ply_count > MAX_PLIES || self.fibers_per_ply > MAX_FIBERS_PER_PLY {
            return Err(Error::Limit(format!(
                "yarn params '{name}': {} plies × {} fibers (at most {MAX_PLIES} plies and \
                 {MAX_FIBERS_PER_PLY} fibers per ply)",
                self.ply_count, self.fibers_per_ply
            )));
        }
        if self.fibers_per_ply == 0 {
            return bad("fibers_per_ply", 0.0, "a ply needs at least one fiber");
        }
        let nonneg = [
            ("ply_center_distance", self.ply_center_distance),
            ("density_beta", self.density_beta),
            ("rho_min", self.rho_min),
            ("migration_rate", self.migration_rate),
            ("fiber_radius", self.fiber_radius),
            ("hair_density", self.hair_density),
            ("loop_density", self.loop_density),
            ("hair_ze.sigma", self.hair_ze.sigma),
            ("hair_r0.sigma", self.hair_r0.sigma),
            ("hair_re.sigma", self.hair_re.sigma),
            ("hair_pe.sigma", self.hair_pe.sigma),
            ("loop_r1.sigma", self.loop_r1.sigma),
        ];
        for (field, v) in nonneg {
            if !(v.is_finite() && v >= 0.0) {
                return bad(field, v, "must be finite and ≥ 0");
            }
        }
        let positive = [
            ("ply_ellipse_n", self.ply_ellipse_n),
            ("ply_ellipse_b", self.ply_ellipse_b),
            ("r_max", self.r_max),
            ("hair_curvature", self.hair_curvature),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, v, "must be finite and > 0");
            }
        }
        for (field, v) in [("ply_pitch", self.ply_pitch), ("fiber_pitch", self.fiber_pitch)] {
            if !(v.is_finite() && v != 0.0) {
                return bad(field, v, "a signed length per turn: finite and non-zero");
            }
        }
        let means = [
            ("hair_ze.mean", self.hair_ze.mean),
            ("hair_r0.mean", self.hair_r0.mean),
            ("hair_re.mean", self.hair_re.mean),
            ("hair_pe.mean", self.hair_pe.mean),
            ("loop_r1.mean", self.loop_r1.mean),
        ];
        for (field, v) in means {
            if !v.is_finite() {
                return bad(field, v, "must be finite");
            }
        }
        if self.density_beta > 100.0 {
            return bad("density_beta", self.density_beta, "at most 100 (fits are below 1)");
        }
        if !(0.0..=0.5).contains(&self.density_epsilon) {
            return bad("density_epsilon", self.density_epsilon, "must lie in [0, 0.5]");
        }
        if !(self.rho_max.is_finite() && self.rho_max >= self.rho_min) {
            return bad("rho_max", self.rho_max, "must be finite and ≥ rho_min");
        }
        if !(0.0..=1.0).contains(&self.core_fraction) {
            return bad("core_fraction", self.core_fraction, "must lie in [0, 1]");
        }
        let p = self.hair_chance() + self.loop_chance();
        if p > 1.0 {
            return Err(Error::Invalid(format!(
                "yarn params '{name}': hair_density and loop_density ask for a flyaway in \
                 {:.0} % of the fibers' migration periods (more than all of them); lower \
                 the densities or shorten the period fiber_pitch/migration_rate",
                100.0 * p
            )));
        }
        Ok(())
    }

    /// Length (metres of length coordinate) of one fiber-type period: `|α|/s`, or one fiber
    /// turn `|α|` when `s = 0` (DESIGN §2.3 item 3; with no migration there is no period
    /// of R, so flyaways are drawn per turn).
    pub fn type_period(&self) -> f64 {
        if self.migration_rate > 0.0 {
            self.fiber_pitch.abs() / self.migration_rate
        } else {
            self.fiber_pitch.abs()
        }
    }

    /// Chance that one (fiber, period) slot carries a hair (DESIGN §2.3 item 4).
    pub fn hair_chance(&self) -> f64 {
        self.hair_density * self.type_period() / self.fibers_per_ply.max(1) as f64
    }

    /// Chance that one (fiber, period) slot is a loop.
    pub fn loop_chance(&self) -> f64 {
        self.loop_density * self.type_period() / self.fibers_per_ply.max(1) as f64
    }

    /// The area density of fiber centres `p(R)` on the normalised ply disk [Z16].
    pub fn density_p(&self, r: f64) -> f64 {
        let e = std::f64::consts::E;
        let t = ((e - (r / self.r_max).exp()) / (e - 1.0)).max(0.0);
        (1.0 - 2.0 * self.density_epsilon) * t.powf(self.density_beta) + self.density_epsilon
    }

    /// The largest distance of a regular fiber centre from its ply centre (metres): the
    /// larger ellipse semi-axis at `ρ_max·R_max`.
    pub fn ply_reach(&self) -> f64 {
        self.ply_ellipse_n.max(self.ply_ellipse_b) * self.rho_max * self.r_max
    }

    /// Radius of the yarn tube without flyaways (metres): ply distance + ply reach + r_f.
    pub fn yarn_radius(&self) -> f64 {
        self.ply_center_distance + self.ply_reach() + self.fiber_radius
    }

    /// Serialises to TOML.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Invalid(format!("yarn params to TOML: {e}")))
    }

    /// Parses TOML (every field required, unknown fields refused) and validates.
    pub fn from_toml(text: &str, source: &str) -> Result<Self> {
        let p: YarnParams =
            toml::from_str(text).map_err(|e| Error::Invalid(format!("{source}: {e}")))?;
        p.validate().map_err(|e| match e {
            Error::Invalid(m) => Error::Invalid(format!("{source}: {m}")),
            other => other,
        })?;
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_round_trip_is_exact_for_every_preset() {
        for name in presets::NAMES {
            let p = YarnParams::preset(name).unwrap();
            let text = p.to_toml().unwrap();
            let back = YarnParams::from_toml(&text, "test").unwrap();
            assert_eq!(back, p, "{name}");
        }
        let mut t = YarnParams::preset("cotton-2ply").unwrap().to_toml().unwrap();
        t.push_str("\nwhatever = 3\n");
        assert!(YarnParams::from_toml(&t, "x.toml").unwrap_err().to_string().contains("whatever"));
    }

    #[test]
    fn validation_names_the_field_and_allows_the_hard_limits() {
        let base = YarnParams::preset("cotton-2ply").unwrap();
        let mut p = base.clone();
        p.fiber_radius = 0.0;
        p.rho_min = p.rho_max;
        p.migration_rate = 0.0;
        p.validate().unwrap();
        type Edit = fn(&mut YarnParams);
        let cases: [(&str, Edit); 6] = [
            ("fiber_radius", |p| p.fiber_radius = -1e-6),
            ("ply_count", |p| p.ply_count = 0),
            ("ply_ellipse_n", |p| p.ply_ellipse_n = f64::NAN),
            ("fiber_pitch", |p| p.fiber_pitch = 0.0),
            ("rho_max", |p| p.rho_max = p.rho_min - 0.1),
            ("hair_density", |p| p.hair_density = 1e12),
        ];
        for (field, f) in cases {
            let mut p = base.clone();
            f(&mut p);
            let msg = p.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "{field}: {msg}");
        }
    }
}
