//! Marching: optical depth, transmittance, and the volume image.
//!
//! **Optical depth** `τ = ∫ σ(x(s), ω) ds` over the ray's tube intervals; each interval of
//! length `ℓ` is cut into `n = ⌈ℓ/Δs⌉` equal steps sampled at `(k + ξ)/n` — `ξ = ½`
//! (midpoint) or one uniform jitter per ray — so a density constant inside the tube is
//! integrated exactly, edges included.
//!
//! **Radiance** along a camera ray `(o, −ω_o)` (the medium of DESIGN §1.3 items 8–11):
//! `L = T(0, ∞) L_bg + Σ_k T(0, s_k) ϖ σ(x_k, ω_o) h_k Σ_lights p(ω_l, ω_o) L_l T_l(x_k) + L_ms`:
//! - single scattering by quadrature (the march itself; [C03 eq. 9] per pixel with the
//!   physical extinction), `T_l` marched from `x_k` towards the light through all yarns
//!   (delta lights: their irradiance; the environment: one importance sample per step);
//! - the phase `p` is Kajiya–Kay diffuse, `sin∠(T, ω_l)/π²` (normalised over the sphere;
//!   `k_d` = ϖ), or isotropic `1/4π`;
//! - `L_ms`, orders ≥ 2 by Monte Carlo: a collision `x_1` on the camera ray by free-flight
//!   sampling (march until `τ ≥ −ln(1 − ξ)`), then isotropic directions and free flights
//!   `x_2, x_3, …`, each collision weighting the path by ϖ and adding next-event estimation
//!   with the isotropic phase; a flight that escapes ends the path (its light was counted
//!   by the previous vertex's NEE).
//!
//! With ϖ = 1, an isotropic phase and a constant environment, `L = 1` exactly (the
//! volumetric furnace, tested).

use super::tubes::VolumeScene;
use crate::camera::Camera;
use crate::integrator::{Background, FirstHit};
use crate::light::Light;
use crate::render::{Image, RenderSettings, RenderStats, render_pixels};
use crate::rng::Rng;
use crate::{Error, Result};
use std::f64::consts::{PI, TAU};
use yarn::vec3::{self, V3};

/// Single-scattering phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Kajiya–Kay diffuse, `sin∠(T, ω_l)/π²`.
    KajiyaKay,
    /// `1/4π`.
    Isotropic,
}

/// Volume marching options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeSettings {
    /// Largest step Δs (metres).
    pub step: f64,
    /// Jitter the step positions per ray (else midpoints).
    pub jitter: bool,
    /// Single-scattering albedo ϖ.
    pub albedo: f64,
    /// Phase of the single-scattering term.
    pub phase: Phase,
    /// Monte-Carlo multiple scattering (orders 2 … `max_order`).
    pub multiple: bool,
    /// Highest scattering order.
    pub max_order: u32,
    /// What camera rays see behind the medium.
    pub background: Background,
}

impl VolumeSettings {
    /// Step `step`, jittered, ϖ = 0.8, Kajiya–Kay, single scattering only.
    pub fn new(step: f64) -> Self {
        VolumeSettings {
            step,
            jitter: true,
            albedo: 0.8,
            phase: Phase::KajiyaKay,
            multiple: false,
            max_order: 16,
            background: Background::Black,
        }
    }
}

impl VolumeScene {
    /// `τ` along `o + t·d`, `t ∈ [t_min, t_max]`, with offset `xi ∈ [0, 1)` of the steps.
    pub fn optical_depth(&self, o: V3, d: V3, t_min: f64, t_max: f64, step: f64, xi: f64) -> f64 {
        let mut tau = 0.0;
        for (a, b) in self.intervals(o, d, t_min, t_max) {
            let n = ((b - a) / step).ceil().max(1.0);
            let h = (b - a) / n;
            for k in 0..n as usize {
                let x = vec3::add_scaled(o, d, a + (k as f64 + xi) * h);
                tau += self.sigma_at(x, d) * h;
            }
        }
        tau
    }

    /// `e^{−τ}` along the ray.
    pub fn transmittance(&self, o: V3, d: V3, t_max: f64, step: f64, xi: f64) -> f64 {
        (-self.optical_depth(o, d, 0.0, t_max, step, xi)).exp()
    }

    /// Free flight from `o` along `d`: the collision point, or `None` if the ray leaves.
    fn free_flight(&self, o: V3, d: V3, step: f64, u: f64) -> Option<V3> {
        let target = -(1.0 - u).ln();
        let mut tau = 0.0;
        for (a, b) in self.intervals(o, d, 0.0, f64::INFINITY) {
            let n = ((b - a) / step).ceil().max(1.0);
            let h = (b - a) / n;
            for k in 0..n as usize {
                let t = a + (k as f64 + 0.5) * h;
                let dt = self.sigma_at(vec3::add_scaled(o, d, t), d) * h;
                if tau + dt >= target {
                    let f = if dt > 0.0 { (target - tau) / dt } else { 0.5 };
                    return Some(vec3::add_scaled(o, d, a + (k as f64 + f) * h));
                }
                tau += dt;
            }
        }
        None
    }

