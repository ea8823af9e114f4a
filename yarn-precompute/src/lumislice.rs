//! `Lumislice`: Chen et al.'s light-scattering cross-section of a yarn [C03 §5.1] made
//! physical, with its level-of-detail pyramid [C03 §5.2.2, eq. 11] and the yarn shadow
//! table of [C03 eq. 10] ([`YarnShadowLut`]) — the precomputation of the lumislice renderer
//! (`yarn_render::lumislice`), DESIGN §1.3 items 8–14, §1.4.
//!
//! **What a table entry is.** The slice is the `res × res` grid of
//! `yarn::density::CrossSectionDensity` in the slice frame that turns with the plies (x along
//! `N'`, y along `B'`, the yarn axis `z`); σ⊥ = 2 r_f n_A per voxel (DESIGN §1.3 item 10).
//! For each voxel `p` and each of the 32 × 21 light directions `L` (longitude
//! `θ_i = 2πi/32` about the axis from `N'`, altitude `φ_j = −π/2 + πj/20` out of the slice
//! plane, DESIGN item 9) the table holds the light the voxel scatters per unit extinction
//! and unit irradiance — the voxel reflectance function of [C03 eq. 7–8], with the
//! multiple-scattering term of [C03 eq. 4]:
//!
//! `V(p, L) = ϖ · (Ψ(L) · T(p, L) + M(p, L))`
//!
//! - `T(p, L)` — the transmittance from `p` towards the light through the *own* yarn: the
//!   straight, twisted yarn (the slice at height `z` is the slice at 0 turned by
//!   `2πz/α_ply`), marched in 3-D with steps ≤ `step` cells and bilinear σ⊥, with the
//!   anisotropic extinction `σ⊥ sin β` (β the angle between the ray and the yarn axis;
//!   [C03 eq. 5]'s isotropic `γρ` is [`Extinction::Isotropic`]). [C03 eq. 5] counts voxels
//!   along a grid line; this is the path integral it approximates.
//! - `Ψ(L) = sin∠(L, z)/π²` — Kajiya–Kay diffuse normalised over the sphere, as the
//!   volumetric reference's phase (`yarn_ref::volume`; [`Phase::Isotropic`]: `1/4π`).
//! - `M(p, L)` — orders ≥ 2 ([C03 eq. 6]'s `I_msp`, deferred there to another paper;
//!   DESIGN item 8): the expected in-scattered light of paths leaving `p` in isotropic
//!   directions, free flights through the same twisted volume, each further collision
//!   weighted by ϖ and adding `T(x_j, L)/4π` (next-event estimation through the table
//!   itself: by the screw symmetry a point at height `z` reads the slice at `z = 0` with
//!   the light's longitude turned by `−2πz/α_ply`). Russian roulette below a path weight
//!   of 0.1. This is the reference marcher's multiple-scattering estimator, term by term.
//!
//! A renderer then needs per march step only `tr · (1 − e^{−σ(ω_o) h}) · E · V` — exactly
//! the volumetric reference's single scattering for the own yarn ([C03 eq. 9] per pixel,
//! with the step's own attenuation of DESIGN item 11). Shadows of *other* yarns are the
//! eq. 10 table's job.
//!
//! **Level of detail** ([C03 §5.2.2]). Level `k` halves the resolution of level `k − 1`
//! down to `min_res` (the paper's 8 × 8 floor). Density by [`LodRule::Eq11`] — the mean of
//! the four (mean optical depth kept) — or [`LodRule::Transmittance`], DESIGN item 14:
//! `σ' = −ln(mean e^{−σ_i ℓ})/ℓ` with `ℓ` the coarse cell's depth, so the mean transmittance
//! through one coarse cell is kept and Jensen's gap `e^{−mean} ≤ mean e^{−·}` (coarse levels
//! too opaque) is closed. The table by [C03 eq. 11]'s density-weighted mean
//! `Σ V_i σ_i / Σ σ_i`. A slice of `m` pixels takes the level with `2ⁿ ≥ m > 2ⁿ⁻¹`
//! ([`Lumislice::level_for`]).
//!
//! **Deviations from [C03]**, each for a reason: a path integral instead of voxel counts
//! (item 10); anisotropic extinction by default (light along the yarn passes between the
//! fibers; the isotropic variant is kept); the table carries the yarn colour as ϖ and the
//! Kajiya–Kay phase normalised, so a furnace holds (tested); the table is cached in this
//! crate's checksummed binary format (as every other bake here), not Zarr.

use crate::cache::{Reader, Writer, key_hash};
use crate::{Error, Result};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::{Path, PathBuf};
use yarn::density::{CrossSectionDensity, DensityOptions, Extinction};
use yarn::fiber::EffectiveTwist;
use yarn::hash::KeyRng;
use yarn::params::YarnParams;

#[cfg(test)]
mod tests;

