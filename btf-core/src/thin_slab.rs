//! Thin semi-transparent cloth as an optically thin, locally plane-parallel slab: direct
//! transmittance and the first-order (single-scattering) diffuse reflection and
//! transmission, as BSDF values (radiance per unit irradiance on the surface).
//!
//! The thin-cloth paper (`thin-semitransparent-cloth.txt`) models a fabric of optical
//! thickness `τ₁` with single-scattering albedo `ϖ₀` by the emergent-radiance equations
//! [TC eq. 2–3] (direct transmission `e^{−τ₁/μ}` plus a diffusion term), replaces the diffusion
//! terms by their single-scattering approximations ([TC eq. 4–5], lost in our copy of the
//! text) and renders [TC eq. 7] (front-lit) or [TC eq. 8] (back-lit) with the alpha of [TC eq. 9].
//!
//! **Derivation of [TC eq. 4–5]** (Chandrasekhar, *Radiative Transfer*, 1960, §I.11 and
//! Chap. IX, first-order solution; the same as Blinn 1982). A collimated beam of
//! perpendicular flux `πF` enters at `τ = 0` with direction cosine `μ₀`; the direct beam at
//! depth `t` is `πF e^{−t/μ₀}`. With phase function `ϖ₀ p(cos Θ)` (`p` normalised to 1 over
//! `dω/4π`), single scattering gives the source `J(t) = ϖ₀ p F/4 · e^{−t/μ₀}`, and the
//! transfer equation `μ dI/dt = I − J` integrated along the exit ray gives
//!
//! - reflected: `I(0, +μ) = ∫₀^τ₁ J(t) e^{−t/μ} dt/μ
//!   = ϖ₀ p F/4 · μ₀/(μ + μ₀) · [1 − e^{−τ₁(1/μ + 1/μ₀)}]`,
//! - transmitted: `I(τ₁, −μ) = ∫₀^τ₁ J(t) e^{−(τ₁−t)/μ} dt/μ
//!   = ϖ₀ p F/4 · μ₀/(μ − μ₀) · [e^{−τ₁/μ} − e^{−τ₁/μ₀}]`.
//!
//! Divided by the irradiance `E = πF μ₀` on the surface these are DESIGN.md §3's BSDFs
//! [`reflection_bsdf`] `f_r` and [`transmission_bsdf`] `f_t` (checked here: they agree).
//! Because the incident and exit directions are fixed, every single-scattering event has
//! the same scattering angle, so an anisotropic phase function (Henyey–Greenstein) only
//! multiplies both by `p(cos Θ)` with `cos Θ = −l·v` (`l` towards the light, `v` towards
//! the eye).
//!
//! **Numerics.** With `a = τ₁/μ`, `b = τ₁/μ₀` both terms are `τ₁/(μμ₀) · e^{−m} · φ₁(d)`,
//! `φ₁(x) = (1 − e^{−x})/x`: reflection with `m = 0, d = a + b`, transmission with
//! `m = min(a, b)`, `d = |a − b| = τ₁|μ₀ − μ|/(μμ₀)`. For `d ≤ 1` this form is used, with
//! `φ₁` from its Taylor series near 0, so `μ = μ₀` (where the raw quotient is 0/0) gives
//! the limit `ϖ₀ τ₁ e^{−τ₁/μ₀}/(4π μ₀²)` and `μ = μ₀ ± 10⁻⁷` is as accurate as anywhere.
//! For `d > 1` the quotient has no cancellation and is used as written, which also
//! covers `μ → 0` (`a → ∞`): `f_r → ϖ₀p/(4πμ₀)`, `f_t → ϖ₀p e^{−τ₁/μ₀}/(4πμ₀)`.
//!
//! The first-order terms are exact for single scattering; against the full
//! (multiple-scattering) solution they are checked by the Monte-Carlo slab in
//! [`monte_carlo`].

pub mod monte_carlo;

use std::f64::consts::PI;

/// The scattering phase function of the slab, normalised to 1 over `dω / 4π`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Phase {
    /// `p = 1` (the paper's choice; cotton-like fabrics).
    #[default]
    Isotropic,
    /// Henyey–Greenstein with asymmetry `g ∈ (−1, 1)` (`g > 0`: forward scattering).
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle.
        g: f64,
    },
}

impl Phase {
    /// `p(cos Θ)`, `Θ` the angle between the propagation directions before and after.
    pub fn value(self, cos_scatter: f64) -> f64 {
        match self {
            Phase::Isotropic => 1.0,
            Phase::HenyeyGreenstein { g } => {
                let c = cos_scatter.clamp(-1.0, 1.0);
                let denom = (1.0 + g * g - 2.0 * g * c).max(1e-300);
                (1.0 - g * g) / (denom * denom.sqrt())
            }
        }
    }

    /// Samples `cos Θ` from `p` with a uniform number `xi ∈ [0, 1)`.
    pub fn sample_cos(self, xi: f64) -> f64 {
        match self {
            Phase::HenyeyGreenstein { g } if g.abs() > 1e-6 => {
                let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
                ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
            }
            _ => 1.0 - 2.0 * xi,
        }
    }
}

/// A slab: optical thickness `τ₁`, single-scattering albedo `ϖ₀`, phase function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slab {
    /// Optical thickness `τ₁ ≥ 0` (may be `∞`).
    pub tau: f64,
    /// Single-scattering albedo `ϖ₀ ∈ [0, 1]`.
    pub albedo: f64,
    /// Phase function.
    pub phase: Phase,
}

