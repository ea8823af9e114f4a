//! A Monte-Carlo solution of radiative transfer in a plane-parallel slab lit by a
//! collimated beam — the numerical reference for the first-order terms of
//! [`super`] (Chandrasekhar 1960, Chap. IX; [TC eq. 4–5]).
//!
//! Photons enter at depth 0 with direction cosine `μ₀`; the first collision is forced
//! inside the slab (depth drawn from the truncated exponential, weight `1 − e^{−τ₁/μ₀}`,
//! the unscattered remainder being the direct transmission `e^{−τ₁/μ₀}`). After each
//! collision the weight is multiplied by `ϖ₀` and a new direction drawn from the phase
//! function; free paths are exponential in optical depth. Two estimators of the emergent
//! BSDF (radiance per unit surface irradiance, as [`super::Slab::f_r`]) are kept:
//!
//! - a **point (next-event) estimator** at given exit directions: each collision at depth
//!   `t` adds `w ϖ₀ p(cos Θ) e^{−t/μ}/(4π μ)` (reflection; `τ₁ − t` for transmission) —
//!   the collision-density form of the transfer integral, low variance;
//! - an **analog tally** of escaping photons in bins of exit cosine, converted with the
//!   bin's projected solid angle `π(μ_b² − μ_a²)` — independent of the point estimator.
//!
//! Each is split into first-order (exactly one scattering) and all orders. Photons are
//! simulated in a fixed number of chunks with seeds derived from one seed, so results are
//! deterministic whatever the thread count.

use super::{Phase, Slab};
use rayon::prelude::*;
use std::f64::consts::PI;

/// A direction of exit: cosine `mu` to the face normal and azimuth `phi_deg` from the
/// plane of incidence (0 = the side the beam travels towards).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExitDir {
    /// Cosine to the normal of the face the light leaves from, `(0, 1]`.
    pub mu: f64,
    /// Azimuth from the incident beam's horizontal direction, degrees.
    pub phi_deg: f64,
}

/// Simulation size and seed.
#[derive(Debug, Clone, Copy)]
pub struct McParams {
    /// Photons launched.
    pub photons: u64,
    /// Seed of the deterministic generator.
    pub seed: u64,
    /// Bins of exit cosine for the analog tally (uniform in `μ²`).
    pub bins: usize,
    /// Scattering orders followed before a photon is dropped.
    pub max_orders: u32,
}

impl Default for McParams {
    fn default() -> Self {
        McParams { photons: 200_000, seed: 0x5eed, bins: 8, max_orders: 400 }
    }
}

/// A mean and its standard error.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Estimate {
    /// Sample mean.
    pub mean: f64,
    /// Standard error of the mean.
    pub std_err: f64,
}

/// What a simulation returns; vectors are indexed like the exit directions or bins.
#[derive(Debug, Clone, Default)]
pub struct McResult {
    /// Point estimator, reflection, first order.
    pub reflect_single: Vec<Estimate>,
    /// Point estimator, reflection, all orders.
    pub reflect_all: Vec<Estimate>,
    /// Point estimator, transmission, first order.
    pub transmit_single: Vec<Estimate>,
    /// Point estimator, transmission, all orders.
    pub transmit_all: Vec<Estimate>,
    /// Analog tally per cosine bin: reflection, first order / all orders.
    pub reflect_bins: [Vec<Estimate>; 2],
    /// Analog tally per cosine bin: transmission, first order / all orders.
    pub transmit_bins: [Vec<Estimate>; 2],
    /// Bin edges in `μ` (`bins + 1` values from 0 to 1).
    pub bin_edges: Vec<f64>,
}

/// SplitMix64: a small, fast, well-mixed deterministic generator.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Rotates `dir` (unit) by polar `cos_t` and azimuth `phi` about itself.
fn scatter(dir: [f64; 3], cos_t: f64, phi: f64) -> [f64; 3] {
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (sp, cp) = phi.sin_cos();
    let [x, y, z] = dir;
    if z.abs() > 0.99999 {
        return [sin_t * cp, sin_t * sp, cos_t * z.signum()];
    }
    let s = (1.0 - z * z).sqrt();
    [
        sin_t * (x * z * cp - y * sp) / s + x * cos_t,
        sin_t * (y * z * cp + x * sp) / s + y * cos_t,
        -sin_t * cp * s + z * cos_t,
    ]
}

