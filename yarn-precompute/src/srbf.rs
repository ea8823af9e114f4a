//! Environment light for the yarn strips [H25 §4.5]: the map fitted by spherical radial
//! basis functions `L(ω) ≈ Σ_j W_j e^{λ(ω·ω_j − 1)}` ([H25 eq. 14]) and the table
//! `I_M(θ_j, θ_o, Δφ) = ∫ e^{λ(ω_i·ω_j − 1)} f(ω_i, ω_o) cos θ_i dω_i` of [H25 eq. 16], so
//! that the strip shader sums `W_j T̃_j Ψ ξ I_M(…)` over the SRBFs (eq. 17).
//!
//! **Choices (DESIGN §3.3 items 12–13, where [H25] is silent):**
//! - centres: a spherical Fibonacci set of `n` points (uniform coverage, no fitting);
//! - one common sharpness λ for all lobes, chosen by golden-section search on `ln λ`;
//! - weights per channel by non-negative least squares (Lawson–Hanson active set on the
//!   normal equations) over the map's pixels, weighted by their solid angle — after a box
//!   downsampling of the map to at most 128 × 64;
//! - `I_M` in the fiber frame (tangent `t`, angles from the normal plane): the lobe centre at
//!   `(θ_j, φ = 0)`, the eye at `(θ_o, Δφ)`; the BCSDF is even in `Δφ`, so `Δφ ∈ [0, π]`.
//!   One λ makes DESIGN's fourth axis (1/λ) unnecessary; the table is built for the fitted λ,
//!   16 × 16 × 16 nodes (θ_j, θ_o over [−π/2, π/2], Δφ over [0, π]), read trilinearly;
//!   DESIGN's third argument `cos(θ_j − θ_o)` is redundant and replaced by Δφ (item 12).
//! - quadrature: midpoint rule, 64 θ_i × 128 φ_i nodes (spacing 0.05 rad; a lobe of
//!   λ ≤ 400 spans at least one σ = λ^{-1/2} ≥ 0.05 rad).

use crate::{Error, Result};
use btf_image::EnvMap;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use yarn::bcsdf::{Bcsdf, FiberBcsdf, FiberDir};

/// Nodes of `I_M` along θ_j, θ_o and Δφ.
pub const IM_NODES: usize = 16;

/// A fitted environment (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SrbfFit {
    /// Unit centres ω_j (world, z up).
    pub centres: Vec<[f64; 3]>,
    /// Common sharpness λ.
    pub lambda: f64,
    /// Weights `W_j` per channel (≥ 0).
    pub weights: Vec<[f64; 3]>,
    /// Relative L2 error of the fit over the sphere (solid-angle weighted, luminance).
    pub rel_error: f64,
    /// Power of the fit over the map's, per channel (`∫ L̂ dω / ∫ L dω`).
    pub power_ratio: [f64; 3],
}

/// `n` points of a spherical Fibonacci set (z from 1 − 1/n to −1 + 1/n).
pub fn fibonacci_sphere(n: usize) -> Vec<[f64; 3]> {
    let golden = PI * (3.0 - 5.0f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * i as f64;
            [r * a.cos(), r * a.sin(), z]
        })
        .collect()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The sample set of a fit: direction, solid angle and radiance of each (downsampled) pixel.
type Samples = Vec<([f64; 3], f64, [f64; 3])>;

fn samples(env: &EnvMap) -> Samples {
    let fx = env.width.div_ceil(128).max(1);
    let fy = env.height.div_ceil(64).max(1);
    let (w, h) = (env.width / fx, env.height / fy);
    let mut out = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut sa) = ([0.0; 3], 0.0);
            let mut d = [0.0; 3];
            for rr in r * fy..(r + 1) * fy {
                let a = env.pixel_solid_angle(rr);
                for cc in c * fx..(c + 1) * fx {
                    let p = env.pixels[rr * env.width + cc];
                    (0..3).for_each(|k| sum[k] += a * p[k] as f64);
                    sa += a;
                    let dd = env.direction(cc, rr);
                    (0..3).for_each(|k| d[k] += a * dd[k]);
                }
            }
            let n = dot(d, d).sqrt();
            if sa > 0.0 && n > 0.0 {
                out.push((d.map(|x| x / n), sa, sum.map(|x| x / sa)));
            }
        }
    }
    out
}

