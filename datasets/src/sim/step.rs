//! The time step, Chen et al. 2003 §4.2 with the knit design's choices (§1.3 item 7):
//! (1) spring, angle-spring, gravity and air forces, (2) the body's thickness field, (3) the
//! cloth's own ([`super::collide`]), (4) a bound `dt ≤ min(c·√(m/k), ½ T / v_max, dt_max)`
//! where `k` sums the stiffnesses acting on a node (springs past their slack, angle springs,
//! contact fields), (5) an explicit update by one of three [`Integrator`]s with friction
//! applied to the velocities of each kick, (6) while a node would end inside the body or
//! cross a triangle, the step is retried with half the `dt` (up to `max_halvings` times,
//! after which a node still inside is put back on the surface, inelastically). Halving and
//! the bound apply to every integrator.
//!
//! The integrators:
//! - [`Integrator::SymplecticEuler`] (the default, and what the older drape used): one
//!   force evaluation, `v += a dt`, `x += v dt`;
//! - [`Integrator::VelocityVerlet`] (the knit default), as kick–drift–kick: half a kick
//!   with the forces at `x`, a drift, the forces at the new positions, the other half
//!   kick. Two evaluations; symplectic and time-reversible for conservative forces, so the
//!   energy error stays bounded. Friction acts in each half kick with half the budget, so
//!   a node held by static friction does not creep;
//! - [`Integrator::MidpointRk2`] (the paper's "RK2", [C03 §4.2] step 7, which does not say
//!   which RK2): the explicit midpoint rule, forces at `(x + v dt/2, v + a dt/2)`. Two
//!   evaluations, second order, but not symplectic: its energy error grows like `dt²`.
use super::angles::AngleForce;
use super::collide::{Candidate, SelfContact, candidates};
use super::field::ThicknessField;
use super::friction::Friction;
use super::{Cloth, Collider};
use crate::vec3::{V3, add, cross, dot, length, scale, sub};
use crate::{Error, Result};
use rayon::prelude::*;
use std::time::Instant;

/// The explicit update rule (see the module documentation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Integrator {
    /// `v += a dt; x += v dt` — one force evaluation per step.
    #[default]
    SymplecticEuler,
    /// Kick–drift–kick velocity Verlet — two evaluations, bounded energy error.
    VelocityVerlet,
    /// The explicit midpoint rule (the paper's RK2) — two evaluations.
    MidpointRk2,
}

/// Contact with the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyContact {
    /// Thickness field between cloth and body (`c₅`, `T`, `τ`).
    pub field: ThicknessField,
    /// Friction against the body.
    pub friction: Friction,
}

/// Simulation constants.
#[derive(Debug, Clone, PartialEq)]
pub struct SimParams {
    /// Gravity (m/s²).
    pub gravity: V3,
    /// Air viscosity `c₉` per unit mass (1/s).
    pub air_viscosity: f64,
    /// Contact with the collider, if any.
    pub body: Option<BodyContact>,
    /// Self-collision, if simulated.
    pub self_contact: Option<SelfContact>,
    /// Upper bound of the time step (s); Chen's default frame step is 1/25 s.
    pub dt_max: f64,
    /// Factor `c` of the stiffness bound `c·√(m/k)`.
    pub cfl: f64,
    /// Halvings tried before a penetration is resolved by projection.
    pub max_halvings: u32,
    /// The update rule.
    pub integrator: Integrator,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            gravity: [0.0, 0.0, -9.81],
            air_viscosity: 0.6,
            body: None,
            self_contact: None,
            dt_max: 1.0 / 25.0,
            cfl: 0.5,
            max_halvings: 6,
            integrator: Integrator::SymplecticEuler,
        }
    }
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Time step taken (s).
    pub dt: f64,
    /// Halvings after predicted penetrations.
    pub halvings: u32,
    /// Nodes put back on the body's surface after the last halving.
    pub projected: usize,
    /// Kinetic energy after the step (J).
    pub kinetic_energy: f64,
    /// Force evaluations, halved attempts included.
    pub force_evaluations: u32,
}

/// What a run up to a given time did (one frame of a scene).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AdvanceReport {
    /// Steps taken.
    pub steps: usize,
    /// Halvings over those steps.
    pub halvings: usize,
    /// Nodes projected out of the body over those steps.
    pub projected: usize,
    /// Force evaluations.
    pub force_evaluations: usize,
    /// Wall-clock time spent (ms).
    pub wall_ms: f64,
}

