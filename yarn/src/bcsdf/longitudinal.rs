//! Longitudinal scattering functions `M(θ_i, θ_o)` of the fiber lobes.
//!
//! - [`Longitudinal::Constant`]: `M = 2/π`, so `∫M cos²θ_i dθ_i = 1` (the measure of a
//!   fiber BCSDF, [W19 eq. 8]); the diffuse lobes. Sampled from `cos²θ` by inverting
//!   `F(θ) = (θ + sin θ cos θ + π/2)/π`.
//! - [`Longitudinal::Gaussian`]: a Gaussian in the half angle `θ_h = (θ_i + θ_o)/2`
//!   about `shift` with width β ([W19 eq. 5]; Khungurn's `M_R`, `M_TT`, DESIGN §2.3 item 12),
//!   in two normalisations:
//!   - [`Normalization::Paper`]: `g(θ_h)/(β√2π)` as the papers write it. Its energy
//!     `∫M cos²θ_i dθ_i ≈ 2cos²θ*` is not 1 and depends on θ_o; kept to tabulate [W19 eq. 8]
//!     as published.
//!   - [`Normalization::EnergyConserving`] (default, ours): the papers do not say how the
//!     Gaussian is normalised on the bounded range `[−π/2, π/2]`. We use
//!     `M = q(θ_i) q(θ_o) g(θ_h)` with `q` the symmetric Sinkhorn scaling that makes
//!     `∫M cos²θ_i dθ_i = 1` for every θ_o: the lobe is still a Gaussian in θ_h modulated by
//!     a smooth separable factor, it is reciprocal (symmetric in θ_i ↔ θ_o) and
//!     energy-conserving by construction, so a white fiber passes the furnace test. `q` is
//!     solved on 256 nodes (cell centres of the θ range, Catmull–Rom interpolation,
//!     constant beyond the outer nodes) with the integrals taken per node interval (4-point Gauss on
//!     the Gaussian's ±8σ support) and iterated `q ← √(q / ∫q g cos²θ_i)` to 1e-13. `q` rises
//!     towards the poles (about `1/max(cos θ, 2β)`) but stays finite, so directions along
//!     the fiber give finite values (DESIGN §4.4).
//!
//!   Sampling draws θ_i from the normal density of mean `2·shift − θ_o` and deviation `2β`
//!   truncated to `[−π/2, π/2]` (the exact θ_i-density of `g`; the scaling factor enters the
//!   sample weight), falling back to `cos²θ` when the truncated mass underflows.

use crate::special::{norm_cdf, norm_inv, norm_pdf};
use std::f64::consts::{FRAC_PI_2, PI};

/// How a Gaussian longitudinal lobe is normalised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Normalization {
    /// Reciprocal and energy-conserving (ours, module documentation).
    #[default]
    EnergyConserving,
    /// `g(θ_h)/(β√2π)` as written in the papers.
    Paper,
}

/// A longitudinal lobe shape.
#[derive(Debug, Clone)]
pub enum Longitudinal {
    /// `2/π`.
    Constant,
    /// A Gaussian in θ_h.
    Gaussian(GaussianLobe),
}

/// A Gaussian lobe in `θ_h` (see the module documentation).
#[derive(Debug, Clone)]
pub struct GaussianLobe {
    /// Longitudinal width β (radians).
    pub beta: f64,
    /// Centre of `θ_h` (radians).
    pub shift: f64,
    /// Normalisation.
    pub normalization: Normalization,
    /// Sinkhorn scaling `q` at the nodes (energy-conserving mode).
    q: Vec<f64>,
}

const NODES: usize = 256;
const COS_MIN: f64 = 1e-6;

fn node(k: usize) -> f64 {
    -FRAC_PI_2 + (k as f64 + 0.5) * PI / NODES as f64
}

/// Catmull–Rom interpolation of node values at θ: four `(node, weight)` pairs (indices
/// clamped at the ends, so the value is constant beyond the outer nodes). C¹, so the
/// integrands built from it are smooth enough for Gauss rules.
fn interp(theta: f64) -> [(usize, f64); 4] {
    let x = ((theta + FRAC_PI_2) / (PI / NODES as f64) - 0.5).clamp(0.0, (NODES - 1) as f64);
    let k = (x.floor() as usize).min(NODES - 2);
    let b = crate::curve::basis(x - k as f64);
    let idx = |d: isize| (k as isize + d).clamp(0, NODES as isize - 1) as usize;
    [(idx(-1), b[0]), (idx(0), b[1]), (idx(1), b[2]), (idx(2), b[3])]
}

