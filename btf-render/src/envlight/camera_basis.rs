//! The per-vertex coefficients of a scene's environment light for one camera (Sattler et
//! al. 2003, §5.3–5.4: `f · ω_m · γ*_{k j_m}` of eq. 11 for the four view slots `j_m` of
//! each vertex, with `γ*` from the eigenweightsets of eq. 13), in the layout of
//! [`crate::per_vertex`].
//!
//! Two paths give the same numbers up to `f32` rounding. The direct one forms `G(δ) = Ḡ +
//! Σ o_k(δ) W_k` for every frame and light, then `γ* = G · P` for the picked slots. The
//! basis path uses that `γ*` is linear in `G`: for a fixed camera the picked `(frame, slot)`
//! pairs do not change, so `γ*(Ḡ)` and `γ*(W_k)` of those pairs are formed once
//! ([`GammaBasis`]) and a rotation only streams `γ*(δ) = γ*(Ḡ) + Σ o_k(δ) γ*(W_k)`. The
//! basis is built when the environment turns under an unchanged camera (a rotation slider,
//! `btf relight`'s rotations), so a camera move costs no more than before.

use super::eigenweights::GammaBasis;
use super::scene_env::SceneEnvironment;
use super::weights::CoefficientMatrix;
use crate::material::MaterialData;
use crate::math::Vec3;
use crate::per_vertex::VertexCoefficients;
use crate::tangent;
use btf_core::{Direction, InterpMode};
use rayon::prelude::*;

/// Camera and mesh inputs of [`SceneEnvironment::fill`].
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
    /// Materials (for their view samplings).
    pub materials: &'a [&'a MaterialData],
}

/// One view slot a vertex reads: vertex, blend position `m < 4`, material, frame (the side
/// shown), slot, blend weight `ω_m`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pick {
    v: usize,
    m: usize,
    material: usize,
    frame: usize,
    slot: usize,
    omega: f32,
}

/// What the picks depend on besides the (fixed) mesh: the camera and the view blending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ViewKey {
    eye: [u32; 3],
    ortho: Option<[u32; 3]>,
    mode: InterpMode,
    vertices: usize,
}

impl ViewKey {
    fn of(view: &ViewInput) -> ViewKey {
        let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        ViewKey {
            eye: bits(view.eye),
            ortho: view.ortho_to_camera.map(bits),
            mode: view.view_mode,
            vertices: view.positions.len(),
        }
    }
}

/// The bases of one camera, one per material that occurs.
pub(super) struct Built {
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

/// What [`SceneEnvironment::fill`] remembers between calls.
#[derive(Default)]
pub(super) struct CameraCache {
    last: Option<(ViewKey, u64)>,
    built: Option<Built>,
    /// Whether the last fill streamed a basis.
    pub(super) used_basis: bool,
}

impl CameraCache {
    /// Forgets the bases (a new environment, hence new eigenweightsets).
    pub(super) fn clear(&mut self) {
        *self = CameraCache::default();
    }
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

/// The hemicube frames the camera of `view` reads (what [`SceneEnvironment::fill`] picks):
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

impl SceneEnvironment {
    /// The view slots every vertex with a material reads for `view`.
    fn picks(&self, view: &ViewInput) -> Vec<Pick> {
        let mut out = Vec::with_capacity(4 * self.vertices);
        for v in 0..self.vertices {
            let Some(&material) = view.material_of.get(v) else { continue };
            if material >= self.coefficients.len() || material >= view.materials.len() {
                continue;
            }
            let (back, tbn, to_cam) = shown_side(view, v);
            let Some(dir) = Direction::from_vector(tangent::to_tangent(to_cam, tbn)) else {
                continue;
            };
            let frame = if back && self.params.two_sided { self.vertices + v } else { v };
            let vw = view.materials[material].view_sampling.view_weights(dir, view.view_mode);
            for (m, &(slot, omega)) in vw.as_slice().iter().enumerate() {
                out.push(Pick { v, m, material, frame, slot, omega: omega as f32 });
            }
        }
        out
    }

    /// Writes this light's coefficients (light `l` of `n_lights`) into `out` for the camera
    /// of `view`: through the camera's `γ*` basis when the eigenweightsets are in use and
    /// the environment turned under this camera (built then, once), else directly.
    pub fn fill(
        &self,
        out: &mut VertexCoefficients,
        view: &ViewInput,
        l: usize,
        n_lights: usize,
        stride: usize,
    ) {
        let Some(o) = self.eigen_coefficients() else {
            self.fill_direct(out, view, l, n_lights, stride);
            return;
        };
        let key = ViewKey::of(view);
        let turn = self.rotation_deg().to_bits();
        let mut cache = self.camera.lock().unwrap_or_else(|e| e.into_inner());
        let fits = |b: &Built| b.key == key && b.e >= o.len();
        let rotated_here = cache.last.is_some_and(|(k, r)| k == key && r != turn);
        if !cache.built.as_ref().is_some_and(fits) && rotated_here {
            cache.built = self.build_bases(view, key, o.len());
        }
        cache.last = Some((key, turn));
        cache.used_basis = false;
        if let Some(built) = cache.built.as_ref().filter(|b| fits(b)) {
            self.fill_from_bases(built, o, out, (l, n_lights, stride));
            cache.used_basis = true;
            return;
        }
        drop(cache);
        self.fill_direct(out, view, l, n_lights, stride);
    }