/// How a run to rest went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RestReport {
    /// Whether the kinetic energy stayed below the threshold for the hold time.
    pub settled: bool,
    /// Simulated time when the quiet period began (s).
    pub settle_time_s: f64,
    /// Simulated time at the end (s).
    pub end_time_s: f64,
    /// Steps taken.
    pub steps: usize,
    /// Halvings over the run.
    pub halvings: usize,
    /// Nodes projected out of the body over the run.
    pub projected: usize,
    /// Kinetic energy per kilogram at the end (J/kg).
    pub kinetic_energy_per_kg: f64,
}

/// Positions and velocities of a cloth, advanced in time.
pub struct Simulator<'a> {
    /// The cloth.
    pub cloth: Cloth,
    /// Positions (m).
    pub x: Vec<V3>,
    /// Velocities (m/s).
    pub v: Vec<V3>,
    /// Constants.
    pub params: SimParams,
    /// Simulated time (s).
    pub time: f64,
    /// Velocity of each pinned node (m/s; zero holds it in place). Unpinned nodes ignore it.
    pub pin_velocity: Vec<V3>,
    collider: Option<&'a dyn Collider>,
    candidates: Vec<Candidate>,
    built_at: Vec<V3>,
}

struct Forces {
    force: Vec<V3>,
    stiffness: Vec<f64>,
    /// Body distance, normal and normal force per node.
    contact: Vec<(f64, V3, f64)>,
    /// Self pushes: (node, triangle, weights, normal, magnitude).
    pushes: Vec<(u32, u32, [f64; 3], V3, f64)>,
}

impl<'a> Simulator<'a> {
    /// A simulator starting at rest at positions `x`.
    pub fn new(
        cloth: Cloth,
        x: Vec<V3>,
        params: SimParams,
        collider: Option<&'a dyn Collider>,
    ) -> Self {
        let n = x.len();
        assert_eq!(cloth.mass.len(), n, "one mass per node");
        Simulator {
            cloth,
            v: vec![[0.0; 3]; n],
            x,
            params,
            time: 0.0,
            pin_velocity: vec![[0.0; 3]; n],
            collider,
            candidates: Vec::new(),
            built_at: Vec::new(),
        }
    }

    /// Total kinetic energy (J), summed in node order.
    pub fn kinetic_energy(&self) -> f64 {
        self.v.iter().zip(&self.cloth.mass).map(|(v, m)| 0.5 * m * dot(*v, *v)).sum()
    }

    /// Energy stored in the springs and angle springs (J), summed in element order.
    pub fn internal_energy(&self) -> f64 {
        let c = &self.cloth;
        let springs: f64 = c
            .springs
            .iter()
            .map(|s| {
                let l = length(sub(self.x[s.b as usize], self.x[s.a as usize]));
                c.laws[s.law as usize].energy(s.k, s.rest, l)
            })
            .sum();
        springs + c.angles.iter().map(|a| a.energy(&self.x)).sum::<f64>()
    }

    /// Potential energy in gravity (J, zero at the origin).
    pub fn gravity_energy(&self) -> f64 {
        self.x.iter().zip(&self.cloth.mass).map(|(x, m)| -m * dot(self.params.gravity, *x)).sum()
    }

    /// Total momentum (kg·m/s), summed in node order.
    pub fn momentum(&self) -> V3 {
        self.v.iter().zip(&self.cloth.mass).fold([0.0; 3], |s, (v, m)| add(s, scale(*v, *m)))
    }

    /// Steps until the simulated time reaches `t_end` (the last step is shortened to land
    /// on it). Fails if the state stops being finite or more than `max_steps` are needed.
    pub fn advance_to(&mut self, t_end: f64, max_steps: usize) -> Result<AdvanceReport> {
        let start = Instant::now();
        let mut r = AdvanceReport::default();
        while t_end - self.time > 1e-12 * t_end.abs().max(1.0) {
            if r.steps >= max_steps {
                return Err(Error::Invalid(format!(
                    "the simulation needed more than {max_steps} steps to reach t = {t_end} s \
                     (at t = {} s, last dt = {:e} s): the springs are too stiff for the masses",
                    self.time,
                    t_end - self.time
                )));
            }
            let s = self.step_capped(t_end - self.time);
            r.steps += 1;
            r.halvings += s.halvings as usize;
            r.projected += s.projected;
            r.force_evaluations += s.force_evaluations as usize;
            if !s.kinetic_energy.is_finite() {
                return Err(Error::Invalid(format!(
                    "the simulation diverged at t = {} s (non-finite velocities); lower \
                     `cfl` or the stiffnesses",
                    self.time
                )));
            }
        }
        r.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(r)
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.cloth.mass.iter().sum()
    }

