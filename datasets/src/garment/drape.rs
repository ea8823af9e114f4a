//! The garment's cloth solver: extended position-based dynamics (XPBD, Macklin, Müller &
//! Chentanez 2016) with small sub-steps (Macklin et al. 2019), one Gauss–Seidel sweep per
//! sub-step. It computes, from panel-rest lengths, the positions the cloth takes under
//! gravity, seam pulls and contact with the body.
//!
//! Each constraint `C(x) = |x_a − x_b| − r` with compliance `α` (m/N, the inverse of the
//! spring stiffness) moves its ends by `Δλ = −(C + α̃ λ)/(w_a + w_b + α̃)`, `α̃ = α / Δt²`
//! [XPBD eq. 18]; with one iteration per sub-step `λ` starts at 0, so
//! `Δλ = −C/(w_a + w_b + α̃)`. Contact with the body is a projection onto the offset surface
//! `d = T` (the cloth's half-thickness `T`) after every sweep, with Coulomb friction on the
//! sub-step's tangential displacement (static when it is below `μ_s` times the
//! penetration, else reduced by `μ_k` times it). Velocities are `(x_new − x_old)/Δt`,
//! damped by `exp(−c Δt)` (air viscosity `c`).
//!
//! Links may be viscoelastic (Kelvin–Voigt: force `k (C + τ Ċ)`, relaxation time `τ`),
//! damped inside the constraint solve [XPBD eq. 26]:
//! `Δλ = −(C + γ ∇C·(x − xⁿ)) / ((1 + γ)(w_a + w_b) + α̃)` with `γ = α̃ β̃ / Δt`; for a
//! damping coefficient `β = τ k` that is `γ = τ / Δt`, the same for every link whatever its
//! stiffness. It damps only motion that changes a link's length, not a rigid swing, and
//! leaves the rest shape unchanged (at rest `x = xⁿ`). The sewing uses it only for cloth
//! that hangs free of the body (the curtain, [`super::sew::DrapeSettings`]): hung flat, the
//! curtain never came to rest without it — an oscillation of its free side edges in the
//! sheet's own plane grew from 6·10⁻⁴ J/kg at 0.7 s to 0.26 J/kg at 3.8 s at 10 000 vertices
//! against the air viscosity, under the single Gauss–Seidel sweep per sub-step (alternating
//! the sweep's direction made it worse: 6.8 J/kg at 4 s) — and hung in pleats at 40 000
//! vertices its lower part kept moving at 0.2–0.3 m/s (6–12·10⁻⁴ J/kg for 4 s, contact or
//! not); with `τ` = 2 ms it rests after 2.2 s. The garments on the body rub on it and do
//! without: with `τ` = 2 ms their rest was declared while the cloth still crept (at 1 500
//! vertices the shirt's most distorted triangle went from 0.46 to 0.78 and a triangle dipped
//! 3.1 mm into the body).
//!
//! Cloth–cloth contact ([`super::self_contact`]) is projected after the links, then the
//! body, alternated [`CONTACT_ROUNDS`] times (the later rounds re-project only the nodes the
//! cloth contact moved).
//!
//! Why not the draft's explicit mass–spring integrator ([`crate::sim`]): its time step is
//! bounded by `√(m/k)` of the contact field and the membrane, about 50 µs at every
//! resolution, so a 3 s drape at 10 000 vertices took several minutes (2 000 vertices had
//! not finished sewing after two). XPBD is unconditionally stable; 600 sub-steps per
//! simulated second suffice at 40 000 vertices. The sweep is sequential in a fixed
//! constraint order, so results are bit-identical from run to run.

use super::self_contact::SelfContact;
use crate::sim::Collider;
use crate::vec3::{V3, add, dot, length, scale, sub};

/// Passes of cloth–cloth contact and the body per sub-step when the cloth has contact. With
/// one pass (contact, then body) a layer pressed between the body and another layer is
/// pushed into the body by the contact and back into the layer by the body every sub-step:
/// the T-shirt's armpit at 10 000 vertices jittered at 0.2–0.5 m/s, came to rest only after
/// 2.1 s and left 6 crossing pairs there; with three it rests after 0.8 s with none.
pub const CONTACT_ROUNDS: usize = 3;

/// A distance constraint between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// First node.
    pub a: u32,
    /// Second node.
    pub b: u32,
    /// Rest length (m).
    pub rest: f64,
    /// Compliance `α` (m/N); 0 is inextensible.
    pub compliance: f64,
}

/// Contact with the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Distance from the body surface the cloth's mid-surface keeps (m).
    pub thickness_m: f64,
    /// Static friction coefficient.
    pub static_coef: f64,
    /// Dynamic friction coefficient.
    pub dynamic_coef: f64,
}

/// Constants of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XpbdParams {
    /// Gravity (m/s²).
    pub gravity: V3,
    /// Air viscosity (1/s).
    pub air_viscosity: f64,
    /// Sub-step (s).
    pub dt: f64,
    /// Relaxation time `τ` of the links' viscous damping (s; 0 for purely elastic links).
    pub link_damping_s: f64,
}

