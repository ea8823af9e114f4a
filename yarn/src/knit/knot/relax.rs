//! Converged yarn–yarn contact relaxation of the knot model's control points (DESIGN
//! §3.3 item 1 and item 9, §3.5 reference (a)): the slow, converged solve that relaxes the
//! stitch templates once and is the reference the three-iteration knot solve is scored
//! against for the contact it lacks.
//!
//! **What it minimises.** Every CP of a [`KnotFrame`] is an unknown (3 per CP; the periodic
//! lattice is fixed). The energy is the knot model's own [H25 eq. 3] — the weighted sum of
//! the signed angle residuals `cos α − cos α₀` ([H25 eq. 5]) at every CP and the relative
//! length residuals `(‖Δx‖ − ‖Δx₀‖)/‖Δx₀‖` ([H25 eq. 6]) of every segment, rest angles and
//! lengths from the model's rest, exactly [`KnotModel::energy`] — plus the contact penalty
//! of DESIGN §3.3 item 1,
//!
//! `E_c = k Σ max(0, 2r·s − d)² / r²`,
//!
//! over pairs of points of the Catmull–Rom yarn curves up-sampled `upsample` times per
//! segment ([`KnotModel::yarn_set`]'s samples, phantom end points on open courses). Each
//! sample is a fixed linear combination of at most four CPs (the Catmull–Rom weights) plus
//! a lattice offset, so `d` and its Jacobian with respect to the CPs are exact by the chain
//! rule. `s` is the target clearance factor, `k` is dimensionless like the eq. 5–6 weights.
//!
//! **Different yarn pieces.** [`super::clearance`] measures two curves as different pieces
//! when they are different courses, or one course and its image along the wales (the
//! periodic course above or below); a course's images along the course are the same yarn.
//! The penalty takes the same pairs and, in addition, two points of the *same* yarn (a
//! course and its images along the course) whose rest arc-length coordinates are more than
//! `4πr` apart: a yarn cannot bend back onto itself within two turns of a circle of
//! radius `2r`, so closer points are neighbours along the yarn, not a contact. (At rest the
//! same-yarn pairs never come within `2r`, so the extension changes nothing there; it
//! keeps a sheared or compressed loop from passing through its own neighbours.)
//!
//! **Candidate pairs** come from a uniform hash grid of cell `2r·s` (27 neighbouring cells,
//! nine lattice images on periodic frames), rebuilt at every energy evaluation (so the
//! energy of a trial step sees every new contact), sorted by `(sample, sample, image)` so
//! that sums run in one order whatever the grid's layout.
//!
//! **Solver: Levenberg–Marquardt** (DESIGN §3.3 item 1) on the stacked residuals
//! `√w_length e_ℓ`, `√w_angle (cos α − cos α₀)`, `√k max(0, 2rs − d)/r`: the damped normal
//! equations `(JᵀJ + λ diag(JᵀJ) + ε I) δ = −Jᵀr` are solved matrix-free (`J` is stored as
//! sparse rows of 3-vectors, `JᵀJ v = Jᵀ(J v)`) by conjugate gradients with the Jacobi
//! preconditioner; `ε = 1e-12 max diag(JᵀJ)` keeps the system regular. Marquardt's
//! `diag(JᵀJ)` is taken per CP (the trace of its 3 × 3 block / 3, the same for its three
//! coordinates), so that damping and preconditioner — and with them every iterate in exact
//! arithmetic — turn with the frame (the per-axis diagonal does not).
//!
//! **Not unique** (measured): eq. 3 acts along each course only, so every course
//! translates freely under it, and only the one-sided, frictionless contact holds the
//! courses against each other — along the contact planes hardly at all. The minimum is a
//! nearly flat valley: started from the symmetric rest the relaxation stops in 42 steps; a
//! rotated copy of the rest (rounding breaks the symmetry) slides along the valley for
//! hundreds of steps to a point a radius or more away at nearly the same energy. Holding
//! every course's centroid does not remove the valley (tried: it then crawls from the rest
//! too). A converged reference under deformation is therefore unique only up to that slide. A step is accepted only if the
//! energy falls (then `λ /= 3`), else `λ *= 4` and it is retried, so the recorded energy
//! never rises. It stops when the relative decrease of an accepted step is below `tol`,
//! when a step's largest coordinate is below `1e-9 r`, when `λ` exceeds `1e12` (no
//! descent left at rounding level) or after `max_iterations`. Everything is serial f64:
//! bit-identical across runs.
//!
//! The relaxed frame keeps the input's `normals`, `theta` (which no longer describe the
//! CPs: they moved freely) and `lattice`; its `stats` are empty.

