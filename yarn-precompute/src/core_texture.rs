//! `CoreTexture`: the core fiber of one ply [W19 §3.2, Fig. 5] — the innermost fibers by
//! `R_i` drawn as one thick camera-facing strip with a texture of those fibers through one
//! full fiber twist.
//!
//! **Bake.** The core fibers of ply 0 of the fiber table (`yarn::fiber::FiberTable`, sorted
//! by `R_i`), with migration rate `s = 1` as [W19 §3.2] asks (so `R` has the period of one
//! twist and the texture tiles), are generated as capsule chains with `FiberModel`
//! ([W19 eq. 1–2]) and ray-cast orthographically with `yarn-ref`'s `FiberScene`,
//! `supersample²` rays per texel, box-downsampled. If the yarn has `s = 0` the core keeps
//! `s = 0`: its radii are then constant, which tiles over one twist just as well (DESIGN
//! §4.4 hard case).
//!
//! **The circular space (our choice).** The fibers are cast in the ply's *circular* space,
//! where the ply ellipse `(e_N, e_B)` becomes the circle of radius `ḡ = √(e_N e_B)`; real
//! space is `x_real = A x_circ`, `A = diag(e_N, e_B)/ḡ` (det 1). In that space every core
//! fiber's angle is `θ_i + θ_fib(z)` and its radius a function of `θ_fib(z) + φ_i`, so the
//! cross-section at `z` is one fixed shape turned by `θ_fib(z)` (screw symmetry, DESIGN §2.3
//! item 5) — exactly, also for elliptical plies. An orthographic view of `A S` along the eye
//! direction `e` is the view of `S` along `A⁻¹e`, with the screen axis scaled by `|A w|`; so
//! the lookup uses the corrected azimuth `ψ' = atan2(sin ψ / e_B, cos ψ / e_N)`. DESIGN's
//! literal `u` with the uncorrected ψ is kept as [`CoreTexcoord::ScrewSymmetricUncorrected`]
//! (exact only for `e_N = e_B`), and [W19 eq. 3] as [`CoreTexcoord::PaperEq3`].
//!
//! **Texture coordinates.** Column `u` shows the core at `θ_fib = 2πu` seen from eye azimuth
//! 0 (eye along `+N̂_ply`), i.e. the shape at `z = 0` seen from azimuth `−2πu`. A fragment at
//! length coordinate z seen from ply-frame eye azimuth ψ (measured from `N̂_ply` towards
//! `B̂_ply = T × N̂_ply`) therefore reads `u = frac((θ_fib(z) − ψ')/2π)`: DESIGN §2.3 item 5's
//! `frac(θ_fib/2π + ψ_ply/2π)` with its `ψ_ply` measured the other way round (from `N̂_ply`
//! towards `−B̂_ply`). `v ∈ [0, 1]` runs across the strip along `w = T × e`, from `−H` to `+H`,
//! `H = ρ_max·max_core R_i·ḡ + r_f` in circular space (DESIGN item 6's core radius plus the
//! fiber radius, so the outermost core fibers are not clipped). In real space the strip's
//! half-width is `H·|A w|` = `H·√((e_N sin ψ)² + (e_B cos ψ)²)/ḡ` — the ellipse's extent
//! across the view (DESIGN item 6 writes the cos and sin the other way round; with ψ the eye
//! azimuth, the view along `N̂` sees the `e_B` extent).
//!
//! **[W19 eq. 3]** `u = (1/2π)(θ α_ply² α/(α_ply − α) + ψ_view/2)` multiplies an angle by a
//! length squared (DESIGN §2.3 item 5): in metres the θ term is about 10⁻⁶ θ, so the
//! texture barely moves along the yarn. It is implemented literally for comparison.
//!
//! **Texel layout** ([`CoreTexture::to_rgba_f32`], two RGBA32F textures, rows `v`, columns
//! `u`, texel `(i, j)` centred at `((i+½)/W, (j+½)/H)`, u repeats, v clamps):
//! - texture A: `R` alpha (covered fraction of the texel's rays), `G` height (distance of the
//!   hit towards the eye from the strip plane, divided by `H`, in `[−1, 1]`), `B` normal·w,
//!   `A` normal·T;
//! - texture B: `R` direction·T, `G` direction·w, `B` direction·e (the fiber tangent, oriented
//!   along +T), `A` normal·e.
//!
//! Normals and directions are means over the texel's hits, renormalised, in the circular
//! strip frame `(w', e', T)`; uncovered texels hold height 0, normal `e'`, direction `T`.
//! [`CoreTexture::surface`] maps a texel to the real ply frame; the WGSL mirrors it.
//!
//! **Screw symmetry needs fibers that do not migrate (DESIGN §2.3 item 5 is wrong here).**
//! With migration a core fiber sits at `(R_i f(θ_fib + φ_i), θ_i + θ_fib)`: its angle turns
//! with the twist but its radius breathes, so the cross-section at z is *not* a rigid
//! rotation of the one at 0 — for any phase convention, [W19 eq. 2]'s `φ_i = θ_i` included —
//! and the appearance depends on θ_fib and on ψ − θ_fib separately, which one u cannot hold.
//! Measured on cotton-2ply (ρ_min = 0.8), an `s = 1` core read by the screw-symmetric u has a
//! coverage IoU of only 0.80–0.87 against the same fibers. Our default core therefore stands
//! for fibers at their mean radius `R_i(ρ_min + ρ_max)/2` without migration
//! ([`CoreMigration::MeanRadius`]): exactly screw-symmetric, and it tiles trivially. The
//! paper's `s = 1` core stays available as [`CoreMigration::PaperS1`].