    fn refresh_candidates(&mut self) {
        let Some(sc) = self.params.self_contact else { return };
        let moved = if self.built_at.len() == self.x.len() {
            self.x.iter().zip(&self.built_at).map(|(a, b)| length(sub(*a, *b))).fold(0.0, f64::max)
        } else {
            f64::INFINITY
        };
        if moved > 0.5 * sc.margin {
            self.candidates =
                candidates(&self.x, &self.cloth.triangles, sc.field.thickness + sc.margin);
            self.built_at = self.x.clone();
        }
    }

    /// Forces, stiffnesses and contacts at positions `x` and velocities `v`.
    fn forces(&self, x: &[V3], v: &[V3]) -> Forces {
        let c = &self.cloth;
        let per_spring: Vec<(V3, f64)> = c
            .springs
            .par_iter()
            .map(|s| {
                let d = sub(x[s.b as usize], x[s.a as usize]);
                let l = length(d);
                if l < 1e-12 {
                    return ([0.0; 3], s.k);
                }
                let dir = scale(d, 1.0 / l);
                let law = &c.laws[s.law as usize];
                let (tension, kt) = law.tension(s.k, s.rest, l);
                let (ma, mb) = (c.mass[s.a as usize], c.mass[s.b as usize]);
                let damping = law.damping * 2.0 * (s.k * ma * mb / (ma + mb)).sqrt();
                let vrel = dot(sub(v[s.b as usize], v[s.a as usize]), dir);
                (
                    scale(dir, tension + damping * vrel),
                    kt.max(if tension != 0.0 { s.k } else { 0.0 }),
                )
            })
            .collect();
        let per_angle: Vec<AngleForce> = c.angles.par_iter().map(|a| a.force(x)).collect();
        let p = &self.params;
        let body = p.body.filter(|_| self.collider.is_some());
        let results: Vec<(V3, f64, (f64, V3, f64))> = (0..x.len())
            .into_par_iter()
            .map(|i| {
                let m = c.mass[i];
                let mut f = add(scale(p.gravity, m), scale(v[i], -p.air_viscosity * m));
                let mut k = 0.0;
                for &(si, sign) in c.springs_at(i) {
                    let (fs, ks) = per_spring[si as usize];
                    f = add(f, scale(fs, sign));
                    k += ks;
                }
                for &(ai, slot) in c.angles_at(i) {
                    let af = &per_angle[ai as usize];
                    f = add(f, af.force[slot as usize]);
                    k += af.stiffness[slot as usize];
                }
                let mut contact = (f64::INFINITY, [0.0; 3], 0.0);
                if let (Some(b), Some(col)) = (body, self.collider) {
                    let (d, n) = col.query(x[i]);
                    let (fnorm, kn) = b.field.force(d);
                    f = add(f, scale(n, fnorm));
                    k += kn;
                    contact = (d, n, fnorm);
                }
                (f, k, contact)
            })
            .collect();
        let mut force = Vec::with_capacity(x.len());
        let mut stiffness = Vec::with_capacity(x.len());
        let mut contact = Vec::with_capacity(x.len());
        for (f, k, ct) in results {
            force.push(f);
            stiffness.push(k);
            contact.push(ct);
        }
        let mut pushes = Vec::new();
        if let Some(sc) = p.self_contact {
            let found: Vec<Option<(u32, u32, super::collide::Push)>> = self
                .candidates
                .par_iter()
                .map(|cand| sc.push(cand, x, &c.triangles).map(|p| (cand.node, cand.tri, p)))
                .collect();
            for (node, tri, push) in found.into_iter().flatten() {
                force[node as usize] = add(force[node as usize], push.force);
                stiffness[node as usize] += push.stiffness;
                let t = c.triangles[tri as usize];
                for k in 0..3 {
                    let corner = t[k] as usize;
                    force[corner] = sub(force[corner], scale(push.force, push.weights[k]));
                    stiffness[corner] += push.stiffness * push.weights[k];
                }
                pushes.push((node, tri, push.weights, push.normal, push.magnitude));
            }
        }
        Forces { force, stiffness, contact, pushes }
    }

    /// The time-step bound of the current state.
    fn bound(&self, f: &Forces) -> f64 {
        let p = &self.params;
        let c = &self.cloth;
        let ratio = (0..self.x.len())
            .filter(|&i| !c.pinned[i])
            .map(|i| f.stiffness[i] / c.mass[i])
            .fold(0.0, f64::max);
        let vmax = self.v.iter().map(|v| length(*v)).fold(0.0, f64::max);
        let reach = [p.body.map(|b| b.field.thickness), p.self_contact.map(|s| s.field.thickness)]
            .into_iter()
            .flatten()
            .fold(f64::INFINITY, f64::min);
        let mut dt = p.dt_max;
        if ratio > 0.0 {
            dt = dt.min(p.cfl / ratio.sqrt());
        }
        if reach.is_finite() && vmax > 0.0 {
            dt = dt.min(0.5 * reach / vmax);
        }
        dt
    }

