//! `StripBake`: the baked textures of Huang et al.'s fiber-textured yarn strips
//! [H25 §4.3, §5.1] — what a camera-facing strip of the yarn's width needs to stand in for
//! the explicit fibers: per texel the fiber coverage, the visible fiber direction, ambient
//! occlusion, the fiber-level shadowing `Ψ^Fiber_G` and the multiple-scattering correction
//! `ξ`, the last two factorised into a longitudinal × azimuthal product ([H25 eq. 10–11]).
//!
//! **The bake (DESIGN §3.4).** One straight yarn of the given parameters, with explicit
//! fibers (`yarn::fiber`, loop flyaways in, hair flyaways out) in `yarn-ref`'s BVH, long
//! enough that a shadow ray at the steepest baked light direction stays inside it. The
//! yarn runs along `T` with curve frame `(N, B)`; the eye is at azimuth 0, along `+N`, so
//! the strip's across axis is `w = T × N = B`. Texel `(i, j)` covers length coordinate
//! `z = z_c + u·α_ply`, `u ∈ [(i)/W, (i+1)/W)` (one ply pitch, `z_c` a whole number of ply
//! turns, so ply 0 sits at azimuth 0 at `u = 0`), and across offset `v·H`,
//! `v ∈ [−1 + 2j/Hn, −1 + 2(j+1)/Hn)`, `H` the largest distance of a regular fiber from the
//! axis plus the fiber radius. `spp` stratified orthographic rays per texel along `−N`;
//! at each first fiber hit:
//! - coverage, and the fiber tangent (oriented along `+T`) in the strip frame `(T, w, e)`;
//! - AO: the fraction of `ao_rays` uniform directions that leave the yarn unoccluded;
//! - for each light direction `ω(θ, φ) = cos θ cos φ N + cos θ sin φ B + sin θ T` of a
//!   `D × D` grid (bin centres, θ ∈ (−π/2, π/2) from the normal plane, φ ∈ (−π, π] from
//!   the eye towards `w`): `L₀` = single scattering without shadows (`f·cos`, tinted),
//!   `L₁` = the same with a shadow ray through the fibers, `L_ref` = the path tracer's
//!   radiance (8 bounces, NEE + MIS, `yarn_ref::integrator`) under a directional light
//!   of unit perpendicular irradiance from ω — all means over the texel's hits.
//!
//! **Factorisation.** With `L_m(ω) = f(ω, e; t̄)·cos θ_i·tint` the model's unshadowed
//! radiance at the texel's mean tangent `t̄` (what the strip shader evaluates):
//! - `Ψ(ω) = L₁/L₀` (luminance), fitted by a rank-1 product `Ψ_M(θ)·Ψ_N(φ)` by weighted
//!   alternating least squares with weights `L₀²` — the error in radiance, not in ratio;
//! - `ξ(ω) = L_ref/(L_m·Ψ̂)` per channel, clamped to `[0.1, 10]` (DESIGN §3.4), fitted the
//!   same way with weights `(L_m Ψ̂)²`. ξ absorbs what the strip cannot have: multiple
//!   scattering (the dual-scattering `(1 + Ψ_L)` of [H25 eq. 8, 11] is folded into it —
//!   DESIGN §3.3 item 10), the spread of fiber directions inside a texel, and the shadows
//!   the rank-1 Ψ misses.
//! - The residual per texel is the relative RMS (luminance, over the bake directions) of
//!   the baked model `L_m·Ψ̂·ξ̂` against `L_ref`; [`StripBake::residual`].
//!
//! **Choices where [H25] is silent or garbled** (DESIGN §3.3 items 10–11):
//! - M is indexed by the light's longitudinal angle θ_i (its path through the yarn grows as
//!   `1/cos θ_i`), N by the signed azimuth of the light about the yarn from the view's
//!   projection — the eye is at φ = 0 in the bake, so the signed angle keeps the chirality
//!   of the ply twist, which an unsigned φ would fold.
//! - The bake looks at the yarn perpendicularly (θ_o = 0); oblique views use the same
//!   texture (the fiber BCSDF, evaluated with the actual ω_o, carries the view dependence).
//! - Texture coordinate (ours, [H25] maps by arc length only): the ply arrangement is
//!   screw-symmetric, so a view from eye azimuth ψ at length z shows what the baked view
//!   shows at `u = frac(z/α_ply − ψ/2π)`; the strip shader reads that u (exact for the
//!   plies, approximate for fibers that migrate inside them).
//!
//! **Cache.** `<name>-strip-<hash>.ysb` in a cache directory, with the header, checksum and
//! rebuild-on-mismatch rules of [`crate::cache`].

use crate::cache::{Reader, Writer, key_hash};
use crate::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use yarn::bcsdf::{AmbientTable, FiberBcsdf};
use yarn::fiber::{EffectiveTwist, YarnPoint};
use yarn::vec3::{self, V3};
use yarn::{CurveFrames, GenOptions, YarnCurve, YarnParams, YarnSet, generate_fibers};
use yarn_ref::geometry::HitKind;
use yarn_ref::integrator::{PathSettings, trace_path};
use yarn_ref::material::Vertex;
use yarn_ref::rng::Rng;
use yarn_ref::{FiberScene, Light, SceneOptions, Shading};