/// Per-photon sums: `[reflect single, reflect all, transmit single, transmit all]` per exit
/// direction, then the four analog bin sets.
struct Tally {
    point: Vec<[f64; 4]>,
    bins: Vec<[f64; 4]>,
}

struct Accum {
    sum: Vec<f64>,
    sq: Vec<f64>,
}

impl Accum {
    fn new(n: usize) -> Accum {
        Accum { sum: vec![0.0; n], sq: vec![0.0; n] }
    }
    fn add(&mut self, t: &Tally) {
        let vals = t.point.iter().chain(&t.bins).flat_map(|v| v.iter());
        for (k, v) in vals.enumerate() {
            self.sum[k] += v;
            self.sq[k] += v * v;
        }
    }
    fn merge(mut self, o: Accum) -> Accum {
        for k in 0..self.sum.len() {
            self.sum[k] += o.sum[k];
            self.sq[k] += o.sq[k];
        }
        self
    }
}

fn walk(
    slab: &Slab,
    mu0: f64,
    exits: &[[f64; 3]],
    edges: &[f64],
    rng: &mut Rng,
    t: &mut Tally,
    p: &McParams,
) {
    let tau = slab.tau;
    let sin0 = (1.0 - mu0 * mu0).max(0.0).sqrt();
    let mut dir = [sin0, 0.0, mu0];
    let hit = -(-tau / mu0).exp_m1();
    let mut w = hit;
    let mut z = -mu0 * (1.0 - rng.next_f64() * hit).ln();
    let k4 = slab.albedo / (4.0 * PI);
    for order in 1..=p.max_orders {
        let single = order == 1;
        for (e, o) in exits.iter().enumerate() {
            let mu = o[2];
            let c = w * k4 / mu;
            let r =
                c * slab.phase.value(dir[0] * o[0] + dir[1] * o[1] - dir[2] * mu) * (-z / mu).exp();
            let tr = c
                * slab.phase.value(dir[0] * o[0] + dir[1] * o[1] + dir[2] * mu)
                * (-(tau - z) / mu).exp();
            t.point[e][1] += r;
            t.point[e][3] += tr;
            if single {
                t.point[e][0] += r;
                t.point[e][2] += tr;
            }
        }
        w *= slab.albedo;
        if w <= 0.0 {
            return;
        }
        let cos_t = slab.phase.sample_cos(rng.next_f64());
        dir = scatter(dir, cos_t, 2.0 * PI * rng.next_f64());
        let z_next = z - (1.0 - rng.next_f64()).ln() * dir[2];
        if z_next <= 0.0 || z_next >= tau {
            let up = z_next <= 0.0;
            let mu = dir[2].abs();
            let bin = edges.partition_point(|&e| e < mu).clamp(1, edges.len() - 1) - 1;
            let col = if up { 0 } else { 2 };
            t.bins[bin][col + 1] += w;
            if single {
                t.bins[bin][col] += w;
            }
            return;
        }
        z = z_next;
    }
}