    /// Velocities after a kick of `dt` with forces `f` from velocities `v`: body friction
    /// with the contact forces of `f`, then dynamic self-friction; pinned nodes take their
    /// prescribed velocity.
    fn kick(&self, v: &[V3], f: &Forces, dt: f64) -> Vec<V3> {
        let c = &self.cloth;
        let body = self.params.body.filter(|_| self.collider.is_some());
        let mut vn = (0..v.len())
            .into_par_iter()
            .map(|i| {
                if c.pinned[i] {
                    return self.pin_velocity[i];
                }
                let m = c.mass[i];
                let mut w = add(v[i], scale(f.force[i], dt / m));
                let (_, nrm, fnorm) = f.contact[i];
                if let (Some(b), true) = (body, fnorm > 0.0) {
                    w = b.friction.apply(w, nrm, fnorm, m, dt);
                }
                w
            })
            .collect::<Vec<V3>>();
        if let Some(sc) = self.params.self_contact {
            for &(node, tri, wts, nrm, mag) in &f.pushes {
                let t = c.triangles[tri as usize];
                let i = node as usize;
                if c.pinned[i] {
                    continue;
                }
                let other = (0..3).fold([0.0; 3], |s, k| add(s, scale(vn[t[k] as usize], wts[k])));
                let rel = sub(vn[i], other);
                let fr = Friction { static_coef: 0.0, dynamic_coef: sc.dynamic_friction };
                let after = fr.apply(rel, nrm, mag, c.mass[i], dt);
                let delta = scale(sub(after, rel), 0.5);
                vn[i] = add(vn[i], delta);
                for k in 0..3 {
                    let corner = t[k] as usize;
                    if !c.pinned[corner] {
                        vn[corner] = sub(vn[corner], scale(delta, wts[k]));
                    }
                }
            }
        }
        vn
    }

    /// Positions `x + v dt`.
    fn drift(x: &[V3], v: &[V3], dt: f64) -> Vec<V3> {
        (0..x.len()).into_par_iter().map(|i| add(x[i], scale(v[i], dt))).collect()
    }

    /// Advances one step.
    pub fn step(&mut self) -> StepReport {
        self.step_capped(f64::INFINITY)
    }

    /// Advances one step of at most `dt_cap` (s).
    pub fn step_capped(&mut self, dt_cap: f64) -> StepReport {
        self.refresh_candidates();
        let f = self.forces(&self.x, &self.v);
        let mut dt = self.bound(&f).min(dt_cap);
        let n = self.x.len();
        let body = self.params.body.filter(|_| self.collider.is_some());
        let mut halvings = 0;
        let mut evaluations = 1;
        let (mut xn, mut vn);
        loop {
            match self.params.integrator {
                Integrator::SymplecticEuler => {
                    vn = self.kick(&self.v, &f, dt);
                    xn = Self::drift(&self.x, &vn, dt);
                }
                Integrator::VelocityVerlet => {
                    vn = self.kick(&self.v, &f, 0.5 * dt);
                    xn = Self::drift(&self.x, &vn, dt);
                }
                Integrator::MidpointRk2 => {
                    let v_mid = self.kick(&self.v, &f, 0.5 * dt);
                    let x_mid = Self::drift(&self.x, &self.v, 0.5 * dt);
                    let f_mid = self.forces(&x_mid, &v_mid);
                    evaluations += 1;
                    vn = self.kick(&self.v, &f_mid, dt);
                    xn = Self::drift(&self.x, &v_mid, dt);
                }
            }
            if halvings >= self.params.max_halvings || !self.penetrates(&f, &xn) {
                break;
            }
            dt *= 0.5;
            halvings += 1;
        }
        if self.params.integrator == Integrator::VelocityVerlet {
            // vn holds the half-kicked velocities; the second half kick uses the new forces.
            let f_end = self.forces(&xn, &vn);
            evaluations += 1;
            vn = self.kick(&vn, &f_end, 0.5 * dt);
        }
        // Safety net: nodes still inside the body go back to its surface.
        let mut projected = 0;
        if let (Some(_), Some(col)) = (body, self.collider) {
            let fixes: Vec<Option<(V3, V3)>> = (0..n)
                .into_par_iter()
                .map(|i| {
                    let moved = match self.params.integrator {
                        Integrator::SymplecticEuler => length(vn[i]) * dt,
                        _ => length(sub(xn[i], self.x[i])),
                    };
                    if f.contact[i].0 - moved > 0.0 {
                        return None;
                    }
                    let (d, nrm) = col.query(xn[i]);
                    if d >= 0.0 {
                        return None;
                    }
                    let x = add(xn[i], scale(nrm, -d));
                    let vnorm = dot(vn[i], nrm);
                    let v = if vnorm < 0.0 { sub(vn[i], scale(nrm, vnorm)) } else { vn[i] };
                    Some((x, v))
                })
                .collect();
            for (i, fix) in fixes.into_iter().enumerate() {
                if let Some((x, v)) = fix {
                    xn[i] = x;
                    vn[i] = v;
                    projected += 1;
                }
            }
        }
        self.x = xn;
        self.v = vn;
        self.time += dt;
        StepReport {
            dt,
            halvings,
            projected,
            kinetic_energy: self.kinetic_energy(),
            force_evaluations: evaluations,
        }
    }

