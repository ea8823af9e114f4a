//! Light descriptions of a scene (`[[lights]]`): directional and point lights with the
//! radiometry of DESIGN.md §3 (`L = BTF · E`, `L = BTF · I / d²`), and the environment
//! light of `[S03 §5]`, `L(v) = f · ∫ L_env(R_δ ω) V(ω) BTF(v, ω) dω` (its per-vertex form is
//! `[S03 eq. 11]`). [`Light::to_raw`] gives the record the BTF pass reads.

use crate::math::v3;
use crate::uniforms::{DIRECTIONAL, LightRaw, POINT};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// A light source.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "lowercase")]
pub enum Light {
    /// Light from direction `direction` (pointing *towards* the light) with perpendicular
    /// irradiance `irradiance` (linear RGB).
    Directional {
        /// Direction to the light (world; need not be unit length).
        direction: [f32; 3],
        /// Perpendicular irradiance, linear RGB.
        irradiance: [f32; 3],
        /// Whether the light casts shadows (when the scene's shadows are on).
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// An isotropic point light of intensity `intensity` (linear RGB).
    Point {
        /// Position (world).
        position: [f32; 3],
        /// Radiant intensity, linear RGB.
        intensity: [f32; 3],
        /// Whether the light casts shadows (when the scene's shadows are on).
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// An equirectangular HDR environment with per-vertex visibility (Sattler et al. 2003,
    /// §5); always evaluated per vertex, added to the other lights.
    Environment(EnvironmentLight),
}

fn yes() -> bool {
    true
}

impl Light {
    /// The light's record in the frame uniform, unshadowed (`color.w` =
    /// [`LightShadow::Unshadowed`](crate::uniforms::LightShadow); the shadow pass sets its
    /// look-up with [`LightRaw::with_shadow`]). An environment light has zero power here:
    /// its light comes from the per-vertex coefficients.
    pub fn to_raw(&self) -> LightRaw {
        match self {
            Light::Directional { direction, irradiance, .. } => {
                let d = v3(*direction).normalize();
                LightRaw {
                    pos: [d.x, d.y, d.z, DIRECTIONAL],
                    color: [irradiance[0], irradiance[1], irradiance[2], 0.0],
                    ..Default::default()
                }
            }
            Light::Point { position, intensity, .. } => LightRaw {
                pos: [position[0], position[1], position[2], POINT],
                color: [intensity[0], intensity[1], intensity[2], 0.0],
                ..Default::default()
            },
            Light::Environment(_) => {
                LightRaw { pos: [0.0, 0.0, 1.0, DIRECTIONAL], ..Default::default() }
            }
        }
    }

    /// Whether this light asks for shadows (environment lights have their visibility maps
    /// instead).
    pub fn casts_shadows(&self) -> bool {
        match self {
            Light::Directional { shadows, .. } | Light::Point { shadows, .. } => *shadows,
            Light::Environment(_) => false,
        }
    }
}

/// An environment light: `L(v) = f · ∫ L_env(R_δ ω) V(ω) BTF(v, ω) dω` (DESIGN.md §3).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentLight {
    /// Equirectangular linear HDR map (`.hdr` or `.exr`, world `+z` up).
    pub path: PathBuf,
    /// Rotation of the environment about world `+z`, degrees.
    #[serde(default)]
    pub rotation_deg: f64,
    /// Exposure factor `f` (`[S03 eq. 11]`).
    #[serde(default = "one")]
    pub exposure: f32,
    /// Hemicube resolution: pixels across the top face of each vertex's visibility map.
    #[serde(default = "visibility_res_default")]
    pub visibility_res: u32,
    /// Separate visibility maps for the back sides of the cloth.
    #[serde(default = "yes")]
    pub two_sided: bool,
    /// Eigenweightsets (`[S03 eq. 13]`) for fast rotation; absent = exact gather per rotation.
    #[serde(default)]
    pub eigenweightsets: Option<EigenSets>,
    /// Folder for the visibility-map cache (absent: no cache).
    #[serde(default)]
    pub cache_dir: Option<PathBuf>,
}

fn visibility_res_default() -> u32 {
    16
}

/// Eigenweightset parameters (`[S03 eq. 13]`).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EigenSets {
    /// Rotations `A` of the environment the PCA is built from (equal steps of 360°/A).
    #[serde(default = "rotations_default")]
    pub rotations: usize,
    /// Components `e` kept.
    #[serde(default = "components_default")]
    pub components: usize,
}

fn rotations_default() -> usize {
    30
}
fn components_default() -> usize {
    5
}

impl EnvironmentLight {
    /// The parameters of the run-time environment.
    pub fn params(&self) -> btf_light::EnvironmentParams {
        btf_light::EnvironmentParams {
            rotation_deg: self.rotation_deg,
            exposure: self.exposure,
            visibility_res: self.visibility_res,
            two_sided: self.two_sided,
            eigen: self.eigenweightsets.map(|e| (e.rotations, e.components)),
            cache_dir: self.cache_dir.clone(),
        }
    }

    pub(crate) fn validate(&self, key: &str) -> std::result::Result<(), (String, String)> {
        let bad = |k: &str, what: &str| Err((format!("{key}.{k}"), what.to_string()));
        if !self.rotation_deg.is_finite() {
            return bad("rotation_deg", "must be finite");
        }
        if !(self.exposure.is_finite()
            && self.exposure >= 0.0
            && self.exposure <= btf_core::MAX_RADIANCE)
        {
            return bad("exposure", "must be a number in [0, 1e12]");
        }
        if !(2..=256).contains(&self.visibility_res) {
            return bad("visibility_res", "must be in 2..=256 pixels");
        }
        if let Some(e) = self.eigenweightsets {
            if !(2..=720).contains(&e.rotations) {
                return bad("eigenweightsets.rotations", "must be in 2..=720");
            }
            if e.components == 0 || e.components >= e.rotations {
                return bad("eigenweightsets.components", "must be in 1..rotations");
            }
        }
        Ok(())
    }
}

fn one() -> f32 {
    1.0
}
