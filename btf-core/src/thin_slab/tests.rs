//! Tests of the first-order slab terms: the closed forms against quadrature of the
//! source integral, the removable singularity at `μ = μ₀`, the `μ → 0` limits, and the
//! Monte-Carlo slab (first order and all orders).

use super::monte_carlo::{ExitDir, McParams, first_order_error_table, simulate};
use super::*;

/// `f_t / (ϖ₀p/4π)` by composite Simpson on the source integral
/// `1/(μμ₀) ∫₀^τ e^{−t/μ₀} e^{−(τ−t)/μ} dt` — no cancellation anywhere.
fn transmission_quadrature(tau: f64, mu: f64, mu0: f64) -> f64 {
    let n = panels(tau, mu, mu0);
    let h = tau / n as f64;
    let f = |t: f64| (-t / mu0 - (tau - t) / mu).exp();
    let mut s = f(0.0) + f(tau);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0 / (mu * mu0)
}

fn reflection_quadrature(tau: f64, mu: f64, mu0: f64) -> f64 {
    let n = panels(tau, mu, mu0);
    let h = tau / n as f64;
    let f = |t: f64| (-t / mu0 - t / mu).exp();
    let mut s = f(0.0) + f(tau);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0 / (mu * mu0)
}

/// Simpson panels with `k·h ≤ 0.01` (`k` the steepest exponent rate), so the error
/// `(k h)⁴/180` stays below 1e-10 relative.
fn panels(tau: f64, mu: f64, mu0: f64) -> usize {
    let k = 1.0 / mu + 1.0 / mu0;
    ((100.0 * k * tau).ceil() as usize).max(2000).next_multiple_of(2)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn closed_forms_match_the_source_integral() {
    for &tau in &[1e-4, 0.05, 0.2, 1.0, 2.0, 5.0] {
        for &mu in &[0.05, 0.3, 0.7, 1.0] {
            for &mu0 in &[0.1, 0.5, 0.9, 1.0] {
                let (r, rq) =
                    (reflection_factor(tau, mu, mu0), reflection_quadrature(tau, mu, mu0));
                let (t, tq) =
                    (transmission_factor(tau, mu, mu0), transmission_quadrature(tau, mu, mu0));
                // Simpson error below 1e-10 (see `panels`); the closed forms are exact.
                assert!(rel(r, rq) < 1e-9, "f_r τ={tau} μ={mu} μ₀={mu0}: {r} vs {rq}");
                assert!(rel(t, tq) < 1e-9, "f_t τ={tau} μ={mu} μ₀={mu0}: {t} vs {tq}");
            }
        }
    }
}

#[test]
fn design_formulas_as_written() {
    // DESIGN.md §3 quotients, where they are well conditioned.
    let s = Slab { tau: 0.3, albedo: 0.8, phase: Phase::Isotropic };
    let (mu, mu0) = (0.4, 0.9);
    let k = 0.8 / (4.0 * PI);
    let fr = k * (1.0 - (-0.3f64 * (1.0 / mu + 1.0 / mu0)).exp()) / (mu + mu0);
    let ft = k * ((-0.3f64 / mu).exp() - (-0.3f64 / mu0).exp()) / (mu - mu0);
    assert!(rel(s.f_r(mu, mu0, 0.0), fr) < 1e-14);
    assert!(rel(s.f_t(mu, mu0, 0.0), ft) < 1e-14);
}

#[test]
fn removable_singularity_at_mu_equal_mu0() {
    for &tau in &[1e-6f64, 0.05, 0.2, 2.0] {
        for &mu0 in &[0.05, 0.5, 1.0] {
            let limit = tau * (-tau / mu0).exp() / (mu0 * mu0);
            let at = transmission_factor(tau, mu0, mu0);
            assert!(rel(at, limit) < 1e-14, "τ={tau} μ₀={mu0}: {at} vs {limit}");
            for &off in &[1e-7, -1e-7] {
                let mu = mu0 + off;
                if mu > 1.0 {
                    continue;
                }
                let v = transmission_factor(tau, mu, mu0);
                let q = transmission_quadrature(tau, mu, mu0);
                assert!(rel(v, q) < 1e-9, "τ={tau} μ₀={mu0} μ={mu}: {v} vs {q}");
                // And it moves smoothly: within |f'|·1e-7 of the limit.
                assert!(rel(v, limit) < 1e-7 * (1.0 + 2.0 * tau / mu0) / mu0 * 2.0 + 1e-12);
            }
        }
    }
}

#[test]
fn the_raw_quotient_fails_in_f32_where_the_series_does_not() {
    // Why the series: in f32 (the GPU) the raw quotient 1e-7 away from μ₀ is garbage.
    let (tau, mu0) = (0.1f32, 0.5f32);
    let mu = mu0 + 1e-7;
    let raw = ((-tau / mu).exp() - (-tau / mu0).exp()) / (mu - mu0);
    let limit = (tau * (-tau / mu0).exp() / (mu0 * mu0)) as f64;
    assert!(rel(raw as f64, limit) > 0.05, "raw f32 quotient {raw} vs {limit}");
    let series = transmission_factor(tau as f64, mu as f64, mu0 as f64);
    assert!(rel(series, limit) < 1e-6);
}

#[test]
fn grazing_view_limits_are_finite_and_right() {
    let s = Slab { tau: 0.2, albedo: 1.0, phase: Phase::Isotropic };
    let k = 1.0 / (4.0 * PI);
    for &mu0 in &[0.2, 0.6, 1.0] {
        let fr_lim = k / mu0;
        let ft_lim = k * (-0.2 / mu0).exp() / mu0;
        for &mu in &[0.0, 1e-300, 1e-12, 1e-7] {
            let (fr, ft) = (s.f_r(mu, mu0, 0.0), s.f_t(mu, mu0, 0.0));
            assert!(fr.is_finite() && ft.is_finite(), "μ={mu}");
            // f_r(μ) = lim + O(μ/μ₀²), f_t likewise.
            let tol = 1e-12 + 4.0 * mu / (mu0 * mu0);
            assert!(rel(fr, fr_lim) < tol, "f_r μ={mu} μ₀={mu0}: {fr} vs {fr_lim}");
            assert!(rel(ft, ft_lim) < tol, "f_t μ={mu} μ₀={mu0}: {ft} vs {ft_lim}");
        }
        // Grazing light: the values per perpendicular irradiance vanish.
        assert_eq!(reflection_per_perpendicular(&s, mu0, 0.0, 0.0), 0.0);
        assert_eq!(transmission_per_perpendicular(&s, mu0, 0.0, 0.0), 0.0);
    }
    // Both grazing: per-perpendicular values stay bounded by ϖ₀/(4π).
    for &m in &[1e-300, 1e-20, 1e-8] {
        let v = reflection_per_perpendicular(&s, m, m, 0.0);
        assert!(v.is_finite() && v <= k * (1.0 + 1e-12), "{v}");
        assert!(transmission_per_perpendicular(&s, m, m, 0.0).is_finite());
    }
    assert_eq!(direct_transmittance(0.2, 0.0), 0.0);
    assert_eq!(direct_transmittance(0.0, 0.0), 1.0);
}

#[test]
fn thickness_limits() {
    for &(mu, mu0) in &[(0.3, 0.8), (1.0, 1.0), (0.5, 0.5)] {
        assert_eq!(transmission_factor(0.0, mu, mu0), 0.0);
        assert_eq!(reflection_factor(0.0, mu, mu0), 0.0);
        assert_eq!(transmission_factor(f64::INFINITY, mu, mu0), 0.0);
        assert!(rel(reflection_factor(f64::INFINITY, mu, mu0), 1.0 / (mu + mu0)) < 1e-15);
        assert!(transmission_factor(1e3, mu, mu0) < 1e-300);
        assert_eq!(reflection_share(1e3, mu, mu0), 1.0);
        assert!(reflection_share(1e-9, mu, mu0) < 1e-8);
        // Small τ: both ≈ τ/(μμ₀).
        let t = 1e-8;
        assert!(rel(reflection_factor(t, mu, mu0), t / (mu * mu0)) < 1e-7);
        assert!(rel(transmission_factor(t, mu, mu0), t / (mu * mu0)) < 1e-7);
    }
}

#[test]
fn henyey_greenstein_is_normalised_and_sampled_right() {
    for &g in &[-0.5, 0.0, 0.3, 0.8] {
        let p = Phase::HenyeyGreenstein { g };
        // ∫ p dω / 4π = ½ ∫ p(c) dc = 1, and the mean cosine is g.
        let n = 20000;
        let (mut norm, mut mean, mut sampled) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let c = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
            norm += 0.5 * p.value(c) * 2.0 / n as f64;
            mean += 0.5 * c * p.value(c) * 2.0 / n as f64;
            sampled += p.sample_cos((i as f64 + 0.5) / n as f64) / n as f64;
        }
        assert!((norm - 1.0).abs() < 1e-3, "g={g}: {norm}");
        assert!((mean - g).abs() < 1e-3, "g={g}: {mean}");
        assert!((sampled - g).abs() < 1e-3, "g={g}: {sampled}");
    }
}