use crate::settings::{CoreMigration, CoreSettings};
use crate::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::TAU;
use yarn::YarnParams;
use yarn::fiber::{EffectiveTwist, FiberKind, FiberModel, FiberTable, Fibers};
use yarn::vec3::{self, V3};
use yarn_ref::{FiberScene, SceneOptions};

/// How the core texture's u is computed (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CoreTexcoord {
    /// `u = frac((θ_fib − ψ')/2π)` with the ellipse-corrected azimuth ψ' (exact).
    ScrewSymmetric,
    /// DESIGN §2.3 item 5 literally: ψ uncorrected, normals not mapped through the ellipse.
    ScrewSymmetricUncorrected,
    /// [W19 eq. 3] literally, `ψ_view` taken as the eye azimuth about the ply.
    PaperEq3,
}

/// One bilinear texture sample, in the texture's circular strip frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreTexel {
    /// Coverage in `[0, 1]`.
    pub alpha: f64,
    /// Height towards the eye over `H`, in `[−1, 1]`.
    pub height: f64,
    /// Unit normal `(w, e, T)` components.
    pub normal: V3,
    /// Unit fiber direction `(T, w, e)` components.
    pub direction: V3,
}

/// Where a view puts the strip on the texture (per vertex on the GPU).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreView {
    /// Texture u of the strip at this length coordinate.
    pub u: f64,
    /// Real half-width of the strip (metres).
    pub half_width: f64,
    /// Eye direction `e` in the ply cross-section `(N̂, B̂)` (unit; real space).
    pub eye: [f64; 2],
    /// The azimuth the texture is read at (ψ' or ψ).
    pub psi_tex: f64,
    /// Map normals and directions through the ellipse.
    pub affine: bool,
}

/// A texel placed on the real ply: what the shader shades.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreSurface {
    /// Coverage.
    pub alpha: f64,
    /// Unit normal in the ply frame `(N̂, B̂, T)`.
    pub normal: V3,
    /// Unit fiber direction in the ply frame.
    pub direction: V3,
    /// Offset of the surface point from the ply centre, `(N̂, B̂)` coefficients (metres).
    pub offset: [f64; 2],
}

/// The baked core texture and the geometry its lookups need.
#[derive(Debug, Clone, PartialEq)]
pub struct CoreTexture {
    /// Texels along u.
    pub width: usize,
    /// Texels along v.
    pub height: usize,
    /// Texture A, RGBA per texel, row-major `[v][u]` (module docs).
    pub tex_a: Vec<f32>,
    /// Texture B, RGBA per texel.
    pub tex_b: Vec<f32>,
    /// Strip half-width `H` in circular space (metres).
    pub half_width_circ: f64,
    /// Ply ellipse semi-axes `e_N`, `e_B` (metres).
    pub ellipse: [f64; 2],
    /// Fiber pitch α (signed, metres per turn).
    pub fiber_pitch: f64,
    /// Ply pitch α_ply (signed), for [W19 eq. 3].
    pub ply_pitch: f64,
    /// Number of core fibers per ply.
    pub core_fibers: usize,
}