use super::{KnotFrame, KnotModel, KnotParams, SolveStats, min_clearance, solve};
use crate::curve::basis;
use crate::vec3::{self, V3};
use crate::{Error, Result};
use std::collections::HashMap;

/// Same-yarn points closer than this many `r` along the rest arc length are neighbours, not
/// a contact (see the module documentation).
const SAME_YARN_GAP: f64 = 4.0 * std::f64::consts::PI;

/// Settings of the contact relaxation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Contact penalty weight `k` (dimensionless, against `w_angle = 1`, `w_length = 10²`).
    /// The default `10²` lifts the flat stockinette rest from 0.88 to 0.996 × 2r with the
    /// sample pairs left ~5e-4 r inside `2r·s` (10¹ and 10³ measured the same clearance:
    /// the rest is the spacing of the samples, not the penalty's gap).
    pub k: f64,
    /// Target clearance factor `s`: the penalty acts below a centre-line distance `2r·s`.
    pub clearance: f64,
    /// Curve samples per CP segment (Catmull–Rom). The default 12 puts the samples
    /// ≤ 0.43 r apart on the rest template (its longest segment is 5.17 r at the default
    /// 9r × 8r gauge; ≤ r/2 up to 6r, i.e. up to ~16 % stretch of that segment).
    pub upsample: usize,
    /// Levenberg–Marquardt iterations at most (accepted steps).
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the energy by less than this fraction.
    pub tol: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams { k: 1e2, clearance: 1.0, upsample: 12, max_iterations: 2000, tol: 1e-10 }
    }
}

impl ContactParams {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &str, value: String, want: &str| {
            Err(Error::Invalid(format!("contact relaxation: {field} = {value} must be {want}")))
        };
        if !(self.k.is_finite() && self.k >= 0.0) {
            return bad("k", self.k.to_string(), "finite and non-negative");
        }
        if !(self.clearance.is_finite() && self.clearance > 0.0 && self.clearance <= 10.0) {
            return bad("clearance", self.clearance.to_string(), "finite, in (0, 10]");
        }
        if !(1..=64).contains(&self.upsample) {
            return bad("upsample", self.upsample.to_string(), "in 1..=64");
        }
        if self.max_iterations > 100_000 {
            return bad("max_iterations", self.max_iterations.to_string(), "≤ 100000");
        }
        if !(self.tol.is_finite() && self.tol >= 0.0) {
            return bad("tol", self.tol.to_string(), "finite and non-negative");
        }
        Ok(())
    }
}

/// What a contact relaxation did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RelaxStats {
    /// Accepted Levenberg–Marquardt steps.
    pub iterations: usize,
    /// Total energy (eq. 3 + contact) of the input frame.
    pub energy_initial: f64,
    /// Total energy after each accepted step (non-increasing).
    pub energy_per_iteration: Vec<f64>,
    /// [H25 eq. 3] part of the final energy (no contact).
    pub energy_knot_final: f64,
    /// Contact part of the final energy.
    pub energy_contact_final: f64,
    /// Steps rejected because the energy would have risen (λ raised).
    pub rejected_steps: usize,
    /// Conjugate-gradient iterations over all steps.
    pub cg_iterations: usize,
    /// Sample pairs closer than `2r·s` at the end.
    pub contact_pairs_final: usize,
    /// [`min_clearance`] ratio (distance / 2r, 8 samples per segment) of the input.
    pub clearance_before: f64,
    /// The same of the relaxed frame.
    pub clearance_after: f64,
    /// Largest CP displacement / r.
    pub max_displacement_over_r: f64,
    /// Wall time.
    pub seconds: f64,
}

/// An up-sampled curve point: `Σ w_j x[cp_j] + wrap · l0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Sample {
    pub cps: [(u32, f64); 4],
    pub n: u8,
    pub wrap: f64,
    pub course: u32,
    /// Rest arc-length coordinate / r.
    pub z: f64,
}

