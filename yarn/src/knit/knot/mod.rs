//! Knot-based yarn deformation ([H25 §3, §5]): the yarn control points (CPs) of a knit
//! follow an animated stitch mesh through per-face "knots" fitted by Gauss–Newton, with the
//! choices of `shared/knit/DESIGN.md` §3.3.
//!
//! **The knot** ([H25 eq. 1–2]). Where a loop's leg passes through the head of the loop
//! below, the two yarns cross twice: at two crossing contacts `c0` (upper) and `c1`
//! (lower) they lie on top of each other, one `h` in front of the face and one `h` behind;
//! halfway they pass side by side at `p0`, `p1`. A knot is `(x_k, θ, l)`: `d = cos θ e1 +
//! sin θ e2` in the face plane, `b = d × n`, `c0,1 = x_k ± l d`, `p = x_k ± r b`; lifted
//! `c0 ± h n`, `c1 ∓ h n` ([H25 eq. 2], `h` = the skeleton depth, `r` by default). The own
//! yarn of the face runs `c0⁺ → p → c1⁻` (a purl: mirrored along `n`), the loop below runs
//! `c0⁻ → p' → c1⁺`. The four constraints of [H25 eq. 4] (midpoints at `x_k`, `‖p0 − p1‖
//! = 2r`, `d ⟂ b`) hold *by construction* (DESIGN §3.3 item 6), so the solve is
//! unconstrained in `Θ`; `tests.rs` checks them to 1e-12.
//!
//! **Where the knots come from.** Our stitch mesh is [`super::StitchMesh`]'s grid of loop
//! cells; the Chen skeleton with interlock points ([`super::skeleton`]) already places,
//! per knit cell, exactly the six points of two knots at the cell's bottom edge: the
//! interlock points `(0.1723, 0.1892)` and `(0.3277, −0.1892)` (the contacts, depth `±h`)
//! and the leg points `(0.125, 0)` of the own loop and `(0.375, 0)` of the loop below
//! (mirrored on the right). The template takes `x_k` = the contacts' midpoint `(0.25, 0)`,
//! `θ₀`, `l₀` from the contacts (`l₀ = 1.667 r` at the default 9r × 8r gauge) and puts the
//! leg points at `x_k ± r b` (the skeleton's are 2.25 r apart and not ⟂ `d`). A loop has 14
//! CPs: 12 on knots (six of its own face's two knots, six of the face above's) and the
//! sinker and head, which are fixed — 14 × 4 = 56 rendering vertices per face, as
//! [H25 §5.2] counts. Knit and purl faces have knots; increase, decrease and yarn-over
//! cells keep the skeleton's shapes mapped through the face (their knot templates,
//! [H25 Fig. 3], need stitch counts our grid does not track); cables are refused ([H25 §7]:
//! layered structures are unsupported). Faces on the bottom course of a non-periodic mesh
//! have no loop below and keep interpolated points.
//!
//! **Per frame** ([H25 §5.2] with DESIGN §3.3 items 3–5):
//! 1. the face map is the bilinear map of its four corners (exact at corners, the affine
//!    `F` on parallelograms). **Not DESIGN's face normal**: each knot takes the surface
//!    normal at its own position (the corner normals interpolated along the bottom edge),
//!    `e1` = the bottom edge made ⟂ to it, `e2 = n × e1` — the same normal field that
//!    places every other CP, so the knots' `±h` lift and the fixed sinker and head agree on
//!    a bent surface; the cross product of the diagonals (DESIGN §3.3 item 5) only decides
//!    the orientation `o = ±1`, and `b = o (d × n)`, so that a chart laid against the
//!    surface's handedness (courses running down a texture, as on `btf knit compare`'s
//!    garment) gives the mirror image of the rest instead of swapping the two yarns' sides
//!    (`tests.rs`: a mirrored layout reproduces the mirrored rest with energy 0);
//! 2. knots on the bottom edge at `s = 0.25, 0.75`, their spacing blended `d0 + β(d1 −
//!    d0)` ([H25 §6.1], called α there by mistake, item 7): β = 1 interpolates uniformly,
//!    β = 0 keeps the rest spacing; initial `θ, l` = the rest half-vector `l₀ d₀` mapped by
//!    the face map's derivative and projected onto the face plane; every other CP is its
//!    rest stitch coordinate through the face map plus its depth along the surface normal;
//! 3. Gauss–Newton over `Θ = (θ1, l1/r, θ2, l2/r)` with the other CPs held at their initial
//!    positions (that is what makes the faces independent, [H25 §5.2]'s "boundary fixed",
//!    and `par_iter` over faces bit-equal to the serial loop) on the energy of [H25 eq. 3]
//!    with **signed** residuals scaled by `√w` (item 3: `r = √E` loses the sign and has a
//!    0/0 Jacobian at the solution): `√w_angle (cos α − cos α₀)` ([H25 eq. 5]) and
//!    `√w_length (‖Δx‖ − ‖Δx₀‖)/‖Δx₀‖` ([H25 eq. 6], **relative**, item 4: the paper's
//!    `w_length = 10²` is a weight per squared length in its unstated unit; ours is
//!    dimensionless, the paper's ≈ ours / L₀² in its unit); `A = Jᵀ J`, `g = Jᵀ r`, a 4 × 4
//!    Cholesky solve. A step that raises the face energy is halved (up to 20 times; the
//!    paper has no guard) and counted in [`SolveStats`];
//! 4. the yarn curve: CPs → Catmull–Rom, up-sampled `upsample` points per segment (item 8),
//!    with the rest length coordinates (fibers do not slide along a stretched yarn).
//!
//! **What it does not do, measured** (`btf knit deform`, BENCHMARKS.md): the rest template
//! already has the crossing yarns at 0.88 × 2r near the contacts (the Catmull–Rom curves
//! bend towards the face between the `±h` contacts and the side points; the Chen skeleton
//! has 0.82), stretching along the wales keeps that clearance, shear and compression lower
//! it (0.85 at 30 % shear, 0.86 at 10 % course compression), and on the drape — where the
//! cloth compresses and creases within a stitch — the knots make it *worse* than naive
//! interpolation (the length terms push compressed loops sideways through their
//! neighbours): the model's missing contact (DESIGN §3.3 item 9). The knots' templates are
//! the projected skeleton — and a relaxation over the knots' `(θ, l)` could not lift the
//! rest clearance: between a contact (`±h` apart along `n`) and the side points (`2r`
//! apart in the plane, depth 0) the two chords are `2 √(r² t² + h² (1 − t)²)` apart at `t`
//! along them, least at `t = h² / (r² + h²)`: `√2 r` (0.71 × 2r) at `h = r`, set by eq. 1–2
//! alone; the spline rounds that to 0.88. Only a larger lift or side points off the face
//! plane would, which is no longer [H25]'s knot. The contact-relaxed template of DESIGN
//! §3.3 item 1 ([`relax`]) is therefore carried as a detail layer on top of the solve
//! ([`detail`]): the rest mesh gives the relaxed template (0.996 × 2r) and the solve itself
//! is unchanged.
//!
//! **References** ([`KnotModel::reference`], DESIGN §3.5): the same energy minimised over
//! *all* faces jointly by block Gauss–Seidel (each face solved with its neighbours' current
//! CPs, sweeps until no knot parameter moves by more than 1e-12): a stationary point of the
//! global energy, against which the three Jacobi iterations are scored. The paper's model
//! has no yarn–yarn contact at run time (item 9); [`clearance`] measures what that costs.

