//! Lights: directional (perpendicular irradiance `E`), point (intensity `I`, radiance
//! arriving `I/d²`) and environment (an [`btf_image::EnvMap`] times a scale), each with a
//! sampler for next-event estimation.
//!
//! **Environment importance sampling.** Pixel `(c, r)` is chosen with probability
//! `P = w/Σw`, `w = luminance(L)·Ω_r` (`Ω_r` = [`btf_image::EnvMap::pixel_solid_angle`]),
//! by a marginal CDF over rows and a conditional CDF over the columns of the chosen row;
//! the direction is uniform in solid angle inside the pixel (uniform in `φ` and in
//! `cos θ` between the pixel's edges), so its density is `P/Ω_r` per steradian. Radiance
//! is looked up in the same pixel (piecewise constant), so the estimator of a constant map
//! has zero variance. A black map (zero total weight) is sampled uniformly by solid angle.

use btf_image::EnvMap;
use std::f64::consts::{PI, TAU};
use yarn::vec3::{self, V3};

/// Rec. 709 luminance.
#[inline]
pub fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// A light.
#[derive(Debug, Clone)]
pub enum Light {
    /// A distant light: unit direction towards it, irradiance on a surface facing it.
    Directional {
        /// Unit direction from the scene towards the light.
        to_light: V3,
        /// Perpendicular irradiance (linear RGB, W/m² per channel).
        irradiance: [f64; 3],
    },
    /// An isotropic point light.
    Point {
        /// World position.
        position: V3,
        /// Radiant intensity (W/sr per channel).
        intensity: [f64; 3],
    },
    /// Environment radiance.
    Environment(EnvLight),
}

/// A light sample at a shading point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction towards the light.
    pub wi: V3,
    /// Radiance arriving (delta lights: irradiance, i.e. the pdf is a delta).
    pub radiance: [f64; 3],
    /// Solid-angle density (1 for delta lights).
    pub pdf: f64,
    /// Distance to the light (∞ for distant lights).
    pub distance: f64,
    /// A delta light (no MIS).
    pub delta: bool,
}

impl Light {
    /// A directional light from unit(`to_light`) of perpendicular irradiance `e`.
    pub fn directional(to_light: V3, e: [f64; 3]) -> Light {
        Light::Directional {
            to_light: vec3::normalize_or(to_light, [0.0, 0.0, 1.0]),
            irradiance: e,
        }
    }

    /// Samples the light from world point `p`.
    pub fn sample(&self, p: V3, u: [f64; 3]) -> Option<LightSample> {
        match self {
            Light::Directional { to_light, irradiance } => Some(LightSample {
                wi: *to_light,
                radiance: *irradiance,
                pdf: 1.0,
                distance: f64::INFINITY,
                delta: true,
            }),
            Light::Point { position, intensity } => {
                let d = vec3::sub(*position, p);
                let dist = vec3::length(d);
                if dist.is_nan() || dist <= 0.0 {
                    return None;
                }
                let inv = 1.0 / (dist * dist);
                Some(LightSample {
                    wi: vec3::scale(d, 1.0 / dist),
                    radiance: intensity.map(|i| i * inv),
                    pdf: 1.0,
                    distance: dist,
                    delta: true,
                })
            }
            Light::Environment(env) => env.sample(u),
        }
    }
}

/// An environment light with its importance sampler.
#[derive(Debug, Clone)]
pub struct EnvLight {
    map: EnvMap,
    scale: f64,
    /// Marginal CDF over rows (`height + 1` entries).
    row_cdf: Vec<f64>,
    /// Conditional CDFs over columns, row-major (`height × (width + 1)`).
    col_cdf: Vec<f64>,
    /// Probability of each pixel (row-major), for the pdf.
    prob: Vec<f64>,
}

impl EnvLight {
    /// The sampler of `map × scale`.
    pub fn new(map: EnvMap, scale: f64) -> Self {
        let (w, h) = (map.width, map.height);
        let mut weights = vec![0.0; w * h];
        for r in 0..h {
            let om = map.pixel_solid_angle(r);
            for c in 0..w {
                let p = map.pixels[r * w + c];
                weights[r * w + c] = luminance(p.map(f64::from)) * om;
            }
        }
        let total: f64 = weights.iter().sum();
        let uniform = !(total > 0.0 && total.is_finite());
        let mut row_cdf = vec![0.0; h + 1];
        let mut col_cdf = vec![0.0; h * (w + 1)];
        let mut prob = vec![0.0; w * h];
        for r in 0..h {
            let base = r * (w + 1);
            for c in 0..w {
                let x = if uniform { map.pixel_solid_angle(r) } else { weights[r * w + c] };
                col_cdf[base + c + 1] = col_cdf[base + c] + x;
            }
            row_cdf[r + 1] = row_cdf[r] + col_cdf[base + w];
        }
        let norm = row_cdf[h];
        for r in 0..h {
            for c in 0..w {
                let base = r * (w + 1);
                prob[r * w + c] = (col_cdf[base + c + 1] - col_cdf[base + c]) / norm;
            }
        }
        EnvLight { map, scale, row_cdf, col_cdf, prob }
    }