/// The core fibers of ply 0 as explicit capsule chains over `z ∈ [z0, z1]` (metres), in
/// circular space (`circular`) or real space, migrating as `migration` says.
pub fn core_fibers(
    params: &YarnParams,
    seed: u64,
    n_core: usize,
    migration: CoreMigration,
    circular: bool,
    z_range: [f64; 2],
    samples_per_turn: usize,
) -> Fibers {
    let g = (params.ply_ellipse_n * params.ply_ellipse_b).sqrt();
    let mut p = params.clone();
    p.ply_center_distance = 0.0;
    p.loop_density = 0.0;
    p.hair_density = 0.0;
    if circular {
        p.ply_ellipse_n = g;
        p.ply_ellipse_b = g;
    }
    let s = match migration {
        CoreMigration::MeanRadius => {
            let mean = 0.5 * (params.rho_min + params.rho_max);
            (p.rho_min, p.rho_max) = (mean, mean);
            0.0
        }
        CoreMigration::PaperS1 if params.migration_rate > 0.0 => 1.0,
        CoreMigration::PaperS1 => 0.0,
    };
    let table = FiberTable::new(params, seed, 0);
    let twist = EffectiveTwist {
        ply_pitch: f64::INFINITY,
        fiber_pitch: params.fiber_pitch,
        migration_rate: s,
        slots_per_wrap: None,
    };
    let model = FiberModel { params: &p, table: &table, twist };
    let step = params.fiber_pitch.abs() / samples_per_turn as f64;
    let (k0, k1) = ((z_range[0] / step).floor() as i64, (z_range[1] / step).ceil() as i64);
    let n_core = n_core.min(params.fibers_per_ply as usize);
    let mut f = Fibers { palette: vec![[1.0; 3]], offsets: vec![0], ..Default::default() };
    for fiber in 0..n_core {
        for k in k0..=k1 {
            let z = k as f64 * step;
            let [a, b] = model.fiber_offset(z, 0, fiber);
            f.points.push([a as f32, b as f32, z as f32]);
            f.radii.push(params.fiber_radius as f32);
            f.color_ids.push(0);
        }
        f.offsets.push(f.points.len() as u32);
        f.yarn.push(0);
        f.ply.push(0);
        f.fiber.push(fiber as u32);
        f.kind.push(FiberKind::Core);
        f.params_id.push(0);
    }
    f
}

/// The number of core fibers and the core radius `ρ·max R_i` (normalised; ρ = ρ_max, or
/// the mean `(ρ_min + ρ_max)/2` for [`CoreMigration::MeanRadius`]).
fn core_extent(params: &YarnParams, seed: u64, settings: &CoreSettings) -> (usize, f64) {
    let n = params.fibers_per_ply as usize;
    let n_core =
        settings.core_fibers.unwrap_or((params.core_fraction * n as f64).round() as usize).min(n);
    let table = FiberTable::new(params, seed, 0);
    let r = (0..n_core).map(|i| table.fiber(0, i).r).fold(0.0, f64::max);
    let rho = match settings.migration {
        CoreMigration::MeanRadius => 0.5 * (params.rho_min + params.rho_max),
        CoreMigration::PaperS1 => params.rho_max,
    };
    (n_core, rho * r)
}

/// Hit statistics of one texel's rays.
#[derive(Default, Clone, Copy)]
struct Acc {
    hits: u32,
    height: f64,
    normal: V3,
    dir: V3,
}

/// One orthographic ray cast towards −X at strip coordinate `s` (along +Y) and height `z`.
fn cast(scene: &FiberScene, s: f64, z: f64, reach: f64, acc: &mut Acc) {
    let o = [reach, s, z];
    let d = [-1.0, 0.0, 0.0];
    if let Some(hit) = scene.intersect(o, d, 2.0 * reach, None)
        && let yarn_ref::geometry::scene::HitKind::Fiber { segment, v } = hit.kind
    {
        let sp = scene.surface(segment, v, hit.position);
        let t = if sp.tangent[2] < 0.0 { vec3::scale(sp.tangent, -1.0) } else { sp.tangent };
        acc.hits += 1;
        acc.height += hit.position[0];
        // (w, e, T) = (y, x, z) for the normal; (T, w, e) = (z, y, x) for the direction.
        acc.normal = vec3::add(acc.normal, [sp.normal[1], sp.normal[0], sp.normal[2]]);
        acc.dir = vec3::add(acc.dir, [t[2], t[1], t[0]]);
    }
}

