//! Fiber scattering (BCSDF) in the fiber-local angles of DESIGN §0: `θ = asin(ω·T)` ∈
//! `[−π/2, π/2]` (`theta_fiber`) and `φ` the azimuth about `T` measured from `N`
//! (`phi_fiber`), both directions pointing away from the fiber.
//!
//! **Convention.** Outgoing radiance averaged over the fiber's width is
//! `L_o = ∫ f(ω_i, ω_o) L_i cos θ_i dω_i` with `dω = cos θ dθ dφ` — the measure of [W19 eq. 8]
//! (`cos²θ_i dθ_i dφ_i`). A lobe is `A_p · M_p(θ_i, θ_o) · N_p(φ_o − φ_i)` with a normalised
//! azimuthal density `N_p` ([`azimuthal`]) and a longitudinal `M_p` whose energy
//! `∫M_p cos²θ_i dθ_i` is 1 in the default normalisation ([`longitudinal`]). So a fiber
//! conserves energy by construction: `∫ f cos θ_i dω_i = Σ_p A_p`, and the white furnace is
//! `Σ_p A_p = 1` per channel. Every lobe is even in `φ_o − φ_i` and symmetric in
//! `θ_i ↔ θ_o`, so `f` is reciprocal.
//!
//! **Models** ([`models`]): (a) simple [W19 eq. 5] + diffuse; (b) Khungurn R + TT
//! [W19 eq. 6–10] (+ the diffuse term [W19 §4.3] adds); (c) R + TT + D for [H25 eq. 7], D
//! being a Lambertian-cylinder lobe. [`ambient`] tabulates [W19 eq. 8–10] over θ_o.
//!
//! **Sampling.** One lobe is chosen with probability ∝ the mean of its colour `A_p`, then θ_i
//! from the lobe's longitudinal sampler and `φ_i = φ_o + Δφ` from its azimuthal one. The
//! returned pdf is the one-sample mixture over all lobes (solid angle), the weight
//! `f·cos θ_i / pdf` per channel.

pub mod ambient;
pub mod azimuthal;
pub mod longitudinal;
pub mod models;

pub use ambient::AmbientTable;
pub use azimuthal::Azimuthal;
pub use longitudinal::{Longitudinal, Normalization};
pub use models::{HuangParams, KhungurnParams, RtShape, SimpleParams};

use crate::frame::Frame;
use crate::vec3::{self, V3};
use std::f64::consts::FRAC_PI_2;

/// A direction in fiber-local angles (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberDir {
    /// `θ = asin(ω·T)` ∈ `[−π/2, π/2]`.
    pub theta_fiber: f64,
    /// Azimuth about `T` from `N` towards `B`.
    pub phi_fiber: f64,
}

impl FiberDir {
    /// From angles.
    pub fn new(theta_fiber: f64, phi_fiber: f64) -> Self {
        FiberDir { theta_fiber, phi_fiber }
    }

    /// The fiber-local angles of the world direction `w` (need not be unit) in `frame`.
    pub fn from_world(frame: &Frame, w: V3) -> Self {
        let w = vec3::normalize_or(w, frame.t);
        let s = vec3::dot(w, frame.t).clamp(-1.0, 1.0);
        FiberDir {
            theta_fiber: s.asin(),
            phi_fiber: vec3::dot(w, frame.b).atan2(vec3::dot(w, frame.n)),
        }
    }

    /// The unit world direction.
    pub fn to_world(&self, frame: &Frame) -> V3 {
        let (st, ct) = self.theta_fiber.sin_cos();
        let (sp, cp) = self.phi_fiber.sin_cos();
        let v = vec3::add_scaled(vec3::scale(frame.t, st), frame.n, ct * cp);
        vec3::add_scaled(v, frame.b, ct * sp)
    }
}

/// A sampled incident direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BcsdfSample {
    /// The direction.
    pub wi: FiberDir,
    /// Its pdf (per unit solid angle).
    pub pdf: f64,
    /// `f(wi, wo)·cos θ_i / pdf` per channel.
    pub weight: [f64; 3],
}

