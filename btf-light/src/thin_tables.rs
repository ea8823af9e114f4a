//! Environment light on thin cloth: per-vertex tables of the slab's environment terms
//! (`[TC eq. 7–8]` integrated over the hemispheres, with the per-vertex hemicube visibility
//! of `[S03 eq. 10]`).
//!
//! For each vertex and each side `s` (front `+N`, back `−N`, the frames of
//! [`SceneEnvironment`]) the environment's visible sources `(ω₀, ∫L dω)` give, with
//! `μ₀ = cos θ(ω₀)` on that side and `f` the exposure:
//!
//! - **transmission** seen from the *other* side at view cosine `μ_k`:
//!   `T_s(μ_k) = f · ϖ₀/(4π) · Σ F_t(τ₁, μ_k, μ₀) · μ₀ · L dω`, i.e. `∫ f_t L V μ₀ dω₀`
//!   over side `s`'s hemisphere (eq. 8 with `f_t` per unit irradiance, DESIGN.md §3), at
//!   `MU_NODES = 16` view cosines `μ_k = (k/15)²` — dense at grazing views, where
//!   `e^{−τ₁/μ}` changes fastest; `μ = 0` is exact and finite (`F_t → e^{−τ₁/μ₀}/μ₀`);
//!   the fragment shader interpolates linearly in `√μ`. Interpolation error under a
//!   uniform sky (against the exact `t(μ)`, 400 views): ≤ 1.0 % for `0.1 ≤ τ₁ ≤ 2` and
//!   `μ ≥ 0.05`, 1.7 % at `τ₁ = 0.05`, 3.8 % at `τ₁ = 0.02`, 1.9 % at `τ₁ = 5` (where `t` is
//!   already 5·10⁻³ of the light); 8 nodes would give 2–8 %.
//! - **reflection share** for an eye on side `s`: the point-light model scales the BTF by
//!   `1 − e^{−τ₁/μ} e^{−τ₁/μ₀}` (`f_r(τ₁)/f_r(∞)`, eq. 7); under an environment the
//!   shader scales the BTF's environment term by `1 − e^{−τ₁/μ} · A_s` with
//!   `A_s = Σ e^{−τ₁/μ₀} μ₀ L dω / Σ μ₀ L dω`, the `e^{−τ₁/μ₀}` averaged over the
//!   side's visible irradiance. Exact for a Lambertian BTF (`BTF ∝ μ₀`) and at both
//!   limits (`τ₁ → 0`: share 0; `τ₁ → ∞`: share 1); for other BTFs it weights `μ₀` by
//!   the irradiance rather than by the BTF's own light dependence.
//!
//! **Per-texel thickness** (`tau_texture`): `T_s` and `A_s` depend on the texel's `τ`, so
//! a textured material gets the tables at `TAU_NODES = 8` thicknesses `τ_j = τ_max (j/7)²`
//! (`τ_max = tau · max(1, largest texel)`; `τ_0 = 0` gives `A = 1`, `T = 0`, i.e. the
//! exact transparent limit), and the shader interpolates linearly in `τ` between the two
//! nodes around the texel's `τ` (bilinear with `√μ`). The nodes share the pass over the
//! sources: per source one exponential gives all `e^{−τ_j/μ₀}` as powers, and the kernel
//! [`ft_mu0`] needs no exponential (node exponentials `e^{−τ_j/μ_k}` precomputed). A
//! scalar-`τ` material fills only the last node (`τ_7 = τ₁`), which the shader reads
//! without interpolation.
//!
//! `f_t` of an isotropic slab depends on `μ, μ₀` only, which is what makes one table per
//! vertex side and τ node enough; Henyey–Greenstein also depends on the azimuth between
//! view and light and is refused by [`check_supported`]. The tables cost one pass over
//! the sources per vertex side and are recomputed when the environment, its rotation or
//! its exposure changes.

use crate::environment::SceneEnvironment;
use crate::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::PI;

/// View cosines tabulated per vertex side.
pub const MU_NODES: usize = 16;

/// Optical thicknesses tabulated per vertex side for a material with a τ texture.
pub const TAU_NODES: usize = 8;

/// Rows of one vertex side: per τ node `j`, `A_s(τ_j)` then `T_s(τ_j, μ_0…μ_15)`.
pub const ROWS_PER_SIDE: usize = TAU_NODES * (1 + MU_NODES);

/// vec4 per vertex: two sides × [`ROWS_PER_SIDE`].
pub const VEC4_PER_VERTEX: usize = 2 * ROWS_PER_SIDE;

/// View cosine of node `k`: `(k / (MU_NODES − 1))²`.
pub fn mu_node(k: usize) -> f64 {
    let u = k as f64 / (MU_NODES - 1) as f64;
    u * u
}