const MAGIC: &[u8; 8] = b"YSTRIPB\0";
/// Version of the strip bake and its file (part of the cache key).
pub const STRIP_FORMAT_VERSION: u32 = 1;
/// Entries of the ambient table `∫ f cos dω_i` over θ_o.
pub const AMBIENT_ENTRIES: usize = 64;

/// Sizes and sample counts of a strip bake.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StripBakeSettings {
    /// Texels along the yarn over one ply pitch (u).
    pub width: usize,
    /// Texels across the strip (v).
    pub height: usize,
    /// Light directions per angle: `D × D` in all ([H25 §5.1]: 8).
    pub directions: usize,
    /// Camera rays per texel (stratified on the nearest square grid).
    pub spp: u32,
    /// AO rays per hit.
    pub ao_rays: u32,
    /// Lit vertices per reference path.
    pub bounces: u32,
    /// Fiber tangents per texel the model averages `f` over: 1 is [H25]'s tangent
    /// texture (the texel's mean tangent); more keep the spread of fiber directions inside
    /// a texel (module docs).
    pub tangents: usize,
    /// Seed of every random draw (fibers and paths).
    pub seed: u64,
}

impl Default for StripBakeSettings {
    /// The benchmark bake: 64 × 32 texels, 8 × 8 directions ([H25 §5.1]), 16 spp.
    fn default() -> Self {
        StripBakeSettings {
            width: 64,
            height: 32,
            directions: 8,
            spp: 16,
            ao_rays: 16,
            bounces: 8,
            tangents: 4,
            seed: 1,
        }
    }
}

impl StripBakeSettings {
    /// The test bake: 16 × 8 texels, 4 × 4 directions, 4 spp (DESIGN §3.4: CI sizes).
    pub fn small() -> Self {
        StripBakeSettings {
            width: 16,
            height: 8,
            directions: 4,
            spp: 4,
            ao_rays: 4,
            ..Self::default()
        }
    }

    /// Refuses sizes out of range, naming the field.
    pub fn validate(&self) -> Result<()> {
        let bad =
            |f: &str, v: u64, r: &str| Err(Error::Invalid(format!("strip bake {f} = {v} ({r})")));
        if !(1..=1024).contains(&self.width) {
            return bad("width", self.width as u64, "1..=1024");
        }
        if !(1..=512).contains(&self.height) {
            return bad("height", self.height as u64, "1..=512");
        }
        if !(2..=32).contains(&self.directions) {
            return bad("directions", self.directions as u64, "2..=32");
        }
        if !(1..=4096).contains(&self.spp) {
            return bad("spp", self.spp as u64, "1..=4096");
        }
        if self.ao_rays > 4096 {
            return bad("ao_rays", self.ao_rays as u64, "0..=4096");
        }
        if !(1..=8).contains(&self.tangents) {
            return bad("tangents", self.tangents as u64, "1..=8");
        }
        if !(1..=64).contains(&self.bounces) {
            return bad("bounces", self.bounces as u64, "1..=64");
        }
        let cells = (self.width * self.height) as u64 * (self.directions * self.directions) as u64;
        if cells > 1 << 24 {
            return Err(Error::Limit(format!(
                "strip bake of {}×{} texels × {}² directions = {cells} cells (limit 2^24)",
                self.width, self.height, self.directions
            )));
        }
        Ok(())
    }

    /// The light direction grid `(θ, φ)` of bin `(a, b)` (bin centres).
    pub fn direction(&self, a: usize, b: usize) -> (f64, f64) {
        let d = self.directions as f64;
        (-FRAC_PI_2 + (a as f64 + 0.5) * PI / d, -PI + (b as f64 + 0.5) * TAU / d)
    }

    /// Every bake direction, θ-major.
    pub fn directions_grid(&self) -> Vec<(f64, f64)> {
        let d = self.directions;
        (0..d * d).map(|k| self.direction(k / d, k % d)).collect()
    }
}

/// Per-texel means of one [`measure`] run.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// Texels along u and v.
    pub width: usize,
    /// Texels along v.
    pub height: usize,
    /// Light directions `(θ, φ)` measured.
    pub dirs: Vec<(f64, f64)>,
    /// Coverage per texel.
    pub alpha: Vec<f32>,
    /// Fiber tangents `(T, w, e)` per texel × [`StripBakeSettings::tangents`] (unit; the
    /// mean tangent when one; `(1, 0, 0)` where nothing was hit).
    pub tangent: Vec<[f32; 3]>,
    /// AO per texel.
    pub ao: Vec<f32>,
    /// Per texel × direction: mean over the hits of `L₀` (unshadowed single scattering).
    pub l_unshadowed: Vec<[f32; 3]>,
    /// … of `L₁` (single scattering with fiber shadows).
    pub l_single: Vec<[f32; 3]>,
    /// … of `L_ref` (path traced).
    pub l_ref: Vec<[f32; 3]>,
    /// Strip half-width `H` (metres).
    pub half_width: f64,
    /// Signed ply pitch α_ply (metres per turn).
    pub ply_pitch: f64,
}

/// The straight yarn of a bake and its frame.
struct Setup {
    scene: FiberScene,
    shading: Shading,
    t: V3,
    n: V3,
    b: V3,
    /// World point of length coordinate 0 on the axis.
    base: V3,
    z_c: f64,
    ply_pitch: f64,
    half_width: f64,
}