pub mod clearance;
pub mod detail;
#[cfg(test)]
mod detail_tests;
pub mod relax;
#[cfg(test)]
mod relax_tests;
mod solve;

use super::chart::Stitch;
use super::skeleton::{Key, SkeletonParams, loop_keys};
use super::stitch_mesh::StitchMesh;
use crate::curve::{YarnCurve, YarnSet};
use crate::vec3::{self, V3};
use crate::{Error, Result};
use rayon::prelude::*;

pub use clearance::{Clearance, min_clearance};
pub use detail::RestDetail;
pub use relax::{ContactParams, RelaxStats};

/// Solver settings ([H25 §5.2, §6.1]; DESIGN §3.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnotParams {
    /// Gauss–Newton iterations per frame (the paper: 3).
    pub iterations: usize,
    /// Weight of the angle residuals (the paper: 1).
    pub w_angle: f64,
    /// Weight of the relative length residuals (the paper: 10², ablated to 10³).
    pub w_length: f64,
    /// Knot spacing blend β: 1 uniform interpolation, 0 rest spacing.
    pub beta: f64,
}

impl Default for KnotParams {
    fn default() -> Self {
        KnotParams { iterations: 3, w_angle: 1.0, w_length: 1e2, beta: 1.0 }
    }
}

impl KnotParams {
    fn validate(&self) -> Result<()> {
        let ok = self.w_angle.is_finite()
            && self.w_length.is_finite()
            && self.w_angle >= 0.0
            && self.w_length >= 0.0
            && self.w_angle + self.w_length > 0.0
            && self.beta.is_finite()
            && self.iterations <= 1000;
        if ok {
            Ok(())
        } else {
            Err(Error::Invalid(format!(
                "knot solver: weights {} (angle) and {} (length) must be finite, non-negative \
                 and not both zero, β {} finite, iterations {} ≤ 1000",
                self.w_angle, self.w_length, self.beta, self.iterations
            )))
        }
    }
}

/// The role of a knot CP.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    C0,
    C1,
    P,
}

/// Where a CP comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Source {
    /// Rest stitch coordinates through the face map, plus depth along the normal.
    Interp(Key),
    /// A point of knot `knot` of knot face `face`; `own`: the face's own yarn (else the
    /// loop below); `course_wrap`: lattice periods along the courses to add.
    Knot { face: u32, knot: u8, role: Role, own: bool, course_wrap: i8 },
}

/// The rest knots of one face.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FaceTemplate {
    course: usize,
    wale: usize,
    /// +1 knit, −1 purl: which side the own yarn's upper contact lies on.
    sigma: f64,
    /// Knot positions along the bottom edge (face parameter s).
    s: [f64; 2],
    /// Rest half-vector `c0 − x_k` of each knot in stitch coordinates.
    delta: [[f64; 2]; 2],
    /// Sign of `b` at the own yarn's side point.
    b_own: [f64; 2],
}

/// A CP of a face's stencil: its global index and periodic wraps along the course.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Local {
    global: usize,
    wrap: i32,
    /// `Some((knot, role, own, course_wrap))` for the face's own knot points.
    owned: Option<(u8, Role, bool, i8)>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Residual {
    /// Relative length of the segment between two locals.
    Length { a: u16, b: u16, rest: f64 },
    /// Cosine of the turning angle at `b`.
    Angle { a: u16, b: u16, c: u16, rest: f64 },
}

/// The residuals touching one face's knot points.
#[derive(Debug, Clone, PartialEq)]
struct Stencil {
    locals: Vec<Local>,
    residuals: Vec<Residual>,
}

/// The frame of one knot face in the deformed mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceFrame {
    /// Knot positions.
    pub xk: [V3; 2],
    /// Per knot: in-plane unit vector along the bottom edge.
    pub e1: [V3; 2],
    /// Per knot: `n × e1`.
    pub e2: [V3; 2],
    /// Per knot: the surface normal at the knot (the stitch mesh's corner normals
    /// interpolated along the bottom edge, as for every other CP).
    pub n: [V3; 2],
    /// +1 where the face map keeps the orientation of the canonical patch about `n`, −1
    /// where it mirrors it (a chart laid with courses running against the surface's
    /// handedness): `b = o (d × n)`.
    pub o: f64,
}

/// Knot parameters of one face: `(θ1, l1/r, θ2, l2/r)`.
pub type Theta = [f64; 4];

/// What a solve did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SolveStats {
    /// Knot faces.
    pub faces: usize,
    /// Sum of the face energies (each face's stencil, neighbours fixed) before iterating.
    pub energy_initial: f64,
    /// The same sum after each iteration.
    pub energy_per_iteration: Vec<f64>,
    /// Steps halved because the face energy rose.
    pub guard_triggers: usize,
    /// Steps rejected after 20 halvings (the face kept its parameters).
    pub rejected_steps: usize,
}

/// One solved frame.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotFrame {
    /// Every CP, course-major (see [`KnotModel::course_range`]).
    pub points: Vec<V3>,
    /// The surface normal at every CP (frame anchoring of the fibers).
    pub normals: Vec<V3>,
    /// Knot parameters per knot face.
    pub theta: Vec<Theta>,
    /// Solver statistics.
    pub stats: SolveStats,
    /// Wale lattice vector of a periodic mesh (the courses' shift).
    pub lattice: Option<[V3; 2]>,
}