/// Optical thickness of node `j` for the node scale `tau_max`: `tau_max · (j / 7)²`.
pub fn tau_node(tau_max: f64, j: usize) -> f64 {
    let u = j as f64 / (TAU_NODES - 1) as f64;
    tau_max * u * u
}

/// Slab parameters of one material for the tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabParams {
    /// Optical thickness `τ₁` (scalar), or with `textured` the node scale: the largest
    /// `τ` of the texture, `tau · max(1, largest texel)`.
    pub tau: f64,
    /// Per-texel `τ`: tables at all [`TAU_NODES`] nodes; else only at the last (`τ = tau`).
    pub textured: bool,
    /// Single-scattering albedo `ϖ₀` (RGB).
    pub albedo: [f64; 3],
}

impl SlabParams {
    /// The τ nodes the tables hold (`j` with `τ_j > 0`; the rows of `τ_0 = 0` are fixed).
    pub fn nodes(&self) -> std::ops::Range<usize> {
        if self.textured { 1..TAU_NODES } else { TAU_NODES - 1..TAU_NODES }
    }
}

/// `1/(n+1)!` for `n = 0…8`: the series of `φ₁`.
#[rustfmt::skip]
const PHI1_SERIES: [f64; 9] = [
    1.0, 1.0 / 2.0, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0, 1.0 / 720.0, 1.0 / 5040.0,
    1.0 / 40320.0, 1.0 / 362880.0,
];

/// `φ₁(d) = (1 − e^{−d})/d` for `0 ≤ d ≤ 0.1` by its series (truncation `d⁹/10! < 3·10⁻¹⁶`).
#[inline]
fn phi1_small(d: f64) -> f64 {
    PHI1_SERIES.iter().rev().fold(0.0, |sum, &c| c - d * sum)
}

/// `F_t(τ, μ, μ₀) · μ₀` from precomputed `e = e^{−τ/μ}`, `e0 = e^{−τ/μ₀}` (`τ > 0`):
/// the quotient `(e − e0) μ₀/(μ − μ₀)` where `d = τ|μ − μ₀|/(μ μ₀) > 0.1` (relative
/// rounding `≈ ε/d`), else `e^{−min(τ/μ, τ/μ₀)} · τ/μ · φ₁(d)` — no exponential either way.
#[inline]
pub fn ft_mu0(tau: f64, mu: f64, mu0: f64, e: f64, e0: f64) -> f64 {
    Pair::new(mu, mu0).ft_mu0(tau, e, e0)
}

/// The parts of [`ft_mu0`] that depend on `(μ, μ₀)` only, shared by the τ nodes.
struct Pair {
    /// `|μ − μ₀|/(μ μ₀)`: `d = τ · c`.
    c: f64,
    /// `μ₀/(μ − μ₀)`.
    r: f64,
    /// `1/μ`.
    inv_mu: f64,
}

impl Pair {
    #[inline]
    fn new(mu: f64, mu0: f64) -> Pair {
        Pair { c: (mu - mu0).abs() / (mu * mu0), r: mu0 / (mu - mu0), inv_mu: 1.0 / mu }
    }

    #[inline]
    fn ft_mu0(&self, tau: f64, e: f64, e0: f64) -> f64 {
        let d = tau * self.c;
        if d > 0.1 { (e - e0) * self.r } else { e.max(e0) * tau * self.inv_mu * phi1_small(d) }
    }
}

/// One vertex side's terms: per τ node `j`, `A_s(τ_j)` then `T_s(τ_j, μ_k)`, RGB, exposure
/// included in `T`. Rows of nodes the slab does not use stay 0; `τ_j = 0` gives `A = 1`,
/// `T = 0`.
pub fn side_terms(
    env: &SceneEnvironment,
    frame: usize,
    slab: &SlabParams,
) -> [[[f64; 3]; 1 + MU_NODES]; TAU_NODES] {
    let nodes = slab.nodes();
    let taus: [f64; TAU_NODES] =
        std::array::from_fn(|j| if nodes.contains(&j) { tau_node(slab.tau, j) } else { 0.0 });
    // e^{−τ_j/μ_k}, 0 at μ = 0 (τ_j > 0).
    let e_node: [[f64; TAU_NODES]; MU_NODES] = std::array::from_fn(|k| {
        let mu = mu_node(k);
        taus.map(|t| if mu > 0.0 { (-t / mu).exp() } else { 0.0 })
    });
    let live: Vec<usize> = nodes.clone().filter(|&j| taus[j] > 0.0).collect();
    let mut irr = [0f64; 3];
    let mut a = [[0f64; 3]; TAU_NODES];
    let mut t = [[[0f64; 3]; MU_NODES]; TAU_NODES];
    let mut e0 = [1f64; TAU_NODES];
    env.visible_sources(frame, |d, power| {
        let mu0 = d[2] as f64;
        let p = power.map(|c| c as f64);
        exponentials(&taus, slab.textured, mu0, &mut e0);
        for c in 0..3 {
            irr[c] += p[c] * mu0;
        }
        for j in nodes.clone() {
            for c in 0..3 {
                a[j][c] += p[c] * mu0 * e0[j];
            }
        }
        for (k, e_k) in e_node.iter().enumerate() {
            let pair = Pair::new(mu_node(k), mu0);
            for &j in &live {
                let ft = pair.ft_mu0(taus[j], e_k[j], e0[j]);
                for c in 0..3 {
                    t[j][k][c] += ft * p[c];
                }
            }
        }
    });
    let f = env.exposure() as f64;
    let mut out = [[[0f64; 3]; 1 + MU_NODES]; TAU_NODES];
    for j in nodes {
        for c in 0..3 {
            out[j][0][c] = if irr[c] > 0.0 { a[j][c] / irr[c] } else { 0.0 };
            for k in 0..MU_NODES {
                out[j][1 + k][c] = f * slab.albedo[c] / (4.0 * PI) * t[j][k][c];
            }
        }
    }
    if slab.textured {
        out[0][0] = [1.0; 3];
    }
    out
}

