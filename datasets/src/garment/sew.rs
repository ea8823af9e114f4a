//! From pattern to draped garment: the panels are triangulated evenly at the spacing that
//! gives the requested vertex count (seam partners sampled with the same number of points),
//! placed around the body apart from each other (no panel through another: tested),
//! pulled together by seam springs (rest length 0, a capped pull) with the body as a
//! frictionless collider (with friction a sleeve lying on the arm held its underarm seam
//! open) and cloth–cloth contact ([`super::self_contact`]) between the panels, welded into
//! one mesh once the seams have closed (one position per seam point, the UVs kept per panel
//! so a seam keeps its UV discontinuity), and draped under gravity with friction against
//! the body and between layers until the kinetic energy stays below a threshold.
//!
//! With [`DrapeSettings::cloth_contact`] (on by default) the contact keeps every layer on the
//! side it starts on, so what crossings remain are made where it does not look: at seam
//! junctions (the armpit, where front, back and both sides of a sleeve meet at one point
//! and their first rows are free to close) and between two creases passing each other
//! between their nodes. [`untangle`] smooths them out after the weld and after the drape
//! (which is then resumed, twice at most) — one round of ten smoothing sweeps removed every
//! one at 1 500 and 3 000 vertices. A crumple the drape makes again each time is smoothed a
//! last time and left ([`Garment::final_smoothing_m`] says how far that moved a vertex):
//! the shirt's armpit at 10 000 vertices, where the pattern's four corners sum to 403°
//! (an excess cone; the trousers' crotch, 472°, crumples without crossing). Drafting the
//! sleeve cap to leave the underarm at a right angle to its seam was tried: the excess
//! moved along the armhole seam (382° still at the junction) and the drape left 22
//! crossing pairs, so the pattern is unchanged.
//!
//! Springs come from the 2-D panels: every mesh edge with its length in the panel as rest
//! length and a stiffness interpolated between warp (panel `y`) and weft (panel `x`) by its
//! direction; every pair of triangles sharing an edge gets a bending spring between the
//! two opposite corners, its rest length that of the pair unfolded flat (so seams rest
//! flat too).

use super::body::Body;
use super::checkpoint::{Checkpointing, Snapshot};
use super::drape::{Contact, Link, Xpbd, XpbdParams};
use super::mesher::{P2, triangulate};
use super::pattern::{GarmentKind, Pattern};
use super::self_contact::SelfContact;
use crate::mesh::Mesh;
use crate::sim::friction::Friction;
use crate::sim::springs::{LawKind, Spring, SpringLaw};
use crate::sim::step::RestReport;
use crate::sim::{Cloth, Collider};
use crate::vec3::{V3, add, length, scale, sub};
use crate::{Error, Result};
use std::collections::HashMap;

/// Mechanical properties of the fabric.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fabric {
    /// Areal density (kg/m²).
    pub density_kg_m2: f64,
    /// Membrane stiffness along the warp (panel `y`), N/m.
    pub warp_n_per_m: f64,
    /// Membrane stiffness along the weft (panel `x`), N/m.
    pub weft_n_per_m: f64,
    /// Bending springs' stiffness as a fraction of the membrane's.
    pub bend_ratio: f64,
    /// Half-width of the slack interval (fraction of the rest length).
    pub slack: f64,
    /// Half-thickness of the cloth: the reach of the contact fields (m).
    pub thickness_m: f64,
    /// Friction against the body.
    pub friction: Friction,
}

impl Default for Fabric {
    /// A cotton jersey: 160 g/m², 400 / 250 N/m, 1 % slack, 3 mm half-thickness.
    fn default() -> Self {
        Fabric {
            density_kg_m2: 0.16,
            warp_n_per_m: 400.0,
            weft_n_per_m: 250.0,
            bend_ratio: 0.02,
            slack: 0.01,
            thickness_m: 0.003,
            friction: Friction { static_coef: 0.6, dynamic_coef: 0.4 },
        }
    }
}

/// How long to simulate and when the drape counts as at rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrapeSettings {
    /// Longest sewing phase (simulated s).
    pub sew_max_s: f64,
    /// Longest drape (simulated s).
    pub drape_max_s: f64,
    /// Rest: kinetic energy per kilogram below this (J/kg) …
    pub rest_ke_per_kg: f64,
    /// … for this long (simulated s).
    pub rest_hold_s: f64,
    /// Air viscosity while draping (1/s).
    pub air_viscosity: f64,
    /// Time over which the seams are pulled shut (simulated s).
    pub sew_close_s: f64,
    /// Longest sub-step of the solver (s); finer meshes get a shorter one
    /// ([`DrapeSettings::substep_for`]).
    pub substep_s: f64,
    /// Mesh spacings the membrane's elastic wave may cross in one sub-step. One Gauss–Seidel
    /// sweep per sub-step carries a correction against the sweep order only one link per
    /// sub-step, so a wave that runs several links per sub-step is not resolved and its
    /// residual comes back as velocity every sub-step: measured on the T-shirt at 10 000
    /// vertices (h = 9.9 mm, wave speed 50 m/s), 1/600 s (8.4 spacings) left 0.47 J/kg
    /// after 1.5 s and crushed triangles to 21 % of their area; 1/2400 s (2.1) came to rest
    /// (< 10⁻⁵ J/kg) after 0.75 s. The unit tests' 1 500 vertices ran at 3.3.
    pub wave_spacings_per_substep: f64,
    /// Cloth–cloth contact ([`super::self_contact`]) while sewing and draping, and
    /// [`untangle`] after the weld and the drape. On by default: at 10 000 vertices it takes
    /// the T-shirt, shirt, trousers and skirt from 139 / 139 / 385 / 0 crossing triangle
    /// pairs to none, all at rest, in 15–27 s instead of 12–19 s (BENCHMARKS.md).
    pub cloth_contact: bool,
    /// Relaxation time of the links' viscous damping (s) for cloth hanging free of the body
    /// (the curtain; see [`super::drape`]: without it the 40 000-vertex curtain never came
    /// to rest). Garments on the body have none.
    pub free_hanging_damping_s: f64,
}