/// The knot model of one stitch-mesh topology and chart (see the module documentation).
#[derive(Debug)]
pub struct KnotModel {
    courses: usize,
    wales: usize,
    periodic: bool,
    radius: f64,
    skeleton: SkeletonParams,
    spacing: (f64, f64),
    sources: Vec<Source>,
    /// Per CP: `(course, loop, key index)` of the skeleton key it comes from.
    cells: Vec<[u32; 3]>,
    course_start: Vec<usize>,
    faces: Vec<FaceTemplate>,
    stencils: Vec<Stencil>,
    /// The rest (template) CPs on the canonical flat mesh.
    rest: KnotFrame,
    rest_set: YarnSet,
    /// Rest length coordinates of the up-sampled curves per up-sampling factor (per course:
    /// the coordinates and the wrap), computed once per factor: they depend on the rest
    /// alone, and their arc-length quadrature costs more than a solve.
    rest_coords: std::sync::Mutex<Vec<(usize, RestCoords)>>,
}

/// Per course: the length coordinates of the up-sampled points and the length wrap.
type RestCoords = std::sync::Arc<Vec<(Vec<f64>, f64)>>;

fn is_knitlike(s: Stitch) -> bool {
    matches!(s, Stitch::Knit | Stitch::Purl)
}

impl KnotModel {
    /// The model of `mesh`'s topology and chart at rest gauge `spacing = (wale, course)`
    /// metres (the gauge of the templates; a mesh whose faces have other sizes is
    /// deformed). The skeleton's yarn radius and depth set `r` and the lift `h`; jitter
    /// must be 0 and interlock points on.
    pub fn new(mesh: &StitchMesh, skeleton: &SkeletonParams, spacing: (f64, f64)) -> Result<Self> {
        if let Some((c, w)) = (0..mesh.chart.height)
            .flat_map(|c| (0..mesh.chart.width).map(move |w| (c, w)))
            .find(|&(c, w)| mesh.chart.at(c as i64, w as i64).is_cable())
        {
            return Err(Error::Unsupported(format!(
                "knot deformation of chart '{}': the cable at chart course {c}, wale {w} is a \
                 layered structure the knot model cannot represent ([H25 §7])",
                mesh.chart.name
            )));
        }
        if skeleton.jitter != 0.0 || !skeleton.interlock_points {
            return Err(Error::Invalid(
                "knot deformation needs the skeleton with interlock points and no jitter".into(),
            ));
        }
        let r = skeleton.yarn_radius;
        if !(r > 0.0 && r.is_finite() && skeleton.depth.is_finite() && skeleton.depth >= 0.0) {
            return Err(Error::Invalid(format!(
                "knot deformation: yarn radius {r} and depth {} must be finite, the radius \
                 positive",
                skeleton.depth
            )));
        }
        let (sw, sc) = spacing;
        if !(sw > 2.0 * r && sc > 2.0 * r && sw.is_finite() && sc.is_finite()) {
            return Err(Error::Invalid(format!(
                "knot deformation: gauge {sw} × {sc} m must be finite and wider than the yarn \
                 diameter {}",
                2.0 * r
            )));
        }
        let (courses, wales) = (mesh.courses, mesh.wales);
        if courses * wales > 1 << 24 {
            return Err(Error::Limit(format!(
                "knot deformation of {wales} × {courses} faces is too large"
            )));
        }
        let periodic = mesh.lattice.is_some();
        // The canonical rest mesh: the same topology, flat, at the rest gauge.
        let rest_mesh = canonical(mesh, spacing);
        let has_knots = |c: usize, w: usize| {
            is_knitlike(mesh.stitch(c as i64, w as i64)) && (periodic || c > 0)
        };
        let mut face_index = vec![u32::MAX; courses * wales];
        let mut faces = Vec::new();
        for c in 0..courses {
            for w in 0..wales {
                if !has_knots(c, w) {
                    continue;
                }
                let keys = loop_keys(&rest_mesh, c, w, skeleton);
                debug_assert_eq!(keys.len(), 14);
                let knot = |ic0: usize, ip: usize, ic1: usize| {
                    let (k0, kp, k1) = (keys[ic0], keys[ip], keys[ic1]);
                    let xk = [0.5 * (k0.w + k1.w), 0.5 * (k0.c + k1.c)];
                    let delta = [0.5 * (k0.w - k1.w), 0.5 * (k0.c - k1.c)];
                    // b = d × z in the canonical metric frame.
                    let d = [delta[0] * sw, delta[1] * sc];
                    let b = [d[1], -d[0]];
                    let to_p = [(kp.w - xk[0]) * sw, (kp.c - xk[1]) * sc];
                    let sign = if b[0] * to_p[0] + b[1] * to_p[1] >= 0.0 { 1.0 } else { -1.0 };
                    (xk[0] - w as f64, delta, sign)
                };
                let (s0, d0, b0) = knot(4, 5, 6);
                let (s1, d1, b1) = knot(10, 9, 8);
                face_index[c * wales + w] = faces.len() as u32;
                faces.push(FaceTemplate {
                    course: c,
                    wale: w,
                    sigma: if mesh.stitch(c as i64, w as i64) == Stitch::Purl { -1.0 } else { 1.0 },
                    s: [s0, s1],
                    delta: [d0, d1],
                    b_own: [b0, b1],
                });
            }
        }
        // CP sources, course by course.
        let mut sources = Vec::new();
        let mut cells = Vec::new();
        let mut course_start = vec![0];
        for c in 0..courses {
            let loops = if periodic { wales } else { wales + 1 };
            for w in 0..loops {
                let keys = loop_keys(&rest_mesh, c, w, skeleton);
                let keys = if w == wales { &keys[..1] } else { &keys[..] };
                let n = keys.len();
                let above = if c + 1 < courses {
                    Some((c + 1, 0i8))
                } else if periodic {
                    Some((0, 1i8))
                } else {
                    None
                };
                let face_above = above.filter(|_| w < wales).and_then(|(ca, wrap)| {
                    let f = face_index[ca * wales + w];
                    (f != u32::MAX).then_some((f, wrap))
                });
                let own_face =
                    (w < wales).then(|| face_index[c * wales + w]).filter(|&f| f != u32::MAX);
                for (i, key) in keys.iter().enumerate() {
                    let knot_point = |face: u32, knot: u8, role: Role, own: bool, wrap: i8| {
                        Source::Knot { face, knot, role, own, course_wrap: wrap }
                    };
                    let src = match (i, face_above, own_face) {
                        (1..=3, Some((f, wrap)), _) if w < wales => {
                            knot_point(f, 0, [Role::C0, Role::P, Role::C1][i - 1], false, wrap)
                        }
                        (_, Some((f, wrap)), _) if w < wales && i + 3 >= n && i > 3 => {
                            knot_point(f, 1, [Role::C1, Role::P, Role::C0][i + 3 - n], false, wrap)
                        }
                        (4..=6, _, Some(f)) => {
                            knot_point(f, 0, [Role::C0, Role::P, Role::C1][i - 4], true, 0)
                        }
                        (8..=10, _, Some(f)) => {
                            knot_point(f, 1, [Role::C1, Role::P, Role::C0][i - 8], true, 0)
                        }
                        _ => Source::Interp(*key),
                    };
                    sources.push(src);
                    cells.push([c as u32, w as u32, i as u32]);
                }
            }
            course_start.push(sources.len());
        }
        let mut model = KnotModel {
            courses,
            wales,
            periodic,
            radius: r,
            skeleton: skeleton.clone(),
            spacing,
            sources,
            cells,
            course_start,
            faces,
            stencils: Vec::new(),
            rest: KnotFrame {
                points: Vec::new(),
                normals: Vec::new(),
                theta: Vec::new(),
                stats: SolveStats::default(),
                lattice: None,
            },
            rest_set: YarnSet::default(),
            rest_coords: std::sync::Mutex::new(Vec::new()),
        };
        // Rest CPs: the initial guess on the canonical mesh (exactly the template).
        let (frames, theta) = model.frames(&rest_mesh, 1.0)?;
        let (points, normals) = model.points(&rest_mesh, &frames, &theta);
        model.rest = KnotFrame {
            points,
            normals,
            theta,
            stats: SolveStats::default(),
            lattice: rest_mesh.lattice,
        };
        model.stencils = model.build_stencils();
        // The rest curves with their arc length (the one place it is computed).
        model.rest_set = YarnSet::new(
            (0..courses)
                .map(|c| {
                    let r = model.course_range(c);
                    let pts = model.rest.points[r.clone()].to_vec();
                    match model.rest.lattice {
                        Some(l) => YarnCurve::periodic(pts, l[0]),
                        None => YarnCurve::open(pts),
                    }
                    .and_then(|cv| cv.with_normals(model.rest.normals[r].to_vec()))
                })
                .collect::<Result<_>>()?,
            None,
        )?;
        Ok(model)
    }

