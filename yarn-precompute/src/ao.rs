//! Ambient occlusion inside a yarn [W19 §4.2, Fig. 7–8]: `AoTexture`, a 2-D texture over the
//! cross-section by stratified Monte-Carlo directions through the 2-D extinction, and
//! `AoCubic`, [W19]'s distance-based approximation — a cubic in the distance to the yarn
//! centre fitted to the texture's radial mean.
//!
//! **Texture.** `AO(q) = (1/N) Σ_k exp(−∫₀^∞ σ(q + t ω_k) dt)` with `ω_k` at angles
//! `2π(k + ξ_k)/N` (one jittered direction per stratum, `ξ` from a key hash of texel and
//! stratum, so bakes are deterministic). `σ = 2 r_f n_A` per unit in-plane length
//! ([`SigmaField`], symmetrised over the plies), `q` in the slice frame that turns with the
//! plies. For fibers along the yarn this 2-D mean *is* the 3-D one: a direction at elevation
//! e travels `x/cos e` to cover in-plane distance x and meets extinction `σ cos e`, so every
//! direction of the sphere has the optical depth of its projection, and the uniform mean
//! over the sphere equals the uniform mean over the in-plane azimuth (DESIGN §2.3 item 11;
//! fibers have no hemisphere, so no cosine weight). [W19] also assumes no twist; the
//! tests check the equivalence against 3-D rays through explicit straight fibers.
//!
//! **Cubic.** [W19] gives no coefficients. We fit `a(d) = c₀ + c₁d + c₂d² + c₃d³`,
//! `d = |q|/R_yarn` (normalised so the shader needs no unit), by weighted least squares to
//! the mean of the texture over `radial_bins` annuli in `[0, 1]`, each weighted by its texel
//! count; evaluation clamps d to `[0, 1]` and the result to `[0, 1]`.
//!
//! **Texel layout** ([`AoTexture::ao`]): one R32F 2-D texture `res × res`, row-major `[y][x]`,
//! spanning `[−h, h]²` of the slice frame, texel centres at `−h + (i + ½)·2h/res`; sample
//! bilinearly with clamp-to-edge (the edge texels are outside the fibers, AO ≈ 1).

use crate::settings::AoSettings;
use crate::sigma::SigmaField;
use rayon::prelude::*;
use std::f64::consts::TAU;
use yarn::hash::{hash_keys, unit_f64};

/// The 2-D AO texture (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct AoTexture {
    /// Texels per side.
    pub res: usize,
    /// The texture spans `[−half_width, half_width]²` (metres).
    pub half_width: f64,
    /// AO in `[0, 1]`, row-major `[y][x]`.
    pub ao: Vec<f32>,
}

/// The distance-based cubic (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoCubic {
    /// `c₀ … c₃` of `a(d) = Σ c_k d^k`.
    pub coeffs: [f64; 4],
    /// The yarn radius d is normalised by (metres).
    pub yarn_radius: f64,
    /// RMS residual of the fit over the annuli (weighted by texel count).
    pub rms_residual: f64,
}

/// AO at `q` from `n` directions, stratum k at angle `2π(k + jitter(k))/n`.
pub fn ao_point(field: &SigmaField, q: [f64; 2], n: usize, jitter: impl Fn(usize) -> f64) -> f64 {
    let step = 0.5 * field.cell();
    let mut sum = 0.0;
    for k in 0..n {
        let phi = TAU * (k as f64 + jitter(k)) / n as f64;
        sum += (-field.optical_depth(q, [phi.cos(), phi.sin()], step)).exp();
    }
    sum / n as f64
}

impl AoTexture {
    /// Bakes the texture of `field` (σ per metre; a plain grid is fastest, see
    /// [`SigmaField::symmetrized`]); `seed` keys the stratified jitter.
    pub fn bake(field: &SigmaField, settings: &AoSettings, seed: u64) -> Self {
        let (res, n) = (settings.res, settings.directions);
        let h = field.half_width;
        let cell = 2.0 * h / res as f64;
        let empty = field.max() <= 0.0;
        let ao: Vec<f32> = (0..res * res)
            .into_par_iter()
            .map(|k| {
                if empty {
                    return 1.0;
                }
                let (i, j) = (k % res, k / res);
                let q = [-h + (i as f64 + 0.5) * cell, -h + (j as f64 + 0.5) * cell];
                let jit = |s: usize| unit_f64(hash_keys(&[seed, k as u64, s as u64]));
                ao_point(field, q, n, jit) as f32
            })
            .collect();
        AoTexture { res, half_width: h, ao }
    }