impl DrapeSettings {
    /// The sub-step for mesh spacing `h` (m) and `fabric`: the longest one
    /// ([`DrapeSettings::substep_s`]) or the one in which the membrane's wave, speed
    /// `√(k_max / ρ)`, crosses [`DrapeSettings::wave_spacings_per_substep`] spacings,
    /// whichever is shorter.
    pub fn substep_for(&self, h: f64, fabric: &Fabric) -> f64 {
        let c = (fabric.warp_n_per_m.max(fabric.weft_n_per_m) / fabric.density_kg_m2).sqrt();
        self.substep_s.min(self.wave_spacings_per_substep * h / c)
    }
}

impl Default for DrapeSettings {
    fn default() -> Self {
        DrapeSettings {
            sew_max_s: 2.0,
            drape_max_s: 4.0,
            rest_ke_per_kg: 1e-5,
            rest_hold_s: 0.1,
            air_viscosity: 4.0,
            sew_close_s: 0.4,
            substep_s: 1.0 / 600.0,
            wave_spacings_per_substep: 2.0,
            cloth_contact: true,
            free_hanging_damping_s: 0.002,
        }
    }
}

/// A sewn, draped garment.
#[derive(Debug, Clone)]
pub struct Garment {
    /// The mesh: welded positions, per-panel UVs (metres of fabric).
    pub mesh: Mesh,
    /// The pattern it was sewn from.
    pub pattern: Pattern,
    /// Panel of each triangle.
    pub triangle_panel: Vec<u16>,
    /// Seam edges of the welded mesh (position index pairs).
    pub seam_edges: Vec<[u32; 2]>,
    /// Spacing of the panels' triangulation (m).
    pub spacing_m: f64,
    /// The fabric.
    pub fabric: Fabric,
    /// The sewing phase.
    pub sewing: RestReport,
    /// Largest distance between seam partners when they were welded (m).
    pub seam_gap_at_weld_m: f64,
    /// The drape.
    pub drape: RestReport,
    /// The solver's sub-step (s).
    pub substep_s: f64,
    /// Smoothing rounds [`untangle`] took at the weld and after the drape (0: none needed).
    pub untangle_rounds: usize,
    /// Farthest a vertex moved in the smoothing after the last drape (m; 0 when the drape
    /// left no crossing): that smoothing is not followed by more draping.
    pub final_smoothing_m: f64,
}

/// Panels triangulated and laid out as one unwelded vertex set.
struct Flat {
    uv: Vec<P2>,
    x: Vec<V3>,
    triangles: Vec<[u32; 3]>,
    triangle_panel: Vec<u16>,
    /// Seam partner pairs (unwelded vertex ids).
    pairs: Vec<(u32, u32)>,
    /// Pinned vertices.
    pinned: Vec<bool>,
}

fn layout(pattern: &Pattern, h: f64) -> Result<Flat> {
    // Points per edge: from its length, partners sharing the larger count.
    let mut counts: Vec<Vec<usize>> = pattern
        .panels
        .iter()
        .map(|p| p.edges.iter().map(|e| ((e.length() / h).round() as usize).max(1)).collect())
        .collect();
    for s in &pattern.seams {
        let n = counts[s.a.panel][s.a.edge].max(counts[s.b.panel][s.b.edge]);
        counts[s.a.panel][s.a.edge] = n;
        counts[s.b.panel][s.b.edge] = n;
    }
    let mut f = Flat {
        uv: Vec::new(),
        x: Vec::new(),
        triangles: Vec::new(),
        triangle_panel: Vec::new(),
        pairs: Vec::new(),
        pinned: Vec::new(),
    };
    let mut edge_ids: Vec<Vec<Vec<u32>>> = Vec::new();
    for (pi, panel) in pattern.panels.iter().enumerate() {
        let mut outline = Vec::new();
        let mut starts = Vec::new();
        for (ei, e) in panel.edges.iter().enumerate() {
            starts.push(outline.len());
            let pts = e.resample(counts[pi][ei]);
            outline.extend_from_slice(&pts[..pts.len() - 1]);
        }
        let m2 = triangulate(&outline, h)
            .map_err(|e| Error::Invalid(format!("panel {}: {e}", panel.name)))?;
        let base = f.uv.len() as u32;
        let nb = outline.len();
        let ids: Vec<Vec<u32>> = (0..panel.edges.len())
            .map(|ei| (0..=counts[pi][ei]).map(|k| base + ((starts[ei] + k) % nb) as u32).collect())
            .collect();
        edge_ids.push(ids);
        for &p in &m2.points {
            f.uv.push(p);
            f.x.push(panel.placement.place(p));
            f.pinned.push(false);
        }
        for t in &m2.triangles {
            f.triangles.push(t.map(|v| v + base));
            f.triangle_panel.push(pi as u16);
        }
    }
    for s in &pattern.seams {
        let a = &edge_ids[s.a.panel][s.a.edge];
        let b = &edge_ids[s.b.panel][s.b.edge];
        let n = a.len();
        for i in 0..n {
            f.pairs.push((a[i], b[n - 1 - i]));
        }
    }
    for e in &pattern.pinned_edges {
        for &v in &edge_ids[e.panel][e.edge] {
            f.pinned[v as usize] = true;
        }
    }
    Ok(f)
}

