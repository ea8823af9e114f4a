//! The scene description of the transmission effect: the `transmission` table of a
//! `[[materials]]` entry (plain data, validated with the key named).
//!
//! ```toml
//! [[materials]]
//! store = "voile.eigen"
//! transmission = { tau = 0.3, albedo = 0.8, phase = "isotropic" }
//! # or: tau_texture = "btf-mean" | "tau.png", albedo = [0.9, 0.8, 0.7], phase = { hg = 0.3 }
//! ```

use crate::material::MaterialData;
use crate::{Error, Result};
use btf_light::thin_tables::SlabParams;
use half::f16;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest accepted optical thickness (beyond it the slab is opaque to f32 precision:
/// `e^{−τ₁}` underflows long before).
pub const MAX_TAU: f32 = 1e4;

/// The `transmission` effect of a material (thin-cloth paper, eq. 7–9).
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
}

/// Luminance of the frontal view slot's mean texture, divided by its average (all ones
/// for a black mean).
pub fn btf_mean_thickness(data: &MaterialData) -> (u32, u32, Vec<f16>) {
    let n = (data.width * data.height) as usize;
    let lum: Vec<f32> = data.mean_layers[..n * 4]
        .chunks_exact(4)
        .map(|p| 0.2126 * p[0].to_f32() + 0.7152 * p[1].to_f32() + 0.0722 * p[2].to_f32())
        .map(|l| l.max(0.0))
        .collect();
    let avg = lum.iter().map(|&l| l as f64).sum::<f64>() / n.max(1) as f64;
    let texels = if avg > 0.0 {
        lum.iter().map(|&l| f16::from_f32((l as f64 / avg) as f32)).collect()
    } else {
        vec![f16::ONE; n]
    };
    (data.width, data.height, texels)
}

/// A grey image's values in `[0, 1]` (8/16-bit: `v / max`; float: as stored, refused
/// outside `[0, 1]` or non-finite).
pub fn image_thickness(path: &std::path::Path) -> Result<(u32, u32, Vec<f16>)> {
    let img = image::open(path)
        .map_err(|e| Error::Invalid(format!("{}: tau_texture: {e}", path.display())))?;
    let grey = img.to_luma32f();
    if let Some((i, v)) =
        grey.iter().enumerate().find(|(_, v)| !(v.is_finite() && (0.0..=1.0).contains(*v)))
    {
        return Err(Error::Invalid(format!(
            "{}: tau_texture pixel x={}, y={} is {v}; values must be in [0, 1]",
            path.display(),
            i as u32 % grey.width(),
            i as u32 / grey.width()
        )));
    }
    Ok((grey.width(), grey.height(), grey.iter().map(|&v| f16::from_f32(v)).collect()))
}

/// The slab parameters of the environment tables (`btf_light::thin_tables`) for a
/// material's `transmission` table and the largest value of its τ texture (ignored without
/// one): with a texture, the τ nodes span `tau · max(1, largest texel)`.
pub fn slab_params(desc: &TransmissionDesc, max_texel: f32) -> SlabParams {
    let textured = desc.tau_texture.is_some();
    let scale = if textured { max_texel.max(1.0) as f64 } else { 1.0 };
    SlabParams {
        tau: desc.tau as f64 * scale,
        textured,
        albedo: desc.albedo.rgb().map(|a| a as f64),
    }
}

/// Refuses what the environment terms cannot represent, naming the material and key.
pub fn check_supported(desc: &TransmissionDesc, material: &str, two_sided: bool) -> Result<()> {
    let refuse = |what: String| Err(Error::Unsupported(format!("{material}: {what}")));
    if let PhaseDesc::Hg { hg } = desc.phase {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_scale_covers_the_texture() {
        let desc = |tau_texture| TransmissionDesc {
            tau: 0.5,
            tau_texture,
            albedo: Albedo::Grey(0.8),
            phase: PhaseDesc::Isotropic,
        };
        // A BTF-mean texture (mean 1) reaches above 1: the nodes go up to tau · max.
        let s = slab_params(&desc(Some(TauTexture::BtfMean)), 2.5);
        assert_eq!((s.tau, s.textured), (1.25, true));
        // An image in [0, 1]: the nodes span [0, tau].
        let s = slab_params(&desc(Some(TauTexture::BtfMean)), 0.7);
        assert_eq!(s.tau, 0.5);
        let s = slab_params(&desc(None), 3.0);
        assert_eq!((s.tau, s.textured), (0.5, false));
    }
}
