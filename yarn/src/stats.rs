//! Goodness-of-fit tests used to check samplers: the one-sample Kolmogorov–Smirnov test
//! (statistic and asymptotic p-value with Stephens' small-sample correction) and Pearson's
//! χ² test (bins with small expected counts pooled, p-value from the incomplete gamma
//! function). Public so that the reference renderer can test its own samplers the same way.

use crate::special::gamma_q;

/// The KS statistic `D = sup |F_n − F|` of `samples` against the CDF `cdf`.
pub fn ks_statistic(samples: &[f64], cdf: impl Fn(f64) -> f64) -> f64 {
    let mut s: Vec<f64> = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len() as f64;
    let mut d: f64 = 0.0;
    for (i, &x) in s.iter().enumerate() {
        let f = cdf(x);
        d = d.max((i as f64 + 1.0) / n - f).max(f - i as f64 / n);
    }
    d
}

/// The p-value of a KS statistic `d` for `n` samples (Kolmogorov's limit distribution at
/// `λ = (√n + 0.12 + 0.11/√n)·d`).
pub fn ks_p_value(d: f64, n: usize) -> f64 {
    let sn = (n as f64).sqrt();
    let lambda = (sn + 0.12 + 0.11 / sn) * d;
    if lambda < 0.2 {
        return 1.0;
    }
    let mut sum = 0.0;
    for k in 1..=100 {
        let k = k as f64;
        let term = 2.0 * (-1f64).powf(k - 1.0) * (-2.0 * k * k * lambda * lambda).exp();
        sum += term;
        if term.abs() < 1e-16 {
            break;
        }
    }
    sum.clamp(0.0, 1.0)
}

/// Pearson's χ² test of observed counts against expected counts (same total). Bins with
/// an expected count below `min_expected` are pooled together (in order) until the pool
/// reaches it. Returns `(χ², degrees of freedom, p-value)`.
pub fn chi2_test(observed: &[f64], expected: &[f64], min_expected: f64) -> (f64, usize, f64) {
    let mut pooled: Vec<(f64, f64)> = Vec::new();
    let (mut po, mut pe) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e >= min_expected {
            pooled.push((o, e));
        } else {
            po += o;
            pe += e;
            if pe >= min_expected {
                pooled.push((po, pe));
                po = 0.0;
                pe = 0.0;
            }
        }
    }
    if pe > 0.0 || po > 0.0 {
        match pooled.last_mut() {
            Some(last) => {
                last.0 += po;
                last.1 += pe;
            }
            None => pooled.push((po, pe)),
        }
    }
    let chi2: f64 =
        pooled.iter().map(|&(o, e)| if e > 0.0 { (o - e) * (o - e) / e } else { 0.0 }).sum();
    let dof = pooled.len().saturating_sub(1).max(1);
    (chi2, dof, gamma_q(dof as f64 / 2.0, chi2 / 2.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hash::KeyRng;

    #[test]
    fn ks_and_chi2_accept_a_true_sampler_and_reject_a_wrong_one() {
        let mut r = KeyRng::new(&[11]);
        let xs: Vec<f64> = (0..5000).map(|_| r.uniform()).collect();
        let d = ks_statistic(&xs, |x| x.clamp(0.0, 1.0));
        assert!(ks_p_value(d, xs.len()) > 0.01);
        let d2 = ks_statistic(&xs, |x| x.clamp(0.0, 1.0).powf(1.1));
        assert!(ks_p_value(d2, xs.len()) < 1e-3);
        let mut obs = vec![0.0; 10];
        for &x in &xs {
            obs[(x * 10.0) as usize] += 1.0;
        }
        let exp = vec![500.0; 10];
        let (_, dof, p) = chi2_test(&obs, &exp, 5.0);
        assert_eq!(dof, 9);
        assert!(p > 0.01, "p = {p}");
    }
}