/// A contact candidate: samples `a < b`, `b` shifted by lattice image `img`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Pair {
    pub a: u32,
    pub b: u32,
    pub img: u8,
}

/// Sparse rows of `J`: each entry is `∂r/∂x_cp` (a 3-vector) of one CP.
#[derive(Debug, Default)]
pub(super) struct Jacobian {
    pub start: Vec<usize>,
    pub cols: Vec<u32>,
    pub vals: Vec<V3>,
}

impl Jacobian {
    fn push_row(&mut self, entries: &[(u32, V3)]) {
        // Merge repeated CPs (a phantom point or two samples sharing a CP).
        let first = self.cols.len();
        for &(c, v) in entries {
            match self.cols[first..].iter().position(|&x| x == c) {
                Some(i) => self.vals[first + i] = vec3::add(self.vals[first + i], v),
                None => {
                    self.cols.push(c);
                    self.vals.push(v);
                }
            }
        }
        self.start.push(self.cols.len());
    }

    pub fn rows(&self) -> usize {
        self.start.len() - 1
    }

    fn row(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }

    /// `J v`.
    fn apply(&self, v: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for e in self.row(i) {
                let c = 3 * self.cols[e] as usize;
                s += vec3::dot(self.vals[e], [v[c], v[c + 1], v[c + 2]]);
            }
            *o = s;
        }
    }

    /// `Jᵀ y`.
    fn apply_t(&self, y: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for (i, &yi) in y.iter().enumerate() {
            for e in self.row(i) {
                let c = 3 * self.cols[e] as usize;
                for k in 0..3 {
                    out[c + k] += yi * self.vals[e][k];
                }
            }
        }
    }

    /// `diag(JᵀJ)`.
    fn diag(&self, n: usize) -> Vec<f64> {
        let mut d = vec![0.0; n];
        for (e, &c) in self.cols.iter().enumerate() {
            for k in 0..3 {
                d[3 * c as usize + k] += self.vals[e][k] * self.vals[e][k];
            }
        }
        d
    }
}

/// The energy split and the active pairs at one point.
pub(super) struct Eval {
    pub knot: f64,
    pub contact: f64,
    pub pairs: Vec<Pair>,
}

impl Eval {
    pub fn total(&self) -> f64 {
        self.knot + self.contact
    }
}

/// A CP with its wraps along the course (as [`KnotModel::at`]).
type Cp = (usize, i32);

/// The fixed data of one relaxation: residual stencils, samples, lattice.
pub(super) struct Problem {
    p: KnotParams,
    k: f64,
    r: f64,
    cutoff: f64,
    l0: V3,
    images: Vec<V3>,
    /// Per image: its shift along the course (l0 multiples) and whether it shifts along the
    /// wales (a different yarn).
    image_kind: Vec<(f64, bool)>,
    lengths: Vec<(Cp, Cp, f64)>,
    angles: Vec<(Cp, Cp, Cp, f64)>,
    pub samples: Vec<Sample>,
    /// Per course: the rest arc length of one period / r (0 on open courses).
    z_wrap: Vec<f64>,
}