/// Lawson–Hanson NNLS on the normal equations: `min ‖Ax − b‖²`, `x ≥ 0`, given `G = AᵀA`
/// (n × n, row-major) and `g = Aᵀb`.
pub fn nnls(gram: &[f64], g: &[f64], n: usize) -> Vec<f64> {
    let mut x = vec![0.0; n];
    let mut passive = vec![false; n];
    for _ in 0..3 * n + 10 {
        // Gradient of ½‖Ax−b‖²: Gx − g; w = −gradient.
        let w: Vec<f64> =
            (0..n).map(|i| g[i] - (0..n).map(|k| gram[i * n + k] * x[k]).sum::<f64>()).collect();
        let scale = g.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(1e-300);
        let Some(j) = (0..n)
            .filter(|&i| !passive[i] && w[i] > 1e-12 * scale)
            .max_by(|&a, &b| w[a].total_cmp(&w[b]))
        else {
            break;
        };
        passive[j] = true;
        loop {
            let idx: Vec<usize> = (0..n).filter(|&i| passive[i]).collect();
            let z = solve_sub(gram, g, n, &idx);
            if z.iter().all(|&v| v > 0.0) {
                for (k, &i) in idx.iter().enumerate() {
                    x[i] = z[k];
                }
                break;
            }
            // Step towards z until a passive variable hits zero.
            let mut alpha = 1.0f64;
            for (k, &i) in idx.iter().enumerate() {
                if z[k] <= 0.0 {
                    let d = x[i] - z[k];
                    if d > 0.0 {
                        alpha = alpha.min(x[i] / d);
                    }
                }
            }
            for (k, &i) in idx.iter().enumerate() {
                x[i] += alpha * (z[k] - x[i]);
                if x[i] <= 1e-15 * scale {
                    x[i] = 0.0;
                    passive[i] = false;
                }
            }
            if idx.iter().all(|&i| !passive[i]) {
                break;
            }
        }
    }
    x
}

/// Solves `G[idx, idx] z = g[idx]` by Cholesky (with a tiny ridge for rank deficiency).
fn solve_sub(gram: &[f64], g: &[f64], n: usize, idx: &[usize]) -> Vec<f64> {
    let m = idx.len();
    let mut a = vec![0.0; m * m];
    let trace: f64 = idx.iter().map(|&i| gram[i * n + i]).sum::<f64>() / m.max(1) as f64;
    for (r, &i) in idx.iter().enumerate() {
        for (c, &k) in idx.iter().enumerate() {
            a[r * m + c] = gram[i * n + k];
        }
        a[r * m + r] += 1e-12 * trace;
    }
    let mut b: Vec<f64> = idx.iter().map(|&i| g[i]).collect();
    for c in 0..m {
        let d =
            (a[c * m + c] - (0..c).map(|k| a[c * m + k].powi(2)).sum::<f64>()).max(1e-300).sqrt();
        a[c * m + c] = d;
        for r in c + 1..m {
            let s = a[r * m + c] - (0..c).map(|k| a[r * m + k] * a[c * m + k]).sum::<f64>();
            a[r * m + c] = s / d;
        }
    }
    for r in 0..m {
        b[r] = (b[r] - (0..r).map(|k| a[r * m + k] * b[k]).sum::<f64>()) / a[r * m + r];
    }
    for r in (0..m).rev() {
        b[r] = (b[r] - (r + 1..m).map(|k| a[k * m + r] * b[k]).sum::<f64>()) / a[r * m + r];
    }
    b
}