/// Rest length of the spring between the corners opposite a shared edge `(a, b)`, with the
/// two triangles unfolded flat; `la_c` … are the edges' lengths in their panels.
fn unfolded(ab: f64, ac: f64, bc: f64, ad: f64, bd: f64) -> f64 {
    // a at the origin, b on +x; c above, d below.
    let cx = (ac * ac - bc * bc + ab * ab) / (2.0 * ab);
    let cy = (ac * ac - cx * cx).max(0.0).sqrt();
    let dx = (ad * ad - bd * bd + ab * ab) / (2.0 * ab);
    let dy = -(ad * ad - dx * dx).max(0.0).sqrt();
    (cx - dx).hypot(cy - dy)
}

fn uv_len(uv: &[P2], a: u32, b: u32) -> f64 {
    let (p, q) = (uv[a as usize], uv[b as usize]);
    (q[0] - p[0]).hypot(q[1] - p[1])
}

/// The cloth of `triangles` over `n` nodes whose corners have panel coordinates
/// `uv[tri_uv[t][k]]`: masses, edge springs and bending springs.
fn build_cloth(
    n: usize,
    triangles: &[[u32; 3]],
    tri_uv: &[[u32; 3]],
    uv: &[P2],
    fabric: &Fabric,
) -> Cloth {
    let mut mass = vec![0.0; n];
    for (t, tu) in triangles.iter().zip(tri_uv) {
        let [a, b, c] = tu.map(|i| uv[i as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs();
        for &v in t {
            mass[v as usize] += fabric.density_kg_m2 * area / 3.0;
        }
    }
    let edge_law = SpringLaw {
        kind: LawKind::Exponential,
        lo: 1.0 - fabric.slack,
        hi: 1.0 + fabric.slack,
        compression: 1.0,
        damping: 0.08,
        max_tension: f64::INFINITY,
    };
    let bend_law = SpringLaw { lo: 1.0, hi: 1.0, kind: LawKind::Linear, ..edge_law };
    let mut cloth = Cloth::new(mass, triangles.to_vec(), vec![edge_law, bend_law]);
    // Edges: (min, max) → (uv length sum, count, uv direction, opposite corners).
    struct E {
        len: f64,
        count: f64,
        dir: [f64; 2],
        opp: Vec<(u32, f64, f64)>,
    }
    let mut edges: HashMap<(u32, u32), E> = HashMap::new();
    let mut order = Vec::new();
    for (t, tu) in triangles.iter().zip(tri_uv) {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (ua, ub, uc) = (tu[k], tu[(k + 1) % 3], tu[(k + 2) % 3]);
            let key = (a.min(b), a.max(b));
            let l = uv_len(uv, ua, ub);
            let d =
                [uv[ub as usize][0] - uv[ua as usize][0], uv[ub as usize][1] - uv[ua as usize][1]];
            let (la, lb) = if a < b {
                (uv_len(uv, ua, uc), uv_len(uv, ub, uc))
            } else {
                (uv_len(uv, ub, uc), uv_len(uv, ua, uc))
            };
            let e = edges.entry(key).or_insert_with(|| {
                order.push(key);
                E { len: 0.0, count: 0.0, dir: [0.0; 2], opp: Vec::new() }
            });
            e.len += l;
            e.count += 1.0;
            e.dir = [d[0] / l.max(1e-12), d[1] / l.max(1e-12)];
            e.opp.push((c, la, lb));
        }
    }
    let k_scale = 3f64.sqrt() / 2.0;
    for key in &order {
        let e = &edges[key];
        let rest = e.len / e.count;
        let k = k_scale
            * (fabric.weft_n_per_m * e.dir[0] * e.dir[0]
                + fabric.warp_n_per_m * e.dir[1] * e.dir[1]);
        cloth.springs.push(Spring { a: key.0, b: key.1, rest, k, law: 0 });
        if e.opp.len() == 2 {
            let (c, ac, bc) = e.opp[0];
            let (d, ad, bd) = e.opp[1];
            if c != d {
                let r = unfolded(rest, ac, bc, ad, bd);
                cloth.springs.push(Spring {
                    a: c,
                    b: d,
                    rest: r,
                    k: fabric.bend_ratio * k,
                    law: 1,
                });
            }
        }
    }
    cloth
}

/// The cloth's springs as XPBD links (compliance = 1 / stiffness).
fn links_of(cloth: &Cloth) -> Vec<Link> {
    cloth
        .springs
        .iter()
        .map(|s| Link { a: s.a, b: s.b, rest: s.rest, compliance: 1.0 / s.k.max(1e-9) })
        .collect()
}

/// Sub-steps until the kinetic energy per kilogram stays below the threshold for the hold
/// time, or the longest drape is reached; `progress` gets the simulated time.
///
/// Resuming `from` a snapshot of this run (its positions, velocities, time and contact list
/// already restored into `sim`) takes its start, step count and quiet period; `save` is
/// offered the state every 64 sub-steps (sim, run start, steps, quiet period start).
fn run_to_rest(
    sim: &mut Xpbd<'_>,
    s: &DrapeSettings,
    progress: &mut dyn FnMut(f64),
    from: Option<&Snapshot>,
    save: &mut SaveFn<'_>,
) -> Result<RestReport> {
    let start = from.map_or(sim.time, |f| f.run_start);
    let mut quiet_since: Option<f64> = from.and_then(|f| f.quiet_since);
    let mut r = RestReport { steps: from.map_or(0, |f| f.steps as usize), ..Default::default() };
    while sim.time - start < s.drape_max_s {
        sim.step();
        r.steps += 1;
        let ke = sim.kinetic_energy_per_kg();
        r.kinetic_energy_per_kg = ke;
        let t = sim.time - start;
        if ke < s.rest_ke_per_kg {
            let since = *quiet_since.get_or_insert(t);
            if t - since >= s.rest_hold_s {
                r.settled = true;
                break;
            }
        } else {
            quiet_since = None;
        }
        if r.steps.is_multiple_of(64) {
            progress(t);
            save(sim, start, r.steps as u64, quiet_since)?;
        }
    }
    r.end_time_s = sim.time - start;
    r.settle_time_s = quiet_since.unwrap_or(r.end_time_s);
    Ok(r)
}

/// What [`run_to_rest`] offers its state to: (sim, run start, steps, quiet period start).
type SaveFn<'a> = dyn FnMut(&Xpbd<'_>, f64, u64, Option<f64>) -> Result<()> + 'a;

