//! The per-vertex coefficients of a scene's environment light for one camera
//! (`[S03 §5.3–5.4]`: `f · ω_m · γ*_{k j_m}` of [S03 eq. 11] for the four view slots `j_m` of
//! each vertex, with `γ*` from the eigenweightsets of eq. 13).
//!
//! **Output layout** (what the renderer's per-vertex pass reads): per vertex, per light
//! `l < n_lights`, per blend position `m < 4`, `stride = 2 + 3G` vec4 (`G = ⌈c/4⌉`): the
//! mean and bias terms as RGB (`[f·ω·γ*_μ]`, `[f·ω·γ*_b]`), then the `3c` component terms
//! packed four to a vec4, component `k`, channel `ch` at flat position `3k + ch`.
//!
//! Two paths give the same numbers up to `f32` rounding. The direct one forms `G(δ) = Ḡ +
//! Σ o_k(δ) W_k` for every frame and light, then `γ* = G · P` for the picked slots. The
//! basis path uses that `γ*` is linear in `G`: for a fixed camera the picked `(frame, slot)`
//! pairs do not change, so `γ*(Ḡ)` and `γ*(W_k)` of those pairs are formed once
//! ([`GammaBasis`]) and a rotation only streams `γ*(δ) = γ*(Ḡ) + Σ o_k(δ) γ*(W_k)`. The
//! basis is built when the environment turns under an unchanged camera (a rotation slider,
//! `btf relight`'s rotations), so a camera move costs no more than before.

use crate::coefficients::CoefficientMatrix;
use crate::eigenweights::GammaBasis;
use crate::environment::SceneEnvironment;
use crate::math::Vec3;
use crate::tangent;
use btf_core::{Direction, InterpMode, Sampling};
use rayon::prelude::*;

/// Camera and mesh inputs of [`EnvCoefficients::fill`].
pub struct ViewInput<'a> {
    /// Eye position.
    pub eye: Vec3,
    /// Direction towards an orthographic camera.
    pub ortho_to_camera: Option<Vec3>,
    /// View blending.
    pub view_mode: InterpMode,
    /// Positions, normals, tangents of the mesh.
    pub positions: &'a [[f32; 3]],
    /// Unit normals.
    pub normals: &'a [[f32; 3]],
    /// Tangents.
    pub tangents: &'a [[f32; 4]],
    /// Material of each vertex (`usize::MAX` = none).
    pub material_of: &'a [usize],
    /// View sampling of every material.
    pub view_samplings: &'a [&'a Sampling],
}

/// One view slot a vertex reads: vertex, blend position `m < 4`, material, frame (the side
/// shown), slot, blend weight `ω_m`.
#[derive(Debug, Clone, Copy)]
struct Pick {
    v: usize,
    m: usize,
    material: usize,
    frame: usize,
    slot: usize,
    omega: f32,
}

/// What the picks depend on besides the (fixed) mesh: the camera and the view blending.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ViewKey {
    eye: [u32; 3],
    ortho: Option<[u32; 3]>,
    mode: InterpMode,
    vertices: usize,
    /// [`SceneEnvironment::revision`]: a new map has new eigenweightsets.
    revision: u64,
}

impl ViewKey {
    fn of(view: &ViewInput, env: &SceneEnvironment) -> ViewKey {
        let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        ViewKey {
            eye: bits(view.eye),
            ortho: view.ortho_to_camera.map(bits),
            mode: view.view_mode,
            vertices: view.positions.len(),
            revision: env.revision(),
        }
    }
}

/// The bases of one camera, one per material that occurs.
struct Built {
    key: ViewKey,
    /// Eigenweightsets the bases hold.
    e: usize,
    picks: Vec<Pick>,
    /// Per pick: its basis and its pair in that basis.
    loc: Vec<(usize, usize)>,
    /// First pick of every vertex, and the end (picks come in vertex order).
    vertex_start: Vec<usize>,
    /// Per material that occurs: the material and its basis.
    bases: Vec<(usize, GammaBasis)>,
}

/// Fills the per-vertex coefficients of an environment light for a camera, remembering
/// the camera's `γ*` bases between calls (see the module docs).
#[derive(Default)]
pub struct EnvCoefficients {
    last: Option<(ViewKey, u64)>,
    built: Option<Built>,
    /// Whether the last fill streamed a basis.
    used_basis: bool,
}