/// Light longitudes of the table ([C03 §5.1.1]: 32).
pub const LONGITUDES: usize = 32;
/// Light altitudes of the table, poles included ([C03 §5.1.1]: 21).
pub const ALTITUDES: usize = 21;
/// Light directions per voxel.
pub const DIRECTIONS: usize = LONGITUDES * ALTITUDES;

const MAGIC: &[u8; 8] = b"YLUMISL\0";
/// Version of the cache format.
pub const LUMISLICE_FORMAT_VERSION: u32 = 1;

/// Unit light direction `k = j·LONGITUDES + i` in the slice frame (x = `N'`, y = `B'`, z =
/// the yarn axis).
pub fn direction(k: usize) -> [f64; 3] {
    let (i, j) = (k % LONGITUDES, k / LONGITUDES);
    let th = TAU * i as f64 / LONGITUDES as f64;
    let ph = -FRAC_PI_2 + PI * j as f64 / (ALTITUDES - 1) as f64;
    [ph.cos() * th.cos(), ph.cos() * th.sin(), ph.sin()]
}

/// The four table directions around `l` (slice frame, unit) with bilinear weights in
/// longitude (wrapping) and altitude (clamped): what the renderer's lookup does.
pub fn direction_weights(l: [f64; 3]) -> [(usize, f64); 4] {
    let th = l[1].atan2(l[0]);
    let ph = l[2].clamp(-1.0, 1.0).asin();
    let x = th.rem_euclid(TAU) / (TAU / LONGITUDES as f64);
    let y = ((ph + FRAC_PI_2) / (PI / (ALTITUDES - 1) as f64)).clamp(0.0, (ALTITUDES - 1) as f64);
    let (x0, y0) = (x.floor(), y.floor().min((ALTITUDES - 2) as f64));
    let (fx, fy) = (x - x0, y - y0);
    let i0 = (x0 as usize) % LONGITUDES;
    let i1 = (i0 + 1) % LONGITUDES;
    let j0 = y0 as usize;
    [
        (j0 * LONGITUDES + i0, (1.0 - fx) * (1.0 - fy)),
        (j0 * LONGITUDES + i1, fx * (1.0 - fy)),
        ((j0 + 1) * LONGITUDES + i0, (1.0 - fx) * fy),
        ((j0 + 1) * LONGITUDES + i1, fx * fy),
    ]
}

/// Which rule builds the coarser levels' density (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LodRule {
    /// [C03 eq. 11]: the mean density (mean optical depth kept).
    Eq11,
    /// The mean transmittance through one coarse cell kept (DESIGN §1.3 item 14).
    Transmittance,
}

/// Single-scattering phase of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Kajiya–Kay diffuse about the yarn axis, `sin∠(L, z)/π²` ([C03 §5.1.1]'s Ψ).
    KajiyaKay,
    /// `1/4π` (the furnace test).
    Isotropic,
}

/// Sizes and switches of a lumislice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumisliceSettings {
    /// Finest resolution (voxels per side, a power of two in 8..=128).
    pub res: usize,
    /// Coarsest level ([C03]: 8).
    pub min_res: usize,
    /// Extinction law.
    pub extinction: Extinction,
    /// Rule of the coarser levels' density.
    pub lod: LodRule,
    /// Single-scattering phase.
    pub phase: Phase,
    /// Light-march step (cells).
    pub step: f64,
    /// Multiple scattering (orders ≥ 2) in the table.
    pub multiple: bool,
    /// Paths per voxel for the multiple scattering.
    pub paths: usize,
    /// Highest scattering order.
    pub max_order: u32,
    /// Length-coordinate samples of the density over one ply twist.
    pub density_samples: usize,
    /// Seed of the fiber table and the paths.
    pub seed: u64,
}

impl Default for LumisliceSettings {
    fn default() -> Self {
        LumisliceSettings {
            res: 32,
            min_res: 8,
            extinction: Extinction::Anisotropic,
            lod: LodRule::Transmittance,
            phase: Phase::KajiyaKay,
            step: 0.5,
            multiple: true,
            paths: 32,
            max_order: 8,
            density_samples: 256,
            seed: 1,
        }
    }
}

impl LumisliceSettings {
    /// Small and fast (tests): 16², single scattering only.
    pub fn small() -> Self {
        LumisliceSettings { res: 16, multiple: false, density_samples: 64, ..Self::default() }
    }