fn lum(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

impl SrbfFit {
    /// Fits `count` SRBFs (1..=64) to `env` (module docs).
    pub fn fit(env: &EnvMap, count: usize) -> Result<Self> {
        if !(1..=64).contains(&count) {
            return Err(Error::Invalid(format!("SRBF count {count} (1..=64)")));
        }
        let s = samples(env);
        if s.is_empty() {
            return Err(Error::Invalid("SRBF fit: the environment map has no pixels".into()));
        }
        let centres = fibonacci_sphere(count);
        let eval = |ln_l: f64| Self::fit_at(&s, &centres, ln_l.exp());
        // Golden-section search on ln λ ∈ [ln 0.25, ln 400].
        let (mut a, mut b) = (0.25f64.ln(), 400.0f64.ln());
        let r = 0.5 * (5.0f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
        let (mut fc, mut fd) = (eval(c).rel_error, eval(d).rel_error);
        for _ in 0..40 {
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - r * (b - a);
                fc = eval(c).rel_error;
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + r * (b - a);
                fd = eval(d).rel_error;
            }
            if b - a < 1e-4 {
                break;
            }
        }
        Ok(eval(0.5 * (a + b)))
    }

    /// The NNLS fit of `centres` at a fixed `lambda` to the samples.
    fn fit_at(s: &Samples, centres: &[[f64; 3]], lambda: f64) -> Self {
        let n = centres.len();
        let rows: Vec<Vec<f64>> = s
            .par_iter()
            .map(|(d, _, _)| centres.iter().map(|c| (lambda * (dot(*d, *c) - 1.0)).exp()).collect())
            .collect();
        let mut gram = vec![0.0; n * n];
        let mut g = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for (row, (_, sa, l)) in rows.iter().zip(s) {
            for i in 0..n {
                for k in 0..n {
                    gram[i * n + k] += sa * row[i] * row[k];
                }
                (0..3).for_each(|ch| g[ch][i] += sa * row[i] * l[ch]);
            }
        }
        let x: Vec<Vec<f64>> = (0..3).map(|ch| nnls(&gram, &g[ch], n)).collect();
        let weights: Vec<[f64; 3]> = (0..n).map(|i| [x[0][i], x[1][i], x[2][i]]).collect();
        let (mut num, mut den) = (0.0, 0.0);
        let (mut p_fit, mut p_map) = ([0.0; 3], [0.0; 3]);
        for (row, (_, sa, l)) in rows.iter().zip(s) {
            let fit: [f64; 3] =
                std::array::from_fn(|ch| (0..n).map(|i| weights[i][ch] * row[i]).sum());
            num += sa * (lum(fit) - lum(*l)).powi(2);
            den += sa * lum(*l).powi(2);
            (0..3).for_each(|ch| {
                p_fit[ch] += sa * fit[ch];
                p_map[ch] += sa * l[ch];
            });
        }
        SrbfFit {
            centres: centres.to_vec(),
            lambda,
            weights,
            rel_error: if den > 0.0 { (num / den).sqrt() } else { 0.0 },
            power_ratio: std::array::from_fn(|ch| {
                if p_map[ch] > 0.0 { p_fit[ch] / p_map[ch] } else { 1.0 }
            }),
        }
    }

    /// The fitted radiance towards `d` (unit).
    pub fn eval(&self, d: [f64; 3]) -> [f64; 3] {
        let mut o = [0.0; 3];
        for (c, w) in self.centres.iter().zip(&self.weights) {
            let g = (self.lambda * (dot(d, *c) - 1.0)).exp();
            (0..3).for_each(|ch| o[ch] += w[ch] * g);
        }
        o
    }

    /// The fit rotated by `deg` about world `+z` (an environment's rotation).
    pub fn rotated_z(&self, deg: f64) -> Self {
        let (s, c) = deg.to_radians().sin_cos();
        let mut out = self.clone();
        for p in &mut out.centres {
            *p = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        }
        out
    }
}

/// `I_M` of one BCSDF at one λ (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ImTable {
    /// The sharpness the table is for.
    pub lambda: f64,
    /// RGB per node, index `((j·N + o)·N + p)`, N = [`IM_NODES`].
    pub values: Vec<[f32; 3]>,
}

