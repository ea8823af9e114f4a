//! Numerical quadrature: Gauss–Legendre rules of any order (nodes by Newton's method on the
//! Legendre recurrence), composite rules over panels, and an adaptive Gauss–Legendre
//! integrator (7-point rule on an interval against the sum over its two halves, recursive
//! bisection until they agree). Used for arc lengths (curve), the p(R) distribution
//! (fiber), BCSDF normalisation and ambient tables (bcsdf) and Crane's arc length (knit).

use std::sync::OnceLock;

/// A Gauss–Legendre rule on `[−1, 1]`.
#[derive(Debug, Clone)]
pub struct GaussLegendre {
    /// Nodes, increasing.
    pub nodes: Vec<f64>,
    /// Weights (sum 2).
    pub weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule (`n ≥ 1`), exact for polynomials of degree `2n − 1`.
    pub fn new(n: usize) -> Self {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            // Tricomi's initial guess for the i-th root (from the top), then Newton.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d.is_finite() {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[n - 1 - i] = x;
            nodes[i] = -x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        GaussLegendre { nodes, weights }
    }

    /// `∫_a^b f` with this rule.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        let (h, m) = (0.5 * (b - a), 0.5 * (a + b));
        let mut s = 0.0;
        for (x, w) in self.nodes.iter().zip(&self.weights) {
            s += w * f(m + h * x);
        }
        s * h
    }

    /// `∫_a^b f` with this rule on `panels` equal panels.
    pub fn composite(&self, a: f64, b: f64, panels: usize, mut f: impl FnMut(f64) -> f64) -> f64 {
        let panels = panels.max(1);
        let h = (b - a) / panels as f64;
        (0..panels).map(|k| self.integrate(a + k as f64 * h, a + (k + 1) as f64 * h, &mut f)).sum()
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

/// The 7-point rule, built once.
pub fn gl7() -> &'static GaussLegendre {
    static R: OnceLock<GaussLegendre> = OnceLock::new();
    R.get_or_init(|| GaussLegendre::new(7))
}

/// The 16-point rule, built once.
pub fn gl16() -> &'static GaussLegendre {
    static R: OnceLock<GaussLegendre> = OnceLock::new();
    R.get_or_init(|| GaussLegendre::new(16))
}

/// Most panels one [`adaptive`] call may split (a noisy or discontinuous integrand stops
/// here instead of recursing to the bottom everywhere).
pub const ADAPTIVE_BUDGET: usize = 20_000;

/// `∫_a^b f` to an absolute tolerance `tol` by adaptive bisection with the 7-point rule
/// (depth ≤ 30, at most [`ADAPTIVE_BUDGET`] splits; a smooth integrand needs a handful).
pub fn adaptive(a: f64, b: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let rule = gl7();
    let whole = rule.integrate(a, b, &mut f);
    let mut budget = ADAPTIVE_BUDGET;
    adaptive_rec(rule, a, b, whole, tol.max(f64::MIN_POSITIVE), 30, &mut budget, &mut f)
}

fn adaptive_rec(
    rule: &GaussLegendre,
    a: f64,
    b: f64,
    whole: f64,
    tol: f64,
    depth: u32,
    budget: &mut usize,
    f: &mut impl FnMut(f64) -> f64,
) -> f64 {
    let m = 0.5 * (a + b);
    let left = rule.integrate(a, m, &mut *f);
    let right = rule.integrate(m, b, &mut *f);
    let sum = left + right;
    // Never ask for more than rounding allows: the halved tolerance is floored at a few
    // ulps of the panel's value, so an unreachable request cannot recurse to the bottom.
    let floor = 8.0 * f64::EPSILON * (left.abs() + right.abs());
    if depth == 0 || *budget == 0 || (sum - whole).abs() <= tol.max(floor) || m <= a || m >= b {
        return sum;
    }
    *budget -= 1;
    adaptive_rec(rule, a, m, left, 0.5 * tol, depth - 1, budget, f)
        + adaptive_rec(rule, m, b, right, 0.5 * tol, depth - 1, budget, f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_are_exact_for_their_degree_and_adaptive_meets_tolerance() {
        for n in [1, 2, 5, 7, 16, 33, 64] {
            let r = GaussLegendre::new(n);
            assert!((r.weights.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n = {n}");
            let deg = 2 * n - 1;
            let got = r.integrate(0.0, 1.0, |x| x.powi(deg as i32));
            assert!((got - 1.0 / (deg as f64 + 1.0)).abs() < 1e-13, "n = {n}: {got}");
        }
        let exact = 1.0 - (-10.0f64).exp();
        let got = adaptive(0.0, 10.0, 1e-13, |x| (-x).exp());
        assert!((got - exact).abs() < 1e-12);
        let c = GaussLegendre::new(8).composite(0.0, std::f64::consts::PI, 20, f64::sin);
        assert!((c - 2.0).abs() < 1e-14);
    }
}
