//! Ambient integral tables over θ_o [W19 eq. 7–10]: `A(θ_o) = ∫ f(ω_i, ω_o) cos θ_i dω_i`,
//! split per lobe as [W19 eq. 8] does into the longitudinal integral
//! `∫ M_p(θ_i, θ_o) cos²θ_i dθ_i` (numerical, per θ_o) times the azimuthal integral
//! `∫ N_p dφ_i` (numerical; [W19 eq. 9] is 1 and eq. 10 is replaced, see below), times the
//! lobe colour. The table holds `n` values at uniformly spaced θ_o including both poles and
//! interpolates linearly between them.
//!
//! With the default energy-conserving lobes every entry is the sum of the colours (the
//! furnace value); with [`super::Normalization::Paper`] the table shows how far the papers'
//! Gaussians are from that. [`w19_eq10`] is [W19 eq. 10] as printed,
//! `γ⁻²/I₀(γ⁻²)·I₀(1)`; it is not the integral of a normalised von Mises density (1 for every
//! γ), which is why the azimuthal integrals are computed numerically (DESIGN §2.3 item 12).

use super::{FiberBcsdf, Lobe};
use std::f64::consts::{FRAC_PI_2, PI};

/// `A(θ_o)` per channel on a uniform θ_o grid.
#[derive(Debug, Clone, PartialEq)]
pub struct AmbientTable {
    /// θ_o of the entries, from −π/2 to π/2.
    pub theta_o: Vec<f64>,
    /// `∫ f cos θ_i dω_i` per entry and channel.
    pub values: Vec<[f64; 3]>,
}

impl AmbientTable {
    /// Tabulates `bcsdf` at `n ≥ 2` values of θ_o.
    pub fn build(bcsdf: &FiberBcsdf, n: usize) -> Self {
        let n = n.max(2);
        let theta_o: Vec<f64> =
            (0..n).map(|k| -FRAC_PI_2 + PI * k as f64 / (n - 1) as f64).collect();
        let values = theta_o
            .iter()
            .map(|&to| {
                let mut v = [0.0; 3];
                for l in &bcsdf.lobes {
                    let e = lobe_integral(l, to);
                    for c in 0..3 {
                        v[c] += l.color[c] * e;
                    }
                }
                v
            })
            .collect();
        AmbientTable { theta_o, values }
    }

    /// `A(θ_o)` by linear interpolation (clamped to the poles).
    pub fn at(&self, theta_o: f64) -> [f64; 3] {
        let n = self.theta_o.len();
        let x = ((theta_o + FRAC_PI_2) / PI * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
        let k = (x.floor() as usize).min(n - 2);
        let f = x - k as f64;
        let (a, b) = (self.values[k], self.values[k + 1]);
        [0, 1, 2].map(|c| a[c] * (1.0 - f) + b[c] * f)
    }
}

/// `∫M cos²θ_i dθ_i · ∫N dφ` of one lobe at `θ_o` ([W19 eq. 8]).
pub fn lobe_integral(lobe: &Lobe, theta_o: f64) -> f64 {
    lobe.m.energy(theta_o) * lobe.n.integral()
}

/// [W19 eq. 10] as printed: `γ⁻² / I₀(γ⁻²) · I₀(1)`.
pub fn w19_eq10(gamma_tt: f64) -> f64 {
    let k = 1.0 / (gamma_tt * gamma_tt);
    k * (ln_i0(1.0) - ln_i0(k)).exp()
}

/// `ln I₀(x)` (modified Bessel function of order 0): power series below 30, the
/// asymptotic expansion above.
pub fn ln_i0(x: f64) -> f64 {
    let x = x.abs();
    if x < 30.0 {
        let q = 0.25 * x * x;
        let (mut term, mut sum, mut k) = (1.0, 1.0, 0.0);
        while term > 1e-17 * sum {
            k += 1.0;
            term *= q / (k * k);
            sum += term;
        }
        sum.ln()
    } else {
        let s = 1.0 + 1.0 / (8.0 * x) + 9.0 / (128.0 * x * x) + 225.0 / (3072.0 * x * x * x);
        x - 0.5 * (2.0 * PI * x).ln() + s.ln()
    }
}
