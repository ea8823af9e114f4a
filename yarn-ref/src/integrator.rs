//! The path tracer: radiance along one camera ray through the explicit fibers.
//!
//! `L(x, ω_o) = Σ_vertices β_k · [Σ_lights NEE_k] (+ environment reached by BCSDF sampling)`,
//! the standard estimator of the rendering equation over fiber scattering:
//! - at each fiber vertex `x_k`, next-event estimation samples every light once:
//!   `β_k · f·cos(ω_i) · L_light · V(x_k, ω_i) / p_light`, with visibility `V` by an
//!   any-hit shadow ray; delta lights (directional, point) take weight 1, the environment
//!   takes the power heuristic `p_light²/(p_light² + p_bsdf²)`;
//! - the path continues by BCSDF sampling, `β_{k+1} = β_k·f·cos/p_bsdf`; a continuation that
//!   escapes collects the environment with the complementary weight
//!   `p_bsdf²/(p_light² + p_bsdf²)` — also after the last vertex, whose BCSDF half of the
//!   direct light would otherwise be lost;
//! - `max_bounces` vertices are lit (1 = direct lighting only); from vertex `rr_start` on,
//!   Russian roulette keeps the path with probability `min(1, max_c β_c)` and divides `β`
//!   by it (unbiased);
//! - the backing plane absorbs (albedo 0); a camera ray that escapes sees `background`.

use crate::geometry::scene::{FiberScene, HitKind};
use crate::light::Light;
use crate::material::{Shading, Vertex};
use crate::rng::Rng;
use yarn::vec3::{self, V3};

/// What a camera ray that hits nothing sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Background {
    /// Black.
    Black,
    /// A constant radiance.
    Constant([f64; 3]),
    /// The environment light (black without one).
    Environment,
}

/// Path-tracing options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSettings {
    /// Lit vertices per path (≥ 1; 1 = direct lighting only).
    pub max_bounces: u32,
    /// First vertex (0-based) after which Russian roulette may end a path.
    pub rr_start: u32,
    /// What escaping camera rays see.
    pub background: Background,
}

impl Default for PathSettings {
    /// 8 bounces with NEE + BCSDF sampling under MIS (DESIGN §3.3 item 18), roulette from
    /// the fourth vertex, black background.
    fn default() -> Self {
        PathSettings { max_bounces: 8, rr_start: 3, background: Background::Black }
    }
}

/// What the camera ray hit first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstHit {
    /// A fiber.
    Fiber,
    /// The backing plane.
    Backing,
    /// Nothing.
    Escaped,
}

/// One path's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathResult {
    /// Radiance estimate (linear RGB).
    pub radiance: [f64; 3],
    /// The camera ray's first hit.
    pub first: FirstHit,
    /// Rays traced (camera, continuation and shadow rays).
    pub rays: u64,
}

#[inline]
fn power(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// The scene an integrator sees.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// Geometry.
    pub fibers: &'a FiberScene,
    /// Lights.
    pub lights: &'a [Light],
    /// Scattering.
    pub shading: &'a Shading,
}

impl Scene<'_> {
    fn environment(&self) -> Option<&crate::light::EnvLight> {
        self.lights.iter().find_map(|l| match l {
            Light::Environment(e) => Some(e),
            _ => None,
        })
    }
}

/// Traces one path from `(o, d)` (`d` unit).
pub fn trace_path(scene: &Scene, o: V3, d: V3, rng: &mut Rng, s: &PathSettings) -> PathResult {
    let env = scene.environment();
    let mut radiance = [0.0; 3];
    let mut beta = [1.0; 3];
    let mut rays = 0u64;
    let mut first = FirstHit::Escaped;
    let (mut o, mut d) = (o, d);
    let mut skip = None;
    let mut prev_pdf: Option<f64> = None;
    let mut bounce = 0u32;
    loop {
        rays += 1;
        let hit = scene.fibers.intersect(o, d, f64::INFINITY, skip);
        let Some(hit) = hit else {
            let le = match (prev_pdf, env) {
                (None, _) => match s.background {
                    Background::Black => [0.0; 3],
                    Background::Constant(c) => c,
                    Background::Environment => env.map_or([0.0; 3], |e| e.radiance(d)),
                },
                (Some(p), Some(e)) => e.radiance(d).map(|v| v * power(p, e.pdf(d))),
                (Some(_), None) => [0.0; 3],
            };
            (0..3).for_each(|c| radiance[c] += beta[c] * le[c]);
            break;
        };
        let HitKind::Fiber { segment, v } = hit.kind else {
            if bounce == 0 {
                first = FirstHit::Backing;
            }
            break;
        };
        if bounce == 0 {
            first = FirstHit::Fiber;
        }
        if bounce >= s.max_bounces {
            break;
        }
        let sp = scene.fibers.surface(segment, v, hit.position);
        let vx = Vertex::new(scene.shading, &sp, hit.position);
        let world = scene.fibers.world(vx.origin, hit.shift);
        let wo = vec3::scale(d, -1.0);
        for light in scene.lights {
            let Some(ls) = light.sample(world, rng.uniform3()) else { continue };
            let (fc, pdf_b) = vx.eval(ls.wi, wo);
            if fc.iter().all(|x| *x <= 0.0) {
                continue;
            }
            rays += 1;
            if scene.fibers.occluded(vx.origin, ls.wi, ls.distance, vx.skip) {
                continue;
            }
            let w = if ls.delta { 1.0 } else { power(ls.pdf, pdf_b) };
            (0..3).for_each(|c| radiance[c] += beta[c] * fc[c] * ls.radiance[c] * w / ls.pdf);
        }
        let Some((wi, weight, pdf)) = vx.sample(wo, rng.uniform3()) else { break };
        (0..3).for_each(|c| beta[c] *= weight[c]);
        if beta.iter().all(|b| *b <= 0.0) || !beta.iter().all(|b| b.is_finite()) {
            break;
        }
        bounce += 1;
        if bounce > s.rr_start {
            let keep = beta.iter().fold(0.0f64, |m, b| m.max(*b)).min(1.0);
            if rng.uniform() >= keep {
                break;
            }
            beta = beta.map(|b| b / keep);
        }
        prev_pdf = Some(pdf);
        o = vx.origin;
        d = wi;
        skip = vx.skip;
    }
    PathResult { radiance, first, rays }
}