    /// CP index range of course `c`.
    pub fn course_range(&self, c: usize) -> std::ops::Range<usize> {
        self.course_start[c]..self.course_start[c + 1]
    }

    /// Number of knot faces.
    pub fn knot_faces(&self) -> usize {
        self.faces.len()
    }

    /// Number of CPs.
    pub fn cp_count(&self) -> usize {
        self.sources.len()
    }

    /// The yarn radius r.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The rest (template) frame on the canonical flat mesh.
    pub fn rest(&self) -> &KnotFrame {
        &self.rest
    }

    /// `(course, wale)` of knot face `f`.
    pub fn face_cell(&self, f: usize) -> (usize, usize) {
        (self.faces[f].course, self.faces[f].wale)
    }

    /// `(course, loop, key index)` of CP `i`: the skeleton key ([`super::skeleton::loop_keys`]
    /// of loop cell `(course, loop)`) it comes from; `loop` = the wales on the closing CP of
    /// an open course.
    pub fn cp_cell(&self, i: usize) -> [u32; 3] {
        self.cells[i]
    }

    /// The rest gauge `(wale, course)` in metres.
    pub fn spacing(&self) -> (f64, f64) {
        self.spacing
    }

    /// The skeleton parameters the model was built with.
    pub fn skeleton(&self) -> &SkeletonParams {
        &self.skeleton
    }

    /// Whether the model's mesh is a periodic patch.
    pub fn is_periodic(&self) -> bool {
        self.periodic
    }

    /// Indices of the CPs that belong to knots (the ones the solver moves).
    pub fn knot_cps(&self) -> Vec<usize> {
        (0..self.sources.len())
            .filter(|&i| matches!(self.sources[i], Source::Knot { .. }))
            .collect()
    }

    fn check_mesh(&self, mesh: &StitchMesh) -> Result<()> {
        if mesh.courses != self.courses
            || mesh.wales != self.wales
            || mesh.lattice.is_some() != self.periodic
        {
            return Err(Error::Invalid(format!(
                "knot deformation: mesh of {} × {} faces ({}) does not match the model's {} × {} \
                 ({})",
                mesh.wales,
                mesh.courses,
                if mesh.lattice.is_some() { "periodic" } else { "open" },
                self.wales,
                self.courses,
                if self.periodic { "periodic" } else { "open" }
            )));
        }
        for (i, (p, n)) in mesh.corners.iter().zip(&mesh.normals).enumerate() {
            if !vec3::is_finite(*p) || vec3::normalize(*n).is_none() {
                let (c, w) = (i / (mesh.wales + 1), i % (mesh.wales + 1));
                return Err(Error::Invalid(format!(
                    "knot deformation: stitch-mesh corner (course {c}, wale {w}) has a \
                     non-finite position {p:?} or normal {n:?}"
                )));
            }
        }
        Ok(())
    }