/// The drape's runs combined: `acc` (the runs before) followed by `more`.
fn combine(acc: Option<RestReport>, more: RestReport) -> RestReport {
    let Some(mut d) = acc else {
        return more;
    };
    d.steps += more.steps;
    d.end_time_s += more.end_time_s;
    d.settle_time_s = d.end_time_s - more.end_time_s + more.settle_time_s;
    d.settled = more.settled;
    d.kinetic_energy_per_kg = more.kinetic_energy_per_kg;
    d
}

/// Where a run stands besides the solver's own state: its phase (0 sewing, `k + 1` the
/// drape's `k`-th run) and what [`Snapshot`] records of the phases before.
struct Stage {
    phase: u32,
    sewing: RestReport,
    gap: f64,
    drape: Option<RestReport>,
    untangle_rounds: u64,
}

/// Gives `c` a snapshot of `sim` when one is due.
fn offer(
    c: Option<&mut Checkpointing<'_>>,
    sim: &Xpbd<'_>,
    stage: &Stage,
    run_start: f64,
    steps: u64,
    quiet_since: Option<f64>,
) -> Result<()> {
    let Some(c) = c else {
        return Ok(());
    };
    if !c.due() {
        return Ok(());
    }
    let (pairs, built_at) = sim.cloth.as_ref().map(|c| c.list()).unwrap_or_default();
    (c.save)(&Snapshot {
        key: c.key,
        phase: stage.phase,
        time: sim.time,
        run_start,
        steps,
        x: sim.x.clone(),
        v: sim.v.clone(),
        pairs,
        built_at,
        quiet_since,
        sewing: stage.sewing,
        gap: stage.gap,
        drape: stage.drape,
        untangle_rounds: stage.untangle_rounds,
    })
}

/// Puts a snapshot's positions, velocities, time and contact list into `sim`.
fn restore(sim: &mut Xpbd<'_>, s: &Snapshot) -> Result<()> {
    if s.x.len() != sim.x.len() {
        return Err(Error::Invalid(format!(
            "garment snapshot holds {} positions, the garment has {}",
            s.x.len(),
            sim.x.len()
        )));
    }
    sim.x = s.x.clone();
    sim.v = s.v.clone();
    sim.time = s.time;
    if let Some(c) = &mut sim.cloth {
        c.set_list(&s.pairs, s.built_at.clone())?;
    }
    Ok(())
}

fn push_out(x: &mut [V3], collider: &dyn Collider, clearance: f64) {
    for p in x.iter_mut() {
        let (d, n) = collider.query(*p);
        if d < clearance {
            *p = add(*p, scale(n, clearance - d));
        }
    }
}

