//! The scene description of the thin-cloth effect (the thin-cloth paper, `[TC eq. 7–9]`):
//! the `transmission` table of a `[[materials]]` entry (plain data, validated with the key
//! named). The pass that draws it is `passes/thin`.
//!
//! ```toml
//! [[materials]]
//! store = "voile.eigen"
//! transmission = { tau = 0.3, albedo = 0.8, phase = "isotropic" }
//! # or: tau_texture = "btf-mean" | "tau.png", albedo = [0.9, 0.8, 0.7], phase = { hg = 0.3 }
//! ```

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest accepted optical thickness (beyond it the slab is opaque to f32 precision:
/// `e^{−τ₁}` underflows long before).
pub const MAX_TAU: f32 = 1e4;

/// The `transmission` effect of a material (`[TC eq. 7–9]`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransmissionDesc {
    /// Optical thickness `τ₁` (the scale of `tau_texture` when one is given).
    pub tau: f32,
    /// Optional per-texel thickness: `"btf-mean"` (the luminance of the BTF's frontal
    /// mean texture divided by its average) or an image whose values in `[0, 1]` multiply
    /// `tau`. Laid out like the BTF's texels (same UV scale).
    #[serde(default)]
    pub tau_texture: Option<TauTexture>,
    /// Single-scattering albedo `ϖ₀`, one number or linear RGB.
    #[serde(default = "default_albedo")]
    pub albedo: Albedo,
    /// Phase function: `"isotropic"` or `{ hg = g }` (Henyey–Greenstein).
    #[serde(default)]
    pub phase: PhaseDesc,
}

fn default_albedo() -> Albedo {
    Albedo::Grey(0.8)
}

/// Where a per-texel thickness comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "String", into = "String")]
pub enum TauTexture {
    /// Luminance of the frontal view slot's mean texture, normalised to mean 1.
    BtfMean,
    /// A grey image (PNG, TIFF, …; values in `[0, 1]`); relative paths are resolved
    /// against the scene's folder.
    Image(PathBuf),
}

impl From<String> for TauTexture {
    fn from(s: String) -> Self {
        if s == "btf-mean" { TauTexture::BtfMean } else { TauTexture::Image(s.into()) }
    }
}

impl From<TauTexture> for String {
    fn from(t: TauTexture) -> String {
        match t {
            TauTexture::BtfMean => "btf-mean".into(),
            TauTexture::Image(p) => p.display().to_string(),
        }
    }
}

/// Single-scattering albedo.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Albedo {
    /// The same for all channels.
    Grey(f32),
    /// Linear RGB.
    Rgb([f32; 3]),
}

impl Albedo {
    /// As linear RGB.
    pub fn rgb(self) -> [f32; 3] {
        match self {
            Albedo::Grey(a) => [a; 3],
            Albedo::Rgb(c) => c,
        }
    }
}

/// Phase function of the scene file: `"isotropic"` or `{ hg = g }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(try_from = "PhaseRepr", into = "PhaseRepr")]
pub enum PhaseDesc {
    /// Isotropic scattering (the paper's).
    #[default]
    Isotropic,
    /// Henyey–Greenstein.
    Hg {
        /// Asymmetry `g ∈ (−1, 1)`.
        hg: f32,
    },
}

/// How a phase function is written in TOML.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum PhaseRepr {
    Name(String),
    Hg { hg: f32 },
}

impl TryFrom<PhaseRepr> for PhaseDesc {
    type Error = String;
    fn try_from(r: PhaseRepr) -> std::result::Result<Self, String> {
        match r {
            PhaseRepr::Name(n) if n == "isotropic" => Ok(PhaseDesc::Isotropic),
            PhaseRepr::Name(n) => {
                Err(format!("unknown phase '{n}' (use \"isotropic\" or {{ hg = g }})"))
            }
            PhaseRepr::Hg { hg } => Ok(PhaseDesc::Hg { hg }),
        }
    }
}

impl From<PhaseDesc> for PhaseRepr {
    fn from(p: PhaseDesc) -> Self {
        match p {
            PhaseDesc::Isotropic => PhaseRepr::Name("isotropic".into()),
            PhaseDesc::Hg { hg } => PhaseRepr::Hg { hg },
        }
    }
}

impl PhaseDesc {
    /// Henyey–Greenstein `g` (0 for isotropic).
    pub fn g(self) -> f32 {
        match self {
            PhaseDesc::Isotropic => 0.0,
            PhaseDesc::Hg { hg } => hg,
        }
    }
}

impl TransmissionDesc {
    /// Checks ranges; `key` is the dotted key of this table (`materials[2].transmission`).
    pub fn validate(&self, scene: &Path, key: &str) -> Result<()> {
        let bad = |k: &str, what: &str| {
            Err(Error::Scene { path: scene.into(), key: format!("{key}.{k}"), what: what.into() })
        };
        if !(self.tau.is_finite() && (0.0..=MAX_TAU).contains(&self.tau)) {
            return bad("tau", &format!("must be in [0, {MAX_TAU}]"));
        }
        if self.albedo.rgb().iter().any(|a| !(a.is_finite() && (0.0..=1.0).contains(a))) {
            return bad("albedo", "must be in [0, 1] (one number or [r, g, b])");
        }
        let g = self.phase.g();
        if !(g.is_finite() && g.abs() < 0.99) {
            return bad("phase.hg", "must be in (−0.99, 0.99)");
        }
        Ok(())
    }

    /// Resolves a relative `tau_texture` path against the scene's folder.
    pub fn resolve(&mut self, dir: &Path) {
        if let Some(TauTexture::Image(p)) = &mut self.tau_texture {
            *p = dir.join(&*p);
        }
    }

    /// Refuses what the environment terms cannot represent, naming the material and key.
    pub fn check_environment(&self, material: &str, two_sided: bool) -> Result<()> {
        let refuse = |what: String| Err(Error::Unsupported(format!("{material}: {what}")));
        if let PhaseDesc::Hg { hg } = self.phase {
            return refuse(format!(
                "transmission.phase = {{ hg = {hg} }} under an environment light: the environment terms are tabulated in μ for isotropic scattering; use phase = \"isotropic\""
            ));
        }
        if !two_sided {
            return refuse(
            "thin cloth under an environment light needs two_sided = true (the back-lit term integrates the far side's visibility)".into(),
        );
        }
        Ok(())
    }
}