    /// Face frames and initial knot parameters of `mesh` (knot spacing blend `beta`).
    pub fn frames(&self, mesh: &StitchMesh, beta: f64) -> Result<(Vec<FaceFrame>, Vec<Theta>)> {
        self.check_mesh(mesh)?;
        let r = self.radius;
        let rest_spacing = |f: &FaceTemplate| (f.s[1] - f.s[0]) * self.spacing.0;
        let out: Vec<Result<(FaceFrame, Theta)>> = self
            .faces
            .iter()
            .map(|f| {
                let (w, c) = (f.wale as f64, f.course as f64);
                let x00 = mesh.eval(w, c).0;
                let x10 = mesh.eval(w + 1.0, c).0;
                let x01 = mesh.eval(w, c + 1.0).0;
                let x11 = mesh.eval(w + 1.0, c + 1.0).0;
                let nd = vec3::normalize(vec3::cross(vec3::sub(x11, x00), vec3::sub(x01, x10)));
                let edge = vec3::sub(x10, x00);
                let (n00, n10) = (mesh.eval(w, c).1, mesh.eval(w + 1.0, c).1);
                let frame_at = |s: f64| -> Option<(V3, V3, V3)> {
                    let n = vec3::normalize(vec3::lerp(n00, n10, s)).or(nd)?;
                    let e1 = vec3::normalize(vec3::reject(edge, n))?;
                    Some((e1, vec3::cross(n, e1), n))
                };
                let (Some(nd), Some(k0), Some(k1)) = (nd, frame_at(f.s[0]), frame_at(f.s[1]))
                else {
                    return Err(Error::Invalid(format!(
                        "knot deformation: stitch face (course {}, wale {}) is degenerate \
                         (corners {x00:?}, {x10:?}, {x01:?}, {x11:?})",
                        f.course, f.wale
                    )));
                };
                let e1 = [k0.0, k1.0];
                let e2 = [k0.1, k1.1];
                let n = [k0.2, k1.2];
                let o = if vec3::dot(nd, vec3::lerp(n[0], n[1], 0.5)) < 0.0 { -1.0 } else { 1.0 };
                let at = |s: f64| vec3::lerp(x00, x10, s);
                let mid = at(0.5 * (f.s[0] + f.s[1]));
                let d1 = vec3::length(edge) * (f.s[1] - f.s[0]);
                let d0 = rest_spacing(f);
                let half = 0.5 * (d0 + beta * (d1 - d0));
                let dir = vec3::normalize_or(edge, e1[0]);
                let xk = if beta == 1.0 {
                    [at(f.s[0]), at(f.s[1])]
                } else {
                    [vec3::add_scaled(mid, dir, -half), vec3::add_scaled(mid, dir, half)]
                };
                let mut theta = [0.0; 4];
                for k in 0..2 {
                    let s = f.s[k];
                    let ds = edge;
                    let dt = vec3::lerp(vec3::sub(x01, x00), vec3::sub(x11, x10), s);
                    let v =
                        vec3::add(vec3::scale(ds, f.delta[k][0]), vec3::scale(dt, f.delta[k][1]));
                    let (a, b) = (vec3::dot(v, e1[k]), vec3::dot(v, e2[k]));
                    theta[2 * k] = b.atan2(a);
                    theta[2 * k + 1] = a.hypot(b) / r;
                }
                Ok((FaceFrame { xk, e1, e2, n, o }, theta))
            })
            .collect();
        let mut frames = Vec::with_capacity(out.len());
        let mut theta = Vec::with_capacity(out.len());
        for o in out {
            let (f, t) = o?;
            frames.push(f);
            theta.push(t);
        }
        Ok((frames, theta))
    }

    /// A knot point of face `f` at parameters `t` (without course wraps).
    fn knot_point(
        &self,
        f: usize,
        frame: &FaceFrame,
        t: &Theta,
        knot: u8,
        role: Role,
        own: bool,
    ) -> V3 {
        let tpl = &self.faces[f];
        let k = knot as usize;
        let (r, h) = (self.radius, self.skeleton.depth);
        let (sn, cs) = t[2 * k].sin_cos();
        let (e1, e2, n) = (frame.e1[k], frame.e2[k], frame.n[k]);
        let d = vec3::add(vec3::scale(e1, cs), vec3::scale(e2, sn));
        let l = t[2 * k + 1] * r;
        let side = if own { tpl.sigma } else { -tpl.sigma };
        let xk = frame.xk[k];
        match role {
            Role::C0 => vec3::add_scaled(vec3::add_scaled(xk, d, l), n, side * h),
            Role::C1 => vec3::add_scaled(vec3::add_scaled(xk, d, -l), n, -side * h),
            Role::P => {
                let b = vec3::scale(vec3::cross(d, n), frame.o);
                let sb = if own { tpl.b_own[k] } else { -tpl.b_own[k] };
                vec3::add_scaled(xk, b, sb * r)
            }
        }
    }

    /// Every CP and its normal for the given knot parameters.
    fn points(
        &self,
        mesh: &StitchMesh,
        frames: &[FaceFrame],
        theta: &[Theta],
    ) -> (Vec<V3>, Vec<V3>) {
        let l1 = mesh.lattice.map_or([0.0; 3], |l| l[1]);
        self.sources
            .par_iter()
            .map(|s| match *s {
                Source::Interp(k) => {
                    let (p, n) = mesh.eval(k.w, k.c);
                    (vec3::add_scaled(p, n, k.depth), n)
                }
                Source::Knot { face, knot, role, own, course_wrap } => {
                    let f = face as usize;
                    let p = self.knot_point(f, &frames[f], &theta[f], knot, role, own);
                    (vec3::add_scaled(p, l1, course_wrap as f64), frames[f].n[knot as usize])
                }
            })
            .unzip()
    }

    /// The knot points of every face from `theta`, written into `points`.
    fn set_knot_points(&self, points: &mut [V3], frames: &[FaceFrame], theta: &[Theta], l1: V3) {
        for (i, s) in self.sources.iter().enumerate() {
            if let Source::Knot { face, knot, role, own, course_wrap } = *s {
                let f = face as usize;
                let p = self.knot_point(f, &frames[f], &theta[f], knot, role, own);
                points[i] = vec3::add_scaled(p, l1, course_wrap as f64);
            }
        }
    }

    /// The stencils: for each knot face, the residuals that touch one of its points.
    fn build_stencils(&self) -> Vec<Stencil> {
        let mut owned_by: Vec<Vec<usize>> = vec![Vec::new(); self.faces.len()];
        for (i, s) in self.sources.iter().enumerate() {
            if let Source::Knot { face, .. } = s {
                owned_by[*face as usize].push(i);
            }
        }
        owned_by
            .iter()
            .enumerate()
            .map(|(f, owned)| {
                let mut locals: Vec<Local> = Vec::new();
                let mut residuals = Vec::new();
                let mut local = |global: usize, wrap: i32| -> u16 {
                    if let Some(i) =
                        locals.iter().position(|l| l.global == global && l.wrap == wrap)
                    {
                        return i as u16;
                    }
                    let owned = match self.sources[global] {
                        Source::Knot { face, knot, role, own, course_wrap }
                            if face as usize == f =>
                        {
                            Some((knot, role, own, course_wrap))
                        }
                        _ => None,
                    };
                    locals.push(Local { global, wrap, owned });
                    (locals.len() - 1) as u16
                };
                let mut seen_len = Vec::new();
                let mut seen_ang = Vec::new();
                for &g in owned {
                    let c = self.course_of(g);
                    for j in [-1i64, 0] {
                        if let Some(seg) = self.at(c, g, j) {
                            let key = (seg.0, seg.1);
                            if !seen_len.contains(&key) {
                                seen_len.push(key);
                                if let (Some(a), Some(b)) = (self.at(c, g, j), self.at(c, g, j + 1))
                                {
                                    let rest = self.rest_distance(a, b);
                                    let (la, lb) = (local(a.0, a.1), local(b.0, b.1));
                                    residuals.push(Residual::Length { a: la, b: lb, rest });
                                }
                            }
                        }
                    }
                    for j in [-1i64, 0, 1] {
                        if let (Some(a), Some(b), Some(cc)) =
                            (self.at(c, g, j - 1), self.at(c, g, j), self.at(c, g, j + 1))
                        {
                            let key = (b.0, b.1);
                            if !seen_ang.contains(&key) {
                                seen_ang.push(key);
                                let rest = self.rest_cos(a, b, cc);
                                let (la, lb, lc) =
                                    (local(a.0, a.1), local(b.0, b.1), local(cc.0, cc.1));
                                residuals.push(Residual::Angle { a: la, b: lb, c: lc, rest });
                            }
                        }
                    }
                }
                Stencil { locals, residuals }
            })
            .collect()
    }