/// The side of vertex `v` the camera of `view` shows — whether it is the back side — its
/// frame `(T, B, ±N)` and the unit direction towards the camera.
fn shown_side(view: &ViewInput, v: usize) -> (bool, (Vec3, Vec3, Vec3), Vec3) {
    let p = Vec3::from(view.positions[v]);
    let (t, b, mut n) = tangent::frame(view.normals[v], view.tangents[v]);
    let to_cam = view.ortho_to_camera.unwrap_or(view.eye - p).try_normalize(0.0).unwrap_or(n);
    let back = to_cam.dot(&n) < 0.0;
    if back {
        n = -n;
    }
    (back, (t, b, n), to_cam)
}

/// The hemicube frames the camera of `view` reads (what [`EnvCoefficients::fill`] picks):
/// for every vertex with `seen[v]`, the side it shows — front frame `v`, or back frame `V +
/// v` when `two_sided`. The input of [`SceneEnvironment::with_frames`] for a fixed camera.
pub fn shown_frames(view: &ViewInput, two_sided: bool, seen: &[bool]) -> Vec<bool> {
    let n = view.positions.len();
    let mut out = vec![false; if two_sided { 2 * n } else { n }];
    for v in (0..n).filter(|&v| seen[v]) {
        let back = shown_side(view, v).0;
        out[if back && two_sided { n + v } else { v }] = true;
    }
    out
}

/// The view slots every vertex with a material reads for `view`.
fn picks(env: &SceneEnvironment, view: &ViewInput) -> Vec<Pick> {
    let vertices = env.vertices();
    let mut out = Vec::with_capacity(4 * vertices);
    for v in 0..vertices {
        let Some(&material) = view.material_of.get(v) else { continue };
        if material >= env.coefficients().len() || material >= view.view_samplings.len() {
            continue;
        }
        let (back, tbn, to_cam) = shown_side(view, v);
        let Some(dir) = Direction::from_vector(tangent::to_tangent(to_cam, tbn)) else {
            continue;
        };
        let frame = if back && env.two_sided() { vertices + v } else { v };
        let vw = view.view_samplings[material].view_weights(dir, view.view_mode);
        for (m, &(slot, omega)) in vw.as_slice().iter().enumerate() {
            out.push(Pick { v, m, material, frame, slot, omega: omega as f32 });
        }
    }
    out
}

/// Where a light's coefficients go: light `l` of `n_lights`, `stride` vec4 per entry (see
/// the module docs).
#[derive(Debug, Clone, Copy)]
pub struct Slots {
    /// The light.
    pub l: usize,
    /// Lights in the layout.
    pub n_lights: usize,
    /// Vec4 per (vertex, light, blend position).
    pub stride: usize,
}

impl EnvCoefficients {
    /// Writes the coefficients of `env` for the camera of `view` into `out` (light `at.l`):
    /// through the camera's `γ*` basis when the eigenweightsets are in use and the
    /// environment turned under this camera (built then, once), else directly.
    pub fn fill(
        &mut self,
        env: &SceneEnvironment,
        out: &mut [[f32; 4]],
        view: &ViewInput,
        at: Slots,
    ) {
        let Some(o) = env.eigen_coefficients() else {
            fill_direct(env, out, view, at);
            self.used_basis = false;
            return;
        };
        let key = ViewKey::of(view, env);
        let turn = env.rotation_deg().to_bits();
        let fits = |b: &Built| b.key == key && b.e >= o.len();
        let rotated_here = self.last.is_some_and(|(k, r)| k == key && r != turn);
        if !self.built.as_ref().is_some_and(fits) && rotated_here {
            self.built = build_bases(env, view, key, o.len());
        }
        self.last = Some((key, turn));
        self.used_basis = false;
        if let Some(built) = self.built.as_ref().filter(|b| fits(b)) {
            fill_from_bases(env, built, o, out, at);
            self.used_basis = true;
            return;
        }
        fill_direct(env, out, view, at);
    }