/// `cos θ` clamped away from 0.
#[inline]
pub fn cos_clamped(theta: f64) -> f64 {
    theta.cos().max(COS_MIN)
}

impl GaussianLobe {
    /// A lobe of width `beta` about `shift` (radians).
    pub fn new(beta: f64, shift: f64, normalization: Normalization) -> Self {
        let mut lobe = GaussianLobe { beta, shift, normalization, q: vec![1.0; NODES] };
        if normalization == Normalization::EnergyConserving {
            lobe.q = lobe.sinkhorn();
        }
        lobe
    }

    /// The unnormalised Gaussian `exp(−(θ_h − shift)²/2β²)`.
    #[inline]
    pub fn g(&self, ti: f64, to: f64) -> f64 {
        let x = 0.5 * (ti + to) - self.shift;
        (-x * x / (2.0 * self.beta * self.beta)).exp()
    }

    fn sinkhorn(&self) -> Vec<f64> {
        // W[o][k] = ∫ φ_k(θ) g(θ, θ_o) cos²θ dθ with φ_k the interpolation hats.
        let sigma = 2.0 * self.beta;
        let gl = crate::quad::GaussLegendre::new(4);
        let mut w = vec![0.0; NODES * NODES];
        for o in 0..NODES {
            let to = node(o);
            let centre = 2.0 * self.shift - to;
            let (lo, hi) =
                ((centre - 8.0 * sigma).max(-FRAC_PI_2), (centre + 8.0 * sigma).min(FRAC_PI_2));
            if lo >= hi {
                continue;
            }
            // Integrate interval by interval between consecutive nodes (and the two ends).
            let mut cuts = vec![lo];
            cuts.extend((0..NODES).map(node).filter(|&t| t > lo && t < hi));
            cuts.push(hi);
            let row = &mut w[o * NODES..(o + 1) * NODES];
            for c in cuts.windows(2) {
                let (a, b) = (c[0], c[1]);
                let (half, mid) = (0.5 * (b - a), 0.5 * (a + b));
                for (x, wt) in gl.nodes.iter().zip(&gl.weights) {
                    let t = mid + half * x;
                    let v = wt * half * self.g(t, to) * t.cos() * t.cos();
                    for (k, wk) in interp(t) {
                        row[k] += v * wk;
                    }
                }
            }
        }
        let mut q = vec![1.0; NODES];
        for _ in 0..5000 {
            let mut worst: f64 = 0.0;
            let s: Vec<f64> = (0..NODES)
                .map(|o| w[o * NODES..(o + 1) * NODES].iter().zip(&q).map(|(a, b)| a * b).sum())
                .collect();
            for o in 0..NODES {
                if s[o] > 0.0 {
                    worst = worst.max((q[o] * s[o] - 1.0).abs());
                    q[o] = (q[o] / s[o]).sqrt();
                }
            }
            if worst < 1e-13 {
                break;
            }
        }
        q
    }

    /// The scaling `q` at its 256 nodes (cell centres of `[−π/2, π/2]`, Catmull–Rom between
    /// them, clamped to the outer nodes): what a GPU shader needs to evaluate the lobe as
    /// [`Self::eval`] does (all ones in the paper's normalisation).
    pub fn q_nodes(&self) -> &[f64] {
        &self.q
    }

    fn q_at(&self, theta: f64) -> f64 {
        interp(theta).iter().map(|&(k, w)| self.q[k] * w).sum()
    }

    /// `M(θ_i, θ_o)`.
    pub fn eval(&self, ti: f64, to: f64) -> f64 {
        match self.normalization {
            Normalization::Paper => self.g(ti, to) / (self.beta * (2.0 * PI).sqrt()),
            Normalization::EnergyConserving => self.q_at(ti) * self.q_at(to) * self.g(ti, to),
        }
    }

