//! The per-face Gauss–Newton step of [H25 §5.2] with the signed, weighted residuals of
//! DESIGN §3.3 item 3: `√w_length (‖x_b − x_a‖ − L₀)/L₀` ([H25 eq. 6], relative) and
//! `√w_angle (cos α − cos α₀)` ([H25 eq. 5]), their analytic Jacobian with respect to
//! `Θ = (θ1, l1/r, θ2, l2/r)`, `A = Jᵀ J`, `g = Jᵀ r` and a 4 × 4 Cholesky solve; a step that
//! raises the face energy is halved (the guard the paper lacks).

use super::{FaceFrame, KnotModel, KnotParams, Residual, Role, Theta};
use crate::vec3::{self, V3};

/// Halvings before a step is rejected.
const MAX_HALVINGS: usize = 20;

/// Face energy treated as converged: residuals of ~1e-11 (relative lengths and cosines)
/// are rounding of metre coordinates, not shape.
const CONVERGED: f64 = 1e-20;

/// Cosine of the turning angle at `b` of the polyline `a → b → c` (1: straight on).
pub(super) fn cos_turn(a: V3, b: V3, c: V3) -> f64 {
    let (p, q) = (vec3::sub(b, a), vec3::sub(c, b));
    let den = vec3::length(p) * vec3::length(q);
    if den > 0.0 { vec3::dot(p, q) / den } else { 1.0 }
}

/// `∂x/∂(θ_k, λ_k)` of a local point and its knot `k` (`None`: a fixed point).
type PointDerivative = Option<(usize, [V3; 2])>;

/// The data one face solve reads.
pub(super) struct Ctx<'a> {
    pub model: &'a KnotModel,
    /// Current CPs (neighbours are read from here).
    pub points: &'a [V3],
    /// Lattice vectors (zero on open meshes).
    pub l0: V3,
    pub l1: V3,
    pub p: &'a KnotParams,
}

/// The outcome of one face solve.
pub(super) struct FaceResult {
    pub theta: Theta,
    /// Face energy before iterating and after each iteration.
    pub energies: Vec<f64>,
    pub guard_triggers: usize,
    pub rejected: usize,
}

/// One knot's frame at the current parameters: `d`, `d' = ∂d/∂θ`, `b = d × n`,
/// `b' = d' × n` and `l` (metres).
#[derive(Clone, Copy)]
struct KnotGeom {
    d: V3,
    dd: V3,
    b: V3,
    bb: V3,
    l: f64,
}

/// Buffers reused across the evaluations of one face solve (no allocation per step).
#[derive(Default)]
pub(super) struct Scratch {
    pos: Vec<V3>,
    der: Vec<PointDerivative>,
    res: Vec<f64>,
    rows: Vec<[f64; 4]>,
}

