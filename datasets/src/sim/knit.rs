//! The knit animation of Chen et al. 2003 §4: a mass–spring mesh over a loop grid, mass
//! points at the loop corners and "two triangles per knit loop" ([C03 §4.1.1]), with
//! stretch/compression springs along wales and courses ([C03 §4.1.1], the corrected
//! exponential law of [`super::springs`]), bending and shear angle springs
//! ([`super::angles`]), the thickness field against a collider ([C03 eq. 1–2], corrected
//! in [`super::field`]), self-contact with its own field and dynamic self-friction
//! (`c₇`, `c₈`, [C03 §4.1.3]), air drag `c₉` and the time loop of [C03 §4.2].
//!
//! **Grid.** `courses × wales` cells, corner nodes `(courses + 1) × (wales + 1)` indexed
//! `c·(wales + 1) + w`, the layout of `yarn::knit::StitchMesh::corners`, so positions can be
//! copied into a stitch mesh as they are. "Along a wale" means from course `c` to `c + 1`
//! at fixed `w`; "along a course" from wale `w` to `w + 1`. Cell `(c, w)` is split into the
//! triangles `[n₀₀, n₀₁, n₁₁]` and `[n₀₀, n₁₁, n₁₀]` (`n_{dc,dw}`).
//!
//! **Constants.** [`KnitSimParams::default`] holds the numbers of [C03 §6] in the paper's
//! own units, corrected as the knit design says (§1.3 items 1–3: slack where the forces
//! vanish, the continuous exponential law, `c₆` and `c₈` replaced by the C¹ barrier), and
//! two scales turn them into SI [choice]:
//! - the paper's **length unit** `L` ([`KnitSimParams::length_unit_m`], 3 mm by default,
//!   about a chunky yarn's diameter): `T = 0.9 L`, `τ = 0.1 L`, so the fabric is `2T =
//!   5.4 mm` thick;
//! - the paper's **force unit** `F` ([`KnitSimParams::force_unit_n`], 1 mN by default):
//!   `c₀, c₁` (N) = value·F, `c₂` (N·m/rad²) = value·F·L, `c₃, c₄` (N/rad) = value·F,
//!   `c₅, c₇` (N/m²) = value·F/L². With a node of 9 mg (300 g/m² over 6 × 5 mm loops)
//!   the field's largest eq.-1 force `c₅(T − τ)² = 0.128 F` carries its weight, so cloth
//!   rests on the field at `d* = T − √(mg/c₅) ≈ 0.7 mm`, not inside the barrier.
//!
//! `c₉ = 0.6` is read as a rate (1/s, drag `−c₉ m v`). Every node has the same mass (a
//! loop's share of the fabric), which keeps the self-friction impulses momentum-exact.

use super::angles::{AngleKind, AngleSpring};
use super::collide::SelfContact;
use super::field::ThicknessField;
use super::friction::Friction;
use super::springs::{LawKind, Spring, SpringLaw};
use super::step::{BodyContact, Integrator, SimParams, Simulator};
use super::{Cloth, Collider};
use crate::vec3::{V3, cross, dot, length, sub};
use crate::{Error, Result};

