//! `BakeSettings`: every knob of the precomputation, with the defaults of DESIGN §2.4
//! (core texture through one twist at 4× supersampling, self-shadow 64² × 16, AO 128²,
//! ∫M tables of 256 entries) and the checks that refuse zero or absurd sizes, naming the
//! field, before anything is allocated.

use crate::{Error, Result};
use yarn::bcsdf::{HuangParams, KhungurnParams, SimpleParams};

/// The fiber model whose ambient integrals ([W19 eq. 8–10]) are tabulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ShadingModel {
    /// [W19 eq. 5] + diffuse.
    Simple(SimpleParams),
    /// Khungurn R + TT [W19 eq. 6–10] + diffuse.
    Khungurn(KhungurnParams),
    /// R + TT + D [H25 eq. 7].
    Huang(HuangParams),
}

/// How the fibers the core stands for migrate (see [`crate::core_texture`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CoreMigration {
    /// No migration, each fiber at its mean radius `R_i(ρ_min + ρ_max)/2`: the core is then
    /// exactly screw-symmetric (our default).
    MeanRadius,
    /// [W19 §3.2]: migration rate `s = 1` (0 if the yarn has `s = 0`). Tiles, but is not
    /// screw-symmetric: the radii breathe with the twist.
    PaperS1,
}

/// Core-fiber texture settings ([`crate::core_texture`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoreSettings {
    /// Texels along u (one full fiber twist).
    pub width: usize,
    /// Texels along v (across the core).
    pub height: usize,
    /// Rays per texel side (4 = 16 rays per texel, box-downsampled).
    pub supersample: usize,
    /// Core fibers per ply (the innermost by `R_i`); `None`: `round(core_fraction·n)` of the
    /// yarn parameters (DESIGN §2.3 item 6).
    pub core_fibers: Option<usize>,
    /// Polyline points per fiber turn of the explicit core fibers.
    pub samples_per_turn: usize,
    /// Migration of the fibers the core stands for.
    pub migration: CoreMigration,
}

/// Self-shadow volume settings ([`crate::self_shadow`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSettings {
    /// Texels per side of a slice.
    pub res: usize,
    /// Slices over the relative angle `[0, 2π/n_ply]`, both ends included (≥ 2).
    pub slices: usize,
    /// Integration steps per texel along the light.
    pub steps_per_texel: usize,
}

/// Ambient-occlusion settings ([`crate::ao`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AoSettings {
    /// Texels per side.
    pub res: usize,
    /// Stratified 2-D directions per texel.
    pub directions: usize,
    /// Radial bins of the mean the cubic is fitted to.
    pub radial_bins: usize,
}

/// All bake settings (part of the cache key).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BakeSettings {
    /// Seed of the fiber table (the same seed the renderer's fibers use).
    pub seed: u64,
    /// Grid of the cross-section density (`yarn::density::DensityOptions::res`).
    pub density_res: usize,
    /// Length-coordinate samples over one ply twist for the density.
    pub density_samples: usize,
    /// Include loop slots in the density.
    pub loops: bool,
    /// Core texture.
    pub core: CoreSettings,
    /// Self-shadow volume.
    pub shadow: ShadowSettings,
    /// Ambient occlusion.
    pub ao: AoSettings,
    /// Entries of the ambient tables over θ_o.
    pub ambient_entries: usize,
    /// Fiber model of the ambient tables.
    pub shading: ShadingModel,
}

impl Default for BakeSettings {
    fn default() -> Self {
        BakeSettings {
            seed: 1,
            density_res: 64,
            density_samples: 256,
            loops: true,
            core: CoreSettings {
                width: 256,
                height: 64,
                supersample: 4,
                core_fibers: None,
                samples_per_turn: 96,
                migration: CoreMigration::MeanRadius,
            },
            shadow: ShadowSettings { res: 64, slices: 16, steps_per_texel: 4 },
            ao: AoSettings { res: 128, directions: 64, radial_bins: 32 },
            ambient_entries: 256,
            shading: ShadingModel::Khungurn(KhungurnParams::default()),
        }
    }
}

/// Largest number of f32 values one baked array may hold (64 Mi values = 256 MiB).
pub const MAX_VALUES: usize = 1 << 26;
/// Largest number of rays (or ray-marching samples) one bake may spend.
pub const MAX_WORK: u128 = 1 << 36;

fn in_range(field: &str, v: usize, lo: usize, hi: usize) -> Result<()> {
    if v < lo {
        return Err(Error::Invalid(format!("bake settings: {field} = {v} (at least {lo})")));
    }
    if v > hi {
        return Err(Error::Limit(format!("bake settings: {field} = {v} (at most {hi})")));
    }
    Ok(())
}

fn values(field: &str, n: u128) -> Result<()> {
    if n > MAX_VALUES as u128 {
        return Err(Error::Limit(format!(
            "bake settings: {field} asks for {n} values (at most {MAX_VALUES}, 256 MiB of f32)"
        )));
    }
    Ok(())
}

impl BakeSettings {
    /// Checks every size; the error names the field.
    pub fn validate(&self) -> Result<()> {
        in_range("density_res", self.density_res, 8, 4096)?;
        in_range("density_samples", self.density_samples, 1, 1 << 20)?;
        let c = &self.core;
        in_range("core.width", c.width, 2, 1 << 16)?;
        in_range("core.height", c.height, 2, 1 << 16)?;
        in_range("core.supersample", c.supersample, 1, 16)?;
        in_range("core.samples_per_turn", c.samples_per_turn, 8, 1 << 16)?;
        if let Some(n) = c.core_fibers {
            in_range("core.core_fibers", n, 0, yarn::params::MAX_FIBERS_PER_PLY as usize)?;
        }
        values("core.width × core.height", 8 * c.width as u128 * c.height as u128)?;
        let rays = (c.width * c.supersample) as u128 * (c.height * c.supersample) as u128;
        if rays > MAX_WORK {
            return Err(Error::Limit(format!(
                "bake settings: core.width × core.height × core.supersample² = {rays} rays"
            )));
        }
        let s = &self.shadow;
        in_range("shadow.res", s.res, 2, 4096)?;
        in_range("shadow.slices", s.slices, 2, 1024)?;
        in_range("shadow.steps_per_texel", s.steps_per_texel, 1, 64)?;
        values("shadow.res² × shadow.slices", (s.res * s.res) as u128 * s.slices as u128)?;
        let a = &self.ao;
        in_range("ao.res", a.res, 2, 4096)?;
        in_range("ao.directions", a.directions, 1, 1 << 16)?;
        in_range("ao.radial_bins", a.radial_bins, 4, 1 << 16)?;
        let work = (a.res * a.res) as u128 * a.directions as u128 * (4 * a.res) as u128;
        if work > MAX_WORK {
            return Err(Error::Limit(format!(
                "bake settings: ao.res² × ao.directions × march steps = {work} samples"
            )));
        }
        in_range("ambient_entries", self.ambient_entries, 2, 1 << 20)?;
        Ok(())
    }
}