    /// Whether moving to `xn` would put a node newly inside the body or through a triangle.
    fn penetrates(&self, f: &Forces, xn: &[V3]) -> bool {
        let n = xn.len();
        if let (Some(_), Some(col)) = (self.params.body, self.collider) {
            let into_body = (0..n).into_par_iter().any(|i| {
                let d0 = f.contact[i].0;
                d0 >= 0.0 && d0 < length(sub(xn[i], self.x[i])) + 1e-12 && col.query(xn[i]).0 < 0.0
            });
            if into_body {
                return true;
            }
        }
        if self.params.self_contact.is_some() {
            let tris = &self.cloth.triangles;
            return self.candidates.par_iter().any(|c| {
                let t = tris[c.tri as usize];
                crosses(
                    t.map(|k| self.x[k as usize]),
                    self.x[c.node as usize],
                    t.map(|k| xn[k as usize]),
                    xn[c.node as usize],
                )
            });
        }
        false
    }

    /// Steps until the kinetic energy per kilogram stays below `ke_per_kg` for `hold_s`
    /// of simulated time, or `max_time_s` is reached; `progress` gets the simulated time.
    pub fn run_to_rest(
        &mut self,
        max_time_s: f64,
        ke_per_kg: f64,
        hold_s: f64,
        progress: &mut dyn FnMut(f64),
    ) -> RestReport {
        let mass = self.total_mass();
        let start = self.time;
        let mut quiet_since: Option<f64> = None;
        let mut r = RestReport::default();
        while self.time - start < max_time_s {
            let s = self.step();
            r.steps += 1;
            r.halvings += s.halvings as usize;
            r.projected += s.projected;
            let ke = s.kinetic_energy / mass;
            r.kinetic_energy_per_kg = ke;
            if ke < ke_per_kg {
                let since = *quiet_since.get_or_insert(self.time - start);
                if self.time - start - since >= hold_s {
                    r.settled = true;
                    break;
                }
            } else {
                quiet_since = None;
            }
            if r.steps % 64 == 0 {
                progress(self.time - start);
                if !self.x.iter().all(|p| p.iter().all(|c| c.is_finite())) {
                    break;
                }
            }
        }
        r.settle_time_s = quiet_since.unwrap_or(self.time - start);
        r.end_time_s = self.time - start;
        r
    }
}

/// Whether point `p0 → p1` passes through the triangle moving `t0 → t1` (tested at the
/// end of the step: opposite sides of the plane, and the end point inside the triangle).
fn crosses(t0: [V3; 3], p0: V3, t1: [V3; 3], p1: V3) -> bool {
    let n0 = cross(sub(t0[1], t0[0]), sub(t0[2], t0[0]));
    let n1 = cross(sub(t1[1], t1[0]), sub(t1[2], t1[0]));
    let s0 = dot(sub(p0, t0[0]), n0);
    let s1 = dot(sub(p1, t1[0]), n1);
    if s0 * s1 > 0.0 || s0 == 0.0 {
        return false;
    }
    // End point's projection inside the end triangle.
    let nn = dot(n1, n1);
    if nn <= 0.0 {
        return false;
    }
    let q = sub(p1, scale(n1, s1 / nn));
    (0..3).all(|k| {
        let (a, b) = (t1[k], t1[(k + 1) % 3]);
        dot(cross(sub(b, a), sub(q, a)), n1) >= 0.0
    })
}