impl Problem {
    pub fn new(
        model: &KnotModel,
        lattice: Option<[V3; 2]>,
        p: &KnotParams,
        c: &ContactParams,
    ) -> Self {
        let r = model.radius;
        let l0 = lattice.map_or([0.0; 3], |l| l[0]);
        let (images, image_kind) = match lattice {
            Some(l) => (-1..=1)
                .flat_map(|i| (-1..=1).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let o = vec3::add(vec3::scale(l[0], i as f64), vec3::scale(l[1], j as f64));
                    (o, (i as f64, j != 0))
                })
                .unzip(),
            None => (vec![[0.0; 3]], vec![(0.0, false)]),
        };
        let mut lengths = Vec::new();
        let mut angles = Vec::new();
        for cc in 0..model.courses {
            for g in model.course_range(cc) {
                if let (Some(a), Some(b)) = (model.at(cc, g, 0), model.at(cc, g, 1)) {
                    lengths.push((a, b, model.rest_distance(a, b)));
                }
            }
        }
        for cc in 0..model.courses {
            for g in model.course_range(cc) {
                if let (Some(a), Some(b), Some(d)) =
                    (model.at(cc, g, -1), model.at(cc, g, 0), model.at(cc, g, 1))
                {
                    angles.push((a, b, d, model.rest_cos(a, b, d)));
                }
            }
        }
        let k = c.upsample;
        let coords = model.rest_coords(k);
        let mut samples = Vec::new();
        let mut z_wrap = Vec::new();
        for cc in 0..model.courses {
            let range = model.course_range(cc);
            let (s0, n) = (range.start, range.len());
            let (zs, zw) = &coords[cc];
            z_wrap.push(zw / r);
            let us = model.sample_params(n, k);
            for (j, &u) in us.iter().enumerate() {
                let (seg, t) = if model.periodic {
                    let s = u.floor();
                    (s as i64, u - s)
                } else {
                    let m = (n - 1) as f64;
                    let u = u.clamp(0.0, m);
                    let s = u.floor().min(m - 1.0);
                    (s as i64, u - s)
                };
                let w = basis(t);
                let mut cps: Vec<(u32, f64)> = Vec::new();
                let mut wrap = 0.0;
                let mut add = |g: usize, wt: f64| {
                    match cps.iter_mut().find(|e| e.0 == g as u32) {
                        Some(e) => e.1 += wt,
                        None => cps.push((g as u32, wt)),
                    };
                };
                for (d, &wt) in w.iter().enumerate() {
                    if wt == 0.0 {
                        continue;
                    }
                    let kv = seg - 1 + d as i64;
                    let n = n as i64;
                    if model.periodic {
                        add(s0 + kv.rem_euclid(n) as usize, wt);
                        wrap += wt * kv.div_euclid(n) as f64;
                    } else if kv < 0 {
                        // P₋₁ = 2P₀ − P₁ (extrapolated phantom, as `YarnCurve`).
                        add(s0, 2.0 * wt);
                        add(s0 + 1, -wt);
                    } else if kv >= n {
                        let e = s0 + n as usize - 1;
                        add(e, 2.0 * wt);
                        add(e - 1, -wt);
                    } else {
                        add(s0 + kv as usize, wt);
                    }
                }
                let mut arr = [(0u32, 0.0); 4];
                arr[..cps.len()].copy_from_slice(&cps);
                samples.push(Sample {
                    cps: arr,
                    n: cps.len() as u8,
                    wrap,
                    course: cc as u32,
                    z: zs[j] / r,
                });
            }
        }
        Problem {
            p: *p,
            k: c.k,
            r,
            cutoff: 2.0 * r * c.clearance,
            l0,
            images,
            image_kind,
            lengths,
            angles,
            samples,
            z_wrap,
        }
    }

    fn sample_pos(&self, s: &Sample, x: &[V3]) -> V3 {
        let mut q = vec3::scale(self.l0, s.wrap);
        for &(g, w) in &s.cps[..s.n as usize] {
            q = vec3::add_scaled(q, x[g as usize], w);
        }
        q
    }

    fn pos(&self, x: &[V3], (g, w): (usize, i32)) -> V3 {
        vec3::add_scaled(x[g], self.l0, w as f64)
    }

    /// Whether samples `a`, `b` (image `img`) are different yarn pieces.
    fn different(&self, a: &Sample, b: &Sample, img: usize) -> bool {
        let (shift, other_yarn) = self.image_kind[img];
        if a.course != b.course || other_yarn {
            return true;
        }
        let dz = a.z - b.z - shift * self.z_wrap[b.course as usize];
        dz.abs() > SAME_YARN_GAP
    }

    /// Sample positions and the sorted pairs of different pieces closer than the cutoff.
    pub fn pairs(&self, x: &[V3]) -> (Vec<V3>, Vec<Pair>) {
        let xs: Vec<V3> = self.samples.iter().map(|s| self.sample_pos(s, x)).collect();
        let mut pairs = Vec::new();
        if self.k == 0.0 {
            return (xs, pairs);
        }
        let cell = self.cutoff;
        let key = |p: V3| [0, 1, 2].map(|i| (p[i] / cell).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, &p) in xs.iter().enumerate() {
            grid.entry(key(p)).or_default().push(i as u32);
        }
        let c2 = self.cutoff * self.cutoff;
        for (a, &pa) in xs.iter().enumerate() {
            for (ii, &o) in self.images.iter().enumerate() {
                let kq = key(vec3::sub(pa, o));
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let Some(list) = grid.get(&[kq[0] + dx, kq[1] + dy, kq[2] + dz]) else {
                                continue;
                            };
                            for &b in list {
                                if b as usize <= a {
                                    continue;
                                }
                                let v = vec3::sub(pa, vec3::add(xs[b as usize], o));
                                if vec3::dot(v, v) < c2
                                    && self.different(
                                        &self.samples[a],
                                        &self.samples[b as usize],
                                        ii,
                                    )
                                {
                                    pairs.push(Pair { a: a as u32, b, img: ii as u8 });
                                }
                            }
                        }
                    }
                }
            }
        }
        pairs.sort_unstable();
        (xs, pairs)
    }

    /// The energy at `x`: eq. 3 (summed as [`KnotModel::energy`]) and the contact term.
    pub fn energy(&self, x: &[V3]) -> Eval {
        let w = &self.p;
        let lengths: f64 = self
            .lengths
            .iter()
            .map(|&(a, b, rest)| {
                let e = (vec3::distance(self.pos(x, a), self.pos(x, b)) - rest) / rest;
                w.w_length * e * e
            })
            .sum();
        let angles: f64 = self
            .angles
            .iter()
            .map(|&(a, b, c, rest)| {
                let e = solve::cos_turn(self.pos(x, a), self.pos(x, b), self.pos(x, c)) - rest;
                w.w_angle * e * e
            })
            .sum();
        let (xs, pairs) = self.pairs(x);
        let contact: f64 = pairs
            .iter()
            .map(|q| {
                let d = self.pair_distance(&xs, q);
                let g = (self.cutoff - d).max(0.0) / self.r;
                self.k * g * g
            })
            .sum();
        Eval { knot: lengths + angles, contact, pairs }
    }

    fn pair_vector(&self, xs: &[V3], q: &Pair) -> V3 {
        let ob = vec3::add(xs[q.b as usize], self.images[q.img as usize]);
        vec3::sub(xs[q.a as usize], ob)
    }

    pub fn pair_distance(&self, xs: &[V3], q: &Pair) -> f64 {
        vec3::length(self.pair_vector(xs, q))
    }

    /// The residual vector (lengths, angles, contacts of `pairs`) and its Jacobian.
    pub fn linearize(&self, x: &[V3], pairs: &[Pair]) -> (Vec<f64>, Jacobian) {
        let mut res = Vec::with_capacity(self.lengths.len() + self.angles.len() + pairs.len());
        let mut jac = Jacobian { start: vec![0], ..Jacobian::default() };
        let (sl, sa, sk) = (self.p.w_length.sqrt(), self.p.w_angle.sqrt(), self.k.sqrt());
        for &(a, b, rest) in &self.lengths {
            let v = vec3::sub(self.pos(x, b), self.pos(x, a));
            let d = vec3::length(v);
            res.push(sl * (d - rest) / rest);
            let u = if d > 0.0 { vec3::scale(v, sl / (rest * d)) } else { [0.0; 3] };
            jac.push_row(&[(a.0 as u32, vec3::scale(u, -1.0)), (b.0 as u32, u)]);
        }
        for &(a, b, c, rest) in &self.angles {
            let (pa, pb, pc) = (self.pos(x, a), self.pos(x, b), self.pos(x, c));
            let cos = solve::cos_turn(pa, pb, pc);
            res.push(sa * (cos - rest));
            let (p, q) = (vec3::sub(pb, pa), vec3::sub(pc, pb));
            let (lp, lq) = (vec3::length(p), vec3::length(q));
            let (dp, dq) = if lp * lq > 0.0 {
                let inv = 1.0 / (lp * lq);
                (
                    vec3::add_scaled(vec3::scale(q, inv), p, -cos / (lp * lp)),
                    vec3::add_scaled(vec3::scale(p, inv), q, -cos / (lq * lq)),
                )
            } else {
                ([0.0; 3], [0.0; 3])
            };
            let (dp, dq) = (vec3::scale(dp, sa), vec3::scale(dq, sa));
            jac.push_row(&[
                (a.0 as u32, vec3::scale(dp, -1.0)),
                (b.0 as u32, vec3::sub(dp, dq)),
                (c.0 as u32, dq),
            ]);
        }
        let xs: Vec<V3> = self.samples.iter().map(|s| self.sample_pos(s, x)).collect();
        let mut entries = Vec::with_capacity(8);
        for q in pairs {
            let v = self.pair_vector(&xs, q);
            let d = vec3::length(v);
            res.push(sk * (self.cutoff - d).max(0.0) / self.r);
            // ∂ρ/∂x_a = −√k/r · v/d where the penalty is active.
            let ga = if d > 0.0 && d < self.cutoff {
                vec3::scale(v, -sk / (self.r * d))
            } else {
                [0.0; 3]
            };
            entries.clear();
            let (sa_, sb_) = (&self.samples[q.a as usize], &self.samples[q.b as usize]);
            for &(g, w) in &sa_.cps[..sa_.n as usize] {
                entries.push((g, vec3::scale(ga, w)));
            }
            for &(g, w) in &sb_.cps[..sb_.n as usize] {
                entries.push((g, vec3::scale(ga, -w)));
            }
            jac.push_row(&entries);
        }
        (res, jac)
    }
}