/// Constants of the knit animation, in the paper's units where it gives them (see the
/// module documentation for the conversion to SI).
#[derive(Debug, Clone, PartialEq)]
pub struct KnitSimParams {
    /// Loop width: rest length along a course (m).
    pub wale_spacing_m: f64,
    /// Loop height: rest length along a wale (m).
    pub course_spacing_m: f64,
    /// Fabric mass per area (kg/m²); each node gets one loop's share.
    pub areal_density_kg_m2: f64,
    /// The paper's length unit in metres.
    pub length_unit_m: f64,
    /// The paper's force unit in newtons.
    pub force_unit_n: f64,
    /// `c₀` along a wale, along a course (1500, 2000).
    pub stretch_wale_course: [f64; 2],
    /// `c₁` compression (3000).
    pub compression: f64,
    /// `c₂` bending along a wale, along a course (100, 150).
    pub bend_wale_course: [f64; 2],
    /// `c₃`, `c₄` shear (1000, 1000): `c₃` at the corners on the cell's split diagonal
    /// (`n₀₀`, `n₁₁`), `c₄` at the other two.
    pub shear: [f64; 2],
    /// Slack interval `[θ₂, θ₁]` × rest length where no stretch force acts (0.95, 1.05;
    /// the paper swaps the names, design §1.3 item 1).
    pub slack: [f64; 2],
    /// The stretch law (the corrected exponential by default).
    pub law: LawKind,
    /// Spring damping as a fraction of critical (not in the paper, which filters the
    /// jitter afterwards instead; 0.02 by default, 0 to follow the paper).
    pub spring_damping: f64,
    /// `c₅` of the body field (0.2, paper units).
    pub field_c5: f64,
    /// `T` of both fields (0.9 L).
    pub field_reach: f64,
    /// `τ`, where the barrier begins (0.1 L).
    pub field_tau: f64,
    /// `c₇` of the self field (0.3, paper units).
    pub self_c7: f64,
    /// `K_s` (1).
    pub static_friction: f64,
    /// `K_d` (0.5), also between layers.
    pub dynamic_friction: f64,
    /// `c₉` air drag (0.6 /s).
    pub air_drag_per_s: f64,
    /// Half-angle of the self-contact influence cone (45°).
    pub cone_half_angle_deg: f64,
    /// Whether the knit collides with itself.
    pub self_collision: bool,
    /// Gravity (m/s²).
    pub gravity: V3,
    /// The update rule (velocity Verlet by default; the paper's is `MidpointRk2`).
    pub integrator: Integrator,
    /// Largest step (s): one frame at 25 fps.
    pub dt_max: f64,
    /// Factor of the stiffness bound `c·√(m/k)`.
    pub cfl: f64,
    /// Halvings before a penetration is resolved by projection.
    pub max_halvings: u32,
}

impl Default for KnitSimParams {
    fn default() -> Self {
        KnitSimParams {
            wale_spacing_m: 0.006,
            course_spacing_m: 0.005,
            areal_density_kg_m2: 0.3,
            length_unit_m: 0.003,
            force_unit_n: 1e-3,
            stretch_wale_course: [1500.0, 2000.0],
            compression: 3000.0,
            bend_wale_course: [100.0, 150.0],
            shear: [1000.0, 1000.0],
            slack: [0.95, 1.05],
            law: LawKind::Exponential,
            spring_damping: 0.02,
            field_c5: 0.2,
            field_reach: 0.9,
            field_tau: 0.1,
            self_c7: 0.3,
            static_friction: 1.0,
            dynamic_friction: 0.5,
            air_drag_per_s: 0.6,
            cone_half_angle_deg: 45.0,
            self_collision: true,
            gravity: [0.0, 0.0, -9.81],
            integrator: Integrator::VelocityVerlet,
            dt_max: 1.0 / 25.0,
            cfl: 0.5,
            max_halvings: 6,
        }
    }
}