    /// Checks every field (the message names the field at fault).
    pub fn validate(&self) -> Result<()> {
        let pow2 = |n: usize| n.is_power_of_two() && (8..=128).contains(&n);
        if !pow2(self.res) {
            return Err(Error::Invalid(format!(
                "lumislice res {} (a power of two in 8..=128)",
                self.res
            )));
        }
        if !pow2(self.min_res) || self.min_res > self.res {
            return Err(Error::Invalid(format!(
                "lumislice min_res {} (a power of two in 8..=res)",
                self.min_res
            )));
        }
        if !(self.step.is_finite() && self.step >= 0.05 && self.step <= 4.0) {
            return Err(Error::Invalid(format!("lumislice step {} (0.05..=4 cells)", self.step)));
        }
        if self.multiple && (self.paths == 0 || self.paths > 1 << 16) {
            return Err(Error::Invalid(format!("lumislice paths {} (1..=65536)", self.paths)));
        }
        if self.max_order > 1024 {
            return Err(Error::Invalid(format!("lumislice max_order {} (≤ 1024)", self.max_order)));
        }
        if self.density_samples == 0 || self.density_samples > 1 << 16 {
            return Err(Error::Invalid(format!(
                "lumislice density_samples {} (1..=65536)",
                self.density_samples
            )));
        }
        Ok(())
    }
}

/// One level of the pyramid.
#[derive(Debug, Clone, PartialEq)]
pub struct LumisliceLevel {
    /// Voxels per side.
    pub res: usize,
    /// σ⊥ per metre, row-major `[y][x]`, cell centres.
    pub sigma: Vec<f32>,
    /// `V` per direction and voxel, `[k][y][x]` (RGB).
    pub vrf: Vec<[f32; 3]>,
}

/// A lumislice and its pyramid (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Lumislice {
    /// The settings it was computed with.
    pub settings: LumisliceSettings,
    /// The grid spans `[−half_width, half_width]²` (metres) at every level.
    pub half_width: f64,
    /// Ply pitch the slice turns with (metres per turn, signed).
    pub ply_pitch: f64,
    /// Fiber radius (metres).
    pub fiber_radius: f64,
    /// ϖ (linear RGB).
    pub albedo: [f32; 3],
    /// Levels, finest first.
    pub levels: Vec<LumisliceLevel>,
    /// Seconds the computation took.
    pub seconds: f64,
    /// Whether it came from the cache.
    pub from_cache: bool,
}

/// A σ⊥ grid for the marches (f64, bilinear between cell centres, 0 outside).
#[derive(Debug, Clone)]
pub struct SliceGrid {
    /// Voxels per side.
    pub res: usize,
    /// Half the side (metres).
    pub half_width: f64,
    /// σ⊥ per metre, row-major.
    pub sigma: Vec<f64>,
}

impl SliceGrid {
    /// Cell size (metres).
    pub fn cell(&self) -> f64 {
        2.0 * self.half_width / self.res as f64
    }

    /// Centre of voxel `(i, j)`.
    pub fn centre(&self, i: usize, j: usize) -> [f64; 2] {
        let c = self.cell();
        [-self.half_width + (i as f64 + 0.5) * c, -self.half_width + (j as f64 + 0.5) * c]
    }

    /// σ⊥ at `(x, y)` (bilinear; 0 outside the grid).
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let c = self.cell();
        let gx = (x + self.half_width) / c - 0.5;
        let gy = (y + self.half_width) / c - 0.5;
        let (x0, y0) = (gx.floor(), gy.floor());
        let (fx, fy) = (gx - x0, gy - y0);
        let n = self.res as f64;
        let get = |i: f64, j: f64| {
            if i < 0.0 || j < 0.0 || i >= n || j >= n {
                0.0
            } else {
                self.sigma[j as usize * self.res + i as usize]
            }
        };
        (1.0 - fx) * (1.0 - fy) * get(x0, y0)
            + fx * (1.0 - fy) * get(x0 + 1.0, y0)
            + (1.0 - fx) * fy * get(x0, y0 + 1.0)
            + fx * fy * get(x0 + 1.0, y0 + 1.0)
    }

    /// Radius beyond which σ⊥ = 0 (the circle through the grid's corners).
    pub fn reach(&self) -> f64 {
        self.half_width * std::f64::consts::SQRT_2
    }
}

/// The twisted straight yarn the light marches through: σ⊥ in the slice frame at `z = 0`,
/// turned by `2πz/α_ply` at height `z`.
pub struct TwistedYarn<'a> {
    /// σ⊥ at slice coordinates.
    pub sigma: &'a (dyn Fn(f64, f64) -> f64 + Sync),
    /// Radius beyond which σ⊥ = 0.
    pub reach: f64,
    /// `2π/α_ply` (radians per metre; 0: untwisted).
    pub twist_rate: f64,
    /// Extinction law.
    pub law: Extinction,
}

