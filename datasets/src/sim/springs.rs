//! Spring laws of the mass–spring cloth, after Chen et al. 2003 §4.1.1 with the
//! corrections of the knit design (§1.3 items 1–2): no force inside the slack interval
//! `[lo, hi]` × rest length; beyond it the continuous exponential laws
//! `|F| = c₀ (e^{(l − θ_hi)/θ_hi} − 1)` for `l > θ_hi` and
//! `|F| = c₁ (e^{(θ_lo − l)/θ_lo} − 1)` for `l < θ_lo` ([C03 §4.1.1], corrected), with
//! `c₀ = k θ_hi` so that `k` (N/m) is the stiffness just past the slack. The paper's literal
//! form `c₀ e^{(l − θ)/θ − 1}`, which jumps by `c₀/e` at the threshold, is kept as
//! [`LawKind::PaperLiteral`] so the difference can be shown; [`LawKind::Linear`] is the
//! plain Hooke spring (used for seam springs, rest length 0).

/// Which force–length law.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LawKind {
    /// `k (l − θ)` outside the slack interval.
    Linear,
    /// The corrected, continuous exponential law.
    Exponential,
    /// The paper's literal law (discontinuous at the threshold).
    PaperLiteral,
}

/// A spring law: kind, slack interval and compression stiffness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringLaw {
    /// The law.
    pub kind: LawKind,
    /// Lower end of the slack interval (× rest length), e.g. 0.99.
    pub lo: f64,
    /// Upper end of the slack interval (× rest length), e.g. 1.01.
    pub hi: f64,
    /// Compression stiffness as a multiple of the stretch stiffness (`c₁/c₀`).
    pub compression: f64,
    /// Damping along the spring as a fraction of critical damping.
    pub damping: f64,
    /// Largest tension (N): a seam spring pulls with at most this force.
    pub max_tension: f64,
}

impl SpringLaw {
    /// Tension (N, positive pulls the ends together) and its derivative with respect to
    /// the length (N/m) for a spring of rest length `rest` and stiffness `k` at length `l`.
    pub fn tension(&self, k: f64, rest: f64, l: f64) -> (f64, f64) {
        let (t, kt) = self.unlimited(k, rest, l);
        if t > self.max_tension { (self.max_tension, 0.0) } else { (t, kt) }
    }

    /// Energy stored in the spring (J): the integral of [`SpringLaw::tension`] from the
    /// slack interval to `l`, ignoring `max_tension` and the exponent cap of 30.
    pub fn energy(&self, k: f64, rest: f64, l: f64) -> f64 {
        let (th_hi, th_lo) = (self.hi * rest, self.lo * rest);
        // ∫ k θ (e^{(s−θ)/θ} − 1) ds = k θ² (e^x − 1 − x), x = (l − θ)/θ; the literal
        // law is e^{−1} times the exponential alone, whose integral is k θ² e^{−1} (e^x − 1).
        let exp_energy = |k: f64, th: f64, x: f64| match self.kind {
            LawKind::Linear => 0.5 * k * (x * th) * (x * th),
            LawKind::Exponential => k * th * th * (x.exp_m1() - x),
            LawKind::PaperLiteral => k * th * th * (-1f64).exp() * x.exp_m1(),
        };
        if l > th_hi {
            if th_hi > 0.0 {
                exp_energy(k, th_hi, (l - th_hi) / th_hi)
            } else {
                0.5 * k * (l - th_hi) * (l - th_hi)
            }
        } else if l < th_lo {
            exp_energy(k * self.compression, th_lo, (th_lo - l) / th_lo)
        } else {
            0.0
        }
    }