    /// The map.
    pub fn map(&self) -> &EnvMap {
        &self.map
    }

    /// Radiance arriving from unit direction `d`.
    pub fn radiance(&self, d: V3) -> [f64; 3] {
        let (c, r) = self.map.pixel_of(d);
        self.map.pixels[r * self.map.width + c].map(|v| v as f64 * self.scale)
    }

    /// Solid-angle density of [`EnvLight::sample`] at `d`.
    pub fn pdf(&self, d: V3) -> f64 {
        let (c, r) = self.map.pixel_of(d);
        self.prob[r * self.map.width + c] / self.map.pixel_solid_angle(r)
    }

    /// A direction by importance.
    pub fn sample(&self, u: [f64; 3]) -> Option<LightSample> {
        let (w, h) = (self.map.width, self.map.height);
        let r = pick(&self.row_cdf, u[0]);
        let base = r * (w + 1);
        let c = pick(&self.col_cdf[base..base + w + 1], u[1]);
        let (c0, c1) = ((PI * r as f64 / h as f64).cos(), (PI * (r + 1) as f64 / h as f64).cos());
        let cos_t = c0 + (c1 - c0) * u[2];
        // Jitter φ inside the pixel with the fractional part of the column pick.
        let row = &self.col_cdf[base..base + w + 1];
        let span = row[c + 1] - row[c];
        let frac = if span > 0.0 { ((u[1] * row[w] - row[c]) / span).clamp(0.0, 1.0) } else { 0.5 };
        let phi = TAU * (c as f64 + frac) / w as f64;
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let wi = [sin_t * phi.cos(), sin_t * phi.sin(), cos_t];
        let pdf = self.prob[r * w + c] / self.map.pixel_solid_angle(r);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let radiance = self.map.pixels[r * w + c].map(|v| v as f64 * self.scale);
        Some(LightSample { wi, radiance, pdf, distance: f64::INFINITY, delta: false })
    }
}

/// The index `i` with `cdf[i] ≤ u·cdf[last] < cdf[i+1]` (skipping empty intervals).
fn pick(cdf: &[f64], u: f64) -> usize {
    let n = cdf.len() - 1;
    let target = u * cdf[n];
    let mut i = cdf.partition_point(|x| *x <= target).saturating_sub(1).min(n - 1);
    while i + 1 < n && cdf[i + 1] <= cdf[i] {
        i += 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn env_sampling_integrates_the_map() {
        // A sky with a bright patch: the estimate of ∫L dω by importance sampling matches
        // the map's own quadrature, and pdf() agrees with sample()'s pdf.
        let map = EnvMap::from_fn(64, |d| {
            let sun = if d[2] > 0.9 && d[0] > 0.0 { 200.0 } else { 0.0 };
            [1.0 + d[2] + sun, 0.5 + sun, 0.2 + 0.1 * d[0] + sun]
        })
        .unwrap();
        let want = map.integral();
        let env = EnvLight::new(map, 1.0);
        let mut rng = Rng::new(&[11]);
        let n = 200_000;
        let mut sum = [0.0; 3];
        for _ in 0..n {
            let s = env.sample(rng.uniform3()).unwrap();
            assert!((env.pdf(s.wi) / s.pdf - 1.0).abs() < 1e-9, "{} {}", env.pdf(s.wi), s.pdf);
            assert!((vec3::length(s.wi) - 1.0).abs() < 1e-12);
            (0..3).for_each(|c| sum[c] += s.radiance[c] / s.pdf / n as f64);
        }
        for c in 0..3 {
            assert!(
                (sum[c] / want[c] - 1.0).abs() < 0.01,
                "channel {c}: {} vs {}",
                sum[c],
                want[c]
            );
        }
        // A constant map is sampled with zero variance: every estimate is 4π.
        let env = EnvLight::new(EnvMap::constant(32, [1.0; 3]).unwrap(), 1.0);
        for _ in 0..1000 {
            let s = env.sample(rng.uniform3()).unwrap();
            assert!((s.radiance[0] / s.pdf / (4.0 * PI) - 1.0).abs() < 1e-9);
        }
    }
}