impl TwistedYarn<'_> {
    /// Slice coordinates of the point `(a, b, z)` of the yarn frame.
    #[inline]
    pub fn to_slice(&self, a: f64, b: f64, z: f64) -> [f64; 2] {
        let (s, c) = (self.twist_rate * z).sin_cos();
        [a * c + b * s, -a * s + b * c]
    }

    /// The march along `p + s·l` (`p` at height `z0`): `(s_max, n, h, factor)`.
    fn path(&self, p: [f64; 2], l: [f64; 3], step: f64) -> (f64, usize, f64, f64) {
        let lxy2 = l[0] * l[0] + l[1] * l[1];
        let factor = match self.law {
            Extinction::Anisotropic => lxy2.sqrt().min(1.0),
            Extinction::Isotropic => 1.0,
        };
        // Leave the cylinder of radius `reach` (in-plane exit), or give up far along the
        // axis (light nearly along the yarn: 64 reaches).
        let far = 64.0 * self.reach;
        let s_max = if lxy2 > 1e-24 {
            let pd = p[0] * l[0] + p[1] * l[1];
            let c = p[0] * p[0] + p[1] * p[1] - self.reach * self.reach;
            let disc = (pd * pd - lxy2 * c).max(0.0);
            (((-pd + disc.sqrt()) / lxy2).max(0.0)).min(far)
        } else {
            far
        };
        let n = (s_max / step).ceil().max(1.0) as usize;
        (s_max, n, s_max / n as f64, factor)
    }

    /// Optical depth from slice point `p` (height `z0`) towards unit `l`, steps ≤ `step`
    /// metres, midpoints (exact for σ constant inside the reach).
    pub fn optical_depth(&self, p: [f64; 2], z0: f64, l: [f64; 3], step: f64) -> f64 {
        let (_, n, h, factor) = self.path(p, l, step);
        if factor == 0.0 {
            return 0.0;
        }
        let mut tau = 0.0;
        for k in 0..n {
            let s = (k as f64 + 0.5) * h;
            let q = self.to_slice(p[0] + s * l[0], p[1] + s * l[1], z0 + s * l[2]);
            tau += (self.sigma)(q[0], q[1]);
        }
        tau * h * factor
    }

    /// Free flight from `(p, z0)` along `l` to optical depth `target`: the collision point
    /// `(a, b, z)` in the yarn frame, or `None` if the path leaves the yarn.
    pub fn free_flight(
        &self,
        p: [f64; 2],
        z0: f64,
        l: [f64; 3],
        step: f64,
        target: f64,
    ) -> Option<[f64; 3]> {
        let (_, n, h, factor) = self.path(p, l, step);
        if factor == 0.0 {
            return None;
        }
        let mut tau = 0.0;
        for k in 0..n {
            let s = (k as f64 + 0.5) * h;
            let (a, b, z) = (p[0] + s * l[0], p[1] + s * l[1], z0 + s * l[2]);
            let q = self.to_slice(a, b, z);
            let dt = (self.sigma)(q[0], q[1]) * h * factor;
            if tau + dt >= target {
                let f = if dt > 0.0 { (target - tau) / dt } else { 0.5 };
                let s = (k as f64 + f) * h;
                return Some([p[0] + s * l[0], p[1] + s * l[1], z0 + s * l[2]]);
            }
            tau += dt;
        }
        None
    }
}

impl Lumislice {
    /// The cache key (format version, yarn parameters, colour, settings).
    pub fn cache_key(
        params: &YarnParams,
        albedo: [f32; 3],
        s: &LumisliceSettings,
    ) -> Result<String> {
        Ok(format!(
            "lumislice v{LUMISLICE_FORMAT_VERSION}\n{}\n{albedo:?}\n{s:?}",
            params.to_toml()?
        ))
    }

