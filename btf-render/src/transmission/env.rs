//! Environment light on thin cloth: per-vertex tables of the slab's environment terms
//! (thin-cloth paper eq. 7–8 integrated over the hemispheres, with Sattler et al. 2003's
//! per-vertex hemicube visibility, eq. 10).
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
//! `f_t` of an isotropic slab depends on `μ, μ₀` only, which is what makes one table per
//! vertex side enough; Henyey–Greenstein also depends on the azimuth between view and
//! light and is refused (as are per-texel thicknesses, whose `τ₁` would need a table per
//! texel) by [`check_supported`]. The tables cost one pass over the sources per vertex
//! side and are recomputed when the environment, its rotation or its exposure changes.

use super::desc::{PhaseDesc, TransmissionDesc};
use crate::envlight::SceneEnvironment;
use crate::{Error, Result};
use btf_core::thin_slab::transmission_factor;
use rayon::prelude::*;
use std::f64::consts::PI;

/// View cosines tabulated per vertex side.
pub const MU_NODES: usize = 16;

/// vec4 per vertex: two sides × (`A_s`, `T_s(μ_0…μ_15)`).
pub const VEC4_PER_VERTEX: usize = 2 * (1 + MU_NODES);

/// View cosine of node `k`: `(k / (MU_NODES − 1))²`.
pub fn mu_node(k: usize) -> f64 {
    let u = k as f64 / (MU_NODES - 1) as f64;
    u * u
}

/// Slab parameters of one material for the tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabParams {
    /// Optical thickness `τ₁`.
    pub tau: f64,
    /// Single-scattering albedo `ϖ₀` (RGB).
    pub albedo: [f64; 3],
}

impl SlabParams {
    /// From a material's `transmission` table.
    pub fn of(desc: &TransmissionDesc) -> SlabParams {
        SlabParams { tau: desc.tau as f64, albedo: desc.albedo.rgb().map(|a| a as f64) }
    }
}

/// Refuses what the environment terms cannot represent, naming the material and key.
pub fn check_supported(desc: &TransmissionDesc, material: &str, two_sided: bool) -> Result<()> {
    let refuse = |what: String| Err(Error::Unsupported(format!("{material}: {what}")));
    if let PhaseDesc::Hg { hg } = desc.phase {
        return refuse(format!(
            "transmission.phase = {{ hg = {hg} }} under an environment light: the environment terms are tabulated in μ for isotropic scattering; use phase = \"isotropic\""
        ));
    }
    if desc.tau_texture.is_some() {
        return refuse(
            "transmission.tau_texture under an environment light: the environment terms are tabulated per vertex for the material's scalar tau; remove tau_texture".into(),
        );
    }
    if !two_sided {
        return refuse(
            "thin cloth under an environment light needs two_sided = true (the back-lit term integrates the far side's visibility)".into(),
        );
    }
    Ok(())
}

/// One vertex side's terms: `A_s` then `T_s(μ_k)`, RGB, exposure included in `T`.
pub fn side_terms(
    env: &SceneEnvironment,
    frame: usize,
    slab: &SlabParams,
) -> [[f64; 3]; 1 + MU_NODES] {
    let tau = slab.tau;
    let nodes: [(f64, f64); MU_NODES] = std::array::from_fn(|k| {
        let mu = mu_node(k);
        let e = if tau <= 0.0 {
            1.0
        } else if mu > 0.0 {
            (-tau / mu).exp()
        } else {
            0.0
        };
        (mu, e)
    });
    let mut irr = [0f64; 3];
    let mut a = [0f64; 3];
    let mut t = [[0f64; 3]; MU_NODES];
    env.visible_sources(frame, |d, power| {
        let mu0 = d[2] as f64;
        let e0 = (-tau / mu0).exp();
        let p = power.map(|c| c as f64);
        for c in 0..3 {
            irr[c] += p[c] * mu0;
            a[c] += p[c] * mu0 * e0;
        }
        for (tk, &(mu, e)) in t.iter_mut().zip(&nodes) {
            // F_t by the raw quotient where it is well conditioned (the same branch as
            // `transmission_factor`, with the node's exponential precomputed), else the series.
            let ft = if mu == 0.0 || tau * (mu0 - mu).abs() > mu * mu0 {
                (e - e0) / (mu - mu0)
            } else {
                transmission_factor(tau, mu, mu0)
            } * mu0;
            for c in 0..3 {
                tk[c] += ft * p[c];
            }
        }
    });
    let f = env.exposure() as f64;
    let mut out = [[0f64; 3]; 1 + MU_NODES];
    for c in 0..3 {
        out[0][c] = if irr[c] > 0.0 { a[c] / irr[c] } else { 0.0 };
        for k in 0..MU_NODES {
            out[1 + k][c] = f * slab.albedo[c] / (4.0 * PI) * t[k][c];
        }
    }
    out
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
            for (i, rgb) in terms.iter().enumerate() {
                dst[side * (1 + MU_NODES) + i] = [rgb[0] as f32, rgb[1] as f32, rgb[2] as f32, 0.0];
            }
        }
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // side_terms' quotient with precomputed node exponentials against
        // transmission_factor, near and far from μ = μ₀ and at the grazing node.
        for tau in [0.0, 1e-6, 0.05, 0.6, 5.0, 1e4] {
            for k in 0..MU_NODES {
                let mu = mu_node(k);
                let e = if tau <= 0.0 {
                    1.0
                } else if mu > 0.0 {
                    (-tau / mu).exp()
                } else {
                    0.0
                };
                for mu0 in [1e-4, 0.1, mu + 1e-7, 0.5, 0.999, 1.0] {
                    let e0 = (-tau / mu0).exp();
                    let reference = transmission_factor(tau, mu, mu0);
                    if mu == 0.0 || tau * (mu0 - mu).abs() > mu * mu0 {
                        let fast = (e - e0) / (mu - mu0);
                        let err = (fast - reference).abs() / reference.abs().max(1e-300);
                        assert!(
                            err < 1e-12 || fast == reference,
                            "τ {tau} μ {mu} μ₀ {mu0}: {fast} vs {reference}"
                        );
                    }
                }
            }
        }
    }
}