    fn unlimited(&self, k: f64, rest: f64, l: f64) -> (f64, f64) {
        let (th_hi, th_lo) = (self.hi * rest, self.lo * rest);
        if l > th_hi {
            match self.kind {
                LawKind::Linear => (k * (l - th_hi), k),
                LawKind::Exponential if th_hi > 0.0 => {
                    let e = ((l - th_hi) / th_hi).min(30.0).exp();
                    (k * th_hi * (e - 1.0), k * e)
                }
                LawKind::PaperLiteral if th_hi > 0.0 => {
                    let e = ((l - th_hi) / th_hi - 1.0).min(30.0).exp();
                    (k * th_hi * e, k * e)
                }
                _ => (k * (l - th_hi), k),
            }
        } else if l < th_lo {
            let kc = k * self.compression;
            match self.kind {
                LawKind::Linear => (-kc * (th_lo - l), kc),
                LawKind::Exponential => {
                    let e = ((th_lo - l) / th_lo).min(30.0).exp();
                    (-kc * th_lo * (e - 1.0), kc * e)
                }
                LawKind::PaperLiteral => {
                    let e = ((th_lo - l) / th_lo - 1.0).min(30.0).exp();
                    (-kc * th_lo * e, kc * e)
                }
            }
        } else {
            (0.0, 0.0)
        }
    }
}

/// A spring between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// First node.
    pub a: u32,
    /// Second node.
    pub b: u32,
    /// Rest length (m).
    pub rest: f64,
    /// Stiffness just past the slack interval (N/m).
    pub k: f64,
    /// Index of its law in the cloth's law table.
    pub law: u16,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(kind: LawKind) -> SpringLaw {
        SpringLaw {
            kind,
            lo: 0.95,
            hi: 1.05,
            compression: 2.0,
            damping: 0.0,
            max_tension: f64::INFINITY,
        }
    }

    #[test]
    fn corrected_law_is_continuous_with_slope_k_at_the_threshold() {
        let l = law(LawKind::Exponential);
        let (k, rest) = (1500.0, 0.01);
        let th = 1.05 * rest;
        let (f0, _) = l.tension(k, rest, th - 1e-12);
        let (f1, k1) = l.tension(k, rest, th + 1e-12);
        assert_eq!(f0, 0.0);
        assert!(f1.abs() < 1e-6, "continuous: {f1}");
        assert!((k1 / k - 1.0).abs() < 1e-6, "slope {k1}");
        // Numerical derivative agrees with the returned one.
        let x = 1.2 * rest;
        let d = (l.tension(k, rest, x + 1e-9).0 - l.tension(k, rest, x - 1e-9).0) / 2e-9;
        assert!((d / l.tension(k, rest, x).1 - 1.0).abs() < 1e-5);
        // Compression pushes apart below the slack.
        assert!(l.tension(k, rest, 0.9 * rest).0 < 0.0);
        assert_eq!(l.tension(k, rest, rest).0, 0.0);
    }

    #[test]
    fn energy_is_the_integral_of_the_tension() {
        let (k, rest) = (1500.0, 0.01);
        for kind in [LawKind::Linear, LawKind::Exponential, LawKind::PaperLiteral] {
            let l = law(kind);
            for x in [0.8, 0.93, 1.0, 1.07, 1.3] {
                let x = x * rest;
                let h = 1e-9;
                let d = (l.energy(k, rest, x + h) - l.energy(k, rest, x - h)) / (2.0 * h);
                let t = l.tension(k, rest, x).0;
                assert!((d - t).abs() <= 1e-5 * t.abs().max(1e-3), "{kind:?} at {x}: {d} vs {t}");
            }
        }
    }

    #[test]
    fn paper_literal_law_jumps_by_c0_over_e() {
        let l = law(LawKind::PaperLiteral);
        let (k, rest) = (1500.0, 0.01);
        let th = 1.05 * rest;
        let (f1, _) = l.tension(k, rest, th + 1e-12);
        let c0 = k * th;
        assert!(
            (f1 - c0 / std::f64::consts::E).abs() < 1e-6 * c0,
            "jump {f1} vs {}",
            c0 / std::f64::consts::E
        );
    }
}