fn mc_params(photons: u64) -> McParams {
    McParams { photons, ..Default::default() }
}

#[test]
fn first_order_terms_equal_monte_carlo_single_scattering() {
    // The formula is exact for one scattering: the MC first-order tally must agree to
    // within 4 standard errors (and, with these photon counts, to better than 1 %).
    let exits: Vec<ExitDir> =
        [0.3, 0.6, 1.0].iter().map(|&mu| ExitDir { mu, phi_deg: 0.0 }).collect();
    for &tau in &[0.05, 0.2, 1.0] {
        let slab = Slab { tau, albedo: 0.9, phase: Phase::Isotropic };
        for &mu0 in &[1.0, 0.5] {
            let mc = simulate(&slab, mu0, &exits, &mc_params(60_000));
            for (e, x) in exits.iter().enumerate() {
                for (f, est) in [
                    (slab.f_r(x.mu, mu0, 0.0), mc.reflect_single[e]),
                    (slab.f_t(x.mu, mu0, 0.0), mc.transmit_single[e]),
                ] {
                    let dev = (f - est.mean).abs();
                    assert!(
                        dev < 4.0 * est.std_err && dev < 0.01 * f,
                        "τ={tau} μ₀={mu0} μ={}: {f} vs {est:?}",
                        x.mu
                    );
                }
            }
            // The analog tally (independent of the point estimator) agrees with the
            // point estimator's all-orders values averaged over each bin, loosely.
            for (b, bin) in mc.reflect_bins[0].iter().enumerate() {
                let (lo, hi) = (mc.bin_edges[b], mc.bin_edges[b + 1]);
                let avg = bin_average(|mu| slab.f_r(mu, mu0, 0.0), lo, hi);
                assert!(
                    (bin.mean - avg).abs() < 4.0 * bin.std_err + 0.02 * avg,
                    "bin {b}: {bin:?} vs {avg}"
                );
            }
        }
    }
}