    fn course_of(&self, g: usize) -> usize {
        self.course_start.partition_point(|&s| s <= g) - 1
    }

    /// The CP `j` places after global CP `g` along course `c`: `(global, wraps)`.
    fn at(&self, c: usize, g: usize, j: i64) -> Option<(usize, i32)> {
        let (s, e) = (self.course_start[c] as i64, self.course_start[c + 1] as i64);
        let n = e - s;
        let k = g as i64 - s + j;
        if self.periodic {
            Some(((s + k.rem_euclid(n)) as usize, k.div_euclid(n) as i32))
        } else {
            (0..n).contains(&k).then_some(((s + k) as usize, 0))
        }
    }

    fn rest_pos(&self, (g, wrap): (usize, i32)) -> V3 {
        let l0 = self.rest.lattice.map_or([0.0; 3], |l| l[0]);
        vec3::add_scaled(self.rest.points[g], l0, wrap as f64)
    }

    fn rest_distance(&self, a: (usize, i32), b: (usize, i32)) -> f64 {
        vec3::distance(self.rest_pos(a), self.rest_pos(b))
    }

    fn rest_cos(&self, a: (usize, i32), b: (usize, i32), c: (usize, i32)) -> f64 {
        solve::cos_turn(self.rest_pos(a), self.rest_pos(b), self.rest_pos(c))
    }

    /// The initial guess of `mesh`: knots interpolated (β), no iteration.
    pub fn initial(&self, mesh: &StitchMesh, beta: f64) -> Result<KnotFrame> {
        let (frames, theta) = self.frames(mesh, beta)?;
        let (points, normals) = self.points(mesh, &frames, &theta);
        Ok(KnotFrame {
            points,
            normals,
            theta,
            stats: SolveStats::default(),
            lattice: mesh.lattice,
        })
    }

    /// Naive interpolation ([H25 Fig. 9] left): every rest CP mapped through the face map
    /// by its rest stitch coordinates and depth, knots ignored.
    pub fn naive(&self, mesh: &StitchMesh) -> Result<KnotFrame> {
        self.check_mesh(mesh)?;
        let (sw, sc) = self.spacing;
        let (points, normals) = self
            .rest
            .points
            .par_iter()
            .map(|p| {
                let (q, n) = mesh.eval(p[0] / sw, p[1] / sc);
                (vec3::add_scaled(q, n, p[2]), n)
            })
            .unzip();
        Ok(KnotFrame {
            points,
            normals,
            theta: Vec::new(),
            stats: SolveStats::default(),
            lattice: mesh.lattice,
        })
    }

    /// One frame: initial guess, `p.iterations` Gauss–Newton iterations per face with its
    /// neighbours fixed (faces in parallel unless `serial`), knot points re-evaluated.
    pub fn solve_with(&self, mesh: &StitchMesh, p: &KnotParams, serial: bool) -> Result<KnotFrame> {
        p.validate()?;
        let (frames, theta0) = self.frames(mesh, p.beta)?;
        let (mut points, normals) = self.points(mesh, &frames, &theta0);
        let l0 = mesh.lattice.map_or([0.0; 3], |l| l[0]);
        let l1 = mesh.lattice.map_or([0.0; 3], |l| l[1]);
        let ctx = solve::Ctx { model: self, points: &points, l0, l1, p };
        let one = |f: usize| ctx.face(f, &frames[f], theta0[f], p.iterations);
        let results: Vec<solve::FaceResult> = if serial {
            (0..self.faces.len()).map(one).collect()
        } else {
            (0..self.faces.len()).into_par_iter().map(one).collect()
        };
        let mut stats = SolveStats {
            faces: self.faces.len(),
            energy_per_iteration: vec![0.0; p.iterations],
            ..SolveStats::default()
        };
        let mut theta = Vec::with_capacity(results.len());
        for r in &results {
            stats.energy_initial += r.energies[0];
            for (i, e) in r.energies[1..].iter().enumerate() {
                stats.energy_per_iteration[i] += e;
            }
            stats.guard_triggers += r.guard_triggers;
            stats.rejected_steps += r.rejected;
            theta.push(r.theta);
        }
        self.set_knot_points(&mut points, &frames, &theta, l1);
        Ok(KnotFrame { points, normals, theta, stats, lattice: mesh.lattice })
    }

    /// [`Self::solve_with`] in parallel.
    pub fn solve(&self, mesh: &StitchMesh, p: &KnotParams) -> Result<KnotFrame> {
        self.solve_with(mesh, p, false)
    }

    /// What a data-parallel solver needs of a frame before iterating (the initial guess of
    /// [`Self::solve_with`]): face frames, initial `Θ`, every CP and its normal.
    pub fn prepare(&self, mesh: &StitchMesh, p: &KnotParams) -> Result<Prepared> {
        p.validate()?;
        let (frames, theta) = self.frames(mesh, p.beta)?;
        let (points, normals) = self.points(mesh, &frames, &theta);
        Ok(Prepared { frames, theta, points, normals, lattice: mesh.lattice })
    }

    /// The frame of solved parameters `theta` (one per knot face) from a [`Prepared`]
    /// initial guess: the knot points re-evaluated, the other CPs kept.
    pub fn frame_from_theta(
        &self,
        prep: Prepared,
        theta: Vec<Theta>,
        stats: SolveStats,
    ) -> Result<KnotFrame> {
        if theta.len() != self.faces.len() || prep.frames.len() != self.faces.len() {
            return Err(Error::Invalid(format!(
                "knot deformation: {} parameter sets and {} frames for {} knot faces",
                theta.len(),
                prep.frames.len(),
                self.faces.len()
            )));
        }
        if let Some(f) = theta.iter().position(|t| t.iter().any(|x| !x.is_finite())) {
            return Err(Error::Invalid(format!(
                "knot deformation: knot face {f} (course {}, wale {}) has non-finite \
                 parameters {:?}",
                self.faces[f].course, self.faces[f].wale, theta[f]
            )));
        }
        let Prepared { frames, points: mut pts, normals, lattice, .. } = prep;
        let l1 = lattice.map_or([0.0; 3], |l| l[1]);
        self.set_knot_points(&mut pts, &frames, &theta, l1);
        Ok(KnotFrame { points: pts, normals, theta, stats, lattice })
    }