/// Smooths the crossings a sewing left where several seams meet (an armpit's few triangle
/// pairs): the corners of every crossing pair and `1 + round/4` rings round them are moved
/// halfway to the mean of their neighbours, ten sweeps a round, until the check finds none
/// or 40 rounds have passed; pinned vertices stay. Returns the rounds taken. A local fold
/// flattens under smoothing; the drape's contact then keeps the layers apart.
fn untangle(x: &mut [V3], triangles: &[[u32; 3]], pinned: &[bool]) -> usize {
    let mut nbr: Vec<Vec<u32>> = vec![Vec::new(); x.len()];
    for t in triangles {
        for k in 0..3 {
            nbr[t[k] as usize].extend([t[(k + 1) % 3], t[(k + 2) % 3]]);
        }
    }
    for n in &mut nbr {
        n.sort_unstable();
        n.dedup();
    }
    let crossings = |x: &[V3]| {
        let m = Mesh { positions: x.to_vec(), triangles: triangles.to_vec(), ..Default::default() };
        super::check::self_intersections(&m)
    };
    let mut si = crossings(x);
    let mut round = 0;
    while !si.is_empty() && round < 40 {
        let mut region: Vec<u32> = si
            .iter()
            .flat_map(|&(a, b)| triangles[a as usize].into_iter().chain(triangles[b as usize]))
            .collect();
        for _ in 0..1 + round / 4 {
            let grown: Vec<u32> =
                region.iter().flat_map(|&v| nbr[v as usize].iter().copied()).collect();
            region.extend(grown);
            region.sort_unstable();
            region.dedup();
        }
        for _ in 0..10 {
            for &v in &region {
                let n = &nbr[v as usize];
                if pinned[v as usize] || n.is_empty() {
                    continue;
                }
                let mean = scale(
                    n.iter().fold([0.0; 3], |s, &j| add(s, x[j as usize])),
                    1.0 / n.len() as f64,
                );
                x[v as usize] = scale(add(x[v as usize], mean), 0.5);
            }
        }
        si = crossings(x);
        round += 1;
    }
    round
}

/// The panels' flat shapes for [`SelfContact::with_rest_shape`]: each triangle's panel and
/// its corners' panel coordinates (`uv[tri_uv[t][k]]`), and for each of the `n` nodes its
/// (panel, coordinates) on every panel it lies on.
#[allow(clippy::type_complexity)]
fn rest_shape(
    n: usize,
    triangles: &[[u32; 3]],
    tri_uv: &[[u32; 3]],
    triangle_panel: &[u16],
    uv: &[[f64; 2]],
) -> (Vec<(u16, [[f64; 2]; 3])>, Vec<Vec<(u16, [f64; 2])>>) {
    let tri_rest =
        tri_uv.iter().zip(triangle_panel).map(|(t, &p)| (p, t.map(|k| uv[k as usize]))).collect();
    let mut node_rest: Vec<Vec<(u16, [f64; 2])>> = vec![Vec::new(); n];
    for ((t, tu), &p) in triangles.iter().zip(tri_uv).zip(triangle_panel) {
        for k in 0..3 {
            let r = &mut node_rest[t[k] as usize];
            if !r.iter().any(|&(q, _)| q == p) {
                r.push((p, uv[tu[k] as usize]));
            }
        }
    }
    (tri_rest, node_rest)
}

/// Progress callback: `(stage, fraction done)`.
pub type Progress<'a> = dyn FnMut(&str, f64) + 'a;