/// Jacobi-preconditioned conjugate gradients on `(JᵀJ + λD + εI) δ = b`, `D = diag(JᵀJ)`:
/// the solution and the iterations used.
fn pcg(jac: &Jacobian, d: &[f64], lambda: f64, eps: f64, b: &[f64], tol: f64) -> (Vec<f64>, usize) {
    let n = b.len();
    let max_it = (2 * n).clamp(50, 4000);
    let a_diag: Vec<f64> = d.iter().map(|&x| (1.0 + lambda) * x + eps).collect();
    let mut tmp = vec![0.0; jac.rows()];
    let apply = |v: &[f64], out: &mut [f64], tmp: &mut [f64]| {
        jac.apply(v, tmp);
        jac.apply_t(tmp, out);
        for i in 0..n {
            out[i] += (lambda * d[i] + eps) * v[i];
        }
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let mut z: Vec<f64> = r.iter().zip(&a_diag).map(|(r, a)| r / a).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let b_norm = dot(b, b).sqrt();
    let mut ap = vec![0.0; n];
    let mut it = 0;
    while it < max_it && dot(&r, &r).sqrt() > tol * b_norm {
        it += 1;
        apply(&p, &mut ap, &mut tmp);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        for i in 0..n {
            z[i] = r[i] / a_diag[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    (x, it)
}

impl KnotModel {
    /// Relaxes every CP of `frame` to a minimum of [H25 eq. 3] (`p`'s weights, the model's
    /// rest) plus the yarn–yarn contact penalty of `c` by Levenberg–Marquardt (see the
    /// module [`relax`](self) documentation). Returns the relaxed frame and what it did.
    pub fn relax_contact(
        &self,
        frame: &KnotFrame,
        p: &KnotParams,
        c: &ContactParams,
    ) -> Result<(KnotFrame, RelaxStats)> {
        let start = std::time::Instant::now();
        p.validate()?;
        c.validate()?;
        self.check_frame(frame)?;
        let r = self.radius;
        let clearance = |points: &[V3]| -> Result<f64> {
            let f = KnotFrame { points: points.to_vec(), ..frame.clone() };
            Ok(min_clearance(&self.yarn_set(&f, 1)?, frame.lattice, r, 8).ratio)
        };
        let prob = Problem::new(self, frame.lattice, p, c);
        let n = 3 * frame.points.len();
        let mut x = frame.points.clone();
        let mut cur = prob.energy(&x);
        let mut stats = RelaxStats {
            energy_initial: cur.total(),
            clearance_before: clearance(&x)?,
            ..RelaxStats::default()
        };
        let mut lambda = 1e-3;
        let mut nu = 2.0;
        let mut jv = Vec::new();
        'outer: while stats.iterations < c.max_iterations && cur.total() > 0.0 {
            let (res, jac) = prob.linearize(&x, &cur.pairs);
            let mut g = vec![0.0; n];
            jac.apply_t(&res, &mut g);
            let b: Vec<f64> = g.iter().map(|v| -v).collect();
            // diag(JᵀJ) averaged over each CP's three coordinates (the trace of its 3 × 3
            // block / 3): damping and preconditioner invariant under rotations.
            let mut d = jac.diag(n);
            for c in d.chunks_mut(3) {
                let m = (c[0] + c[1] + c[2]) / 3.0;
                c.fill(m);
            }
            let eps = 1e-12 * d.iter().cloned().fold(0.0, f64::max);
            jv.resize(jac.rows(), 0.0);
            loop {
                let (delta, its) = pcg(&jac, &d, lambda, eps, &b, 1e-10);
                stats.cg_iterations += its;
                let step = delta.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if !step.is_finite() || step < 1e-9 * r {
                    break 'outer;
                }
                // Reduction the Gauss–Newton model predicts: −gᵀδ − ½‖Jδ‖².
                jac.apply(&delta, &mut jv);
                let gd: f64 = g.iter().zip(&delta).map(|(a, b)| a * b).sum();
                let predicted = -gd - 0.5 * jv.iter().map(|v| v * v).sum::<f64>();
                let trial: Vec<V3> = x
                    .iter()
                    .enumerate()
                    .map(|(i, q)| vec3::add(*q, [delta[3 * i], delta[3 * i + 1], delta[3 * i + 2]]))
                    .collect();
                let e = prob.energy(&trial);
                if e.total() < cur.total() {
                    let rel = (cur.total() - e.total()) / cur.total();
                    // Nielsen's update: the better the model predicted the decrease, the
                    // less damping.
                    let rho =
                        if predicted > 0.0 { (cur.total() - e.total()) / predicted } else { 0.0 };
                    lambda =
                        (lambda * (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3))).max(1e-15);
                    nu = 2.0;
                    x = trial;
                    cur = e;
                    stats.iterations += 1;
                    stats.energy_per_iteration.push(cur.total());
                    if rel < c.tol {
                        break 'outer;
                    }
                    break;
                }
                stats.rejected_steps += 1;
                lambda *= nu;
                nu *= 2.0;
                if lambda > 1e12 {
                    break 'outer;
                }
            }
        }
        stats.energy_knot_final = cur.knot;
        stats.energy_contact_final = cur.contact;
        stats.contact_pairs_final = cur.pairs.len();
        stats.max_displacement_over_r = x
            .iter()
            .zip(&frame.points)
            .map(|(a, b)| vec3::distance(*a, *b) / r)
            .fold(0.0, f64::max);
        stats.clearance_after = clearance(&x)?;
        stats.seconds = start.elapsed().as_secs_f64();
        let out = KnotFrame {
            points: x,
            normals: frame.normals.clone(),
            theta: frame.theta.clone(),
            stats: SolveStats::default(),
            lattice: frame.lattice,
        };
        Ok((out, stats))
    }

    /// The contact-relaxed template: [`Self::relax_contact`] of the model's own rest frame.
    pub fn relaxed_rest(
        &self,
        p: &KnotParams,
        c: &ContactParams,
    ) -> Result<(KnotFrame, RelaxStats)> {
        self.relax_contact(&self.rest, p, c)
    }

    fn check_frame(&self, frame: &KnotFrame) -> Result<()> {
        if frame.points.len() != self.cp_count()
            || frame.normals.len() != self.cp_count()
            || frame.lattice.is_some() != self.periodic
        {
            return Err(Error::Invalid(format!(
                "contact relaxation: frame of {} points, {} normals ({}) does not match the \
                 model's {} CPs ({})",
                frame.points.len(),
                frame.normals.len(),
                if frame.lattice.is_some() { "periodic" } else { "open" },
                self.cp_count(),
                if self.periodic { "periodic" } else { "open" }
            )));
        }
        if let Some(i) = frame.points.iter().position(|q| !vec3::is_finite(*q)) {
            return Err(Error::Invalid(format!(
                "contact relaxation: frame point {i} is not finite: {:?}",
                frame.points[i]
            )));
        }
        if let Some(l) = frame.lattice
            && !(vec3::is_finite(l[0]) && vec3::is_finite(l[1]))
        {
            return Err(Error::Invalid(format!("contact relaxation: lattice {l:?} is not finite")));
        }
        Ok(())
    }
}