fn setup(
    params: &YarnParams,
    bcsdf: &FiberBcsdf,
    color: [f32; 3],
    s: &StripBakeSettings,
) -> Result<Setup> {
    params.validate()?;
    let r = params.yarn_radius();
    let pitch = EffectiveTwist::nominal(params).ply_pitch;
    if !(pitch.is_finite() && pitch.abs() > 0.0) {
        return Err(Error::Invalid(format!("yarn '{}': ply pitch {pitch}", params.name)));
    }
    let theta_max = FRAC_PI_2 - 0.5 * PI / s.directions as f64;
    let margin = 2.0 * r * theta_max.tan() + 6.0 * r;
    let turns = (margin / pitch.abs()).ceil() + 1.0;
    let z_c = turns * pitch.abs();
    let length = z_c + pitch.abs() + margin;
    let n_cp = ((length / (2.0 * r)).ceil() as usize).clamp(8, 4096);
    let pts: Vec<V3> = (0..=n_cp).map(|i| [0.0, 0.0, length * i as f64 / n_cp as f64]).collect();
    let curve =
        YarnCurve::open(pts)?.with_normals(vec![[1.0, 0.0, 0.0]; n_cp + 1])?.with_color(color);
    let frames = CurveFrames::new(&curve, 16);
    let yp = YarnPoint::at(&curve, &frames, 0.5 * n_cp as f64);
    // The length coordinate runs along +z from the first point (collinear, equally spaced
    // control points): check instead of assuming.
    let base = vec3::add_scaled(yp.position, yp.frame.t, -yp.z);
    if (base[2]).abs() > 1e-9 * length || (yp.frame.t[2] - 1.0).abs() > 1e-9 {
        return Err(Error::Invalid(format!(
            "strip bake: the straight yarn's length coordinate is not its z (base {base:?}, T {:?})",
            yp.frame.t
        )));
    }
    let set = YarnSet::new(vec![curve], None)?;
    let opts =
        GenOptions { seed: s.seed, hairs: false, samples_per_turn: 24, ..GenOptions::default() };
    let fibers = generate_fibers(&set, std::slice::from_ref(params), &opts)?;
    let mut half_width: f64 = 0.0;
    for k in 0..fibers.fiber_count() {
        for p in fibers.fiber_points(k) {
            let d = (p[0] as f64).hypot(p[1] as f64);
            half_width = half_width.max(d);
        }
    }
    half_width += params.fiber_radius;
    let scene = FiberScene::new(&fibers, &SceneOptions::default())?;
    let shading = Shading::Fiber { bcsdf: Arc::new(bcsdf.clone()), tint: true };
    Ok(Setup {
        scene,
        shading,
        t: yp.frame.t,
        n: yp.frame.n,
        b: yp.frame.b,
        base,
        z_c,
        ply_pitch: pitch,
        half_width,
    })
}