    /// Whether the last [`EnvCoefficients::fill`] streamed the camera's basis.
    pub fn used_basis(&self) -> bool {
        self.used_basis
    }
}

/// [`EnvCoefficients::fill`] without the camera basis: `G(δ)` of every frame, then `γ*` of
/// the picked slots (the reference of the basis path).
pub fn fill_direct(env: &SceneEnvironment, out: &mut [[f32; 4]], view: &ViewInput, at: Slots) {
    let k3 = 3 * env.coefficients().iter().map(|c| c.per_slot()).max().unwrap_or(2);
    let mut gs = vec![0f32; k3];
    let radiances = env.radiances();
    let per_vertex = at.n_lights * 4 * at.stride;
    for pick in picks(env, view) {
        let pm = &env.coefficients()[pick.material];
        radiances.gamma_star(pm, pick.frame, pick.slot, &mut gs);
        if let Some(dst) = out.get_mut(pick.v * per_vertex..(pick.v + 1) * per_vertex) {
            write_slot(env, dst, at, &pick, pm, &gs);
        }
    }
}

fn build_bases(env: &SceneEnvironment, view: &ViewInput, key: ViewKey, e: usize) -> Option<Built> {
    let ews = env.eigenweightsets()?;
    let picks = picks(env, view);
    let mut loc = vec![(0, 0); picks.len()];
    let mut bases = vec![];
    for (mi, pm) in env.coefficients().iter().enumerate() {
        let mut pairs = vec![];
        for (i, p) in picks.iter().enumerate().filter(|(_, p)| p.material == mi) {
            loc[i] = (bases.len(), pairs.len());
            pairs.push((p.frame, p.slot));
        }
        if !pairs.is_empty() {
            bases.push((mi, ews.gamma_basis(pm, &pairs, e).ok()?));
        }
    }
    let mut vertex_start = vec![0; env.vertices() + 1];
    for p in &picks {
        vertex_start[p.v + 1] += 1;
    }
    for v in 0..env.vertices() {
        vertex_start[v + 1] += vertex_start[v];
    }
    Some(Built { key, e, picks, loc, vertex_start, bases })
}

/// `γ*` of every pick from the bases, written straight into the vertices' coefficients
/// (vertices in parallel).
fn fill_from_bases(
    env: &SceneEnvironment,
    built: &Built,
    o: &[f64],
    out: &mut [[f32; 4]],
    at: Slots,
) {
    let o: Vec<f32> = o.iter().map(|&x| x as f32).collect();
    let per_vertex = at.n_lights * 4 * at.stride;
    let k3 = built.bases.iter().map(|(_, b)| b.per_pick).max().unwrap_or(0);
    out.par_chunks_mut(per_vertex).enumerate().for_each_init(
        || vec![0f32; k3],
        |gs, (v, dst)| {
            let Some(range) = built.vertex_start.get(v..v + 2) else { return };
            for i in range[0]..range[1] {
                let (b, pair) = built.loc[i];
                let (mi, basis) = &built.bases[b];
                basis.at_one(pair, &o, gs);
                let pick = &built.picks[i];
                write_slot(env, dst, at, pick, &env.coefficients()[*mi], gs);
            }
        },
    );
}

/// Scatters `γ*` of one pick (layout of [`crate::Radiances::gamma_star`]) times `f · ω_m`
/// into the coefficients `dst` of the pick's vertex.
fn write_slot(
    env: &SceneEnvironment,
    dst: &mut [[f32; 4]],
    at: Slots,
    pick: &Pick,
    pm: &CoefficientMatrix,
    gs: &[f32],
) {
    let k = pm.per_slot();
    let s = pick.omega * env.exposure();
    let base = (at.l * 4 + pick.m) * at.stride;
    let Some(dst) = dst.get_mut(base..base + at.stride) else { return };
    for col in 0..2 {
        dst[col] = [s * gs[col], s * gs[k + col], s * gs[2 * k + col], 0.0];
    }
    for kk in 0..pm.components {
        for ch in 0..3 {
            let flat = 3 * kk + ch;
            let (g, lane) = (flat / 12, flat % 12);
            dst[2 + 3 * g + lane / 4][lane % 4] = s * gs[ch * k + 2 + kk];
        }
    }
}
