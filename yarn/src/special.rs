//! Special functions the samplers and the statistical tests need: `erf`/`erfc` (power
//! series below 3, Lentz's continued fraction above: ≈1e-14 relative), the standard normal
//! CDF and its inverse (Acklam's rational start, then Newton on our own CDF so that
//! sampling and pdf stay consistent), `ln Γ` (Lanczos) and the regularised incomplete
//! gamma function `Q(a, x)` (series / continued fraction), which gives χ² p-values.

use std::f64::consts::PI;

/// The error function.
pub fn erf(x: f64) -> f64 {
    if x.abs() < 3.0 { erf_series(x) } else { x.signum() * (1.0 - erfc_cf(x.abs())) }
}

/// The complementary error function `1 − erf(x)`, accurate in the far tail.
pub fn erfc(x: f64) -> f64 {
    if x >= 3.0 {
        erfc_cf(x)
    } else if x <= -3.0 {
        2.0 - erfc_cf(-x)
    } else {
        1.0 - erf_series(x)
    }
}

fn erf_series(x: f64) -> f64 {
    // erf x = 2/√π · e^{−x²} Σ 2^n x^{2n+1} / (1·3·…·(2n+1)): all terms positive.
    let x2 = x * x;
    let mut term = x;
    let mut sum = x;
    let mut n = 0.0;
    while term.abs() > 1e-17 * sum.abs() {
        n += 1.0;
        term *= 2.0 * x2 / (2.0 * n + 1.0);
        sum += term;
        if n > 200.0 {
            break;
        }
    }
    2.0 / PI.sqrt() * (-x2).exp() * sum
}

fn erfc_cf(x: f64) -> f64 {
    // erfc x = e^{−x²}/√π · 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + …)))), modified Lentz.
    let tiny = 1e-300;
    let mut f = x;
    let mut c = x;
    let mut d = 0.0;
    for n in 1..300 {
        let a = n as f64 * 0.5;
        d = x + a * d;
        d = if d.abs() < tiny { tiny } else { d };
        c = x + a / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        let delta = c * d;
        f *= delta;
        if (delta - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (-x * x).exp() / (PI.sqrt() * f)
}

/// The standard normal CDF `Φ(x)`.
pub fn norm_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// The standard normal density.
pub fn norm_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * PI).sqrt()
}

/// The inverse of [`norm_cdf`] for `p ∈ (0, 1)`.
pub fn norm_inv(p: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    let mut x = acklam(p);
    // Newton on Φ(x) − p (in the lower tail on log Φ, which stays well scaled).
    for _ in 0..4 {
        let (c, d) = (norm_cdf(x), norm_pdf(x));
        if d <= 0.0 {
            break;
        }
        let step = if p < 1e-3 { (c.ln() - p.ln()) * c / d } else { (c - p) / d };
        x -= step;
        if step.abs() < 1e-15 * x.abs().max(1.0) {
            break;
        }
    }
    x
}

fn acklam(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] =
        [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// Solves `f(x) = 0` for an increasing `f` on `[lo, hi]` (`f(lo) ≤ 0 ≤ f(hi)`) by Newton
/// steps from `x0`, safeguarded by bisection of the bracket; `df` is `f'`.
pub fn solve_increasing(
    f: impl Fn(f64) -> f64,
    df: impl Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    x0: f64,
) -> f64 {
    let mut x = x0.clamp(lo, hi);
    for _ in 0..200 {
        let e = f(x);
        if e == 0.0 {
            return x;
        }
        if e > 0.0 {
            hi = x
        } else {
            lo = x
        }
        if hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
            return 0.5 * (lo + hi);
        }
        let d = df(x);
        let step = if d > 0.0 { e / d } else { f64::NAN };
        let nx = x - step;
        if nx > lo && nx < hi {
            if step.abs() <= 2.0 * f64::EPSILON * nx.abs().max(1e-300) {
                return nx;
            }
            x = nx;
        } else {
            x = 0.5 * (lo + hi);
        }
    }
    x
}

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, 9 terms).
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.5203681218851,
        -1259.1392167224028,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507343278686905,
        -0.13857109526572012,
        9.984_369_578_019_572e-6,
        1.5056327351493116e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised upper incomplete gamma function `Q(a, x) = Γ(a, x)/Γ(a)`.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_pre = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // Series for P(a, x).
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        1.0 - sum * ln_pre.exp()
    } else {
        // Continued fraction for Q(a, x), modified Lentz.
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        ln_pre.exp() * h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_normal_and_gamma_match_known_values() {
        // Reference values (Abramowitz & Stegun tables, 15 digits).
        assert!((erf(0.5) - 0.520_499_877_813_047).abs() < 1e-14);
        assert!((erf(2.0) - 0.995_322_265_018_953).abs() < 1e-14);
        assert!((erfc(4.0) / 1.541_725_790_028_002e-8 - 1.0).abs() < 1e-12);
        assert!((erfc(-1.0) - 1.842_700_792_949_715).abs() < 1e-14);
        for p in [1e-12, 1e-5, 0.01, 0.3, 0.5, 0.77, 0.999, 1.0 - 1e-9] {
            let x = norm_inv(p);
            assert!((norm_cdf(x) / p - 1.0).abs() < 1e-10, "p = {p}: Φ(x) = {}", norm_cdf(x));
        }
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-13);
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
        // χ² with 2 degrees of freedom: Q(1, x/2) = e^{−x/2}.
        for x in [0.1, 1.0, 3.0, 10.0, 40.0] {
            assert!((gamma_q(1.0, x / 2.0) - (-x / 2.0f64).exp()).abs() < 1e-13);
        }
        // χ² with 10 dof at 18.307 has p = 0.05.
        assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
    }
}