    /// The stencils flattened for a data-parallel solver (see [`FlatStencils`]).
    pub fn flat_stencils(&self) -> FlatStencils {
        let mut out = FlatStencils::default();
        for (f, st) in self.stencils.iter().enumerate() {
            let tpl = &self.faces[f];
            out.faces.push(FlatFace {
                sigma: tpl.sigma,
                b_own: tpl.b_own,
                locals: (out.locals.len() as u32, st.locals.len() as u32),
                residuals: (out.residuals.len() as u32, st.residuals.len() as u32),
            });
            for l in &st.locals {
                out.locals.push(FlatLocal {
                    global: l.global as u32,
                    wrap: l.wrap,
                    owned: l.owned.map(|(knot, role, own, course_wrap)| FlatKnotPoint {
                        knot,
                        role: match role {
                            Role::C0 => 0,
                            Role::C1 => 1,
                            Role::P => 2,
                        },
                        own,
                        course_wrap,
                    }),
                });
            }
            for r in &st.residuals {
                out.residuals.push(match *r {
                    Residual::Length { a, b, rest } => FlatResidual { a, b, c: None, rest },
                    Residual::Angle { a, b, c, rest } => FlatResidual { a, b, c: Some(c), rest },
                });
            }
        }
        out
    }

    /// The converged reference (DESIGN §3.5 (b)): block Gauss–Seidel over the faces, each
    /// solved to convergence with its neighbours' current points, until no parameter moves
    /// by more than `1e-12` in a sweep (at most `max_sweeps`). Returns the frame and the
    /// sweeps used.
    pub fn reference(
        &self,
        mesh: &StitchMesh,
        p: &KnotParams,
        max_sweeps: usize,
    ) -> Result<(KnotFrame, usize)> {
        p.validate()?;
        let (frames, mut theta) = self.frames(mesh, p.beta)?;
        let (mut points, normals) = self.points(mesh, &frames, &theta);
        let l0 = mesh.lattice.map_or([0.0; 3], |l| l[0]);
        let l1 = mesh.lattice.map_or([0.0; 3], |l| l[1]);
        let mut sweeps = 0;
        while sweeps < max_sweeps {
            sweeps += 1;
            let mut moved = 0.0f64;
            for f in 0..self.faces.len() {
                let ctx = solve::Ctx { model: self, points: &points, l0, l1, p };
                let res = ctx.face(f, &frames[f], theta[f], 20);
                for i in 0..4 {
                    moved = moved.max((res.theta[i] - theta[f][i]).abs());
                }
                theta[f] = res.theta;
                // Write this face's points so that the next face sees them.
                for l in &self.stencils[f].locals {
                    if let (Some((knot, role, own, course_wrap)), 0) = (l.owned, l.wrap) {
                        let q = self.knot_point(f, &frames[f], &theta[f], knot, role, own);
                        points[l.global] = vec3::add_scaled(q, l1, course_wrap as f64);
                    }
                }
            }
            if moved <= 1e-12 {
                break;
            }
        }
        Ok((
            KnotFrame {
                points,
                normals,
                theta,
                stats: SolveStats::default(),
                lattice: mesh.lattice,
            },
            sweeps,
        ))
    }

    /// The total energy of [H25 eq. 3] (signed, weighted residuals squared) of a frame.
    pub fn energy(&self, frame: &KnotFrame, p: &KnotParams) -> f64 {
        let l0 = frame.lattice.map_or([0.0; 3], |l| l[0]);
        let pos = |(g, w): (usize, i32)| vec3::add_scaled(frame.points[g], l0, w as f64);
        let lengths: f64 = self.segment_strains(frame).iter().map(|r| p.w_length * r * r).sum();
        let angles: f64 = (0..self.courses)
            .flat_map(|c| self.course_range(c).map(move |g| (c, g)))
            .filter_map(|(c, g)| {
                let (a, b, cc) = (self.at(c, g, -1)?, self.at(c, g, 0)?, self.at(c, g, 1)?);
                let r = solve::cos_turn(pos(a), pos(b), pos(cc)) - self.rest_cos(a, b, cc);
                Some(p.w_angle * r * r)
            })
            .sum();
        lengths + angles
    }

    /// The relative length strain `(‖Δx‖ − ‖Δx₀‖) / ‖Δx₀‖` of every segment.
    fn segment_strains(&self, frame: &KnotFrame) -> Vec<f64> {
        let l0 = frame.lattice.map_or([0.0; 3], |l| l[0]);
        let pos = |(g, w): (usize, i32)| vec3::add_scaled(frame.points[g], l0, w as f64);
        (0..self.courses)
            .flat_map(|c| self.course_range(c).map(move |g| (c, g)))
            .filter_map(|(c, g)| {
                let (a, b) = (self.at(c, g, 0)?, self.at(c, g, 1)?);
                let rest = self.rest_distance(a, b);
                Some((vec3::distance(pos(a), pos(b)) - rest) / rest)
            })
            .collect()
    }