/// The node angle `k` of `n` over `[lo, hi]` (ends included).
fn node(k: usize, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * k as f64 / (IM_NODES - 1) as f64
}

/// `∫ e^{λ(ω_i·ω_j − 1)} f(ω_i, ω_o) cos θ_i dω_i` by the module's quadrature.
pub fn im_quadrature(
    bcsdf: &FiberBcsdf,
    lambda: f64,
    theta_j: f64,
    theta_o: f64,
    dphi: f64,
) -> [f64; 3] {
    let (nt, np) = (64usize, 128usize);
    let wj = [theta_j.cos(), 0.0, theta_j.sin()];
    let o = FiberDir::new(theta_o, dphi);
    let mut sum = [0.0; 3];
    for a in 0..nt {
        let ti = -FRAC_PI_2 + (a as f64 + 0.5) * PI / nt as f64;
        let (st, ct) = ti.sin_cos();
        let dw = ct * (PI / nt as f64) * (TAU / np as f64);
        for b in 0..np {
            let pi = (b as f64 + 0.5) * TAU / np as f64;
            let wi = [ct * pi.cos(), ct * pi.sin(), st];
            let g = (lambda * (dot(wi, wj) - 1.0)).exp();
            if g < 1e-12 {
                continue;
            }
            let f = bcsdf.eval(FiberDir::new(ti, pi), o);
            (0..3).for_each(|c| sum[c] += g * f[c] * ct * dw);
        }
    }
    sum
}

impl ImTable {
    /// Tabulates `I_M` of `bcsdf` at `lambda` on the 16³ nodes.
    pub fn build(bcsdf: &FiberBcsdf, lambda: f64) -> Result<Self> {
        if !(lambda.is_finite() && lambda > 0.0) {
            return Err(Error::Invalid(format!("I_M table: λ = {lambda}")));
        }
        let n = IM_NODES;
        let values = (0..n * n * n)
            .into_par_iter()
            .map(|k| {
                let (j, o, p) = (k / (n * n), (k / n) % n, k % n);
                let v = im_quadrature(
                    bcsdf,
                    lambda,
                    node(j, -FRAC_PI_2, FRAC_PI_2),
                    node(o, -FRAC_PI_2, FRAC_PI_2),
                    node(p, 0.0, PI),
                );
                v.map(|x| x as f32)
            })
            .collect();
        Ok(ImTable { lambda, values })
    }

    /// Trilinear read at `(θ_j, θ_o, Δφ)` (Δφ folded into [0, π]), as the shader reads it.
    pub fn at(&self, theta_j: f64, theta_o: f64, dphi: f64) -> [f64; 3] {
        let n = IM_NODES;
        let coord = |x: f64, lo: f64, hi: f64| {
            let t = ((x - lo) / (hi - lo) * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
            let k = (t.floor() as usize).min(n - 2);
            (k, t - k as f64)
        };
        let dp = {
            let a = dphi.rem_euclid(TAU);
            if a > PI { TAU - a } else { a }
        };
        let (j, fj) = coord(theta_j, -FRAC_PI_2, FRAC_PI_2);
        let (o, fo) = coord(theta_o, -FRAC_PI_2, FRAC_PI_2);
        let (p, fp) = coord(dp, 0.0, PI);
        let mut out = [0.0; 3];
        for (dj, wj) in [(0, 1.0 - fj), (1, fj)] {
            for (d_o, wo) in [(0, 1.0 - fo), (1, fo)] {
                for (dpp, wp) in [(0, 1.0 - fp), (1, fp)] {
                    let v = self.values[((j + dj) * n + o + d_o) * n + p + dpp];
                    (0..3).for_each(|c| out[c] += wj * wo * wp * v[c] as f64);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests;