/// `e0[j] = e^{−τ_j/μ₀}`: with τ nodes `τ_j = τ_max (j/7)²` from one exponential
/// `x = e^{−τ_max/(49 μ₀)}` as `x^{j²}` (`x^{(j+1)²} = x^{j²} · x^{2j+1}`, 49 products at
/// most: relative rounding ≤ 10⁻¹⁴); for a scalar τ the one exponential of the last node.
fn exponentials(taus: &[f64; TAU_NODES], textured: bool, mu0: f64, e0: &mut [f64; TAU_NODES]) {
    let last = TAU_NODES - 1;
    if !textured {
        e0[last] = (-taus[last] / mu0).exp();
        return;
    }
    let x = (-taus[last] / ((last * last) as f64 * mu0)).exp();
    let x2 = x * x;
    let (mut pow_sq, mut pow_odd) = (1.0, x);
    for e in e0.iter_mut() {
        *e = pow_sq;
        pow_sq *= pow_odd;
        pow_odd *= x2;
    }
}

/// Interpolates one vertex side's table (the `ROWS_PER_SIDE` rows of [`tables`]) as the
/// fragment shader does: linear in `√μ` between view nodes and linear in `τ` between
/// the τ nodes (a scalar-τ slab reads its last node). Returns `(A, T)`.
pub fn interpolate(
    side: &[[f32; 4]],
    slab: &SlabParams,
    mu: f64,
    tau: f64,
) -> ([f64; 3], [f64; 3]) {
    let (j0, j1, w) = tau_weights(slab, tau);
    let u = mu.clamp(0.0, 1.0).sqrt() * (MU_NODES - 1) as f64;
    let k = (u.floor() as usize).min(MU_NODES - 2);
    let s = u - k as f64;
    let row = |j: usize, i: usize| side[j * (1 + MU_NODES) + i].map(|v| v as f64);
    let lerp = |x: f64, y: f64, t: f64| x + t * (y - x);
    let mut a = [0.0; 3];
    let mut tr = [0.0; 3];
    for c in 0..3 {
        a[c] = lerp(row(j0, 0)[c], row(j1, 0)[c], w);
        let at = |j: usize| lerp(row(j, 1 + k)[c], row(j, 2 + k)[c], s);
        tr[c] = lerp(at(j0), at(j1), w);
    }
    (a, tr)
}

/// The two τ nodes around `tau` and the weight of the upper one (linear in τ).
fn tau_weights(slab: &SlabParams, tau: f64) -> (usize, usize, f64) {
    let last = TAU_NODES - 1;
    if !slab.textured || slab.tau <= 0.0 {
        return (last, last, 0.0);
    }
    let u = (tau / slab.tau).clamp(0.0, 1.0).sqrt() * last as f64;
    let j = (u.floor() as usize).min(last - 1);
    let (t0, t1) = (tau_node(slab.tau, j), tau_node(slab.tau, j + 1));
    (j, j + 1, ((tau - t0) / (t1 - t0)).clamp(0.0, 1.0))
}

