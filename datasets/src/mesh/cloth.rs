//! A square cloth dropped over a sphere standing on the ground: a mass-spring simulation in
//! the spirit of Chen et al. 2003, §4 ("knitwear animation"), with only the effects this
//! set-up calls for.
//!
//! - **Springs with a slack interval** (§4.1.1): structural, shear and bending springs
//!   exert no force while their length stays within `[1 − s, 1 + s]` × rest length (the
//!   paper models a 5 % interval for knitwear), and a linear force outside it (the paper's
//!   exponential law is replaced by a linear one, which is enough for a drape), plus a
//!   little damping along each spring.
//! - **Thickness force field** (§4.1.2, [C03 eq. 1]): an obstacle point at distance `d < T` from
//!   the cloth's mid-surface is repelled with `c₅ (T − d)²` along the contact normal; the
//!   field is applied to cloth nodes near the sphere and the ground.
//! - **Friction** (§4.1.3): static (tangential force cancelled while below `K_s |F|`) and
//!   dynamic (`K_d |F|` against the sliding velocity), plus air viscosity `−c₉ v`.
//! - **Adaptive time step** (§4.2): each step starts from a default limited by a CFL-type
//!   condition (spring stiffness and node speed against the thickness); when a node would
//!   end inside an obstacle, the step is retried with half the time step (up to six
//!   times; a node still inside is then put back on the surface, inelastically).
//!
//! Integration is velocity Verlet (second order like the paper's RK2, but symplectic, so
//! stiff springs do not gain energy). Self-collision is not simulated: a cloth settling on
//! a convex obstacle barely touches itself.

use super::Mesh;
use crate::vec3::{V3, add, dot, length, scale, sub};
use crate::{Error, Result};

/// Parameters of the drape (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct DrapeParams {
    /// Vertices per side of the square cloth.
    pub n: usize,
    /// Side of the cloth (m).
    pub size_m: f64,
    /// Radius of the sphere (m); its centre is the origin, the ground is at `z = −r`.
    pub sphere_radius_m: f64,
    /// Total mass (kg).
    pub mass_kg: f64,
    /// Stiffness of structural springs (N/m); shear ×0.5, bending ×0.05.
    pub stretch_n_per_m: f64,
    /// Half-width of the slack interval, as a fraction of the rest length.
    pub slack: f64,
    /// Half-thickness `T` of the force field around the cloth (m).
    pub thickness_m: f64,
    /// Static friction coefficient `K_s`.
    pub static_friction: f64,
    /// Dynamic friction coefficient `K_d`.
    pub dynamic_friction: f64,
    /// Air viscosity per unit mass `c₉/m` (1/s).
    pub air_viscosity: f64,
    /// Simulated time (s).
    pub duration_s: f64,
}

impl DrapeParams {
    /// Defaults for an `n × n` cloth of 1 m over a sphere of 0.3 m.
    pub fn new(n: usize) -> Self {
        DrapeParams {
            n,
            size_m: 1.0,
            sphere_radius_m: 0.3,
            mass_kg: 0.2,
            stretch_n_per_m: 100.0,
            slack: 0.03,
            thickness_m: 0.004,
            static_friction: 0.6,
            dynamic_friction: 0.4,
            air_viscosity: 1.5,
            duration_s: 1.6,
        }
    }
}

/// The draped cloth and how the simulation went.
#[derive(Debug, Clone)]
pub struct DrapeResult {
    /// The cloth mesh (UVs: one unit per metre, `u = x`, `v = y` of the flat cloth).
    pub mesh: Mesh,
    /// Time steps taken.
    pub steps: usize,
    /// Steps retried with a halved time step after a predicted penetration.
    pub halvings: usize,
    /// Deepest remaining penetration of a node into an obstacle (m, ≥ 0).
    pub max_penetration_m: f64,
}

struct Spring {
    a: usize,
    b: usize,
    rest: f64,
    k: f64,
}

struct Sim<'a> {
    p: &'a DrapeParams,
    springs: Vec<Spring>,
    node_mass: f64,
    c5: f64,
}

const G: f64 = 9.81;