impl KnitSimParams {
    /// Checks every constant; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("wale_spacing_m", self.wale_spacing_m),
            ("course_spacing_m", self.course_spacing_m),
            ("areal_density_kg_m2", self.areal_density_kg_m2),
            ("length_unit_m", self.length_unit_m),
            ("force_unit_n", self.force_unit_n),
            ("stretch (wale)", self.stretch_wale_course[0]),
            ("stretch (course)", self.stretch_wale_course[1]),
            ("field_reach", self.field_reach),
            ("dt_max", self.dt_max),
            ("cfl", self.cfl),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Invalid(format!(
                    "knit sim: {name} = {v} must be finite and > 0"
                )));
            }
        }
        let non_negative = [
            ("compression", self.compression),
            ("bend (wale)", self.bend_wale_course[0]),
            ("bend (course)", self.bend_wale_course[1]),
            ("shear c3", self.shear[0]),
            ("shear c4", self.shear[1]),
            ("spring_damping", self.spring_damping),
            ("field_c5", self.field_c5),
            ("self_c7", self.self_c7),
            ("static_friction", self.static_friction),
            ("dynamic_friction", self.dynamic_friction),
            ("air_drag_per_s", self.air_drag_per_s),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Invalid(format!(
                    "knit sim: {name} = {v} must be finite and ≥ 0"
                )));
            }
        }
        let [lo, hi] = self.slack;
        if !(lo > 0.0 && lo <= 1.0 && hi >= 1.0 && hi.is_finite()) {
            return Err(Error::Invalid(format!(
                "knit sim: slack [{lo}, {hi}] must satisfy 0 < θ₂ ≤ 1 ≤ θ₁"
            )));
        }
        if !(self.field_tau > 0.0 && self.field_tau < self.field_reach) {
            return Err(Error::Invalid(format!(
                "knit sim: the barrier start τ = {} must lie in (0, T = {})",
                self.field_tau, self.field_reach
            )));
        }
        if !(self.cone_half_angle_deg > 0.0 && self.cone_half_angle_deg <= 90.0) {
            return Err(Error::Invalid(format!(
                "knit sim: cone half-angle {}° must lie in (0°, 90°]",
                self.cone_half_angle_deg
            )));
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return Err(Error::Invalid("knit sim: gravity must be finite".into()));
        }
        Ok(())
    }

    /// Mass of one node (kg).
    pub fn node_mass_kg(&self) -> f64 {
        self.areal_density_kg_m2 * self.wale_spacing_m * self.course_spacing_m
    }

    /// The body field in SI (`c₅`, `T`, `τ`).
    pub fn body_field(&self) -> ThicknessField {
        let l = self.length_unit_m;
        let c5 = self.field_c5 * self.force_unit_n / (l * l);
        ThicknessField::new(c5, self.field_reach * l, self.field_tau * l)
    }

    /// The self field in SI (`c₇`, `T`, `τ`).
    pub fn self_field(&self) -> ThicknessField {
        let l = self.length_unit_m;
        let c7 = self.self_c7 * self.force_unit_n / (l * l);
        ThicknessField::new(c7, self.field_reach * l, self.field_tau * l)
    }

    /// The simulator constants (with a body field only if there is a collider).
    pub fn sim_params(&self, with_body: bool) -> SimParams {
        let friction =
            Friction { static_coef: self.static_friction, dynamic_coef: self.dynamic_friction };
        let l = self.length_unit_m;
        SimParams {
            gravity: self.gravity,
            air_viscosity: self.air_drag_per_s,
            body: with_body.then(|| BodyContact { field: self.body_field(), friction }),
            self_contact: self.self_collision.then(|| SelfContact {
                field: self.self_field(),
                margin: 0.5 * self.field_reach * l,
                dynamic_friction: self.dynamic_friction,
                cone_cos: self.cone_half_angle_deg.to_radians().cos(),
            }),
            dt_max: self.dt_max,
            cfl: self.cfl,
            max_halvings: self.max_halvings,
            integrator: self.integrator,
        }
    }
}

/// The loop grid's size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopGrid {
    /// Courses (cell rows).
    pub courses: usize,
    /// Wales (cell columns).
    pub wales: usize,
}

impl LoopGrid {
    /// Node index of corner `(c, w)`.
    pub fn node(&self, c: usize, w: usize) -> u32 {
        (c * (self.wales + 1) + w) as u32
    }

    /// Number of corner nodes.
    pub fn nodes(&self) -> usize {
        (self.courses + 1) * (self.wales + 1)
    }

    /// Two triangles per loop, course-major.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut t = Vec::with_capacity(2 * self.courses * self.wales);
        for c in 0..self.courses {
            for w in 0..self.wales {
                let (n00, n01) = (self.node(c, w), self.node(c, w + 1));
                let (n10, n11) = (self.node(c + 1, w), self.node(c + 1, w + 1));
                t.push([n00, n01, n11]);
                t.push([n00, n11, n10]);
            }
        }
        t
    }
}