/// The tables of every vertex (`VEC4_PER_VERTEX` vec4 each, zeros where `slab_of[v]` is
/// `None`): side 0 (front frame `v`) then side 1 (back frame `V + v`).
pub fn tables(env: &SceneEnvironment, slab_of: &[Option<SlabParams>]) -> Result<Vec<[f32; 4]>> {
    let n = env.vertices();
    if slab_of.len() != n {
        return Err(Error::Invalid(format!(
            "thin-cloth environment tables: {} vertex materials for {n} vertices",
            slab_of.len()
        )));
    }
    if !env.two_sided() {
        return Err(Error::Unsupported("thin cloth under a one-sided environment light".into()));
    }
    let mut out = vec![[0f32; 4]; n * VEC4_PER_VERTEX];
    out.par_chunks_mut(VEC4_PER_VERTEX).enumerate().for_each(|(v, dst)| {
        let Some(slab) = &slab_of[v] else { return };
        for side in 0..2 {
            let terms = side_terms(env, side * n + v, slab);
            for (i, rgb) in terms.iter().flatten().enumerate() {
                dst[side * ROWS_PER_SIDE + i] = [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32, 0.0];
            }
        }
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use btf_core::thin_slab::transmission_factor;

    #[test]
    fn nodes_span_grazing_to_normal() {
        assert_eq!(mu_node(0), 0.0);
        assert_eq!(mu_node(MU_NODES - 1), 1.0);
        assert!((1..MU_NODES).all(|k| mu_node(k) > mu_node(k - 1)));
        // μ = 0 is finite: F_t → e^{−τ/μ₀}/μ₀.
        let (tau, mu0) = (0.2f64, 0.5f64);
        let f = transmission_factor(tau, 0.0, mu0);
        assert!((f - (-tau / mu0).exp() / mu0).abs() < 1e-12, "{f}");
    }

    #[test]
    fn fast_kernel_equals_the_slab_function_on_both_branches() {
        // ft_mu0 with precomputed exponentials against transmission_factor · μ₀, near and
        // far from μ = μ₀ (both branches, d on both sides of 0.1) and at the grazing node.
        let mut worst = 0f64;
        for tau in [1e-6, 1e-3, 0.05, 0.6, 5.0, 1e4] {
            for k in 0..MU_NODES {
                let mu = mu_node(k);
                let e = if mu > 0.0 { (-tau / mu).exp() } else { 0.0 };
                for mu0 in [1e-4, 0.1, mu + 1e-7, mu * 1.05 + 1e-3, 0.5, 0.999, 1.0] {
                    let e0 = (-tau / mu0).exp();
                    let reference = transmission_factor(tau, mu, mu0) * mu0;
                    let fast = ft_mu0(tau, mu, mu0, e, e0);
                    let err = (fast - reference).abs() / reference.abs().max(1e-300);
                    assert!(
                        err < 1e-12 || fast == reference,
                        "τ {tau} μ {mu} μ₀ {mu0}: {fast} vs {reference}"
                    );
                    worst = worst.max(err);
                }
            }
        }
        eprintln!("worst relative difference {worst:.1e}");
    }

    #[test]
    fn powers_give_the_node_exponentials() {
        let tau_max = 3.0;
        let taus: [f64; TAU_NODES] = std::array::from_fn(|j| tau_node(tau_max, j));
        assert_eq!(taus[0], 0.0);
        assert_eq!(taus[TAU_NODES - 1], tau_max);
        for mu0 in [1e-3, 0.07, 0.5, 1.0] {
            let mut e0 = [0.0; TAU_NODES];
            exponentials(&taus, true, mu0, &mut e0);
            for (j, (&e, &t)) in e0.iter().zip(&taus).enumerate() {
                // exp's own conditioning: an argument rounded by ε·τ/μ₀ moves e^{−τ/μ₀} by
                // that much relatively; the 49 products add ≤ 49 ε.
                let want = (-t / mu0).exp();
                assert!(
                    (e - want).abs() <= (50.0 + 4.0 * t / mu0) * f64::EPSILON * want,
                    "μ₀ {mu0} node {j}: {e} vs {want}"
                );
            }
        }
    }

    #[test]
    fn tau_interpolation_hits_the_nodes_and_the_scalar_row() {
        let slab = SlabParams { tau: 2.0, textured: true, albedo: [1.0; 3] };
        assert_eq!(tau_weights(&slab, 0.0), (0, 1, 0.0));
        assert_eq!(tau_weights(&slab, 2.0), (TAU_NODES - 2, TAU_NODES - 1, 1.0));
        let (j0, j1, w) = tau_weights(&slab, tau_node(2.0, 3));
        assert!((j0 == 3 && w.abs() < 1e-12) || (j1 == 3 && (w - 1.0).abs() < 1e-12));
        let (j0, j1, w) = tau_weights(&slab, 0.5 * (tau_node(2.0, 4) + tau_node(2.0, 5)));
        assert_eq!((j0, j1), (4, 5));
        assert!((w - 0.5).abs() < 1e-12);
        let scalar = SlabParams { textured: false, ..slab };
        assert_eq!(tau_weights(&scalar, 0.7), (TAU_NODES - 1, TAU_NODES - 1, 0.0));
    }
}