/// `∫ f μ dμ / ∫ μ dμ` over `[lo, hi]` (the projected-solid-angle bin average).
fn bin_average(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    let n = 200;
    let h = (hi - lo) / n as f64;
    let s: f64 = (0..n).map(|i| lo + (i as f64 + 0.5) * h).map(|m| f(m) * m * h).sum();
    s / (0.5 * (hi * hi - lo * lo))
}

#[test]
fn henyey_greenstein_single_scattering_matches_monte_carlo() {
    let slab = Slab { tau: 0.2, albedo: 1.0, phase: Phase::HenyeyGreenstein { g: 0.5 } };
    let mu0: f64 = 0.7;
    let exits: Vec<ExitDir> = [(0.5, 0.0), (0.5, 180.0), (0.9, 90.0)]
        .iter()
        .map(|&(mu, phi_deg)| ExitDir { mu, phi_deg })
        .collect();
    let mc = simulate(&slab, mu0, &exits, &mc_params(60_000));
    let sin0 = (1.0 - mu0 * mu0).sqrt();
    for (e, x) in exits.iter().enumerate() {
        let s = (1.0 - x.mu * x.mu).sqrt() * x.phi_deg.to_radians().cos();
        let (cos_r, cos_t) = (sin0 * s - mu0 * x.mu, sin0 * s + mu0 * x.mu);
        for (f, est) in [
            (slab.f_r(x.mu, mu0, cos_r), mc.reflect_single[e]),
            (slab.f_t(x.mu, mu0, cos_t), mc.transmit_single[e]),
        ] {
            assert!(
                (f - est.mean).abs() < 4.0 * est.std_err + 1e-3 * f,
                "exit {x:?}: {f} vs {est:?}"
            );
        }
    }
}

#[test]
fn monte_carlo_is_deterministic() {
    let slab = Slab { tau: 0.1, albedo: 0.5, phase: Phase::Isotropic };
    let exits = [ExitDir { mu: 0.5, phi_deg: 0.0 }];
    let a = simulate(&slab, 0.8, &exits, &mc_params(5_000));
    let b = simulate(&slab, 0.8, &exits, &mc_params(5_000));
    assert_eq!(a.reflect_all, b.reflect_all);
    assert_eq!(a.transmit_bins, b.transmit_bins);
}

#[test]
fn multiple_scattering_share_grows_with_thickness() {
    // The first-order terms undershoot the full solution by a share that grows with τ₁
    // (the numbers themselves go to BENCHMARKS.md via `btf thin validate`).
    let rows = first_order_error_table(&[0.05, 0.2, 1.0], 1.0, &mc_params(20_000));
    assert!(rows[0].single_rel_err < 0.02, "{rows:?}");
    assert!(rows[0].reflect_rel_err < rows[1].reflect_rel_err);
    assert!(rows[1].reflect_rel_err < rows[2].reflect_rel_err);
    assert!(rows[2].transmit_rel_err > 0.1, "{rows:?}");
}