    /// RMS relative length strain over all segments.
    pub fn length_strain(&self, frame: &KnotFrame) -> f64 {
        let e = self.segment_strains(frame);
        (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt()
    }

    /// Mean absolute relative length strain over all segments.
    pub fn mean_length_strain(&self, frame: &KnotFrame) -> f64 {
        let e = self.segment_strains(frame);
        e.iter().map(|x| x.abs()).sum::<f64>() / e.len().max(1) as f64
    }

    /// The curve parameters of the up-sampled points of a course of `n` CPs: `j / k`.
    fn sample_params(&self, n: usize, k: usize) -> Vec<f64> {
        let count = if self.periodic { n * k } else { (n - 1) * k + 1 };
        (0..count).map(|j| j as f64 / k as f64).collect()
    }

    /// The rest length coordinates of the curves up-sampled `k` times (cached per `k`).
    fn rest_coords(&self, k: usize) -> RestCoords {
        let mut cache = self.rest_coords.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, c)) = cache.iter().find(|(kk, _)| *kk == k) {
            return c.clone();
        }
        let coords: RestCoords = std::sync::Arc::new(
            self.rest_set
                .curves
                .par_iter()
                .map(|rc| {
                    let us = self.sample_params(rc.points.len(), k);
                    (us.iter().map(|&u| rc.length_coord(u)).collect(), rc.length_wrap)
                })
                .collect(),
        );
        cache.push((k, coords.clone()));
        coords
    }

    /// A course curve straight from its points, normals and length coordinates, validated
    /// but without the arc-length quadrature of [`YarnCurve::open`] (the coordinates are the
    /// rest ones, given).
    fn course_curve(
        &self,
        c: usize,
        points: Vec<V3>,
        normals: Vec<V3>,
        (length_coords, length_wrap): (Vec<f64>, f64),
        shift: Option<V3>,
    ) -> Result<YarnCurve> {
        let n = points.len();
        let curve = YarnCurve {
            points,
            length_coords,
            colors: vec![self.skeleton.color; n],
            params_ids: vec![self.skeleton.params_id; n],
            normals: Some(normals),
            closed: shift.is_some(),
            shift: shift.unwrap_or([0.0; 3]),
            length_wrap,
        };
        curve.validate(c).map_err(|e| match e {
            Error::Invalid(m) => Error::Invalid(format!("knot yarns: {m}")),
            other => other,
        })?;
        Ok(curve)
    }

    /// The yarn curves of a frame: one Catmull–Rom curve per course through the CPs,
    /// up-sampled `upsample` points per segment (1: the CPs themselves), with the rest
    /// length coordinates (fibers do not slide along a stretched yarn); colour and params
    /// id from the skeleton parameters.
    pub fn yarn_set(&self, frame: &KnotFrame, upsample: usize) -> Result<YarnSet> {
        let k = upsample.max(1);
        let l0 = frame.lattice.map(|l| l[0]);
        let coords = (k > 1).then(|| self.rest_coords(k));
        let curves: Vec<Result<YarnCurve>> = (0..self.courses)
            .into_par_iter()
            .map(|c| {
                let range = self.course_range(c);
                let pts = frame.points[range.clone()].to_vec();
                let nrm = frame.normals[range].to_vec();
                let rest = &self.rest_set.curves[c];
                let rest_z = (rest.length_coords.clone(), rest.length_wrap);
                let base = self.course_curve(c, pts, nrm, rest_z, l0)?;
                let Some(coords) = &coords else { return Ok(base) };
                let us = self.sample_params(base.points.len(), k);
                let pts: Vec<V3> = us.iter().map(|&u| base.point(u)).collect();
                let normals = base.normals.as_ref().expect("set above");
                let n = normals.len() as isize;
                let nrm: Vec<V3> = us
                    .iter()
                    .map(|&u| {
                        let (s, t) = base.locate(u);
                        let a = normals[s.rem_euclid(n) as usize];
                        let b = normals[(s + 1).rem_euclid(n).min(n - 1) as usize];
                        vec3::normalize_or(vec3::lerp(a, b, t), a)
                    })
                    .collect();
                self.course_curve(c, pts, nrm, coords[c].clone(), l0)
            })
            .collect();
        let period = frame.lattice.and_then(|l| {
            let rect = l[0][1] == 0.0 && l[0][2] == 0.0 && l[1][0] == 0.0 && l[1][2] == 0.0;
            rect.then_some([l[0][0], l[1][1]])
        });
        YarnSet::new(curves.into_iter().collect::<Result<_>>()?, period)
    }
}

/// The initial guess of one frame ([`KnotModel::prepare`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Per knot face: its frame on the deformed mesh.
    pub frames: Vec<FaceFrame>,
    /// Per knot face: the initial parameters.
    pub theta: Vec<Theta>,
    /// Every CP at the initial parameters (the fixed neighbours of each face solve).
    pub points: Vec<V3>,
    /// The surface normal at every CP.
    pub normals: Vec<V3>,
    /// The mesh's lattice (periodic patches).
    pub lattice: Option<[V3; 2]>,
}

/// A knot point of a face's stencil: knot 0/1, role (0 = `c0`, 1 = `c1`, 2 = the side
/// point `p`), the face's own yarn or the loop below, lattice periods along the courses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlatKnotPoint {
    /// Knot 0 or 1 of the face.
    pub knot: u8,
    /// 0 = `c0`, 1 = `c1`, 2 = the side point `p`.
    pub role: u8,
    /// The face's own yarn (else the loop below).
    pub own: bool,
    /// Lattice periods along the courses.
    pub course_wrap: i8,
}

/// A point of a face's stencil: CP `global` shifted by `wrap` lattice periods along the
/// wales; `owned` when it is one of the face's own knot points (else it is held fixed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlatLocal {
    /// The CP's index.
    pub global: u32,
    /// Lattice periods along the wales.
    pub wrap: i32,
    /// The face's own knot point it is, if it is one.
    pub owned: Option<FlatKnotPoint>,
}

/// A residual of a face's stencil over its locals: the relative length of `a → b`
/// (`c = None`) or the cosine of the turn at `b` of `a → b → c`, against `rest`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatResidual {
    /// First local.
    pub a: u16,
    /// Second local (the corner of a turn).
    pub b: u16,
    /// Third local of a turn; `None` for a length.
    pub c: Option<u16>,
    /// Rest length (metres) or rest cosine.
    pub rest: f64,
}

/// A knot face: its template's side signs and its ranges of locals and residuals
/// (`(start, count)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatFace {
    /// +1 knit, −1 purl.
    pub sigma: f64,
    /// Sign of `b` at the own yarn's side point, per knot.
    pub b_own: [f64; 2],
    /// `(start, count)` in [`FlatStencils::locals`].
    pub locals: (u32, u32),
    /// `(start, count)` in [`FlatStencils::residuals`].
    pub residuals: (u32, u32),
}

/// Every knot face's stencil in flat arrays, for a data-parallel solver (the WGSL port in
/// `yarn-render`): the same points and residuals the CPU face solve evaluates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FlatStencils {
    /// Per knot face.
    pub faces: Vec<FlatFace>,
    /// Every face's stencil points.
    pub locals: Vec<FlatLocal>,
    /// Every face's residuals.
    pub residuals: Vec<FlatResidual>,
}

/// The flat canonical rest mesh of `mesh`'s topology at gauge `spacing`.
fn canonical(mesh: &StitchMesh, spacing: (f64, f64)) -> StitchMesh {
    let (sw, sc) = spacing;
    let mut m = mesh.clone();
    m.corners = (0..=mesh.courses)
        .flat_map(|c| (0..=mesh.wales).map(move |w| [w as f64 * sw, c as f64 * sc, 0.0]))
        .collect();
    m.normals = vec![[0.0, 0.0, 1.0]; m.corners.len()];
    m.lattice = mesh
        .lattice
        .map(|_| [[mesh.wales as f64 * sw, 0.0, 0.0], [0.0, mesh.courses as f64 * sc, 0.0]]);
    m
}

#[cfg(test)]
mod tests;