/// Sews and drapes `pattern` on `body` (or, for a curtain, alone) at about `vertices`
/// vertices.
pub fn sew_and_drape(
    pattern: Pattern,
    body: Option<&Body>,
    vertices: usize,
    fabric: &Fabric,
    settings: &DrapeSettings,
    progress: &mut Progress<'_>,
    mut checkpoints: Option<&mut Checkpointing<'_>>,
) -> Result<Garment> {
    let resume = checkpoints.as_mut().and_then(|c| c.from.take());
    let drape_from = resume.as_ref().filter(|s| s.phase >= 1);
    if !(200..=400_000).contains(&vertices) {
        return Err(Error::Invalid(format!("--vertices = {vertices} is outside 200 … 400000")));
    }
    let area = pattern.area();
    let h = (2.0 * area / (3f64.sqrt() * vertices as f64)).sqrt();
    // Cloth–cloth contact keeps layers a half-thickness apart and finds candidates within
    // three: on a mesh finer than the half-thickness a node's list holds ~100 triangles of
    // every layer near it (the scarf at 40 000 vertices, h = 2.3 mm: 4.3 million pairs, its
    // drape 0.04 s after 16 minutes).
    if settings.cloth_contact && h < fabric.thickness_m {
        let most = (2.0 * area / (3f64.sqrt() * fabric.thickness_m.powi(2))) as usize;
        return Err(Error::Invalid(format!(
            "--vertices = {vertices} makes the {}'s mesh spacing {:.1} mm, finer than the \
             cloth's {:.1} mm half-thickness that cloth–cloth contact keeps between layers; \
             at most {most} vertices for it (or --no-cloth-contact)",
            pattern.kind.name(),
            1e3 * h,
            1e3 * fabric.thickness_m
        )));
    }
    let mut flat = layout(&pattern, h)?;
    let collider: Option<&dyn Collider> =
        if pattern.kind.on_body() { body.map(|b| &b.sdf as &dyn Collider) } else { None };
    if let Some(c) = collider {
        push_out(&mut flat.x, c, 2.0 * fabric.thickness_m);
    }
    let n0 = flat.uv.len();
    let identity: Vec<[u32; 3]> = flat.triangles.clone();
    let cloth = build_cloth(n0, &flat.triangles, &identity, &flat.uv, fabric);
    let contact = Contact {
        thickness_m: fabric.thickness_m,
        static_coef: fabric.friction.static_coef,
        dynamic_coef: fabric.friction.dynamic_coef,
    };
    let body_contact = collider.map(|c| (c, contact));
    let link_damping_s = if collider.is_none() { settings.free_hanging_damping_s } else { 0.0 };
    // Weld seam partners (union–find; the smallest id is the root).
    let mut parent: Vec<u32> = (0..n0 as u32).collect();
    fn root(p: &mut [u32], mut i: u32) -> u32 {
        while p[i as usize] != i {
            p[i as usize] = p[p[i as usize] as usize];
            i = p[i as usize];
        }
        i
    }
    for &(a, b) in &flat.pairs {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut new_id = vec![u32::MAX; n0];
    let mut members: Vec<Vec<u32>> = Vec::new();
    for i in 0..n0 as u32 {
        let r = root(&mut parent, i);
        if new_id[r as usize] == u32::MAX {
            new_id[r as usize] = members.len() as u32;
            members.push(Vec::new());
        }
        new_id[i as usize] = new_id[r as usize];
        members[new_id[i as usize] as usize].push(i);
    }
    // Sewing: seam links whose rest length shrinks from the placed gap to 0 over
    // `sew_close_s`, no gravity, heavy air damping, the body as collider.
    let mut sewing = RestReport::default();
    let mut gap = 0.0;
    let mut x = flat.x.clone();
    let dt = settings.substep_for(h, fabric);
    if let Some(s) = drape_from {
        sewing = s.sewing;
        gap = s.gap;
    }
    if !flat.pairs.is_empty() && drape_from.is_none() {
        let mut links = links_of(&cloth);
        let first_seam = links.len();
        let pairs: Vec<(u32, u32)> = flat.pairs.iter().copied().filter(|&(a, b)| a != b).collect();
        let gap0: Vec<f64> =
            pairs.iter().map(|&(a, b)| length(sub(x[a as usize], x[b as usize]))).collect();
        for (&(a, b), &g0) in pairs.iter().zip(&gap0) {
            links.push(Link { a, b, rest: g0, compliance: 0.0 });
        }
        let params = XpbdParams { gravity: [0.0; 3], air_viscosity: 20.0, dt, link_damping_s };
        // Sewn without friction: the panels slide round the body as their seams close (with
        // the fabric's friction a sleeve lying on the arm held its underarm seam 19.6 mm
        // open); the drape below has the friction.
        let sliding = Contact { static_coef: 0.0, dynamic_coef: 0.0, ..contact };
        let sew_contact = collider.map(|c| (c, sliding));
        let mut sim = Xpbd::new(x, cloth.mass.clone(), &flat.pinned, links, params, sew_contact);
        if settings.cloth_contact {
            let (tri_rest, node_rest) =
                rest_shape(n0, &flat.triangles, &flat.triangles, &flat.triangle_panel, &flat.uv);
            sim.cloth = Some(
                SelfContact::new(flat.triangles.clone(), new_id.clone(), fabric.thickness_m, h)
                    .with_rest_shape(tri_rest, node_rest, 3.0 * fabric.thickness_m),
            );
        }
        let max_gap = |s: &Xpbd| {
            pairs
                .iter()
                .map(|&(a, b)| length(sub(s.x[a as usize], s.x[b as usize])))
                .fold(0.0, f64::max)
        };
        let close_s = settings.sew_close_s;
        let mut steps = 0;
        if let Some(s) = resume.as_ref().filter(|s| s.phase == 0) {
            restore(&mut sim, s)?;
            steps = s.steps as usize;
        }
        while sim.time < settings.sew_max_s {
            let f = (1.0 - sim.time / close_s).max(0.0);
            for (l, &g0) in sim.links[first_seam..].iter_mut().zip(&gap0) {
                l.rest = f * g0;
            }
            sim.step();
            steps += 1;
            if steps % 32 == 0 {
                progress("sewing", (sim.time / close_s).min(1.0));
                if sim.time >= close_s && max_gap(&sim) < 0.15 * h {
                    break;
                }
            }
            if steps % 64 == 0 {
                let stage = Stage {
                    phase: 0,
                    sewing: RestReport::default(),
                    gap: 0.0,
                    drape: None,
                    untangle_rounds: 0,
                };
                offer(checkpoints.as_deref_mut(), &sim, &stage, 0.0, steps as u64, None)?;
            }
        }
        gap = max_gap(&sim);
        sewing.steps = steps;
        sewing.end_time_s = sim.time;
        sewing.settle_time_s = sim.time;
        sewing.settled = gap < 0.15 * h;
        sewing.kinetic_energy_per_kg = sim.kinetic_energy_per_kg();
        x = sim.x;
    }
    let mut xw: Vec<V3> = members
        .iter()
        .map(|ms| {
            scale(ms.iter().fold([0.0; 3], |s, &i| add(s, x[i as usize])), 1.0 / ms.len() as f64)
        })
        .collect();
    let pinned: Vec<bool> =
        members.iter().map(|ms| ms.iter().any(|&i| flat.pinned[i as usize])).collect();
    let mut triangles = Vec::new();
    let mut tri_uv = Vec::new();
    let mut triangle_panel = Vec::new();
    for (t, &p) in flat.triangles.iter().zip(&flat.triangle_panel) {
        let w = t.map(|i| new_id[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            return Err(Error::Invalid(
                "sewing welded a triangle onto itself (a seam is shorter than one mesh step)"
                    .into(),
            ));
        }
        triangles.push(w);
        tri_uv.push(*t);
        triangle_panel.push(p);
    }
    let nw = xw.len();
    let mut seam_edges: Vec<[u32; 2]> = Vec::new();
    for s in &pattern.seams {
        let _ = s;
    }
    {
        let mut set = std::collections::BTreeSet::new();
        let pair_set: std::collections::HashSet<u32> =
            flat.pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
        for t in &flat.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if pair_set.contains(&a) && pair_set.contains(&b) {
                    let (wa, wb) = (new_id[a as usize], new_id[b as usize]);
                    // A seam edge is one that two different triangles' edges welded onto.
                    set.insert([wa.min(wb), wa.max(wb)]);
                }
            }
        }
        // Keep only edges used by triangles of two different panels or twice by one panel.
        let mut uses: HashMap<[u32; 2], Vec<u16>> = HashMap::new();
        for (t, &p) in triangles.iter().zip(&triangle_panel) {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                uses.entry([a.min(b), a.max(b)]).or_default().push(p);
            }
        }
        for e in set {
            if uses.get(&e).is_some_and(|u| u.len() == 2) {
                seam_edges.push(e);
            }
        }
    }
    // Drape: gravity, the body, until the kinetic energy stays low.
    let cloth = build_cloth(nw, &triangles, &tri_uv, &flat.uv, fabric);
    let mut untangle_rounds = 0;
    if let Some(s) = drape_from {
        untangle_rounds = s.untangle_rounds as usize;
    } else {
        if settings.cloth_contact {
            untangle_rounds += untangle(&mut xw, &triangles, &pinned);
        }
        if let Some(c) = collider {
            push_out(&mut xw, c, fabric.thickness_m);
        }
    }
    let params = XpbdParams {
        gravity: [0.0, 0.0, -9.81],
        air_viscosity: settings.air_viscosity,
        dt,
        link_damping_s,
    };
    let mut sim =
        Xpbd::new(xw, cloth.mass.clone(), &pinned, links_of(&cloth), params, body_contact);
    if settings.cloth_contact {
        // Each node ignores its own panel within the list's reach (3d) in the flat panel:
        // a flat sheet's own triangles are never candidates, at any resolution (at 40 000
        // vertices the reach is two mesh spacings, and the second and third rings filled
        // the list: ~20 pairs a node, each projected three times a sub-step).
        let (tri_rest, node_rest) = rest_shape(nw, &triangles, &tri_uv, &triangle_panel, &flat.uv);
        let mut layers =
            SelfContact::new(triangles.clone(), (0..nw as u32).collect(), fabric.thickness_m, h)
                .with_rest_shape(tri_rest, node_rest, 3.0 * fabric.thickness_m);
        // The drape has the fabric's friction between its layers too (the sewing has none).
        layers.friction = fabric.friction;
        sim.cloth = Some(layers);
    }
    if let Some(s) = drape_from {
        restore(&mut sim, s)?;
    }
    // Crossings the drape made (two creases passing between their nodes, which the node–
    // triangle contact does not see) are smoothed out and the drape resumed, twice at most.
    let first_run = drape_from.map_or(0, |s| s.phase as usize - 1).min(2);
    let mut acc: Option<RestReport> = drape_from.and_then(|s| s.drape);
    for run in first_run..3 {
        let resumed = drape_from.filter(|_| run == first_run);
        if run > 0 && resumed.is_none() {
            if !settings.cloth_contact {
                break;
            }
            let rounds = untangle(&mut sim.x, &triangles, &pinned);
            if rounds == 0 {
                break;
            }
            untangle_rounds += rounds;
            if let Some(c) = collider {
                push_out(&mut sim.x, c, fabric.thickness_m);
            }
        }
        let stage = Stage {
            phase: run as u32 + 1,
            sewing,
            gap,
            drape: acc,
            untangle_rounds: untangle_rounds as u64,
        };
        let mut save = |sim: &Xpbd<'_>, start: f64, steps: u64, quiet: Option<f64>| {
            offer(checkpoints.as_deref_mut(), sim, &stage, start, steps, quiet)
        };
        let more = run_to_rest(
            &mut sim,
            settings,
            &mut |t| progress("draping", t / settings.drape_max_s),
            resumed,
            &mut save,
        )?;
        acc = Some(combine(acc, more));
    }
    let drape = acc.unwrap_or_default();
    // A crumple the drape makes again after every resume (a seam junction whose corners
    // sum to more than 360°: the shirt's armpit at 10 000 vertices, 403°) is smoothed once
    // more and left; how far that moved a vertex is reported.
    let mut final_smoothing_m = 0.0;
    if settings.cloth_contact {
        let before = sim.x.clone();
        let rounds = untangle(&mut sim.x, &triangles, &pinned);
        if rounds > 0 {
            untangle_rounds += rounds;
            if let Some(c) = collider {
                push_out(&mut sim.x, c, fabric.thickness_m);
            }
            final_smoothing_m =
                sim.x.iter().zip(&before).map(|(p, q)| length(sub(*p, *q))).fold(0.0, f64::max);
        }
    }
    if !sim.x.iter().all(|p| p.iter().all(|c| c.is_finite())) {
        return Err(Error::Invalid(format!("the drape diverged after {} steps", drape.steps)));
    }
    let mut mesh = Mesh {
        positions: sim.x,
        uvs: flat.uv,
        triangles,
        triangle_uvs: tri_uv,
        ..Default::default()
    };
    mesh.compute_normals();
    Ok(Garment {
        mesh,
        pattern,
        triangle_panel,
        seam_edges,
        spacing_m: h,
        fabric: *fabric,
        sewing,
        seam_gap_at_weld_m: gap,
        drape,
        substep_s: dt,
        untangle_rounds,
        final_smoothing_m,
    })
}