    fn truncated(&self, to: f64) -> (f64, f64, f64, f64) {
        let (mu, sigma) = (2.0 * self.shift - to, 2.0 * self.beta);
        let (a, b) = ((-FRAC_PI_2 - mu) / sigma, (FRAC_PI_2 - mu) / sigma);
        (mu, sigma, a, b)
    }

    /// Samples θ_i for `θ_o = to` from `u`.
    pub fn sample(&self, to: f64, u: f64) -> f64 {
        let (mu, sigma, a, b) = self.truncated(to);
        // Work in the lower tail for accuracy (mirror when the interval lies above 0).
        let (a2, b2, sign) = if a > 0.0 { (-b, -a, -1.0) } else { (a, b, 1.0) };
        let (ca, cb) = (norm_cdf(a2), norm_cdf(b2));
        if cb - ca <= 1e-300 || (cb - ca).is_nan() {
            return sample_cos2(u);
        }
        let x = norm_inv(ca + u * (cb - ca)).clamp(a2, b2);
        (mu + sign * sigma * x).clamp(-FRAC_PI_2, FRAC_PI_2)
    }

    /// The θ_i density of [`Self::sample`].
    pub fn pdf_theta(&self, ti: f64, to: f64) -> f64 {
        let (mu, sigma, a, b) = self.truncated(to);
        let (a2, b2) = if a > 0.0 { (-b, -a) } else { (a, b) };
        let z = norm_cdf(b2) - norm_cdf(a2);
        if z <= 1e-300 || z.is_nan() {
            return pdf_cos2(ti);
        }
        if !(-FRAC_PI_2..=FRAC_PI_2).contains(&ti) {
            return 0.0;
        }
        norm_pdf((ti - mu) / sigma) / (sigma * z)
    }
}

/// θ from the density `(2/π) cos²θ` on `[−π/2, π/2]`.
pub fn sample_cos2(u: f64) -> f64 {
    let f = |t: f64| (t + t.sin() * t.cos() + FRAC_PI_2) / PI - u;
    crate::special::solve_increasing(f, pdf_cos2, -FRAC_PI_2, FRAC_PI_2, 0.5 * PI * (u - 0.5))
}

/// `(2/π) cos²θ`.
#[inline]
pub fn pdf_cos2(t: f64) -> f64 {
    if (-FRAC_PI_2..=FRAC_PI_2).contains(&t) { 2.0 / PI * t.cos() * t.cos() } else { 0.0 }
}

impl Longitudinal {
    /// `M(θ_i, θ_o)`.
    pub fn eval(&self, ti: f64, to: f64) -> f64 {
        match self {
            Longitudinal::Constant => 2.0 / PI,
            Longitudinal::Gaussian(g) => g.eval(ti, to),
        }
    }

    /// Samples θ_i.
    pub fn sample(&self, to: f64, u: f64) -> f64 {
        match self {
            Longitudinal::Constant => sample_cos2(u),
            Longitudinal::Gaussian(g) => g.sample(to, u),
        }
    }

    /// The θ_i density of [`Self::sample`].
    pub fn pdf_theta(&self, ti: f64, to: f64) -> f64 {
        match self {
            Longitudinal::Constant => pdf_cos2(ti),
            Longitudinal::Gaussian(g) => g.pdf_theta(ti, to),
        }
    }

    /// `∫ M(θ_i, θ_o) cos²θ_i dθ_i` ([W19 eq. 8]'s longitudinal integral), by quadrature.
    pub fn energy(&self, to: f64) -> f64 {
        let f = |t: f64| self.eval(t, to) * t.cos() * t.cos();
        match self {
            Longitudinal::Constant => crate::quad::gl16().composite(-FRAC_PI_2, FRAC_PI_2, 8, f),
            Longitudinal::Gaussian(g) => {
                let centre = 2.0 * g.shift - to;
                let s = 2.0 * g.beta;
                let (lo, hi) =
                    ((centre - 10.0 * s).max(-FRAC_PI_2), (centre + 10.0 * s).min(FRAC_PI_2));
                if lo >= hi { 0.0 } else { crate::quad::adaptive(lo, hi, 1e-12, f) }
            }
        }
    }
}