/// Positions and velocities of the cloth, advanced by [`Xpbd::step`].
pub struct Xpbd<'a> {
    /// Positions (m).
    pub x: Vec<V3>,
    /// Velocities (m/s).
    pub v: Vec<V3>,
    /// Inverse masses (1/kg), 0 for pinned nodes.
    pub inv_mass: Vec<f64>,
    /// Masses (kg).
    pub mass: Vec<f64>,
    /// Constraints, in sweep order.
    pub links: Vec<Link>,
    /// Simulated time (s).
    pub time: f64,
    params: XpbdParams,
    body: Option<(&'a dyn Collider, Contact)>,
    /// Cloth–cloth contact, projected after the links, alternated with the body.
    pub cloth: Option<SelfContact>,
    pred: Vec<V3>,
    touched: Vec<u32>,
}

impl<'a> Xpbd<'a> {
    /// A cloth at rest at `x` with node masses `mass`; `pinned` nodes do not move.
    pub fn new(
        x: Vec<V3>,
        mass: Vec<f64>,
        pinned: &[bool],
        links: Vec<Link>,
        params: XpbdParams,
        body: Option<(&'a dyn Collider, Contact)>,
    ) -> Self {
        let inv_mass = mass
            .iter()
            .zip(pinned)
            .map(|(&m, &p)| if p || m <= 0.0 { 0.0 } else { 1.0 / m })
            .collect();
        let n = x.len();
        Xpbd {
            pred: x.clone(),
            x,
            v: vec![[0.0; 3]; n],
            inv_mass,
            mass,
            links,
            time: 0.0,
            params,
            body,
            cloth: None,
            touched: Vec::new(),
        }
    }

    /// Changes the constants (gravity, damping, sub-step) between phases.
    pub fn set_params(&mut self, params: XpbdParams) {
        self.params = params;
    }

    /// Kinetic energy per kilogram of the moving nodes (J/kg).
    pub fn kinetic_energy_per_kg(&self) -> f64 {
        let (mut e, mut m) = (0.0, 0.0);
        for i in 0..self.x.len() {
            if self.inv_mass[i] > 0.0 {
                e += 0.5 * self.mass[i] * dot(self.v[i], self.v[i]);
                m += self.mass[i];
            }
        }
        if m > 0.0 { e / m } else { 0.0 }
    }

    /// Projects node `i`'s prediction out of the body, with friction on its motion over
    /// the sub-step.
    fn collide_with_body(&mut self, i: usize) {
        let Some((col, ct)) = self.body else {
            return;
        };
        if self.inv_mass[i] == 0.0 {
            return;
        }
        let (d, n) = col.query(self.pred[i]);
        if d >= ct.thickness_m {
            return;
        }
        let depth = ct.thickness_m - d;
        let mut q = add(self.pred[i], scale(n, depth));
        let moved = sub(q, self.x[i]);
        let tangential = sub(moved, scale(n, dot(moved, n)));
        let t = length(tangential);
        if t < ct.static_coef * depth {
            q = sub(q, tangential);
        } else if t > 0.0 {
            q = sub(q, scale(tangential, (ct.dynamic_coef * depth / t).min(1.0)));
        }
        self.pred[i] = q;
    }

    /// One sub-step: predict, one sweep over the links, cloth–cloth contact and contact with
    /// the body ([`CONTACT_ROUNDS`] times when the cloth has contact), velocities.
    pub fn step(&mut self) {
        let p = self.params;
        let dt = p.dt;
        let damp = (-p.air_viscosity * dt).exp();
        for i in 0..self.x.len() {
            if self.inv_mass[i] == 0.0 {
                self.pred[i] = self.x[i];
                continue;
            }
            let v = scale(add(self.v[i], scale(p.gravity, dt)), damp);
            self.pred[i] = add(self.x[i], scale(v, dt));
        }
        let inv_dt2 = 1.0 / (dt * dt);
        let gamma = p.link_damping_s / dt;
        for l in &self.links {
            let (a, b) = (l.a as usize, l.b as usize);
            let w = self.inv_mass[a] + self.inv_mass[b];
            if w == 0.0 {
                continue;
            }
            let d = sub(self.pred[b], self.pred[a]);
            let len = length(d);
            if len < 1e-15 {
                continue;
            }
            let c = len - l.rest;
            // The link's lengthening over the sub-step so far, ∇C·(x − xⁿ) [XPBD eq. 26].
            let stretch = dot(sub(sub(self.pred[b], self.x[b]), sub(self.pred[a], self.x[a])), d);
            let dl = -(c + gamma * stretch / len) / ((1.0 + gamma) * w + l.compliance * inv_dt2);
            let g = scale(d, dl / len);
            self.pred[a] = sub(self.pred[a], scale(g, self.inv_mass[a]));
            self.pred[b] = add(self.pred[b], scale(g, self.inv_mass[b]));
        }
        match &mut self.cloth {
            None => {
                for i in 0..self.x.len() {
                    self.collide_with_body(i);
                }
            }
            Some(_) => {
                // Cloth contact and the body, alternated: a layer pressed between the body
                // and another layer (an armpit, the inseams) is pushed by both, and one pass
                // of each left it jittering (see `CONTACT_ROUNDS`). Later rounds re-project
                // only the nodes the cloth contact moved.
                let mut touched = std::mem::take(&mut self.touched);
                for round in 0..CONTACT_ROUNDS {
                    touched.clear();
                    if let Some(c) = &mut self.cloth {
                        c.project(&mut self.pred, &self.x, &self.inv_mass, &mut touched);
                    }
                    if round == 0 {
                        for i in 0..self.x.len() {
                            self.collide_with_body(i);
                        }
                    } else {
                        touched.sort_unstable();
                        touched.dedup();
                        for &i in &touched {
                            self.collide_with_body(i as usize);
                        }
                    }
                }
                self.touched = touched;
            }
        }
        for i in 0..self.x.len() {
            self.v[i] = scale(sub(self.pred[i], self.x[i]), 1.0 / dt);
            self.x[i] = self.pred[i];
        }
        self.time += dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of 20 nodes hanging from a pinned end comes to rest with the links at
    /// their stretched length, the links' damping notwithstanding: link `k` from the bottom
    /// carries the weight `k m g`, so with compliance `α` it is `r + α k m g` long (exact for
    /// the equilibrium of XPBD, whose fixed point is the spring equilibrium).
    #[test]
    fn hanging_chain_stretches_by_its_compliance() {
        let n = 20;
        let (m, r, alpha) = (0.01, 0.05, 0.02);
        let x: Vec<V3> = (0..n).map(|i| [0.0, 0.0, -(i as f64) * r]).collect();
        let mut pinned = vec![false; n];
        pinned[0] = true;
        let links = (0..n - 1)
            .map(|i| Link { a: i as u32, b: i as u32 + 1, rest: r, compliance: alpha })
            .collect();
        let params = XpbdParams {
            gravity: [0.0, 0.0, -9.81],
            air_viscosity: 5.0,
            dt: 1e-3,
            link_damping_s: 0.002,
        };
        let mut s = Xpbd::new(x, vec![m; n], &pinned, links, params, None);
        for _ in 0..20_000 {
            s.step();
        }
        assert!(s.kinetic_energy_per_kg() < 1e-8, "at rest");
        for i in 0..n - 1 {
            let below = (n - 1 - i) as f64;
            let expect = r + alpha * below * m * 9.81;
            let got = length(sub(s.x[i + 1], s.x[i]));
            // One sweep per sub-step leaves a residual of order (α̃ / w)·… — 1 % here.
            assert!(
                (got - expect).abs() < 0.01 * (expect - r) + 1e-6,
                "link {i}: {got} vs {expect}"
            );
        }
    }

    /// A node on a damped link oscillates as `m ẍ = −k x − τ k ẋ`: successive peaks of its
    /// stretch shrink by `exp(−τ k T_d / 2m)`, `T_d` the damped period. The integrator's own
    /// damping, `π ω₀ Δt` a period (1.6 % at `Δt = T_d / 1 250`), is made negligible with
    /// `Δt = T_d / 31 000` (0.06 %): without the link's damping the peaks stay within 0.1 %.
    #[test]
    fn a_damped_link_decays_at_the_kelvin_voigt_rate() {
        let (m, k, r) = (0.01, 100.0, 0.1);
        let peaks = |tau: f64| {
            let x = vec![[0.0; 3], [r + 1e-3, 0.0, 0.0]];
            let links = vec![Link { a: 0, b: 1, rest: r, compliance: 1.0 / k }];
            let params =
                XpbdParams { gravity: [0.0; 3], air_viscosity: 0.0, dt: 2e-6, link_damping_s: tau };
            let mut s = Xpbd::new(x, vec![m; 2], &[true, false], links, params, None);
            let mut stretch = [f64::NAN; 3];
            let mut found = Vec::new();
            while found.len() < 3 {
                s.step();
                stretch = [stretch[1], stretch[2], s.x[1][0] - r];
                if stretch[1] > stretch[0] && stretch[1] >= stretch[2] {
                    found.push(stretch[1]);
                }
            }
            (found[1] / found[0], found[2] / found[1])
        };
        let (a, b) = peaks(0.0);
        assert!((a - 1.0).abs() < 1e-3 && (b - 1.0).abs() < 1e-3, "undamped: {a} {b}");
        let tau = 2e-3;
        let w0 = (k / m).sqrt();
        let zeta = 0.5 * tau * w0;
        let period = 2.0 * std::f64::consts::PI / (w0 * (1.0 - zeta * zeta).sqrt());
        let expect = (-0.5 * tau * k / m * period).exp();
        let (a, b) = peaks(tau);
        for got in [a, b] {
            assert!((got / expect - 1.0).abs() < 0.02, "peak ratio {got} vs {expect}");
        }
    }
}