/// The static cloth of a knit loop grid: masses, springs, angle springs and triangles.
pub fn knit_cloth(grid: LoopGrid, p: &KnitSimParams) -> Result<Cloth> {
    p.validate()?;
    if grid.courses == 0 || grid.wales == 0 {
        return Err(Error::Invalid(format!(
            "knit sim: a loop grid of {} × {} cells needs at least one cell",
            grid.courses, grid.wales
        )));
    }
    if grid.nodes() > u32::MAX as usize / 8 {
        return Err(Error::Invalid(format!("knit sim: {} nodes are too many", grid.nodes())));
    }
    let [lo, hi] = p.slack;
    let law = |c0: f64| SpringLaw {
        kind: p.law,
        lo,
        hi,
        compression: p.compression / c0,
        damping: p.spring_damping,
        max_tension: f64::INFINITY,
    };
    let f = p.force_unit_n;
    let laws = vec![law(p.stretch_wale_course[0]), law(p.stretch_wale_course[1])];
    let mut cloth = Cloth::new(vec![p.node_mass_kg(); grid.nodes()], grid.triangles(), laws);
    let (lw, lc) = (p.course_spacing_m, p.wale_spacing_m);
    let (ks_wale, ks_course) = (p.stretch_wale_course[0] * f, p.stretch_wale_course[1] * f);
    for c in 0..=grid.courses {
        for w in 0..=grid.wales {
            let n = grid.node(c, w);
            // c₀ = k θ_hi, so k = c₀ / (hi · rest).
            if c < grid.courses {
                let b = grid.node(c + 1, w);
                cloth.springs.push(Spring { a: n, b, rest: lw, k: ks_wale / (hi * lw), law: 0 });
            }
            if w < grid.wales {
                let b = grid.node(c, w + 1);
                cloth.springs.push(Spring { a: n, b, rest: lc, k: ks_course / (hi * lc), law: 1 });
            }
        }
    }
    let bend = |nodes: [u32; 3], c2: f64| AngleSpring {
        nodes,
        rest: std::f64::consts::PI,
        kappa: c2 * f * p.length_unit_m,
        kind: AngleKind::Bend,
    };
    for c in 0..=grid.courses {
        for w in 0..=grid.wales {
            if c >= 1 && c < grid.courses && p.bend_wale_course[0] > 0.0 {
                let nodes = [grid.node(c - 1, w), grid.node(c, w), grid.node(c + 1, w)];
                cloth.angles.push(bend(nodes, p.bend_wale_course[0]));
            }
            if w >= 1 && w < grid.wales && p.bend_wale_course[1] > 0.0 {
                let nodes = [grid.node(c, w - 1), grid.node(c, w), grid.node(c, w + 1)];
                cloth.angles.push(bend(nodes, p.bend_wale_course[1]));
            }
        }
    }
    let lever = 0.5 * (lw + lc);
    for c in 0..grid.courses {
        for w in 0..grid.wales {
            let (n00, n01) = (grid.node(c, w), grid.node(c, w + 1));
            let (n10, n11) = (grid.node(c + 1, w), grid.node(c + 1, w + 1));
            // Corner, its course neighbour, its wale neighbour within the cell.
            for (corner, along_course, along_wale, c34) in [
                (n00, n01, n10, p.shear[0]),
                (n11, n10, n01, p.shear[0]),
                (n01, n00, n11, p.shear[1]),
                (n10, n11, n00, p.shear[1]),
            ] {
                if c34 > 0.0 {
                    cloth.angles.push(AngleSpring {
                        nodes: [along_course, corner, along_wale],
                        rest: 0.5 * std::f64::consts::PI,
                        kappa: c34 * f * lever,
                        kind: AngleKind::Shear,
                    });
                }
            }
        }
    }
    cloth.finish();
    Ok(cloth)
}