impl Sim<'_> {
    /// Signed distance to the nearest obstacle and its outward normal.
    fn obstacle(&self, x: V3) -> (f64, V3) {
        let r = self.p.sphere_radius_m;
        let len = length(x).max(1e-12);
        let d_sphere = len - r;
        let d_ground = x[2] + r;
        if d_sphere < d_ground {
            (d_sphere, scale(x, 1.0 / len))
        } else {
            (d_ground, [0.0, 0.0, 1.0])
        }
    }

    fn accelerations(&self, x: &[V3], v: &[V3], acc: &mut [V3]) {
        let m = self.node_mass;
        for (i, a) in acc.iter_mut().enumerate() {
            *a = add([0.0, 0.0, -G * m], scale(v[i], -self.p.air_viscosity * m));
        }
        for s in &self.springs {
            let d = sub(x[s.b], x[s.a]);
            let l = length(d).max(1e-12);
            let dir = scale(d, 1.0 / l);
            let (lo, hi) = (s.rest * (1.0 - self.p.slack), s.rest * (1.0 + self.p.slack));
            let stretch = l - l.clamp(lo, hi);
            let damp = 0.05 * (s.k * m).sqrt() * dot(sub(v[s.b], v[s.a]), dir);
            let f = scale(dir, s.k * stretch + damp);
            acc[s.a] = add(acc[s.a], f);
            acc[s.b] = sub(acc[s.b], f);
        }
        let t = self.p.thickness_m;
        for i in 0..x.len() {
            let (d, n) = self.obstacle(x[i]);
            if d >= t {
                acc[i] = scale(acc[i], 1.0 / m);
                continue;
            }
            // [C03 eq. 1] of the force field, with a stiff linear extension inside the obstacle.
            let push = self.c5 * (t - d.max(0.0)).powi(2)
                + if d < 0.0 { 2.0 * self.c5 * t * (-d) } else { 0.0 };
            let f_other = acc[i];
            let mut f = add(f_other, scale(n, push));
            let vt = sub(v[i], scale(n, dot(v[i], n)));
            let speed_t = length(vt);
            let ft = sub(f_other, scale(n, dot(f_other, n)));
            if speed_t > 1e-3 {
                f = sub(f, scale(vt, self.p.dynamic_friction * push / speed_t));
            } else if length(ft) <= self.p.static_friction * push {
                f = sub(f, ft);
            }
            acc[i] = scale(f, 1.0 / m);
        }
    }
}

/// Simulates the drape and returns the settled cloth.
pub fn drape(p: &DrapeParams) -> Result<DrapeResult> {
    drape_frames(p, 0).map(|(r, _)| r)
}

/// The cloth mesh of node positions `xs` (UVs: one unit per metre of the flat cloth).
fn cloth_mesh(p: &DrapeParams, xs: &[V3]) -> Mesh {
    let n = p.n;
    let mut mesh = Mesh::default();
    mesh.add_grid(
        n - 1,
        n - 1,
        false,
        |s, tt| {
            let (i, j) =
                ((s * (n - 1) as f64).round() as usize, (tt * (n - 1) as f64).round() as usize);
            xs[j * n + i]
        },
        |s, tt| [s * p.size_m, tt * p.size_m],
    );
    mesh.compute_normals();
    mesh
}