    /// [`SceneEnvironment::fill`] without the camera basis: `G(δ)` of every frame, then `γ*`
    /// of the picked slots (the reference of the basis path).
    pub fn fill_direct(
        &self,
        out: &mut VertexCoefficients,
        view: &ViewInput,
        l: usize,
        n_lights: usize,
        stride: usize,
    ) {
        let k3 = 3 * self.coefficients.iter().map(|c| c.per_slot()).max().unwrap_or(2);
        let mut gs = vec![0f32; k3];
        let weights = self.weights();
        for pick in self.picks(view) {
            let pm = &self.coefficients[pick.material];
            weights.gamma_star(pm, pick.frame, pick.slot, &mut gs);
            self.write(out, &pick, pm, &gs, (l, n_lights, stride));
        }
    }

    /// Whether the last [`SceneEnvironment::fill`] streamed the camera's basis.
    pub fn fill_used_basis(&self) -> bool {
        self.camera.lock().map(|c| c.used_basis).unwrap_or(false)
    }

    fn build_bases(&self, view: &ViewInput, key: ViewKey, e: usize) -> Option<Built> {
        let ews = self.eigenweightsets()?;
        let picks = self.picks(view);
        let mut loc = vec![(0, 0); picks.len()];
        let mut bases = vec![];
        for (mi, pm) in self.coefficients.iter().enumerate() {
            let mut pairs = vec![];
            for (i, p) in picks.iter().enumerate().filter(|(_, p)| p.material == mi) {
                loc[i] = (bases.len(), pairs.len());
                pairs.push((p.frame, p.slot));
            }
            if !pairs.is_empty() {
                bases.push((mi, ews.gamma_basis(pm, &pairs, e).ok()?));
            }
        }
        let mut vertex_start = vec![0; self.vertices + 1];
        for p in &picks {
            vertex_start[p.v + 1] += 1;
        }
        for v in 0..self.vertices {
            vertex_start[v + 1] += vertex_start[v];
        }
        Some(Built { key, e, picks, loc, vertex_start, bases })
    }

    /// `γ*` of every pick from the bases, written straight into the vertices' coefficients
    /// (vertices in parallel).
    fn fill_from_bases(
        &self,
        built: &Built,
        o: &[f64],
        out: &mut VertexCoefficients,
        (l, n_lights, stride): (usize, usize, usize),
    ) {
        let o: Vec<f32> = o.iter().map(|&x| x as f32).collect();
        let per_vertex = n_lights * 4 * stride;
        let k3 = built.bases.iter().map(|(_, b)| b.per_pick).max().unwrap_or(0);
        out.coef.par_chunks_mut(per_vertex).enumerate().for_each_init(
            || vec![0f32; k3],
            |gs, (v, dst)| {
                let Some(range) = built.vertex_start.get(v..v + 2) else { return };
                for i in range[0]..range[1] {
                    let (b, pair) = built.loc[i];
                    let (mi, basis) = &built.bases[b];
                    basis.at_one(pair, &o, gs);
                    let pick = &built.picks[i];
                    self.write_slot(dst, l, stride, pick, &self.coefficients[*mi], gs);
                }
            },
        );
    }

    /// Scatters `γ*` of one pick (layout of [`super::WeightSet::gamma_star`]) times
    /// `f · ω_m` into the vertex's coefficients.
    fn write(
        &self,
        out: &mut VertexCoefficients,
        pick: &Pick,
        pm: &CoefficientMatrix,
        gs: &[f32],
        (l, n_lights, stride): (usize, usize, usize),
    ) {
        let per_vertex = n_lights * 4 * stride;
        if let Some(dst) = out.coef.get_mut(pick.v * per_vertex..(pick.v + 1) * per_vertex) {
            self.write_slot(dst, l, stride, pick, pm, gs);
        }
    }

    /// [`SceneEnvironment::write`] into the coefficients `dst` of the pick's vertex.
    fn write_slot(
        &self,
        dst: &mut [[f32; 4]],
        l: usize,
        stride: usize,
        pick: &Pick,
        pm: &CoefficientMatrix,
        gs: &[f32],
    ) {
        let k = pm.per_slot();
        let s = pick.omega * self.params.exposure;
        let base = (l * 4 + pick.m) * stride;
        let Some(dst) = dst.get_mut(base..base + stride) else { return };
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
}
