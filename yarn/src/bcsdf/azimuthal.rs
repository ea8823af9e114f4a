//! Azimuthal scattering functions `N(Δφ)` of the fiber lobes, each a normalised density on
//! `Δφ ∈ [−π, π]` (`∫N dΔφ = 1`, so a lobe's energy sits in its longitudinal part and its
//! colour), with exact inverse-CDF sampling from one uniform number:
//!
//! - [`Azimuthal::Uniform`]: `1/2π` — [W19 eq. 9]'s `N_R` and the diffuse lobe;
//! - [`Azimuthal::HalfCos`]: `cos(Δφ/2)/4` — [W19 eq. 5]'s azimuthal factor, normalised
//!   (inverse CDF `Δφ = 2 asin(2u − 1)`);
//! - [`Azimuthal::VonMises`]: `e^{κ cos(Δφ − π)}/Z` about the forward direction Δφ = π with
//!   `κ = 1/γ_TT²` (DESIGN §2.3 item 12). [W19 eq. 10]'s closed form for `∫N_TT` is not the
//!   integral of a normalised von Mises density (which is 1); `Z` is integrated numerically
//!   instead, and sampling inverts a tabulated CDF refined by Newton steps on the exact
//!   density, so samples and pdf agree to ~1e-12;
//! - [`Azimuthal::Cylinder`]: `[(π − |Δφ|) cos Δφ + sin |Δφ|]/8`, the far-field azimuthal
//!   scattering of a Lambertian cylinder (derived from the overlap of the lit and the seen
//!   half of the circumference: `∫cos⁺(φ_i − ψ)cos⁺(φ_o − ψ)dψ`); our choice for the D lobe of
//!   [H25 eq. 7], which names the lobe but gives no form. Its CDF
//!   `((π − x) sin x − 2 cos x + 2)/8` on each half is inverted by Newton steps.
//!
//! `Δφ = φ_o − φ_i` wrapped to `[−π, π]`; every function is even in Δφ, which makes the lobes
//! reciprocal.

use crate::quad;
use std::f64::consts::{PI, TAU};

/// An azimuthal lobe shape (see the module documentation).
#[derive(Debug, Clone)]
pub enum Azimuthal {
    /// `1/2π`.
    Uniform,
    /// `cos(Δφ/2)/4`.
    HalfCos,
    /// Von Mises about `Δφ = π`.
    VonMises(VonMises),
    /// Lambertian cylinder.
    Cylinder,
}

/// A von Mises density about `Δφ = π` with a tabulated CDF.
#[derive(Debug, Clone)]
pub struct VonMises {
    /// Concentration `κ = 1/γ²`.
    pub kappa: f64,
    /// `∫_{−π}^{π} e^{κ(cos(x − π) − 1)} dx`.
    norm: f64,
    /// CDF at `−π + 2π·k/CELLS`, `k = 0..=CELLS`.
    cdf: Vec<f64>,
}

const CELLS: usize = 1024;

impl VonMises {
    /// The lobe of width `gamma` (radians): `κ = 1/γ²`.
    pub fn new(gamma: f64) -> Self {
        let kappa = 1.0 / (gamma * gamma);
        let raw = |x: f64| (kappa * ((x - PI).cos() - 1.0)).exp();
        let h = TAU / CELLS as f64;
        let rule = quad::gl16();
        let mut cdf = Vec::with_capacity(CELLS + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for k in 0..CELLS {
            let a = -PI + k as f64 * h;
            acc += rule.integrate(a, a + h, raw);
            cdf.push(acc);
        }
        let norm = acc;
        cdf.iter_mut().for_each(|c| *c /= norm);
        VonMises { kappa, norm, cdf }
    }

    /// The density at `Δφ` (wrapped).
    pub fn pdf(&self, d: f64) -> f64 {
        (self.kappa * ((d - PI).cos() - 1.0)).exp() / self.norm
    }

    /// The normalisation `∫ exp(κ(cos(x − π) − 1)) dx` over one turn (the density is the
    /// exponential divided by it).
    pub fn norm(&self) -> f64 {
        self.norm
    }

    fn cdf_at(&self, x: f64) -> f64 {
        let h = TAU / CELLS as f64;
        let k = (((x + PI) / h).floor() as usize).min(CELLS - 1);
        let a = -PI + k as f64 * h;
        self.cdf[k] + quad::gl16().integrate(a, x, |s| self.pdf(s))
    }

    fn sample(&self, u: f64) -> f64 {
        let k = self.cdf.partition_point(|&c| c <= u).clamp(1, CELLS) - 1;
        let h = TAU / CELLS as f64;
        let (lo, hi) = (-PI + k as f64 * h, -PI + (k + 1) as f64 * h);
        crate::special::solve_increasing(
            |x| self.cdf_at(x) - u,
            |x| self.pdf(x),
            lo,
            hi,
            0.5 * (lo + hi),
        )
    }
}

/// `Δφ` wrapped to `[−π, π]`.
#[inline]
pub fn wrap_pi(d: f64) -> f64 {
    let w = (d + PI).rem_euclid(TAU) - PI;
    if w < -PI { w + TAU } else { w }
}

impl Azimuthal {
    /// `N(Δφ)` (a density: its own sampling pdf).
    pub fn eval(&self, d: f64) -> f64 {
        let d = wrap_pi(d);
        match self {
            Azimuthal::Uniform => 1.0 / TAU,
            Azimuthal::HalfCos => 0.25 * (0.5 * d).cos().max(0.0),
            Azimuthal::VonMises(v) => v.pdf(d),
            Azimuthal::Cylinder => {
                let a = d.abs();
                (((PI - a) * a.cos() + a.sin()) / 8.0).max(0.0)
            }
        }
    }

    /// `∫ N dΔφ` by quadrature (1 up to rounding; [W19 eq. 9–10] tabulate this).
    pub fn integral(&self) -> f64 {
        quad::gl16().composite(-PI, PI, 64, |d| self.eval(d))
    }

    /// A `Δφ` distributed as `N`, from `u ∈ [0, 1)`.
    pub fn sample(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0 - f64::EPSILON);
        match self {
            Azimuthal::Uniform => TAU * u - PI,
            Azimuthal::HalfCos => 2.0 * (2.0 * u - 1.0).clamp(-1.0, 1.0).asin(),
            Azimuthal::VonMises(v) => v.sample(u),
            Azimuthal::Cylinder => {
                let (sign, v) = if u < 0.5 { (-1.0, 1.0 - 2.0 * u) } else { (1.0, 2.0 * u - 1.0) };
                sign * cylinder_half_inverse(v)
            }
        }
    }
}

/// Inverts `G(x)/4 = ((π − x) sin x − 2 cos x + 2)/4 = v` on `[0, π]`.
fn cylinder_half_inverse(v: f64) -> f64 {
    let g = |x: f64| ((PI - x) * x.sin() - 2.0 * x.cos() + 2.0) / 4.0 - v;
    let dg = |x: f64| ((PI - x) * x.cos() + x.sin()) / 4.0;
    crate::special::solve_increasing(g, dg, 0.0, PI, PI * v)
}