/// [`drape`], also returning the cloth at `frames + 1` evenly spaced times from the flat
/// start (`t = 0`) to the end (`frames = 0`: none): an animated stitch surface with the same
/// vertices and UVs in every frame (a frame is the first state at or after its time).
pub fn drape_frames(p: &DrapeParams, frames: usize) -> Result<(DrapeResult, Vec<Mesh>)> {
    let positive =
        [p.size_m, p.sphere_radius_m, p.mass_kg, p.stretch_n_per_m, p.thickness_m, p.duration_s];
    let valid = (4..=400).contains(&p.n)
        && positive.iter().all(|x| x.is_finite() && *x > 0.0)
        && [p.slack, p.static_friction, p.dynamic_friction, p.air_viscosity]
            .iter()
            .all(|x| x.is_finite() && *x >= 0.0);
    if !valid {
        return Err(Error::Invalid(
            "drape: n must be in 4..=400, sizes, mass, stiffness and time positive".into(),
        ));
    }
    let n = p.n;
    let h = p.size_m / (n - 1) as f64;
    let z0 = p.sphere_radius_m + 1.5 * p.thickness_m;
    let mut x: Vec<V3> = (0..n * n)
        .map(|k| [(k % n) as f64 * h - p.size_m / 2.0, (k / n) as f64 * h - p.size_m / 2.0, z0])
        .collect();
    let mut springs = Vec::new();
    let k = p.stretch_n_per_m;
    for j in 0..n {
        for i in 0..n {
            let id = j * n + i;
            let mut add_spring = |di: usize, dj: isize, kk: f64| {
                let (i2, j2) = (i + di, j as isize + dj);
                if i2 < n && j2 >= 0 && (j2 as usize) < n {
                    let b = j2 as usize * n + i2;
                    springs.push(Spring { a: id, b, rest: length(sub(x[b], x[id])), k: kk });
                }
            };
            add_spring(1, 0, k);
            add_spring(0, 1, k);
            add_spring(1, 1, 0.5 * k);
            add_spring(1, -1, 0.5 * k);
            add_spring(2, 0, 0.05 * k);
            add_spring(0, 2, 0.05 * k);
        }
    }
    let node_mass = p.mass_kg / (n * n) as f64;
    let c5 = 500.0 * node_mass * G / (p.thickness_m * p.thickness_m);
    let sim = Sim { p, springs, node_mass, c5 };
    let k_node = 4.0 * k * 2.0 + 2.0 * c5 * p.thickness_m;
    let dt_cfl = 0.5 * (node_mass / k_node).sqrt();
    let mut v = vec![[0.0; 3]; n * n];
    let mut acc = vec![[0.0; 3]; n * n];
    sim.accelerations(&x, &v, &mut acc);
    let mut recorded = Vec::with_capacity(if frames > 0 { frames + 1 } else { 0 });
    if frames > 0 {
        recorded.push(cloth_mesh(p, &x));
    }
    let frame_time = |k: usize| p.duration_s * k as f64 / frames.max(1) as f64;
    let (mut t, mut steps, mut halvings) = (0.0, 0, 0);
    let (mut xn, mut vh, mut an) = (x.clone(), v.clone(), acc.clone());
    while t < p.duration_s {
        let vmax = v.iter().map(|&w| length(w)).fold(0.0, f64::max);
        let mut dt = dt_cfl.min(0.5 * p.thickness_m / vmax.max(1e-9)).min(1.0 / 25.0);
        for attempt in 0.. {
            for i in 0..n * n {
                vh[i] = add(v[i], scale(acc[i], 0.5 * dt));
                xn[i] = add(x[i], scale(vh[i], dt));
            }
            // Only new penetrations count (a node already inside is being pushed out).
            let penetrates =
                (0..n * n).any(|i| sim.obstacle(xn[i]).0 < 0.0 && sim.obstacle(x[i]).0 >= 0.0);
            if !penetrates || attempt == 6 {
                break;
            }
            dt *= 0.5;
            halvings += 1;
        }
        // Safety net: a node still inside is put back on the surface, its inward velocity
        // removed (an inelastic contact).
        for i in 0..n * n {
            let (d, nrm) = sim.obstacle(xn[i]);
            if d < 0.0 {
                xn[i] = add(xn[i], scale(nrm, -d));
                let vn = dot(vh[i], nrm);
                if vn < 0.0 {
                    vh[i] = sub(vh[i], scale(nrm, vn));
                }
            }
        }
        sim.accelerations(&xn, &vh, &mut an);
        for i in 0..n * n {
            v[i] = add(vh[i], scale(an[i], 0.5 * dt));
        }
        std::mem::swap(&mut x, &mut xn);
        std::mem::swap(&mut acc, &mut an);
        t += dt;
        steps += 1;
        while frames > 0 && recorded.len() <= frames && t >= frame_time(recorded.len()) {
            recorded.push(cloth_mesh(p, &x));
        }
        if x.iter().any(|q| !q.iter().all(|c| c.is_finite())) {
            return Err(Error::Invalid(format!("drape simulation diverged after {steps} steps")));
        }
    }
    let max_penetration_m = x.iter().map(|&q| (-sim.obstacle(q).0).max(0.0)).fold(0.0, f64::max);
    let mesh = cloth_mesh(p, &x);
    while frames > 0 && recorded.len() <= frames {
        recorded.push(mesh.clone());
    }
    Ok((DrapeResult { mesh, steps, halvings, max_penetration_m }, recorded))
}