    /// The lumislice of the regular fibers of `params` (colour `albedo` = ϖ), computed.
    /// `progress` receives voxel counts as rows finish.
    pub fn compute(
        params: &YarnParams,
        albedo: [f32; 3],
        s: &LumisliceSettings,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self> {
        s.validate()?;
        check_albedo(albedo)?;
        let t0 = std::time::Instant::now();
        let density = CrossSectionDensity::from_params(
            params,
            &DensityOptions { res: s.res, samples: s.density_samples, seed: s.seed, loops: true },
        )?;
        let grid = SliceGrid {
            res: density.res,
            half_width: density.half_width,
            sigma: density.n_a.iter().map(|n| 2.0 * density.fiber_radius * n).collect(),
        };
        let pitch = EffectiveTwist::nominal(params).ply_pitch;
        let mut out = Self::from_grid(&grid, pitch, albedo, s, progress)?;
        out.fiber_radius = density.fiber_radius;
        out.seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// The lumislice of a given σ⊥ grid turning with ply pitch `ply_pitch` (the closed-form
    /// tests use uniform disks).
    pub fn from_grid(
        grid: &SliceGrid,
        ply_pitch: f64,
        albedo: [f32; 3],
        s: &LumisliceSettings,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self> {
        s.validate()?;
        check_albedo(albedo)?;
        if grid.res != s.res || grid.sigma.len() != s.res * s.res {
            return Err(Error::Invalid(format!(
                "lumislice grid {}² ({} values) for res {}",
                grid.res,
                grid.sigma.len(),
                s.res
            )));
        }
        if grid.sigma.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(Error::Invalid(
                "lumislice σ grid: a value is negative or not finite".into(),
            ));
        }
        let t0 = std::time::Instant::now();
        let twist_rate =
            if ply_pitch != 0.0 && ply_pitch.is_finite() { TAU / ply_pitch } else { 0.0 };
        let lookup = |x: f64, y: f64| grid.at(x, y);
        let yarn =
            TwistedYarn { sigma: &lookup, reach: grid.reach(), twist_rate, law: s.extinction };
        let step = s.step * grid.cell();
        let res = s.res;
        let dirs: Vec<[f64; 3]> = (0..DIRECTIONS).map(direction).collect();
        // T(p, L), [voxel][k].
        let trans: Vec<Vec<f32>> = (0..res * res)
            .into_par_iter()
            .map(|v| {
                let p = grid.centre(v % res, v / res);
                let t = dirs
                    .iter()
                    .map(|l| (-yarn.optical_depth(p, 0.0, *l, step)).exp() as f32)
                    .collect();
                if v % res == res - 1 {
                    progress(res as u64);
                }
                t
            })
            .collect();
        let phase = |l: &[f64; 3]| match s.phase {
            Phase::KajiyaKay => (l[0] * l[0] + l[1] * l[1]).sqrt() / (PI * PI),
            Phase::Isotropic => 1.0 / (4.0 * PI),
        };
        let ms: Vec<Vec<[f64; 3]>> = if s.multiple && albedo.iter().any(|a| *a > 0.0) {
            (0..res * res)
                .into_par_iter()
                .map(|v| multiple(&yarn, grid, &trans, v, albedo, s, step))
                .collect()
        } else {
            vec![Vec::new(); res * res]
        };
        let mut vrf = vec![[0f32; 3]; DIRECTIONS * res * res];
        for v in 0..res * res {
            for (k, l) in dirs.iter().enumerate() {
                let ss = phase(l) * trans[v][k] as f64;
                let m = ms[v].get(k).copied().unwrap_or([0.0; 3]);
                vrf[k * res * res + v] = [0, 1, 2].map(|c| (albedo[c] as f64 * (ss + m[c])) as f32);
            }
        }
        let mut levels = vec![LumisliceLevel {
            res,
            sigma: grid.sigma.iter().map(|v| *v as f32).collect(),
            vrf,
        }];
        while levels.last().is_some_and(|l| l.res > s.min_res) {
            let next = downsample(
                levels.last().unwrap(),
                grid.cell() * (res / levels.last().unwrap().res) as f64,
                s.lod,
            );
            levels.push(next);
        }
        Ok(Lumislice {
            settings: *s,
            half_width: grid.half_width,
            ply_pitch,
            fiber_radius: 0.0,
            albedo,
            levels,
            seconds: t0.elapsed().as_secs_f64(),
            from_cache: false,
        })
    }

    /// The lumislice read from `cache_dir` when a valid file for exactly these inputs is
    /// there, otherwise computed (and written there, atomically).
    pub fn for_params(
        params: &YarnParams,
        albedo: [f32; 3],
        s: &LumisliceSettings,
        cache_dir: Option<&Path>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Self> {
        s.validate()?;
        let Some(dir) = cache_dir else {
            return Self::compute(params, albedo, s, progress);
        };
        let key = Self::cache_key(params, albedo, s)?;
        let path = Self::cache_path(dir, params, &key);
        if let Ok(bytes) = std::fs::read(&path)
            && let Some(mut l) = decode(&bytes, &key, s)
        {
            l.from_cache = true;
            return Ok(l);
        }
        let l = Self::compute(params, albedo, s, progress)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        btf_core::fs::write_atomic(&path, &encode(&l, &key))?;
        Ok(l)
    }

    fn cache_path(dir: &Path, params: &YarnParams, key: &str) -> PathBuf {
        let name: String = params
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' })
            .take(48)
            .collect();
        dir.join(format!("{name}-lumislice-{:016x}.ysb", key_hash(key.as_bytes())))
    }

    /// The level for a slice `m` pixels across: the finest level no larger than the
    /// smallest `2ⁿ ≥ m` ([C03 §5.2.2]), clamped to the pyramid.
    pub fn level_for(&self, m: f64) -> usize {
        let want = if m.is_finite() && m > 1.0 { m.log2().ceil().exp2() } else { 1.0 };
        self.levels.iter().position(|l| (l.res as f64) <= want).unwrap_or(self.levels.len() - 1)
    }

    /// Radius beyond which the density is zero (metres).
    pub fn reach(&self) -> f64 {
        self.half_width * std::f64::consts::SQRT_2
    }

    /// `V` at level `lvl`, slice point `(x, y)` and slice-frame light `l`: bilinear in the
    /// voxel, bilinear over the four nearest directions (the renderer's lookup).
    pub fn vrf_at(&self, lvl: usize, x: f64, y: f64, l: [f64; 3]) -> [f64; 3] {
        let level = &self.levels[lvl];
        let res = level.res;
        let cell = 2.0 * self.half_width / res as f64;
        let gx = (x + self.half_width) / cell - 0.5;
        let gy = (y + self.half_width) / cell - 0.5;
        let (x0, y0) = (gx.floor(), gy.floor());
        let (fx, fy) = (gx - x0, gy - y0);
        let mut out = [0.0; 3];
        for (k, w) in direction_weights(l) {
            for (dx, dy, wt) in [
                (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
                (1.0, 0.0, fx * (1.0 - fy)),
                (0.0, 1.0, (1.0 - fx) * fy),
                (1.0, 1.0, fx * fy),
            ] {
                let (i, j) = (x0 + dx, y0 + dy);
                if w * wt == 0.0 || i < 0.0 || j < 0.0 || i >= res as f64 || j >= res as f64 {
                    continue;
                }
                let v = level.vrf[k * res * res + j as usize * res + i as usize];
                (0..3).for_each(|c| out[c] += w * wt * v[c] as f64);
            }
        }
        out
    }

    /// Floats the renderer uploads per level: σ⊥ (`res²`), then `V` as `[k][y][x]` RGBA
    /// (`4·DIRECTIONS·res²`).
    pub fn gpu_level(&self, lvl: usize) -> Vec<f32> {
        let l = &self.levels[lvl];
        let mut v = Vec::with_capacity(l.sigma.len() * (1 + 4 * DIRECTIONS));
        v.extend(&l.sigma);
        for c in &l.vrf {
            v.extend([c[0], c[1], c[2], 0.0]);
        }
        v
    }

    /// Bytes of the pyramid as uploaded.
    pub fn gpu_bytes(&self) -> u64 {
        self.levels.iter().map(|l| (l.res * l.res * (1 + 4 * DIRECTIONS) * 4) as u64).sum()
    }
}

fn check_albedo(a: [f32; 3]) -> Result<()> {
    if a.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
        Ok(())
    } else {
        Err(Error::Invalid(format!("lumislice albedo {a:?} (each channel in [0, 1])")))
    }
}

/// `M(p, L)` of voxel `v` for every table direction (module docs).
fn multiple(
    yarn: &TwistedYarn,
    grid: &SliceGrid,
    trans: &[Vec<f32>],
    v: usize,
    albedo: [f32; 3],
    s: &LumisliceSettings,
    step: f64,
) -> Vec<[f64; 3]> {
    let res = s.res;
    let mut acc = vec![[0.0f64; 3]; DIRECTIONS];
    let p0 = grid.centre(v % res, v / res);
    if grid.sigma[v] <= 0.0 {
        return acc;
    }
    let mut rng = KeyRng::new(&[s.seed, 0x6c75_6d69, v as u64]);
    let inv_paths = 1.0 / s.paths as f64;
    let dth = TAU / LONGITUDES as f64;
    for _ in 0..s.paths {
        let (mut p, mut z) = (p0, 0.0);
        let mut beta = [1.0f64; 3];
        for _order in 2..=s.max_order.max(1) {
            let (u1, u2) = (rng.uniform(), rng.uniform());
            let zc = 1.0 - 2.0 * u1;
            let r = (1.0 - zc * zc).max(0.0).sqrt();
            let w = [r * (TAU * u2).cos(), r * (TAU * u2).sin(), zc];
            let target = -(1.0 - rng.uniform()).ln();
            let Some(x) = yarn.free_flight(p, z, w, step, target) else { break };
            (0..3).for_each(|c| beta[c] *= albedo[c] as f64);
            // The collision in the slice frame: position and light longitudes turned back.
            let q = yarn.to_slice(x[0], x[1], x[2]);
            let shift = yarn.twist_rate * x[2] / dth;
            let cell = grid.cell();
            let gx = (q[0] + grid.half_width) / cell - 0.5;
            let gy = (q[1] + grid.half_width) / cell - 0.5;
            let (x0, y0) = (gx.floor(), gy.floor());
            let (fx, fy) = (gx - x0, gy - y0);
            let taps: Vec<(usize, f64)> = [
                (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
                (1.0, 0.0, fx * (1.0 - fy)),
                (0.0, 1.0, (1.0 - fx) * fy),
                (1.0, 1.0, fx * fy),
            ]
            .into_iter()
            .filter_map(|(dx, dy, wt)| {
                let (i, j) = (x0 + dx, y0 + dy);
                (i >= 0.0 && j >= 0.0 && i < res as f64 && j < res as f64 && wt > 0.0)
                    .then(|| (j as usize * res + i as usize, wt))
            })
            .collect();
            // Longitude i of a fixed light is i − shift in the collision's slice frame.
            let sx = -shift;
            let s0 = sx.floor();
            let sf = sx - s0;
            let s0 = (s0 as i64).rem_euclid(LONGITUDES as i64) as usize;
            let scale = inv_paths / (4.0 * PI);
            for j in 0..ALTITUDES {
                for i in 0..LONGITUDES {
                    let a = j * LONGITUDES + (i + s0) % LONGITUDES;
                    let b = j * LONGITUDES + (i + s0 + 1) % LONGITUDES;
                    let mut t = 0.0;
                    for &(vi, wt) in &taps {
                        t += wt * ((1.0 - sf) * trans[vi][a] as f64 + sf * trans[vi][b] as f64);
                    }
                    let k = j * LONGITUDES + i;
                    (0..3).for_each(|c| acc[k][c] += beta[c] * t * scale);
                }
            }
            let bmax = beta.iter().cloned().fold(0.0, f64::max);
            if bmax <= 0.0 {
                break;
            }
            if bmax < 0.1 {
                let q = bmax / 0.1;
                if rng.uniform() >= q {
                    break;
                }
                beta.iter_mut().for_each(|b| *b /= q);
            }
            p = [x[0], x[1]];
            z = x[2];
        }
    }
    acc
}

/// The next level: density by `rule` with coarse-cell depth `2·fine_cell`, table by
/// [C03 eq. 11]'s density-weighted mean (the plain mean where the block is empty).
pub fn downsample(l: &LumisliceLevel, fine_cell: f64, rule: LodRule) -> LumisliceLevel {
    let (r, h) = (l.res, l.res / 2);
    let depth = 2.0 * fine_cell;
    let mut sigma = vec![0f32; h * h];
    let mut vrf = vec![[0f32; 3]; DIRECTIONS * h * h];
    for j in 0..h {
        for i in 0..h {
            let idx = [
                (2 * j) * r + 2 * i,
                (2 * j) * r + 2 * i + 1,
                (2 * j + 1) * r + 2 * i,
                (2 * j + 1) * r + 2 * i + 1,
            ];
            let s: Vec<f64> = idx.iter().map(|&v| l.sigma[v] as f64).collect();
            let sum: f64 = s.iter().sum();
            sigma[j * h + i] = match rule {
                LodRule::Eq11 => (sum / 4.0) as f32,
                LodRule::Transmittance => {
                    let t = s.iter().map(|x| (-x * depth).exp()).sum::<f64>() / 4.0;
                    (-t.ln() / depth) as f32
                }
            };
            for k in 0..DIRECTIONS {
                let mut c = [0.0f64; 3];
                for (n, &v) in idx.iter().enumerate() {
                    let w = if sum > 0.0 { s[n] / sum } else { 0.25 };
                    let x = l.vrf[k * r * r + v];
                    (0..3).for_each(|ch| c[ch] += w * x[ch] as f64);
                }
                vrf[k * h * h + j * h + i] = c.map(|x| x as f32);
            }
        }
    }
    LumisliceLevel { res: h, sigma, vrf }
}

/// Which yarn-to-yarn shadow law [C03 eq. 10] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShadowVariant {
    /// The paper's `1 − k0 (1 − e^{−τ(d)}) / (1 − e^{−τ(0)})`.
    Empirical,
    /// The transmittance `e^{−τ(d)}` itself (DESIGN §1.3 item 13's physical variant).
    Physical,
}

/// `T_y(d)`: light through another yarn whose centre line passes at distance `d` from the
/// ray, `τ(d)` the optical depth along the chord ⟂ the yarn (azimuthally averaged density);
/// 1 beyond the reach `R_y` ([C03 eq. 10], DESIGN §1.3 item 13).
#[derive(Debug, Clone, PartialEq)]
pub struct YarnShadowLut {
    /// `R_y` (metres).
    pub reach: f64,
    /// Variant.
    pub variant: ShadowVariant,
    /// `k0` (the empirical variant's depth; the paper: 0.8).
    pub k0: f64,
    /// `T_y` at `d = R_y·i/(n − 1)`.
    pub values: Vec<f32>,
}

impl YarnShadowLut {
    /// Entries of the table.
    pub const ENTRIES: usize = 1024;

    /// The table of a radial σ⊥ profile reaching `reach`.
    pub fn new(
        sigma_r: &dyn Fn(f64) -> f64,
        reach: f64,
        k0: f64,
        variant: ShadowVariant,
    ) -> Result<Self> {
        Self::check(reach, k0)?;
        Ok(Self::from_depths(&Self::depths(sigma_r, reach), reach, k0, variant))
    }

    /// Both variants (empirical, physical) from one set of chord optical depths.
    pub fn both(sigma_r: &dyn Fn(f64) -> f64, reach: f64, k0: f64) -> Result<[Self; 2]> {
        Self::check(reach, k0)?;
        let t = Self::depths(sigma_r, reach);
        Ok([ShadowVariant::Empirical, ShadowVariant::Physical]
            .map(|v| Self::from_depths(&t, reach, k0, v)))
    }

    fn check(reach: f64, k0: f64) -> Result<()> {
        if !(reach.is_finite() && reach > 0.0) {
            return Err(Error::Invalid(format!("yarn shadow reach {reach} (> 0)")));
        }
        if !(k0.is_finite() && (0.0..=1.0).contains(&k0)) {
            return Err(Error::Invalid(format!("yarn shadow k0 {k0} (in [0, 1])")));
        }
        Ok(())
    }

    /// `τ(d)` at the table's distances: the chord ⟂ the yarn at distance `d`, 2048
    /// midpoints a half chord (exact for a uniform disk).
    fn depths(sigma_r: &dyn Fn(f64) -> f64, reach: f64) -> Vec<f64> {
        let n = Self::ENTRIES;
        (0..n)
            .map(|i| {
                let d = reach * i as f64 / (n - 1) as f64;
                let half = (reach * reach - d * d).max(0.0).sqrt();
                let m = 2048;
                let h = half / m as f64;
                2.0 * h * (0..m).map(|k| sigma_r(d.hypot((k as f64 + 0.5) * h))).sum::<f64>()
            })
            .collect()
    }

    fn from_depths(tau: &[f64], reach: f64, k0: f64, variant: ShadowVariant) -> Self {
        let (n, t0) = (tau.len(), tau[0]);
        let values = tau
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let v = match variant {
                    ShadowVariant::Physical => (-t).exp(),
                    ShadowVariant::Empirical if t0 > 0.0 => {
                        1.0 - k0 * (1.0 - (-t).exp()) / (1.0 - (-t0).exp())
                    }
                    ShadowVariant::Empirical => 1.0,
                };
                if i == n - 1 { 1.0 } else { v as f32 }
            })
            .collect();
        YarnShadowLut { reach, variant, k0, values }
    }

    /// The table of a cross-section density's azimuthal average.
    pub fn from_density(d: &CrossSectionDensity, k0: f64, variant: ShadowVariant) -> Result<Self> {
        let reach = d.radial.dr * d.radial.n_a.len() as f64;
        let rf = d.fiber_radius;
        Self::new(&|r| 2.0 * rf * d.radial.n_a_at(r), reach, k0, variant)
    }

    /// `T_y(d)` (linear between entries; 1 at and beyond the reach).
    pub fn at(&self, d: f64) -> f64 {
        let n = self.values.len();
        let x = (d.abs() / self.reach) * (n - 1) as f64;
        if x.is_nan() || x >= (n - 1) as f64 {
            return 1.0;
        }
        let i = x.floor() as usize;
        let f = x - i as f64;
        (1.0 - f) * self.values[i] as f64 + f * self.values[i + 1] as f64
    }
}

fn encode(l: &Lumislice, key: &str) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.f64s(&[l.half_width, l.ply_pitch, l.fiber_radius, l.seconds]);
    w.f32s(&l.albedo);
    w.u64(l.levels.len());
    for lv in &l.levels {
        w.u64(lv.res);
        w.f32s(&lv.sigma);
        w.f32s(&lv.vrf.concat());
    }
    crate::cache::frame(MAGIC, LUMISLICE_FORMAT_VERSION, key, &w.0)
}