impl Ctx<'_> {
    fn geom(&self, frame: &FaceFrame, t: &Theta) -> [KnotGeom; 2] {
        std::array::from_fn(|k| {
            let (sn, cs) = t[2 * k].sin_cos();
            let (e1, e2, n) = (frame.e1[k], frame.e2[k], frame.n[k]);
            let d = vec3::add(vec3::scale(e1, cs), vec3::scale(e2, sn));
            let dd = vec3::add(vec3::scale(e1, -sn), vec3::scale(e2, cs));
            KnotGeom {
                d,
                dd,
                b: vec3::scale(vec3::cross(d, n), frame.o),
                bb: vec3::scale(vec3::cross(dd, n), frame.o),
                l: t[2 * k + 1] * self.model.radius,
            }
        })
    }

    /// Positions of the stencil's locals at `t` into `sc.pos`, and with `jac` for owned
    /// ones `∂x/∂(θ_k, λ_k)` with their knot index into `sc.der`. The points of eq. 1–2
    /// are the same expressions as [`KnotModel::knot_point`], with the knot frames shared.
    fn positions(&self, f: usize, frame: &FaceFrame, t: &Theta, jac: bool, sc: &mut Scratch) {
        let m = self.model;
        let st = &m.stencils[f];
        let (r, h, tpl) = (m.radius, m.skeleton.depth, &m.faces[f]);
        let g = self.geom(frame, t);
        sc.pos.clear();
        sc.der.clear();
        for l in &st.locals {
            match l.owned {
                Some((knot, role, own, course_wrap)) => {
                    let k = knot as usize;
                    let kg = &g[k];
                    let side = if own { tpl.sigma } else { -tpl.sigma };
                    let xk = frame.xk[k];
                    let q = match role {
                        Role::C0 => {
                            vec3::add_scaled(vec3::add_scaled(xk, kg.d, kg.l), frame.n[k], side * h)
                        }
                        Role::C1 => vec3::add_scaled(
                            vec3::add_scaled(xk, kg.d, -kg.l),
                            frame.n[k],
                            -side * h,
                        ),
                        Role::P => {
                            let sb = if own { tpl.b_own[k] } else { -tpl.b_own[k] };
                            vec3::add_scaled(xk, kg.b, sb * r)
                        }
                    };
                    let q = vec3::add_scaled(q, self.l1, course_wrap as f64);
                    sc.pos.push(vec3::add_scaled(q, self.l0, l.wrap as f64));
                    if jac {
                        let gr = match role {
                            Role::C0 => [vec3::scale(kg.dd, kg.l), vec3::scale(kg.d, r)],
                            Role::C1 => [vec3::scale(kg.dd, -kg.l), vec3::scale(kg.d, -r)],
                            Role::P => {
                                let sb = if own { tpl.b_own[k] } else { -tpl.b_own[k] };
                                [vec3::scale(kg.bb, sb * r), [0.0; 3]]
                            }
                        };
                        sc.der.push(Some((k, gr)));
                    }
                }
                None => {
                    sc.pos.push(vec3::add_scaled(self.points[l.global], self.l0, l.wrap as f64));
                    if jac {
                        sc.der.push(None);
                    }
                }
            }
        }
    }

    /// Residuals of face `f` at `t` into `sc.res` (and with `jac` the Jacobian rows into
    /// `sc.rows`); returns the face energy `Σ r²`.
    fn eval(&self, f: usize, frame: &FaceFrame, t: &Theta, jac: bool, sc: &mut Scratch) -> f64 {
        let st = &self.model.stencils[f];
        self.positions(f, frame, t, jac, sc);
        let (sl, sa) = (self.p.w_length.sqrt(), self.p.w_angle.sqrt());
        sc.res.clear();
        sc.rows.clear();
        let (pos, der) = (&sc.pos, &sc.der);
        // Adds `∂r/∂x_i · ∂x_i/∂Θ` to a Jacobian row.
        let add = |row: &mut [f64; 4], i: usize, grad: V3| {
            if let Some((k, g)) = der[i] {
                row[2 * k] += vec3::dot(grad, g[0]);
                row[2 * k + 1] += vec3::dot(grad, g[1]);
            }
        };
        let mut e = 0.0;
        for res_def in &st.residuals {
            match *res_def {
                Residual::Length { a, b, rest } => {
                    let (a, b) = (a as usize, b as usize);
                    let ev = vec3::sub(pos[b], pos[a]);
                    let len = vec3::length(ev);
                    let r = sl * (len - rest) / rest;
                    sc.res.push(r);
                    e += r * r;
                    if jac {
                        let mut row = [0.0; 4];
                        if len > 0.0 {
                            let u = vec3::scale(ev, sl / (len * rest));
                            add(&mut row, b, u);
                            add(&mut row, a, vec3::scale(u, -1.0));
                        }
                        sc.rows.push(row);
                    }
                }
                Residual::Angle { a, b, c, rest } => {
                    let (a, b, c) = (a as usize, b as usize, c as usize);
                    let (p, q) = (vec3::sub(pos[b], pos[a]), vec3::sub(pos[c], pos[b]));
                    let (lp, lq) = (vec3::length(p), vec3::length(q));
                    let den = lp * lq;
                    let cos = if den > 0.0 { vec3::dot(p, q) / den } else { 1.0 };
                    let r = sa * (cos - rest);
                    sc.res.push(r);
                    e += r * r;
                    if jac {
                        let mut row = [0.0; 4];
                        if den > 0.0 {
                            let gp = vec3::scale(
                                vec3::sub(
                                    vec3::scale(q, 1.0 / den),
                                    vec3::scale(p, cos / (lp * lp)),
                                ),
                                sa,
                            );
                            let gq = vec3::scale(
                                vec3::sub(
                                    vec3::scale(p, 1.0 / den),
                                    vec3::scale(q, cos / (lq * lq)),
                                ),
                                sa,
                            );
                            add(&mut row, a, vec3::scale(gp, -1.0));
                            add(&mut row, b, vec3::sub(gp, gq));
                            add(&mut row, c, gq);
                        }
                        sc.rows.push(row);
                    }
                }
            }
        }
        e
    }

    /// Residuals and Jacobian rows of face `f` at `t` (the finite-difference test).
    #[cfg(test)]
    pub fn residuals_and_jacobian(
        &self,
        f: usize,
        frame: &FaceFrame,
        t: &Theta,
    ) -> (Vec<f64>, Vec<[f64; 4]>) {
        let mut sc = Scratch::default();
        self.eval(f, frame, t, true, &mut sc);
        (sc.res, sc.rows)
    }

    /// `iterations` guarded Gauss–Newton steps of face `f` from `theta0`.
    pub fn face(
        &self,
        f: usize,
        frame: &FaceFrame,
        theta0: Theta,
        iterations: usize,
    ) -> FaceResult {
        let mut sc = Scratch::default();
        let mut t = theta0;
        let mut out = FaceResult {
            theta: t,
            energies: Vec::with_capacity(iterations + 1),
            guard_triggers: 0,
            rejected: 0,
        };
        let mut e = self.eval(f, frame, &t, iterations > 0, &mut sc);
        out.energies.push(e);
        for it in 0..iterations {
            if e <= CONVERGED {
                // Residuals at rounding level: a step would only follow the noise (and
                // trip the guard); keep the parameters.
                out.energies.push(e);
                continue;
            }
            if it > 0 {
                self.eval(f, frame, &t, true, &mut sc);
            }
            let mut a = [[0.0; 4]; 4];
            let mut g = [0.0; 4];
            for (ri, row) in sc.res.iter().zip(&sc.rows) {
                for i in 0..4 {
                    g[i] += row[i] * ri;
                    for j in i..4 {
                        a[i][j] += row[i] * row[j];
                    }
                }
            }
            for i in 0..4 {
                for j in 0..i {
                    a[i][j] = a[j][i];
                }
            }
            let step = solve4(a, g.map(|x| -x));
            let mut scale = 1.0;
            let mut accepted = false;
            for h in 0..=MAX_HALVINGS {
                let trial: Theta = std::array::from_fn(|i| t[i] + scale * step[i]);
                let et = self.eval(f, frame, &trial, false, &mut sc);
                if et <= e {
                    t = trial;
                    e = et;
                    accepted = true;
                    if h > 0 {
                        out.guard_triggers += 1;
                    }
                    break;
                }
                scale *= 0.5;
            }
            if !accepted {
                out.rejected += 1;
            }
            out.energies.push(e);
        }
        out.theta = t;
        out
    }
}

/// Solves the symmetric positive semi-definite `a x = b` by Cholesky with a tiny
/// Levenberg damping (1e-12 of the trace, so a rank-deficient `a` — a knot whose residuals
/// do not see one of its parameters — gives the least-norm-ish step instead of NaN).
fn solve4(mut a: [[f64; 4]; 4], b: [f64; 4]) -> [f64; 4] {
    let tr: f64 = (0..4).map(|i| a[i][i]).sum();
    if !(tr > 0.0 && tr.is_finite()) {
        return [0.0; 4];
    }
    for i in 0..4 {
        a[i][i] += 1e-12 * tr;
    }
    let mut l = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s <= 0.0 {
                    return [0.0; 4];
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = [0.0; 4];
    for i in 0..4 {
        y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; 4];
    for i in (0..4).rev() {
        x[i] = (y[i] - (i + 1..4).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    x
}
