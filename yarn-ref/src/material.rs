//! What a fiber does to light: a Lambertian surface BRDF on the capsule (the analytic
//! validation case and Mitsuba's `diffuse` on curves), or a fiber BCSDF of the `yarn`
//! crate in fiber-local angles (DESIGN §0).
//!
//! **Lambert.** `f = ρ/π` with the capsule's geometric normal `n`; the estimator weight of
//! a light is `f·max(0, n·ω_i)`; sampling is cosine-weighted about `n`. Rays leave from the
//! hit point pushed out by `10⁻⁴ r` along `n`.
//!
//! **Fiber BCSDF** ([`yarn::bcsdf`]). The fiber is treated as a line that scatters: rays
//! leave from the point on the segment axis (the "pseudo-ribbon" of hair renderers), the
//! outgoing radiance is `∫ f(ω_i, ω_o) L_i cos θ_i dω_i` with `θ_i = asin(ω_i·T)` — the
//! BCSDF's own measure [W19 eq. 8] — and `T` is the tangent interpolated along the
//! polyline. `f` depends on the azimuths only through `φ_o − φ_i`, so the normal of the
//! local frame is any unit vector ⟂ `T`. With `tint`, `f` is multiplied by the fiber's
//! colour (≤ 1 per channel, so energy is still conserved).

use crate::geometry::scene::{Skip, SurfacePoint, perpendicular};
use std::f64::consts::{FRAC_1_PI, TAU};
use std::sync::Arc;
use yarn::bcsdf::{Bcsdf, FiberBcsdf, FiberDir};
use yarn::frame::Frame;
use yarn::vec3::{self, V3};

/// The fibers' scattering.
#[derive(Debug, Clone)]
pub enum Shading {
    /// Lambertian surface; albedo `Some(ρ)` for all fibers, `None` for the fiber colours.
    Lambert {
        /// Albedo override.
        albedo: Option<[f64; 3]>,
    },
    /// A fiber BCSDF.
    Fiber {
        /// The lobes.
        bcsdf: Arc<FiberBcsdf>,
        /// Multiply by the fiber colour.
        tint: bool,
    },
}

impl Shading {
    /// A short name for provenance and reports.
    pub fn name(&self) -> String {
        match self {
            Shading::Lambert { albedo: Some(a) } => format!("lambert {a:?}"),
            Shading::Lambert { albedo: None } => "lambert (fiber colours)".into(),
            Shading::Fiber { bcsdf, tint } => {
                let lobes: Vec<&str> = bcsdf.lobes.iter().map(|l| l.name).collect();
                format!("fiber bcsdf {}{}", lobes.join("+"), if *tint { " tinted" } else { "" })
            }
        }
    }
}

/// A shading point: where rays leave and how light scatters.
#[derive(Debug, Clone)]
pub struct Vertex {
    /// Origin of rays leaving the vertex (box coordinates).
    pub origin: V3,
    /// Segments those rays ignore.
    pub skip: Option<Skip>,
    kind: Kind,
}

#[derive(Debug, Clone)]
enum Kind {
    Lambert { n: V3, albedo: [f64; 3] },
    Fiber { frame: Frame, bcsdf: Arc<FiberBcsdf>, tint: [f64; 3] },
}

impl Vertex {
    /// The vertex of a fiber hit at `position` with local geometry `sp`.
    pub fn new(shading: &Shading, sp: &SurfacePoint, position: V3) -> Self {
        let color = sp.color.map(f64::from);
        match shading {
            Shading::Lambert { albedo } => Vertex {
                origin: vec3::add_scaled(position, sp.normal, 1e-4 * sp.radius),
                skip: None,
                kind: Kind::Lambert { n: sp.normal, albedo: albedo.unwrap_or(color) },
            },
            Shading::Fiber { bcsdf, tint } => Vertex {
                origin: sp.axis_point,
                skip: Some(sp.skip),
                kind: Kind::Fiber {
                    frame: Frame::new(sp.tangent, perpendicular(sp.tangent)),
                    bcsdf: bcsdf.clone(),
                    tint: if *tint { color } else { [1.0; 3] },
                },
            },
        }
    }

    /// `f(ω_i, ω_o)·cos` (the integrand's weight per unit radiance) and the pdf of
    /// [`Vertex::sample`] at `ω_i`.
    pub fn eval(&self, wi: V3, wo: V3) -> ([f64; 3], f64) {
        match &self.kind {
            Kind::Lambert { n, albedo } => {
                let c = vec3::dot(*n, wi);
                if c <= 0.0 || vec3::dot(*n, wo) <= 0.0 {
                    return ([0.0; 3], 0.0);
                }
                (albedo.map(|a| a * FRAC_1_PI * c), c * FRAC_1_PI)
            }
            Kind::Fiber { frame, bcsdf, tint } => {
                let (i, o) = (FiberDir::from_world(frame, wi), FiberDir::from_world(frame, wo));
                let f = bcsdf.eval(i, o);
                let c = i.theta_fiber.cos().max(0.0);
                ([f[0] * c * tint[0], f[1] * c * tint[1], f[2] * c * tint[2]], bcsdf.pdf(i, o))
            }
        }
    }

    /// Samples `ω_i` for `ω_o`: `(ω_i, f·cos/pdf, pdf)`.
    pub fn sample(&self, wo: V3, u: [f64; 3]) -> Option<(V3, [f64; 3], f64)> {
        match &self.kind {
            Kind::Lambert { n, albedo } => {
                if vec3::dot(*n, wo) <= 0.0 {
                    return None;
                }
                let r = u[0].sqrt();
                let phi = TAU * u[1];
                let z = (1.0 - u[0]).max(0.0).sqrt();
                let t = perpendicular(*n);
                let b = vec3::cross(*n, t);
                let wi = vec3::add_scaled(
                    vec3::add_scaled(vec3::scale(*n, z), t, r * phi.cos()),
                    b,
                    r * phi.sin(),
                );
                let pdf = z * FRAC_1_PI;
                (pdf > 0.0).then_some((wi, *albedo, pdf))
            }
            Kind::Fiber { frame, bcsdf, tint } => {
                let o = FiberDir::from_world(frame, wo);
                let s = bcsdf.sample(o, u)?;
                let w = [s.weight[0] * tint[0], s.weight[1] * tint[1], s.weight[2] * tint[2]];
                Some((s.wi.to_world(frame), w, s.pdf))
            }
        }
    }
}