/// The lumislice in `bytes` if the header carries exactly `key`, the payload is intact and
/// every level has the size `s` implies.
fn decode(bytes: &[u8], key: &str, s: &LumisliceSettings) -> Option<Lumislice> {
    let payload = crate::cache::unframe(bytes, MAGIC, LUMISLICE_FORMAT_VERSION, key)?;
    let mut r = Reader(payload);
    let (half_width, ply_pitch, fiber_radius, seconds) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
    let albedo: [f32; 3] = r.f32s()?.try_into().ok()?;
    let n = r.u64()?;
    let mut levels = Vec::new();
    let mut want = s.res;
    for _ in 0..n.min(8) {
        let res = r.u64()?;
        if res != want {
            return None;
        }
        let sigma = r.f32s()?;
        let vrf = r.f32s()?;
        if sigma.len() != res * res || vrf.len() != 3 * DIRECTIONS * res * res {
            return None;
        }
        let vrf = vrf.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        levels.push(LumisliceLevel { res, sigma, vrf });
        want /= 2;
    }
    (r.0.is_empty() && levels.len() == n && levels.last()?.res == s.min_res).then_some(Lumislice {
        settings: *s,
        half_width,
        ply_pitch,
        fiber_radius,
        albedo,
        levels,
        seconds,
        from_cache: false,
    })
}