impl Slab {
    /// Diffuse reflection `f_r` for view cosine `mu`, light cosine `mu0` (both on the lit
    /// face) and `cos Θ = −l·v`.
    pub fn f_r(&self, mu: f64, mu0: f64, cos_scatter: f64) -> f64 {
        self.albedo * self.phase.value(cos_scatter) / (4.0 * PI)
            * reflection_factor(self.tau, mu, mu0)
    }

    /// Diffuse transmission `f_t`, the eye on the face opposite the light.
    pub fn f_t(&self, mu: f64, mu0: f64, cos_scatter: f64) -> f64 {
        self.albedo * self.phase.value(cos_scatter) / (4.0 * PI)
            * transmission_factor(self.tau, mu, mu0)
    }
}

/// `φ₁(x) = (1 − e^{−x})/x` for `x ≥ 0`, 1 at 0, from its series below `10⁻³`.
pub fn phi1(x: f64) -> f64 {
    if x < 1e-3 {
        // 1 − x/2 + x²/6 − x³/24: truncation below x⁴/120 < 1e-14.
        1.0 - x * (0.5 - x * (1.0 / 6.0 - x / 24.0))
    } else if x.is_finite() {
        -(-x).exp_m1() / x
    } else {
        0.0
    }
}

/// Direct (unscattered) transmittance `e^{−τ₁/μ}`: the alpha of [TC eq. 9]. 1 for `τ₁ = 0`,
/// 0 for `μ ≤ 0` (grazing) when `τ₁ > 0`.
pub fn direct_transmittance(tau: f64, mu: f64) -> f64 {
    if tau <= 0.0 {
        1.0
    } else if mu <= 0.0 {
        0.0
    } else {
        (-tau / mu).exp()
    }
}

/// `[1 − e^{−τ₁(1/μ + 1/μ₀)}]/(μ + μ₀)`: `f_r` without `ϖ₀ p/(4π)`. Finite for
/// `μ + μ₀ > 0`; `+∞` only at `μ = μ₀ = 0` (the BSDF diverges there; `f_r · μ₀` is 0).
pub fn reflection_factor(tau: f64, mu: f64, mu0: f64) -> f64 {
    let (mu, mu0) = (mu.max(0.0), mu0.max(0.0));
    if tau <= 0.0 {
        return 0.0;
    }
    if mu + mu0 <= 0.0 {
        return f64::INFINITY;
    }
    let d = tau / mu + tau / mu0;
    if d > 1.0 { -(-d).exp_m1() / (mu + mu0) } else { tau / mu / mu0 * phi1(d) }
}

/// `[e^{−τ₁/μ} − e^{−τ₁/μ₀}]/(μ − μ₀)`: `f_t` without `ϖ₀ p/(4π)`; at `μ = μ₀` its limit
/// `τ₁ e^{−τ₁/μ₀}/μ₀²`. 0 for `τ₁ = 0` or `∞`; finite unless `μ = μ₀ = 0`.
pub fn transmission_factor(tau: f64, mu: f64, mu0: f64) -> f64 {
    let (mu, mu0) = (mu.max(0.0), mu0.max(0.0));
    if tau <= 0.0 || tau == f64::INFINITY {
        return 0.0;
    }
    if mu <= 0.0 && mu0 <= 0.0 {
        return f64::INFINITY;
    }
    let (a, b) = (tau / mu, tau / mu0);
    let d = tau * (mu0 - mu).abs() / (mu * mu0);
    if d > 1.0 {
        ((-a).exp() - (-b).exp()) / (mu - mu0)
    } else {
        let m = a.min(b);
        a * (-m).exp() / mu0 * phi1(d)
    }
}

/// `f_r · μ₀`: reflected radiance per unit irradiance *perpendicular to the light* (the
/// BTF convention of DESIGN.md §3); 0 at `μ₀ ≤ 0`.
pub fn reflection_per_perpendicular(slab: &Slab, mu: f64, mu0: f64, cos_scatter: f64) -> f64 {
    if mu0 <= 0.0 { 0.0 } else { slab.f_r(mu, mu0, cos_scatter) * mu0 }
}

/// `f_t · μ₀`: transmitted radiance per unit perpendicular irradiance; 0 at `μ₀ ≤ 0`.
pub fn transmission_per_perpendicular(slab: &Slab, mu: f64, mu0: f64, cos_scatter: f64) -> f64 {
    if mu0 <= 0.0 { 0.0 } else { slab.f_t(mu, mu0, cos_scatter) * mu0 }
}

/// Share of the optically thick (`τ₁ → ∞`) single-scattering reflection that a slab of
/// thickness `τ₁` reflects: `f_r(τ₁)/f_r(∞) = 1 − e^{−τ₁(1/μ + 1/μ₀)}` — how the renderer
/// scales a measured (thick-cloth) BTF reflection for a thin slab.
pub fn reflection_share(tau: f64, mu: f64, mu0: f64) -> f64 {
    if tau <= 0.0 {
        return 0.0;
    }
    let (mu, mu0) = (mu.max(0.0), mu0.max(0.0));
    let d = tau / mu + tau / mu0;
    if d.is_nan() { 1.0 } else { -(-d).exp_m1() }
}

#[cfg(test)]
mod tests;