    /// Direct light at `x` scattered towards `wo`: `Σ p·L·T_l`.
    fn direct(
        &self,
        x: V3,
        wo: V3,
        lights: &[Light],
        s: &VolumeSettings,
        phase: Phase,
        rng: &mut Rng,
    ) -> [f64; 3] {
        let mut out = [0.0; 3];
        let t = match phase {
            Phase::KajiyaKay => self.tangent_at(x),
            Phase::Isotropic => None,
        };
        let _ = wo;
        for light in lights {
            let Some(ls) = light.sample(x, rng.uniform3()) else { continue };
            let p = match (phase, t) {
                (Phase::KajiyaKay, Some(t)) => super::density::sin_angle(ls.wi, t) / (PI * PI),
                _ => 1.0 / (4.0 * PI),
            };
            let xi = if s.jitter { rng.uniform() } else { 0.5 };
            let tr = self.transmittance(x, ls.wi, ls.distance, s.step, xi);
            (0..3).for_each(|c| out[c] += p * ls.radiance[c] * tr / ls.pdf);
        }
        out
    }

    /// Radiance along `(o, d)`.
    pub fn radiance(
        &self,
        o: V3,
        d: V3,
        lights: &[Light],
        s: &VolumeSettings,
        rng: &mut Rng,
    ) -> ([f64; 3], FirstHit) {
        let wo = vec3::scale(d, -1.0);
        let xi = if s.jitter { rng.uniform() } else { 0.5 };
        let mut l = [0.0; 3];
        let mut tr = 1.0;
        let ivs = self.intervals(o, d, 0.0, f64::INFINITY);
        let first = if ivs.is_empty() { FirstHit::Escaped } else { FirstHit::Fiber };
        for (a, b) in ivs {
            let n = ((b - a) / s.step).ceil().max(1.0);
            let h = (b - a) / n;
            for k in 0..n as usize {
                let x = vec3::add_scaled(o, d, a + (k as f64 + xi) * h);
                let sig = self.sigma_at(x, d);
                if sig <= 0.0 {
                    continue;
                }
                if s.albedo > 0.0 {
                    let e = self.direct(x, wo, lights, s, s.phase, rng);
                    // [C03 eq. 9] with the step's own attenuation: the scattered light of a
                    // step is T·(1 − e^{−σh})·ϖ·(...) — exact for a constant step.
                    let w = tr * (1.0 - (-sig * h).exp()) * s.albedo;
                    (0..3).for_each(|c| l[c] += w * e[c]);
                }
                tr *= (-sig * h).exp();
            }
        }
        let bg = match s.background {
            Background::Black => [0.0; 3],
            Background::Constant(c) => c,
            Background::Environment => lights
                .iter()
                .find_map(|li| match li {
                    Light::Environment(e) => Some(e.radiance(d)),
                    _ => None,
                })
                .unwrap_or([0.0; 3]),
        };
        (0..3).for_each(|c| l[c] += tr * bg[c]);
        if s.multiple && s.albedo > 0.0 && s.max_order >= 2 {
            let ms = self.multiple(o, d, lights, s, rng);
            (0..3).for_each(|c| l[c] += ms[c]);
        }
        (l, first)
    }

    fn multiple(
        &self,
        o: V3,
        d: V3,
        lights: &[Light],
        s: &VolumeSettings,
        rng: &mut Rng,
    ) -> [f64; 3] {
        let mut out = [0.0; 3];
        let Some(mut x) = self.free_flight(o, d, s.step, rng.uniform()) else { return out };
        let mut beta = s.albedo;
        for _order in 2..=s.max_order {
            let [u1, u2] = rng.uniform2();
            let z = 1.0 - 2.0 * u1;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let w = [r * (TAU * u2).cos(), r * (TAU * u2).sin(), z];
            let Some(next) = self.free_flight(x, w, s.step, rng.uniform()) else { break };
            beta *= s.albedo;
            let e = self.direct(next, vec3::scale(w, -1.0), lights, s, Phase::Isotropic, rng);
            (0..3).for_each(|c| out[c] += beta * e[c]);
            x = next;
            if beta < 0.1 {
                if rng.uniform() >= beta / 0.1 {
                    break;
                }
                beta = 0.1;
            }
        }
        out
    }
}

/// Renders the volume through `camera` (the pixel loop of [`crate::render`]; `top` is the
/// height oblique rays start from).
pub fn render_volume(
    scene: &VolumeScene,
    lights: &[Light],
    camera: &Camera,
    settings: &RenderSettings,
    vs: &VolumeSettings,
) -> Result<(Image, RenderStats)> {
    if !(vs.step > 0.0 && vs.step.is_finite() && (0.0..=1.0).contains(&vs.albedo)) {
        return Err(Error::Invalid(format!(
            "volume: step {} must be positive, albedo {} in [0, 1]",
            vs.step, vs.albedo
        )));
    }
    let top = scene.bounds().max[2] as f64;
    render_pixels(camera, settings, top, &|| {}, |o, d, rng| {
        let (l, first) = scene.radiance(o, d, lights, vs, rng);
        (l, first, 1)
    })
}