/// Corner positions of a flat rest grid: corner `(c, w)` at
/// `origin + w·wale_spacing·along_course + c·course_spacing·along_wale`.
pub fn flat_positions(
    grid: LoopGrid,
    p: &KnitSimParams,
    origin: V3,
    along_course: V3,
    along_wale: V3,
) -> Result<Vec<V3>> {
    let (u, v) = (unit(along_course)?, unit(along_wale)?);
    if length(cross(u, v)) < 1e-6 {
        return Err(Error::Invalid("knit sim: the grid's two directions are parallel".into()));
    }
    let mut x = Vec::with_capacity(grid.nodes());
    for c in 0..=grid.courses {
        for w in 0..=grid.wales {
            let (a, b) = (w as f64 * p.wale_spacing_m, c as f64 * p.course_spacing_m);
            x.push([0, 1, 2].map(|k| origin[k] + a * u[k] + b * v[k]));
        }
    }
    Ok(x)
}

fn unit(a: V3) -> Result<V3> {
    let l = length(a);
    if l.is_finite() && l > 0.0 {
        Ok([a[0] / l, a[1] / l, a[2] / l])
    } else {
        Err(Error::Invalid(format!("knit sim: direction {a:?} must be finite and non-zero")))
    }
}

/// A knit in motion: the loop grid, its simulator and the collider it meets.
pub struct KnitSim<'a> {
    /// The loop grid.
    pub grid: LoopGrid,
    /// Positions, velocities, cloth and constants.
    pub sim: Simulator<'a>,
}

impl<'a> KnitSim<'a> {
    /// A knit of `grid` starting at rest at `positions` (`(courses+1)·(wales+1)` corners in
    /// the `StitchMesh` order), colliding with `collider` if given. Rest lengths come from
    /// the parameters, not from `positions`, so a knit may start stretched.
    pub fn new(
        grid: LoopGrid,
        positions: Vec<V3>,
        params: &KnitSimParams,
        collider: Option<&'a dyn Collider>,
    ) -> Result<Self> {
        let cloth = knit_cloth(grid, params)?;
        if positions.len() != grid.nodes() {
            return Err(Error::Invalid(format!(
                "knit sim: {} positions for a {} × {} loop grid, which has {} corners",
                positions.len(),
                grid.courses,
                grid.wales,
                grid.nodes()
            )));
        }
        if !positions.iter().all(|p| p.iter().all(|c| c.is_finite())) {
            return Err(Error::Invalid("knit sim: positions must be finite".into()));
        }
        let sim = Simulator::new(cloth, positions, params.sim_params(collider.is_some()), collider);
        Ok(KnitSim { grid, sim })
    }

    /// Corner positions in the `StitchMesh::corners` order (m).
    pub fn positions(&self) -> &[V3] {
        &self.sim.x
    }

    /// Pins or frees a whole course, moving at `velocity` while pinned.
    pub fn pin_course(&mut self, course: usize, pinned: bool, velocity: V3) {
        for w in 0..=self.grid.wales {
            let i = self.grid.node(course, w) as usize;
            self.sim.cloth.pinned[i] = pinned;
            self.sim.pin_velocity[i] = if pinned { velocity } else { [0.0; 3] };
        }
    }

    /// Mean unit normal of the knit (for tests and scenes).
    pub fn mean_normal(&self) -> V3 {
        let x = &self.sim.x;
        let s = self.sim.cloth.triangles.iter().fold([0.0; 3], |s, t| {
            let n = cross(
                sub(x[t[1] as usize], x[t[0] as usize]),
                sub(x[t[2] as usize], x[t[0] as usize]),
            );
            [s[0] + n[0], s[1] + n[1], s[2] + n[2]]
        });
        let l = dot(s, s).sqrt();
        if l > 0.0 { [s[0] / l, s[1] / l, s[2] / l] } else { [0.0, 0.0, 1.0] }
    }
}