    /// Bilinear lookup at slice-frame `(x, y)` (metres), clamped to the edge texels.
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let n = self.res as f64;
        let g = |c: f64| {
            ((c + self.half_width) / (2.0 * self.half_width) * n - 0.5).clamp(0.0, n - 1.0)
        };
        let (gx, gy) = (g(x), g(y));
        let (x0, y0) = (gx.floor() as usize, gy.floor() as usize);
        let (fx, fy) = (gx - x0 as f64, gy - y0 as f64);
        let (x1, y1) = ((x0 + 1).min(self.res - 1), (y0 + 1).min(self.res - 1));
        let t = |i: usize, j: usize| self.ao[j * self.res + i] as f64;
        (1.0 - fx) * (1.0 - fy) * t(x0, y0)
            + fx * (1.0 - fy) * t(x1, y0)
            + (1.0 - fx) * fy * t(x0, y1)
            + fx * fy * t(x1, y1)
    }

    /// Mean AO and texel count per annulus of width `yarn_radius/bins` (texel centres).
    pub fn radial_mean(&self, yarn_radius: f64, bins: usize) -> Vec<(f64, usize)> {
        let mut acc = vec![(0.0, 0usize); bins];
        let cell = 2.0 * self.half_width / self.res as f64;
        for j in 0..self.res {
            for i in 0..self.res {
                let x = -self.half_width + (i as f64 + 0.5) * cell;
                let y = -self.half_width + (j as f64 + 0.5) * cell;
                let b = (x.hypot(y) / yarn_radius * bins as f64) as usize;
                if b < bins {
                    acc[b].0 += self.ao[j * self.res + i] as f64;
                    acc[b].1 += 1;
                }
            }
        }
        acc.into_iter().map(|(s, n)| (if n > 0 { s / n as f64 } else { 1.0 }, n)).collect()
    }
}

impl AoCubic {
    /// Fits the cubic to the texture's radial mean over `bins` annuli of `[0, yarn_radius]`.
    pub fn fit(tex: &AoTexture, yarn_radius: f64, bins: usize) -> Self {
        let mean = tex.radial_mean(yarn_radius, bins);
        // Normal equations of the weighted least squares, 4 × 4.
        let mut m = [[0.0f64; 5]; 4];
        for (b, &(a, n)) in mean.iter().enumerate() {
            let d = (b as f64 + 0.5) / bins as f64;
            let p = [1.0, d, d * d, d * d * d];
            for r in 0..4 {
                for c in 0..4 {
                    m[r][c] += n as f64 * p[r] * p[c];
                }
                m[r][4] += n as f64 * p[r] * a;
            }
        }
        let coeffs = solve4(m).unwrap_or([1.0, 0.0, 0.0, 0.0]);
        let mut cubic = AoCubic { coeffs, yarn_radius, rms_residual: 0.0 };
        let (mut se, mut w) = (0.0, 0.0);
        for (b, &(a, n)) in mean.iter().enumerate() {
            let d = (b as f64 + 0.5) / bins as f64;
            se += n as f64 * (cubic.eval_normalized(d) - a).powi(2);
            w += n as f64;
        }
        cubic.rms_residual = if w > 0.0 { (se / w).sqrt() } else { 0.0 };
        cubic
    }

    /// `a(d)` at normalised distance `d = |q|/R_yarn` (clamped as the module says).
    pub fn eval_normalized(&self, d: f64) -> f64 {
        let d = d.clamp(0.0, 1.0);
        let c = &self.coeffs;
        (c[0] + d * (c[1] + d * (c[2] + d * c[3]))).clamp(0.0, 1.0)
    }

    /// `a` at distance `dist` (metres) from the yarn centre.
    pub fn eval(&self, dist: f64) -> f64 {
        let r = if self.yarn_radius > 0.0 { dist / self.yarn_radius } else { 1.0 };
        self.eval_normalized(r)
    }
}

/// Gaussian elimination with partial pivoting on an augmented 4 × 5 system.
fn solve4(mut m: [[f64; 5]; 4]) -> Option<[f64; 4]> {
    for col in 0..4 {
        let piv = (col..4).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[piv][col].abs() < 1e-300 {
            return None;
        }
        m.swap(col, piv);
        for r in 0..4 {
            if r != col {
                let f = m[r][col] / m[col][col];
                for c in col..5 {
                    m[r][c] -= f * m[col][c];
                }
            }
        }
    }
    let x = [0, 1, 2, 3].map(|i| m[i][4] / m[i][i]);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests;