/// The light direction `(θ, φ)` in the bake frame.
fn light_dir(st: &Setup, (theta, phi): (f64, f64)) -> V3 {
    let (st_, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    vec3::add_scaled(vec3::add_scaled(vec3::scale(st.n, ct * cp), st.b, ct * sp), st.t, st_)
}

fn lum(c: [f64; 3]) -> f64 {
    yarn_ref::light::luminance(c)
}

/// Measures the per-texel radiances of the bake (module docs) for the light directions
/// `dirs`; `progress` is called with the texels done so far.
pub fn measure(
    params: &YarnParams,
    bcsdf: &FiberBcsdf,
    color: [f32; 3],
    s: &StripBakeSettings,
    dirs: &[(f64, f64)],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Measured> {
    s.validate()?;
    let st = setup(params, bcsdf, color, s)?;
    measure_in(&st, params, s, dirs, progress)
}

/// [`measure`] on a yarn already set up (fibers generated, BVH built).
fn measure_in(
    st: &Setup,
    params: &YarnParams,
    s: &StripBakeSettings,
    dirs: &[(f64, f64)],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Measured> {
    if dirs.is_empty() || dirs.iter().any(|d| !(d.0.abs() < FRAC_PI_2 && d.1.is_finite())) {
        return Err(Error::Invalid(format!("strip bake: light directions {dirs:?}")));
    }
    let lights: Vec<[Light; 1]> =
        dirs.iter().map(|&d| [Light::directional(light_dir(st, d), [1.0; 3])]).collect();
    let wdirs: Vec<V3> = dirs.iter().map(|&d| light_dir(st, d)).collect();
    let path = PathSettings { max_bounces: s.bounces, ..PathSettings::default() };
    let (w, h, nd) = (s.width, s.height, dirs.len());
    let nx = (s.spp as f64).sqrt().ceil() as u32;
    let ny = s.spp.div_ceil(nx);
    let done = AtomicU64::new(0);
    let wo = st.n;
    let r = params.yarn_radius();
    struct Texel {
        alpha: f32,
        tangent: Vec<[f32; 3]>,
        ao: f32,
        l0: Vec<[f32; 3]>,
        l1: Vec<[f32; 3]>,
        lr: Vec<[f32; 3]>,
    }
    let texels: Vec<Texel> = (0..w * h)
        .into_par_iter()
        .map(|texel| {
            let (i, j) = (texel % w, texel / w);
            let mut hits = 0u32;
            let mut tsum = [0.0f64; 3];
            let mut hit_tangents: Vec<[f64; 3]> = Vec::new();
            let mut ao = 0.0f64;
            let mut l0 = vec![[0.0f64; 3]; nd];
            let mut l1 = vec![[0.0f64; 3]; nd];
            let mut lr = vec![[0.0f64; 3]; nd];
            for k in 0..nx * ny {
                let mut rng = Rng::new(&[s.seed, 0x5752_4950, texel as u64, k as u64]);
                let (sx, sy) = (k % nx, k / nx);
                let u = (i as f64 + (sx as f64 + rng.uniform()) / nx as f64) / w as f64;
                let v =
                    -1.0 + 2.0 * (j as f64 + (sy as f64 + rng.uniform()) / ny as f64) / h as f64;
                let z = st.z_c + u * st.ply_pitch;
                let p =
                    vec3::add_scaled(vec3::add_scaled(st.base, st.t, z), st.b, v * st.half_width);
                let o = vec3::add_scaled(p, st.n, 3.0 * r + st.half_width);
                let d = vec3::scale(st.n, -1.0);
                let Some(hit) = st.scene.intersect(o, d, f64::INFINITY, None) else { continue };
                let HitKind::Fiber { segment, v: sv } = hit.kind else { continue };
                let sp = st.scene.surface(segment, sv, hit.position);
                hits += 1;
                let mut t = sp.tangent;
                if vec3::dot(t, st.t) < 0.0 {
                    t = vec3::scale(t, -1.0);
                }
                let tl = [vec3::dot(t, st.t), vec3::dot(t, st.b), vec3::dot(t, st.n)];
                (0..3).for_each(|c| tsum[c] += tl[c]);
                hit_tangents.push(tl);
                if s.ao_rays > 0 {
                    let mut free = 0;
                    for _ in 0..s.ao_rays {
                        let zz = 2.0 * rng.uniform() - 1.0;
                        let a = TAU * rng.uniform();
                        let rr = (1.0 - zz * zz).max(0.0).sqrt();
                        let dir = [rr * a.cos(), rr * a.sin(), zz];
                        if !st.scene.occluded(sp.axis_point, dir, f64::INFINITY, Some(sp.skip)) {
                            free += 1;
                        }
                    }
                    ao += free as f64 / s.ao_rays as f64;
                }
                let vx = Vertex::new(&st.shading, &sp, hit.position);
                for (q, wi) in wdirs.iter().enumerate() {
                    let (fc, _) = vx.eval(*wi, wo);
                    if fc.iter().any(|&x| x > 0.0) {
                        (0..3).for_each(|c| l0[q][c] += fc[c]);
                        if !st.scene.occluded(vx.origin, *wi, f64::INFINITY, vx.skip) {
                            (0..3).for_each(|c| l1[q][c] += fc[c]);
                        }
                    }
                    let scene = yarn_ref::Scene {
                        fibers: &st.scene,
                        lights: &lights[q],
                        shading: &st.shading,
                    };
                    let res = trace_path(&scene, o, d, &mut rng, &path);
                    (0..3).for_each(|c| lr[q][c] += res.radiance[c]);
                }
            }
            let n = (nx * ny) as f64;
            let m = hits.max(1) as f64;
            let tl = (tsum.iter().map(|x| x * x).sum::<f64>()).sqrt();
            let mean_t = if tl > 1e-12 { tsum.map(|x| (x / tl) as f32) } else { [1.0, 0.0, 0.0] };
            let tangent: Vec<[f32; 3]> = if s.tangents == 1 || hit_tangents.is_empty() {
                vec![mean_t; s.tangents]
            } else {
                // Evenly among the hits, which the stratified rays spread over the texel.
                let n = hit_tangents.len();
                (0..s.tangents)
                    .map(|k| hit_tangents[k * n / s.tangents].map(|x| x as f32))
                    .collect()
            };
            let mean =
                |v: Vec<[f64; 3]>| v.into_iter().map(|c| c.map(|x| (x / m) as f32)).collect();
            let out = Texel {
                alpha: (hits as f64 / n) as f32,
                tangent,
                ao: if hits > 0 { (ao / m) as f32 } else { 1.0 },
                l0: mean(l0),
                l1: mean(l1),
                lr: mean(lr),
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            out
        })
        .collect();
    let mut m = Measured {
        width: w,
        height: h,
        dirs: dirs.to_vec(),
        alpha: Vec::with_capacity(w * h),
        tangent: Vec::with_capacity(w * h),
        ao: Vec::with_capacity(w * h),
        l_unshadowed: Vec::with_capacity(w * h * nd),
        l_single: Vec::with_capacity(w * h * nd),
        l_ref: Vec::with_capacity(w * h * nd),
        half_width: st.half_width,
        ply_pitch: st.ply_pitch,
    };
    for t in texels {
        m.alpha.push(t.alpha);
        m.tangent.extend(t.tangent);
        m.ao.push(t.ao);
        m.l_unshadowed.extend(t.l0);
        m.l_single.extend(t.l1);
        m.l_ref.extend(t.lr);
    }
    Ok(m)
}

/// Weighted rank-1 fit `x[a·d + b] ≈ p[a]·q[b]` of a `d × d` matrix (alternating least
/// squares, weights `w ≥ 0`); returns `(p, q)` with `max q = 1` (rows or columns without
/// weight get 1) and the relative weighted residual `√(Σw(x − pq)²/Σw x²)` (0 without
/// weight).
pub fn rank1(x: &[f64], w: &[f64], d: usize) -> (Vec<f64>, Vec<f64>, f64) {
    let mut p = vec![1.0; d];
    let mut q = vec![1.0; d];
    for _ in 0..60 {
        for a in 0..d {
            let (mut num, mut den) = (0.0, 0.0);
            for b in 0..d {
                num += w[a * d + b] * x[a * d + b] * q[b];
                den += w[a * d + b] * q[b] * q[b];
            }
            p[a] = if den > 0.0 { num / den } else { f64::NAN };
        }
        for b in 0..d {
            let (mut num, mut den) = (0.0, 0.0);
            for a in 0..d {
                if p[a].is_finite() {
                    num += w[a * d + b] * x[a * d + b] * p[a];
                    den += w[a * d + b] * p[a] * p[a];
                }
            }
            q[b] = if den > 0.0 { num / den } else { f64::NAN };
        }
    }
    let qmax = q.iter().copied().filter(|v| v.is_finite()).fold(0.0f64, |a, v| a.max(v.abs()));
    if qmax > 0.0 {
        q.iter_mut().for_each(|v| *v /= qmax);
        p.iter_mut().for_each(|v| *v *= qmax);
    }
    // Weightless rows/columns: the weighted mean of the others, so interpolation into them
    // stays in scale.
    let fill = |v: &mut Vec<f64>| {
        let ok: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let mean = if ok.is_empty() { 1.0 } else { ok.iter().sum::<f64>() / ok.len() as f64 };
        v.iter_mut().filter(|x| !x.is_finite()).for_each(|x| *x = mean);
    };
    fill(&mut p);
    fill(&mut q);
    let (mut num, mut den) = (0.0, 0.0);
    for a in 0..d {
        for b in 0..d {
            let k = a * d + b;
            num += w[k] * (x[k] - p[a] * q[b]).powi(2);
            den += w[k] * x[k] * x[k];
        }
    }
    (p, q, if den > 0.0 { (num / den).sqrt() } else { 0.0 })
}

/// The baked strip textures of one yarn type (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct StripBake {
    /// The settings baked with.
    pub settings: StripBakeSettings,
    /// Strip half-width `H` (metres).
    pub half_width: f64,
    /// Signed ply pitch α_ply (metres per turn).
    pub ply_pitch: f64,
    /// The tint the bake's fibers had (linear RGB).
    pub color: [f32; 3],
    /// Coverage per texel, row-major `[v][u]`.
    pub alpha: Vec<f32>,
    /// Fiber tangents `(T, w, e)` per texel × [`StripBakeSettings::tangents`].
    pub tangent: Vec<[f32; 3]>,
    /// AO per texel.
    pub ao: Vec<f32>,
    /// `Ψ_M(θ)` per texel × θ bin.
    pub psi_m: Vec<f32>,
    /// `Ψ_N(φ)` per texel × φ bin.
    pub psi_n: Vec<f32>,
    /// `ξ_M(θ)` per texel × θ bin (RGB).
    pub xi_m: Vec<[f32; 3]>,
    /// `ξ_N(φ)` per texel × φ bin (RGB).
    pub xi_n: Vec<[f32; 3]>,
    /// Relative RMS of the baked model against `L_ref` per texel (luminance, bake
    /// directions).
    pub residual: Vec<f32>,
    /// Relative weighted residual of the rank-1 Ψ per texel.
    pub residual_psi: Vec<f32>,
    /// The measurement the factors were fitted to (texel × direction, θ-major).
    pub l_ref: Vec<[f32; 3]>,
    /// `∫ f cos θ_i dω_i` at [`AMBIENT_ENTRIES`] θ_o from −π/2 to π/2 (the ambient term).
    pub ambient: Vec<[f32; 3]>,
    /// Seconds the bake took (0 when loaded).
    pub seconds: f64,
    /// Loaded from a valid cache file.
    pub from_cache: bool,
}

impl StripBake {
    /// Bakes the strip textures of `params` shaded by `bcsdf` with fibers of colour `color`.
    pub fn bake(
        params: &YarnParams,
        bcsdf: &FiberBcsdf,
        color: [f32; 3],
        s: &StripBakeSettings,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self> {
        let t0 = Instant::now();
        s.validate()?;
        let dirs = s.directions_grid();
        // One yarn (fibers and BVH) for the measurement and the model fit.
        let st = setup(params, bcsdf, color, s)?;
        let m = measure_in(&st, params, s, &dirs, progress)?;
        let d = s.directions;
        let nd = d * d;
        let texels = s.width * s.height;
        let wdirs: Vec<V3> = dirs.iter().map(|&x| light_dir(&st, x)).collect();
        let mut out = StripBake {
            settings: *s,
            half_width: m.half_width,
            ply_pitch: m.ply_pitch,
            color,
            alpha: m.alpha.clone(),
            tangent: m.tangent.clone(),
            ao: m.ao.clone(),
            psi_m: vec![1.0; texels * d],
            psi_n: vec![1.0; texels * d],
            xi_m: vec![[1.0; 3]; texels * d],
            xi_n: vec![[1.0; 3]; texels * d],
            residual: vec![0.0; texels],
            residual_psi: vec![0.0; texels],
            l_ref: m.l_ref.clone(),
            ambient: ambient_table(bcsdf),
            seconds: 0.0,
            from_cache: false,
        };
        let fitted: Vec<_> = (0..texels)
            .into_par_iter()
            .map(|tx| {
                if m.alpha[tx] <= 0.0 {
                    return None;
                }
                let k = s.tangents;
                let lm = model_unshadowed(&st, &m.tangent[tx * k..(tx + 1) * k], color, &wdirs);
                Some(fit_texel(&m, tx, nd, d, &lm))
            })
            .collect();
        for (tx, f) in fitted.into_iter().enumerate() {
            let Some(f) = f else { continue };
            out.psi_m[tx * d..(tx + 1) * d].copy_from_slice(&f.psi_m);
            out.psi_n[tx * d..(tx + 1) * d].copy_from_slice(&f.psi_n);
            out.xi_m[tx * d..(tx + 1) * d].copy_from_slice(&f.xi_m);
            out.xi_n[tx * d..(tx + 1) * d].copy_from_slice(&f.xi_n);
            out.residual[tx] = f.residual;
            out.residual_psi[tx] = f.residual_psi;
        }
        out.seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// The cache key of a bake (format version, parameters, BCSDF, colour, settings).
    pub fn cache_key(
        params: &YarnParams,
        bcsdf: &FiberBcsdf,
        color: [f32; 3],
        s: &StripBakeSettings,
    ) -> Result<String> {
        Ok(format!(
            "strip v{STRIP_FORMAT_VERSION}\n{}\n{bcsdf:?}\n{color:?}\n{s:?}",
            params.to_toml()?
        ))
    }

    /// The bake read from `cache_dir` when a valid file for exactly these inputs is there,
    /// otherwise baked (and written there, atomically).
    pub fn for_params(
        params: &YarnParams,
        bcsdf: &FiberBcsdf,
        color: [f32; 3],
        s: &StripBakeSettings,
        cache_dir: Option<&Path>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self> {
        s.validate()?;
        let Some(dir) = cache_dir else {
            return Self::bake(params, bcsdf, color, s, progress);
        };
        let key = Self::cache_key(params, bcsdf, color, s)?;
        let path = Self::cache_path(dir, params, &key);
        if let Ok(bytes) = std::fs::read(&path)
            && let Some(mut b) = decode(&bytes, &key, s)
        {
            b.from_cache = true;
            return Ok(b);
        }
        let b = Self::bake(params, bcsdf, color, s, progress)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        btf_core::fs::write_atomic(&path, &encode(&b, &key))?;
        Ok(b)
    }

    fn cache_path(dir: &Path, params: &YarnParams, key: &str) -> PathBuf {
        let name: String = params
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' })
            .take(48)
            .collect();
        dir.join(format!("{name}-strip-{:016x}.ysb", key_hash(key.as_bytes())))
    }

    /// Floats per texel in [`StripBake::gpu_texels`]: coverage, AO, tangents (3K), Ψ_M,
    /// Ψ_N (D each), ξ_M, ξ_N (3D each).
    pub fn texel_stride(&self) -> usize {
        2 + 3 * self.settings.tangents + 8 * self.settings.directions
    }

    /// The texels as the strip shader reads them: per texel `[α, AO, (t_T, t_w, t_e)[K],
    /// Ψ_M[D], Ψ_N[D], ξ_M[D][3], ξ_N[D][3]]`, then the ambient table (`AMBIENT_ENTRIES`
    /// × RGB).
    pub fn gpu_texels(&self) -> Vec<f32> {
        let d = self.settings.directions;
        let n = self.settings.width * self.settings.height;
        let mut v = Vec::with_capacity(n * self.texel_stride() + 3 * AMBIENT_ENTRIES);
        for t in 0..n {
            let k = self.settings.tangents;
            v.push(self.alpha[t]);
            v.push(self.ao[t]);
            self.tangent[t * k..(t + 1) * k].iter().for_each(|c| v.extend(c));
            v.extend(&self.psi_m[t * d..(t + 1) * d]);
            v.extend(&self.psi_n[t * d..(t + 1) * d]);
            self.xi_m[t * d..(t + 1) * d].iter().for_each(|c| v.extend(c));
            self.xi_n[t * d..(t + 1) * d].iter().for_each(|c| v.extend(c));
        }
        self.ambient.iter().for_each(|c| v.extend(c));
        v
    }

    /// The texel at `(u, v)` as the strip shader reads it: nearest, u repeats, v ∈ [−1, 1]
    /// clamps (nearest because the texels are box-filtered means and the shading is
    /// non-linear in them; `yarn_render::strips`).
    pub fn texel_at(&self, u: f64, v: f64) -> usize {
        let (w, h) = (self.settings.width, self.settings.height);
        let i = (((u - u.floor()) * w as f64).floor() as usize).min(w - 1);
        let j = ((v + 1.0) * 0.5 * h as f64).floor().clamp(0.0, (h - 1) as f64) as usize;
        j * w + i
    }

    /// Linear bin weights of light angle θ (clamped) or φ (wrapping): `[(bin, w); 2]`.
    pub fn bin_weights(&self, angle: f64, azimuthal: bool) -> [(usize, f64); 2] {
        let d = self.settings.directions;
        if azimuthal {
            let x = (angle + PI) / (TAU / d as f64) - 0.5;
            let x0 = x.floor();
            let f = x - x0;
            let b0 = (x0 as i64).rem_euclid(d as i64) as usize;
            [(b0, 1.0 - f), ((b0 + 1) % d, f)]
        } else {
            let x = ((angle + FRAC_PI_2) / (PI / d as f64) - 0.5).clamp(0.0, (d - 1) as f64);
            let b0 = (x.floor() as usize).min(d - 2);
            let f = x - b0 as f64;
            [(b0, 1.0 - f), (b0 + 1, f)]
        }
    }

    /// `(Ψ̂, ξ̂)` of one texel at light angles `(θ, φ)` (interpolated factors, as the shader).
    pub fn factors_at(&self, texel: usize, theta: f64, phi: f64) -> (f64, [f64; 3]) {
        let d = self.settings.directions;
        let bm = self.bin_weights(theta, false);
        let bn = self.bin_weights(phi, true);
        let lerp1 = |v: &[f32], b: [(usize, f64); 2]| {
            b.iter().map(|&(k, w)| w * v[texel * d + k] as f64).sum::<f64>()
        };
        let lerp3 = |v: &[[f32; 3]], b: [(usize, f64); 2]| {
            let mut o = [0.0; 3];
            for &(k, w) in &b {
                (0..3).for_each(|c| o[c] += w * v[texel * d + k][c] as f64);
            }
            o
        };
        let psi = lerp1(&self.psi_m, bm) * lerp1(&self.psi_n, bn);
        let (a, b) = (lerp3(&self.xi_m, bm), lerp3(&self.xi_n, bn));
        (psi, [a[0] * b[0], a[1] * b[1], a[2] * b[2]])
    }

    /// The baked model's radiance `(1/K) Σ_k f(ω, e; t_k) cos θ_i · tint · Ψ̂ · ξ̂` of one
    /// texel under a unit directional light from `(θ, φ)` (the bake's angles; the eye at
    /// azimuth 0, perpendicular): what the strip shader computes there.
    pub fn model_at(&self, bcsdf: &FiberBcsdf, texel: usize, theta: f64, phi: f64) -> [f64; 3] {
        let k = self.settings.tangents;
        let shading = Shading::Fiber { bcsdf: Arc::new(bcsdf.clone()), tint: true };
        // The canonical bake frame (N, B, T) = (x, y, z); a tangent (T, w, e) is (e, w, T).
        let (n, t) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let wi = [theta.cos() * phi.cos(), theta.cos() * phi.sin(), theta.sin()];
        let mut f = [0.0; 3];
        for tk in &self.tangent[texel * k..(texel + 1) * k] {
            let tt = tk.map(f64::from);
            let tw = vec3::normalize([tt[2], tt[1], tt[0]]).unwrap_or(t);
            let v = model_radiance(&shading, tw, self.color, n, &[wi])[0];
            (0..3).for_each(|c| f[c] += v[c] / k as f64);
        }
        let (psi, xi) = self.factors_at(texel, theta, phi);
        std::array::from_fn(|c| f[c] * psi * xi[c])
    }

    /// Coverage-weighted mean of [`StripBake::residual`] over the texels.
    pub fn mean_residual(&self) -> f64 {
        let a: f64 = self.alpha.iter().map(|&x| x as f64).sum();
        let r: f64 =
            self.alpha.iter().zip(&self.residual).map(|(&a, &r)| a as f64 * r as f64).sum();
        if a > 0.0 { r / a } else { 0.0 }
    }

    /// Bytes of the texels on the GPU.
    pub fn gpu_bytes(&self) -> usize {
        4 * (self.settings.width * self.settings.height * self.texel_stride() + 3 * AMBIENT_ENTRIES)
    }
}

/// The tinted unshadowed model radiance `f(ω, e; t̄)·cos·tint` of a texel's mean tangent for
/// each light direction (what the shader evaluates before Ψ and ξ).
fn model_unshadowed(
    st: &Setup,
    tangents: &[[f32; 3]],
    color: [f32; 3],
    wdirs: &[V3],
) -> Vec<[f64; 3]> {
    let mut sum = vec![[0.0; 3]; wdirs.len()];
    for tangent in tangents {
        let tt = tangent.map(f64::from);
        let t = vec3::normalize(vec3::add_scaled(
            vec3::add_scaled(vec3::scale(st.t, tt[0]), st.b, tt[1]),
            st.n,
            tt[2],
        ))
        .unwrap_or(st.t);
        for (acc, f) in sum.iter_mut().zip(model_radiance(&st.shading, t, color, st.n, wdirs)) {
            (0..3).for_each(|c| acc[c] += f[c] / tangents.len() as f64);
        }
    }
    sum
}

/// `f(ω_i, ω_o; t)·cos θ_i·tint` for each `ω_i` (the fiber BCSDF of `yarn-ref`'s vertex).
pub fn model_radiance(
    shading: &Shading,
    t: V3,
    color: [f32; 3],
    wo: V3,
    wis: &[V3],
) -> Vec<[f64; 3]> {
    let sp = yarn_ref::geometry::SurfacePoint {
        axis_point: [0.0; 3],
        normal: wo,
        tangent: t,
        fiber: 0,
        color,
        radius: 0.0,
        skip: yarn_ref::geometry::Skip { fiber: u32::MAX, point: u32::MAX },
    };
    let vx = Vertex::new(shading, &sp, [0.0; 3]);
    wis.iter().map(|&wi| vx.eval(wi, wo).0).collect()
}

struct TexelFit {
    psi_m: Vec<f32>,
    psi_n: Vec<f32>,
    xi_m: Vec<[f32; 3]>,
    xi_n: Vec<[f32; 3]>,
    residual: f32,
    residual_psi: f32,
}

fn fit_texel(m: &Measured, tx: usize, nd: usize, d: usize, lm: &[[f64; 3]]) -> TexelFit {
    let at = |v: &[[f32; 3]], k: usize| v[tx * nd + k].map(f64::from);
    let l0: Vec<f64> = (0..nd).map(|k| lum(at(&m.l_unshadowed, k))).collect();
    let l1: Vec<f64> = (0..nd).map(|k| lum(at(&m.l_single, k))).collect();
    let psi: Vec<f64> =
        (0..nd).map(|k| if l0[k] > 0.0 { (l1[k] / l0[k]).clamp(0.0, 1.0) } else { 1.0 }).collect();
    let wpsi: Vec<f64> = l0.iter().map(|x| x * x).collect();
    let (pm, pn, res_psi) = rank1(&psi, &wpsi, d);
    let psi_hat: Vec<f64> = (0..nd).map(|k| pm[k / d] * pn[k % d]).collect();
    let mut xm = vec![[1.0f32; 3]; d];
    let mut xn = vec![[1.0f32; 3]; d];
    for c in 0..3 {
        let den: Vec<f64> = (0..nd).map(|k| lm[k][c] * psi_hat[k]).collect();
        let xi: Vec<f64> = (0..nd)
            .map(
                |k| if den[k] > 0.0 { (at(&m.l_ref, k)[c] / den[k]).clamp(0.1, 10.0) } else { 1.0 },
            )
            .collect();
        let wxi: Vec<f64> = den.iter().map(|x| x * x).collect();
        let (a, b, _) = rank1(&xi, &wxi, d);
        (0..d).for_each(|k| {
            xm[k][c] = a[k] as f32;
            xn[k][c] = b[k] as f32;
        });
    }
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..nd {
        let model: [f64; 3] = std::array::from_fn(|c| {
            lm[k][c] * psi_hat[k] * xm[k / d][c] as f64 * xn[k % d][c] as f64
        });
        let r = lum(at(&m.l_ref, k));
        num += (r - lum(model)).powi(2);
        den += r * r;
    }
    TexelFit {
        psi_m: pm.iter().map(|&x| x as f32).collect(),
        psi_n: pn.iter().map(|&x| x as f32).collect(),
        xi_m: xm,
        xi_n: xn,
        residual: if den > 0.0 { (num / den).sqrt() as f32 } else { 0.0 },
        residual_psi: res_psi as f32,
    }
}

fn ambient_table(bcsdf: &FiberBcsdf) -> Vec<[f32; 3]> {
    let t = AmbientTable::build(bcsdf, AMBIENT_ENTRIES);
    t.values.iter().map(|v| v.map(|x| x as f32)).collect()
}

fn encode(b: &StripBake, key: &str) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.f64s(&[b.half_width, b.ply_pitch, b.seconds]);
    w.f32s(&b.color);
    w.f32s(&b.alpha);
    w.f32s(&b.tangent.concat());
    w.f32s(&b.ao);
    w.f32s(&b.psi_m);
    w.f32s(&b.psi_n);
    w.f32s(&b.xi_m.concat());
    w.f32s(&b.xi_n.concat());
    w.f32s(&b.residual);
    w.f32s(&b.residual_psi);
    w.f32s(&b.l_ref.concat());
    w.f32s(&b.ambient.concat());
    crate::cache::frame(MAGIC, STRIP_FORMAT_VERSION, key, &w.0)
}

/// The bake in `bytes` if the header carries exactly `key`, the payload is intact and every
/// array has the size `s` implies.
fn decode(bytes: &[u8], key: &str, s: &StripBakeSettings) -> Option<StripBake> {
    let payload = crate::cache::unframe(bytes, MAGIC, STRIP_FORMAT_VERSION, key)?;
    let mut r = Reader(payload);
    let (half_width, ply_pitch, seconds) = (r.f64()?, r.f64()?, r.f64()?);
    let color: [f32; 3] = r.f32s()?.try_into().ok()?;
    let (n, d) = (s.width * s.height, s.directions);
    let exact = |v: Vec<f32>, len: usize| (v.len() == len).then_some(v);
    let triples = |v: Vec<f32>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>();
    let alpha = exact(r.f32s()?, n)?;
    let tangent = triples(exact(r.f32s()?, 3 * n * s.tangents)?);
    let ao = exact(r.f32s()?, n)?;
    let psi_m = exact(r.f32s()?, n * d)?;
    let psi_n = exact(r.f32s()?, n * d)?;
    let xi_m = triples(exact(r.f32s()?, 3 * n * d)?);
    let xi_n = triples(exact(r.f32s()?, 3 * n * d)?);
    let residual = exact(r.f32s()?, n)?;
    let residual_psi = exact(r.f32s()?, n)?;
    let l_ref = triples(exact(r.f32s()?, 3 * n * d * d)?);
    let ambient = triples(exact(r.f32s()?, 3 * AMBIENT_ENTRIES)?);
    r.0.is_empty().then_some(StripBake {
        settings: *s,
        half_width,
        ply_pitch,
        color,
        alpha,
        tangent,
        ao,
        psi_m,
        psi_n,
        xi_m,
        xi_n,
        residual,
        residual_psi,
        l_ref,
        ambient,
        seconds,
        from_cache: false,
    })
}

#[cfg(test)]
mod tests;
