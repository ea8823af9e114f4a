//! The thickness force field that keeps cloth off obstacles and off itself, Chen et al.
//! 2003 §4.1.2: `|F| = c₅ (T − d)²` for `τ ≤ d < T` ([C03 eq. 1]) and, closer in, a barrier
//! `c₆′ e^{α/d}` for `0 < d < τ` ([C03 eq. 2]) whose constants are chosen as in the knit
//! design §1.3 item 3 — `β = 0`, `α = 2τ²/(T − τ)`, `c₆′ = c₅ (T − τ)² e^{−α/τ}` — so that the
//! force and its slope are continuous at `τ` (C¹) and the force grows without bound as
//! `d → 0`. Below `d_min = τ/20` the barrier continues linearly with its slope there, so a
//! node that did get through is pushed out with a finite force.

/// The field's constants (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThicknessField {
    /// `c₅` (N/m²).
    pub c5: f64,
    /// Reach `T` (m).
    pub thickness: f64,
    /// Start of the barrier `τ` (m).
    pub tau: f64,
    alpha: f64,
    c6: f64,
}

impl ThicknessField {
    /// The field of strength `c5` and reach `thickness`, the barrier below `tau`.
    pub fn new(c5: f64, thickness: f64, tau: f64) -> Self {
        let alpha = 2.0 * tau * tau / (thickness - tau);
        let c6 = c5 * (thickness - tau).powi(2) * (-alpha / tau).exp();
        ThicknessField { c5, thickness, tau, alpha, c6 }
    }

    /// Repulsion (N, ≥ 0) at distance `d` and its stiffness `−dF/dd` (N/m, ≥ 0).
    pub fn force(&self, d: f64) -> (f64, f64) {
        let (t, tau) = (self.thickness, self.tau);
        if d >= t {
            (0.0, 0.0)
        } else if d >= tau {
            (self.c5 * (t - d).powi(2), 2.0 * self.c5 * (t - d))
        } else {
            let dm = tau / 20.0;
            let x = d.max(dm);
            let f = self.c6 * (self.alpha / x).exp();
            let k = f * self.alpha / (x * x);
            if d >= dm { (f, k) } else { (f + k * (dm - d), k) }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barrier_is_c1_at_tau_and_grows_without_bound() {
        // The knit design's numbers: c5 = 0.2, T = 0.9, τ = 0.1 → α = 0.025, c6' = 0.0997.
        let f = ThicknessField::new(0.2, 0.9, 0.1);
        assert!((f.alpha - 0.025).abs() < 1e-12);
        assert!((f.c6 - 0.0997).abs() < 1e-4, "c6' = {}", f.c6);
        let (a, ka) = f.force(0.1 - 1e-9);
        let (b, kb) = f.force(0.1 + 1e-9);
        assert!((a - b).abs() < 1e-7, "C0: {a} {b}");
        assert!((ka - kb).abs() < 1e-5, "C1: {ka} {kb}");
        // exp(α/x) grows without bound as x → 0: ×9.5 from 0.1 to 0.01, ×10⁵ by 0.002
        assert!(f.force(0.002).0 > 10.0 * f.force(0.1).0);
        assert_eq!(f.force(0.9).0, 0.0);
        let mut last = 0.0;
        for i in (0..200).rev() {
            let (v, _) = f.force(i as f64 * 0.0045 - 0.05);
            assert!(v >= last, "monotone");
            last = v;
        }
    }
}