impl CoreTexture {
    /// Bakes the core texture of `params` (see the module documentation).
    pub fn bake(params: &YarnParams, seed: u64, settings: &CoreSettings) -> Result<Self> {
        params.validate()?;
        let (n_core, r_core) = core_extent(params, seed, settings);
        let g = (params.ply_ellipse_n * params.ply_ellipse_b).sqrt();
        let h = r_core * g + params.fiber_radius;
        let alpha = params.fiber_pitch;
        let margin = 0.05 * alpha.abs() + 4.0 * params.fiber_radius;
        let z_range = [alpha.min(0.0) - margin, alpha.max(0.0) + margin];
        let fibers = core_fibers(
            params,
            seed,
            n_core,
            settings.migration,
            true,
            z_range,
            settings.samples_per_turn,
        );
        let scene = FiberScene::new(&fibers, &SceneOptions::default())?;
        let (w, hgt, ss) = (settings.width, settings.height, settings.supersample);
        let reach = 2.0 * h + 1e-9;
        let rows: Vec<Vec<Acc>> = (0..hgt)
            .into_par_iter()
            .map(|j| {
                let mut row = vec![Acc::default(); w];
                if h <= 0.0 {
                    return row;
                }
                for (i, acc) in row.iter_mut().enumerate() {
                    for b in 0..ss {
                        let v = (j as f64 + (b as f64 + 0.5) / ss as f64) / hgt as f64;
                        for a in 0..ss {
                            let u = (i as f64 + (a as f64 + 0.5) / ss as f64) / w as f64;
                            cast(&scene, (2.0 * v - 1.0) * h, u * alpha, reach, acc);
                        }
                    }
                }
                row
            })
            .collect();
        let n_rays = (ss * ss) as f64;
        let mut tex_a = Vec::with_capacity(w * hgt * 4);
        let mut tex_b = Vec::with_capacity(w * hgt * 4);
        for acc in rows.iter().flatten() {
            let (hh, n, d) = if acc.hits > 0 {
                let hh = acc.height / acc.hits as f64 / h;
                let n = vec3::normalize(acc.normal).unwrap_or([0.0, 1.0, 0.0]);
                let d = vec3::normalize(acc.dir).unwrap_or([1.0, 0.0, 0.0]);
                (hh, n, d)
            } else {
                (0.0, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
            };
            tex_a.extend(
                [acc.hits as f64 / n_rays, hh.clamp(-1.0, 1.0), n[0], n[2]].map(|x| x as f32),
            );
            tex_b.extend([d[0], d[1], d[2], n[1]].map(|x| x as f32));
        }
        Ok(CoreTexture {
            width: w,
            height: hgt,
            tex_a,
            tex_b,
            half_width_circ: h,
            ellipse: [params.ply_ellipse_n, params.ply_ellipse_b],
            fiber_pitch: alpha,
            ply_pitch: params.ply_pitch,
            core_fibers: n_core,
        })
    }

    /// The two RGBA32F textures for upload (layout in the module documentation).
    pub fn to_rgba_f32(&self) -> (&[f32], &[f32]) {
        (&self.tex_a, &self.tex_b)
    }

    fn texel(&self, i: usize, j: usize) -> [f64; 8] {
        let k = 4 * (j * self.width + i);
        let a = &self.tex_a[k..k + 4];
        let b = &self.tex_b[k..k + 4];
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]].map(f64::from)
    }

    /// Bilinear lookup at `(u, v)`: u repeats, v clamps to the edge texels (a sampler with
    /// `AddressMode::Repeat` / `ClampToEdge` and linear filtering does the same).
    pub fn sample(&self, u: f64, v: f64) -> CoreTexel {
        let (w, h) = (self.width as f64, self.height as f64);
        let x = (u - u.floor()) * w - 0.5;
        let y = (v * h - 0.5).clamp(0.0, h - 1.0);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let i0 = (x0 as i64).rem_euclid(self.width as i64) as usize;
        let i1 = (i0 + 1) % self.width;
        let j0 = y0 as usize;
        let j1 = (j0 + 1).min(self.height - 1);
        let mut c = [0.0; 8];
        for (i, j, wt) in [
            (i0, j0, (1.0 - fx) * (1.0 - fy)),
            (i1, j0, fx * (1.0 - fy)),
            (i0, j1, (1.0 - fx) * fy),
            (i1, j1, fx * fy),
        ] {
            let t = self.texel(i, j);
            for k in 0..8 {
                c[k] += wt * t[k];
            }
        }
        CoreTexel {
            alpha: c[0],
            height: c[1],
            normal: vec3::normalize([c[2], c[7], c[3]]).unwrap_or([0.0, 1.0, 0.0]),
            direction: vec3::normalize([c[4], c[5], c[6]]).unwrap_or([1.0, 0.0, 0.0]),
        }
    }

    /// The strip of a view: `theta_fib = 2πz/α` at the fragment, `eye_ply` the direction
    /// towards the eye in the ply frame `(N̂, B̂, T)` (need not be unit).
    pub fn view(&self, theta_fib: f64, eye_ply: V3, mode: CoreTexcoord) -> CoreView {
        let [en, eb] = self.ellipse;
        let g = (en * eb).sqrt();
        let el = eye_ply[0].hypot(eye_ply[1]);
        // Looking along the ply the strip is edge-on; any azimuth will do.
        let eye = if el > 1e-12 { [eye_ply[0] / el, eye_ply[1] / el] } else { [1.0, 0.0] };
        let psi = eye[1].atan2(eye[0]);
        let (affine, psi_tex) = match mode {
            CoreTexcoord::ScrewSymmetric => (true, (eye[1] / eb).atan2(eye[0] / en)),
            _ => (false, psi),
        };
        let u = match mode {
            CoreTexcoord::PaperEq3 => u_paper_eq3(theta_fib, self.ply_pitch, self.fiber_pitch, psi),
            _ => ((theta_fib - psi_tex) / TAU).rem_euclid(1.0),
        };
        let half_width = self.half_width_circ * (en * eye[1]).hypot(eb * eye[0]) / g;
        CoreView { u, half_width, eye, psi_tex, affine }
    }

    /// A texel read at strip coordinate `v` of `view`, placed on the real ply.
    pub fn surface(&self, view: &CoreView, v: f64, t: &CoreTexel) -> CoreSurface {
        let [en, eb] = self.ellipse;
        let g = (en * eb).sqrt();
        let a = if view.affine { [en / g, eb / g] } else { [1.0, 1.0] };
        // The texture's frame: e' at the azimuth it was read at, w' = T × e'.
        let (sp, cp) = view.psi_tex.sin_cos();
        let (e1, w1) = ([cp, sp], [-sp, cp]);
        // Real fibers are round: their normal is the radial vector from the axis, which the
        // affine map carries as a direction (`A n`, not the covector rule `A⁻ᵀ n` of a
        // stretched surface; measured: 8° against 13° mean error on cotton-2ply).
        let n2 =
            [t.normal[0] * w1[0] + t.normal[1] * e1[0], t.normal[0] * w1[1] + t.normal[1] * e1[1]];
        let normal = vec3::normalize([n2[0] * a[0], n2[1] * a[1], t.normal[2]]).unwrap_or([
            view.eye[0],
            view.eye[1],
            0.0,
        ]);
        let d2 = [
            t.direction[1] * w1[0] + t.direction[2] * e1[0],
            t.direction[1] * w1[1] + t.direction[2] * e1[1],
        ];
        let direction = vec3::normalize([d2[0] * a[0], d2[1] * a[1], t.direction[0]])
            .unwrap_or([0.0, 0.0, 1.0]);
        let h = self.half_width_circ;
        let (s, hh) = ((2.0 * v - 1.0) * h, t.height * h);
        let c = [s * w1[0] + hh * e1[0], s * w1[1] + hh * e1[1]];
        let offset = if view.affine {
            [c[0] * a[0], c[1] * a[1]]
        } else {
            // The uncorrected strip is the circular one stretched to the real half-width.
            let k = view.half_width / h.max(1e-300);
            [c[0] * k, c[1] * k]
        };
        CoreSurface { alpha: t.alpha, normal, direction, offset }
    }

    /// Texel of `(u, v)` placed on the ply for `view` (`u` from the view).
    pub fn lookup(&self, view: &CoreView, v: f64) -> CoreSurface {
        self.surface(view, v, &self.sample(view.u, v))
    }
}

/// [W19 eq. 3] literally: `frac((θ α_ply² α/(α_ply − α) + ψ_view/2)/2π)` (lengths in
/// metres; α_ply = α makes it infinite, and then the θ term is dropped).
pub fn u_paper_eq3(theta: f64, ply_pitch: f64, fiber_pitch: f64, psi_view: f64) -> f64 {
    let den = ply_pitch - fiber_pitch;
    let k = if den != 0.0 { ply_pitch * ply_pitch * fiber_pitch / den } else { 0.0 };
    ((theta * k + 0.5 * psi_view) / TAU).rem_euclid(1.0)
}

/// Refuses a texture whose data do not match its size (for the cache reader).
pub(crate) fn check_sizes(t: &CoreTexture) -> Result<()> {
    let n = 4 * t.width * t.height;
    if t.width == 0 || t.height == 0 || t.tex_a.len() != n || t.tex_b.len() != n {
        return Err(Error::Invalid(format!(
            "core texture {}×{}: wrong data size",
            t.width, t.height
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