/// A fiber scattering function.
pub trait Bcsdf: Send + Sync {
    /// `f(ω_i, ω_o)` per channel (linear RGB).
    fn eval(&self, wi: FiberDir, wo: FiberDir) -> [f64; 3];
    /// Samples `ω_i` for `ω_o` from three uniform numbers in `[0, 1)`.
    fn sample(&self, wo: FiberDir, u: [f64; 3]) -> Option<BcsdfSample>;
    /// The pdf of [`Bcsdf::sample`] (per unit solid angle).
    fn pdf(&self, wi: FiberDir, wo: FiberDir) -> f64;
}

/// One lobe `A · M(θ_i, θ_o) · N(φ_o − φ_i)`.
#[derive(Debug, Clone)]
pub struct Lobe {
    /// A name for reports (`"R"`, `"TT"`, `"D"`, …).
    pub name: &'static str,
    /// Colour `A_p` (its energy per channel in the default normalisation).
    pub color: [f64; 3],
    /// Longitudinal part.
    pub m: Longitudinal,
    /// Azimuthal part.
    pub n: Azimuthal,
}

/// A sum of lobes (the three models of [`models`] are instances).
#[derive(Debug, Clone)]
pub struct FiberBcsdf {
    /// The lobes.
    pub lobes: Vec<Lobe>,
}

impl FiberBcsdf {
    fn weights(&self) -> (Vec<f64>, f64) {
        let w: Vec<f64> =
            self.lobes.iter().map(|l| (l.color.iter().sum::<f64>() / 3.0).max(0.0)).collect();
        let total = w.iter().sum();
        (w, total)
    }
}

/// `cos θ` of a fiber-local direction (never negative).
#[inline]
pub fn cos_theta(d: FiberDir) -> f64 {
    d.theta_fiber.cos().max(0.0)
}

impl Bcsdf for FiberBcsdf {
    fn eval(&self, wi: FiberDir, wo: FiberDir) -> [f64; 3] {
        let dphi = wo.phi_fiber - wi.phi_fiber;
        let mut f = [0.0; 3];
        for l in &self.lobes {
            let v = l.m.eval(wi.theta_fiber, wo.theta_fiber) * l.n.eval(dphi);
            for c in 0..3 {
                f[c] += l.color[c] * v;
            }
        }
        f
    }

    fn sample(&self, wo: FiberDir, u: [f64; 3]) -> Option<BcsdfSample> {
        let (w, total) = self.weights();
        if total <= 0.0 {
            return None;
        }
        let mut pick = u[0] * total;
        let mut idx = self.lobes.len() - 1;
        for (i, wi) in w.iter().enumerate() {
            if pick < *wi {
                idx = i;
                break;
            }
            pick -= wi;
        }
        let lobe = &self.lobes[idx];
        let theta = lobe.m.sample(wo.theta_fiber, u[1]).clamp(-FRAC_PI_2, FRAC_PI_2);
        let phi = azimuthal::wrap_pi(wo.phi_fiber + lobe.n.sample(u[2]));
        let wi = FiberDir::new(theta, phi);
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let f = self.eval(wi, wo);
        let c = cos_theta(wi);
        Some(BcsdfSample { wi, pdf, weight: f.map(|v| v * c / pdf) })
    }

    fn pdf(&self, wi: FiberDir, wo: FiberDir) -> f64 {
        let (w, total) = self.weights();
        if total <= 0.0 {
            return 0.0;
        }
        let dphi = wo.phi_fiber - wi.phi_fiber;
        let c = longitudinal::cos_clamped(wi.theta_fiber);
        self.lobes
            .iter()
            .zip(&w)
            .map(|(l, wt)| {
                wt / total * l.m.pdf_theta(wi.theta_fiber, wo.theta_fiber) * l.n.eval(dphi) / c
            })
            .sum()
    }
}

#[cfg(test)]
mod tests;