/// Default vertex count for `kind` (`btf synth garment` without `--vertices`): 10 000, the
/// scarf 3 000 (its drape with cloth–cloth contact is the slowest, BENCHMARKS.md).
pub fn default_vertices(kind: GarmentKind) -> usize {
    match kind {
        GarmentKind::Scarf => 3000,
        _ => 10_000,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::garment::body::Mannequin;
    use crate::garment::{BodyParams, PatternOptions, Size, check};

    /// Two parallel sheets 1 cm apart, one node of the upper one pushed 1 cm through the
    /// lower: smoothing removes the crossings in one round and leaves a pinned node where
    /// it was.
    #[test]
    fn untangle_flattens_a_node_poked_through_another_sheet() {
        let n = 7;
        let mut x = Vec::new();
        let mut triangles = Vec::new();
        for (sheet, z) in [0.0, 0.01].into_iter().enumerate() {
            let base = (sheet * n * n) as u32;
            for j in 0..n {
                for i in 0..n {
                    x.push([i as f64 * 0.01, j as f64 * 0.01, z]);
                }
            }
            for j in 0..n - 1 {
                for i in 0..n - 1 {
                    let v = base + (j * n + i) as u32;
                    let w = n as u32;
                    triangles.push([v, v + 1, v + w + 1]);
                    triangles.push([v, v + w + 1, v + w]);
                }
            }
        }
        let poked = n * n + 3 * n + 3;
        x[poked][2] = -0.01;
        let mut pinned = vec![false; x.len()];
        // The poked node's neighbour in its own sheet: smoothing would pull it down.
        let held = n * n + 3 * n + 4;
        pinned[held] = true;
        let crossings = |x: &[V3]| {
            let m =
                Mesh { positions: x.to_vec(), triangles: triangles.clone(), ..Default::default() };
            check::self_intersections(&m).len()
        };
        assert!(crossings(&x) > 0);
        let before = x[held];
        assert_eq!(untangle(&mut x, &triangles, &pinned), 1);
        assert_eq!(crossings(&x), 0);
        assert_eq!(x[held], before);
        assert!(x[poked][2] > 0.0, "{:?}", x[poked]);
        // Nothing to do: no round.
        assert_eq!(untangle(&mut x, &triangles, &pinned), 0);
    }

    /// Every garment's panels are placed apart: no triangle of one panel crosses another
    /// panel (the cloth–cloth contact of the sewing and the drape keeps each layer on the
    /// side it starts on, so a crossing placed here would stay in the garment).
    #[test]
    fn panels_are_placed_without_crossings() {
        for size in [Size::S, Size::M, Size::L] {
            let p = BodyParams::new(size);
            let man = Mannequin::new(&p).unwrap();
            for kind in [
                GarmentKind::TShirt,
                GarmentKind::Shirt,
                GarmentKind::Trousers,
                GarmentKind::Skirt,
                GarmentKind::Scarf,
            ] {
                let pat =
                    Pattern::new(kind, &p.measurements, &man.landmarks, &PatternOptions::default())
                        .unwrap();
                let h = (2.0 * pat.area() / (3f64.sqrt() * 1500.0)).sqrt();
                let flat = layout(&pat, h).unwrap();
                let m = Mesh {
                    positions: flat.x.clone(),
                    triangles: flat.triangles.clone(),
                    ..Default::default()
                };
                let si = check::self_intersections(&m);
                assert_eq!(si.len(), 0, "{size:?} {kind:?}: crossing triangle pairs as placed");
            }
        }
    }
}