/// Simulates the slab lit at `mu0` and estimates the emergent BSDFs at `exits`.
pub fn simulate(slab: &Slab, mu0: f64, exits: &[ExitDir], params: &McParams) -> McResult {
    const CHUNKS: u64 = 64;
    let exit_vecs: Vec<[f64; 3]> = exits
        .iter()
        .map(|e| {
            let s = (1.0 - e.mu * e.mu).max(0.0).sqrt();
            let (sp, cp) = e.phi_deg.to_radians().sin_cos();
            [s * cp, s * sp, e.mu]
        })
        .collect();
    let nb = params.bins.max(1);
    let edges: Vec<f64> = (0..=nb).map(|k| (k as f64 / nb as f64).sqrt()).collect();
    let n_vals = 4 * (exits.len() + nb);
    let acc = (0..CHUNKS)
        .into_par_iter()
        .map(|c| {
            let mut rng = Rng(params.seed ^ (c.wrapping_mul(0xd1b5_4a32_d192_ed03)));
            let mut acc = Accum::new(n_vals);
            let n = params.photons / CHUNKS + u64::from(c < params.photons % CHUNKS);
            let mut t = Tally { point: vec![[0.0; 4]; exits.len()], bins: vec![[0.0; 4]; nb] };
            for _ in 0..n {
                t.point.iter_mut().chain(t.bins.iter_mut()).for_each(|v| *v = [0.0; 4]);
                walk(slab, mu0, &exit_vecs, &edges, &mut rng, &mut t, params);
                acc.add(&t);
            }
            acc
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold(Accum::new(n_vals), Accum::merge);
    let n = params.photons.max(1) as f64;
    let est = |k: usize, scale: f64| {
        let mean = acc.sum[k] / n;
        let var = (acc.sq[k] / n - mean * mean).max(0.0);
        Estimate { mean: mean * scale, std_err: (var / n).sqrt() * scale }
    };
    let point = |col: usize| (0..exits.len()).map(|e| est(4 * e + col, 1.0)).collect::<Vec<_>>();
    let bins = |col: usize| {
        (0..nb)
            .map(|b| {
                let proj = PI * (edges[b + 1].powi(2) - edges[b].powi(2));
                est(4 * (exits.len() + b) + col, 1.0 / proj)
            })
            .collect::<Vec<_>>()
    };
    McResult {
        reflect_single: point(0),
        reflect_all: point(1),
        transmit_single: point(2),
        transmit_all: point(3),
        reflect_bins: [bins(0), bins(1)],
        transmit_bins: [bins(2), bins(3)],
        bin_edges: edges,
    }
}

/// One row of the first-order error table.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ErrorRow {
    /// Optical thickness.
    pub tau: f64,
    /// Largest `|f_first − MC_first| / MC_first` (formula vs first-order Monte Carlo),
    /// reflection and transmission.
    pub single_rel_err: f64,
    /// Largest `(MC_all − f_first) / MC_all` for reflection (the share of multiple scattering).
    pub reflect_rel_err: f64,
    /// Same for transmission.
    pub transmit_rel_err: f64,
    /// Largest relative standard error of the Monte-Carlo values used.
    pub mc_rel_std_err: f64,
}

/// Light and exit cosines of the table: `μ₀ ∈ {1, 0.5}`, `μ ∈ {0.3, 0.5, 0.7, 1}`.
pub const TABLE_MU0: [f64; 2] = [1.0, 0.5];
/// Exit cosines of the table.
pub const TABLE_MU: [f64; 4] = [0.3, 0.5, 0.7, 1.0];

/// The error of the first-order terms against Monte Carlo for each `τ₁` (isotropic
/// phase, albedo `albedo`), maximised over [`TABLE_MU0`] × [`TABLE_MU`].
pub fn first_order_error_table(taus: &[f64], albedo: f64, params: &McParams) -> Vec<ErrorRow> {
    let exits: Vec<ExitDir> = TABLE_MU.iter().map(|&mu| ExitDir { mu, phi_deg: 0.0 }).collect();
    taus.iter()
        .map(|&tau| {
            let slab = Slab { tau, albedo, phase: Phase::Isotropic };
            let mut row = ErrorRow {
                tau,
                single_rel_err: 0.0,
                reflect_rel_err: 0.0,
                transmit_rel_err: 0.0,
                mc_rel_std_err: 0.0,
            };
            for &mu0 in &TABLE_MU0 {
                let mc = simulate(&slab, mu0, &exits, params);
                for (e, x) in exits.iter().enumerate() {
                    let (fr, ft) = (slab.f_r(x.mu, mu0, 0.0), slab.f_t(x.mu, mu0, 0.0));
                    let rel = |a: f64, b: Estimate| (a - b.mean).abs() / b.mean;
                    row.single_rel_err = row
                        .single_rel_err
                        .max(rel(fr, mc.reflect_single[e]))
                        .max(rel(ft, mc.transmit_single[e]));
                    row.reflect_rel_err = row.reflect_rel_err.max(rel(fr, mc.reflect_all[e]));
                    row.transmit_rel_err = row.transmit_rel_err.max(rel(ft, mc.transmit_all[e]));
                    for v in [
                        mc.reflect_single[e],
                        mc.transmit_single[e],
                        mc.reflect_all[e],
                        mc.transmit_all[e],
                    ] {
                        row.mc_rel_std_err = row.mc_rel_std_err.max(v.std_err / v.mean);
                    }
                }
            }
            row
        })
        .collect()
}
