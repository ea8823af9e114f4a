//! The three fiber models as lobe sums ([`super::FiberBcsdf`]), with their parameters.
//!
//! - **Simple** [W19 eq. 5] + diffuse: `k_d·(2/π)(1/2π)` (the Kajiya–Kay diffuse term is a
//!   constant BCSDF, `1/π²` for unit energy) plus `k_s` times a Gaussian in θ_h of width β
//!   about 0 with the azimuthal factor `cos(φ/2)` (normalised to `cos(φ/2)/4`). Eq. 5's
//!   unnormalised form has an energy that varies with θ_o; ours integrates to `k_s`.
//! - **Khungurn R + TT** [W19 eq. 6]: `M_R = G(θ_h; −α, β_R)`, `N_R = 1/2π` [eq. 9];
//!   `M_TT = G(θ_h; α/2, β_TT)`, `N_TT` = von Mises about π with `κ = 1/γ_TT²`
//!   (DESIGN §2.3 item 12), plus the diffuse term [W19 §4.3] adds. The longitudinal shifts
//!   (R towards −α, TT towards +α/2, α the cuticle tilt, Marschner's convention) are our
//!   choice; [W19] gives none.
//! - **Huang R + TT + D** [H25 eq. 7]: R and TT as above, D = `(2/π)·N_cyl(φ)` the
//!   Lambertian-cylinder lobe ([`super::azimuthal`]).
//!
//! **Valid ranges** (checked): β ∈ [1°, 60°] (narrower Gaussians in θ_h leave the θ range
//! near the poles faster than the normalisation can follow), γ_TT ∈ [0.5°, 180°],
//! |α| ≤ 10°, colours finite and ≥ 0. No absorption ⇔ the colours sum to 1 per channel.

use super::azimuthal::{Azimuthal, VonMises};
use super::longitudinal::{GaussianLobe, Longitudinal, Normalization};
use super::{FiberBcsdf, Lobe};
use crate::{Error, Result};

const DEG: f64 = std::f64::consts::PI / 180.0;

/// Parameters of the simple model (a).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimpleParams {
    /// Diffuse colour `k_d`.
    pub kd: [f64; 3],
    /// Specular colour `k_s`.
    pub ks: [f64; 3],
    /// Longitudinal width β (radians).
    pub beta: f64,
}

impl Default for SimpleParams {
    fn default() -> Self {
        SimpleParams { kd: [0.7; 3], ks: [0.3; 3], beta: 8.0 * DEG }
    }
}

/// Parameters of the Khungurn model (b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KhungurnParams {
    /// R colour `A_R`.
    pub a_r: [f64; 3],
    /// TT colour `A_TT`.
    pub a_tt: [f64; 3],
    /// Diffuse colour.
    pub kd: [f64; 3],
    /// Widths and tilt of the R and TT lobes.
    pub shape: RtShape,
    /// Normalisation of the Gaussians.
    pub normalization: Normalization,
}

impl Default for KhungurnParams {
    fn default() -> Self {
        KhungurnParams {
            a_r: [0.2; 3],
            a_tt: [0.5; 3],
            kd: [0.3; 3],
            shape: RtShape::default(),
            normalization: Normalization::EnergyConserving,
        }
    }
}

/// The shape of the R and TT lobes shared by models (b) and (c): Gaussian widths in θ_h,
/// the von Mises width of TT about φ = π, and the cuticle tilt that shifts R by `−α` and TT
/// by `+α/2`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RtShape {
    /// R width β_R (radians).
    pub beta_r: f64,
    /// TT width β_TT (radians).
    pub beta_tt: f64,
    /// TT azimuthal width γ_TT (radians).
    pub gamma_tt: f64,
    /// Cuticle tilt α (radians).
    pub tilt: f64,
}

impl Default for RtShape {
    fn default() -> Self {
        RtShape { beta_r: 4.0 * DEG, beta_tt: 12.0 * DEG, gamma_tt: 25.0 * DEG, tilt: 5.0 * DEG }
    }
}

impl RtShape {
    /// The R and TT lobes of colours `a_r`, `a_tt` (checked, with the parameter named).
    fn lobes(&self, a_r: [f64; 3], a_tt: [f64; 3], n: Normalization) -> Result<[Lobe; 2]> {
        check("beta_r", self.beta_r, DEG, 60.0 * DEG)?;
        check("beta_tt", self.beta_tt, DEG, 60.0 * DEG)?;
        check("gamma_tt", self.gamma_tt, 0.5 * DEG, 180.0 * DEG)?;
        check("tilt", self.tilt, -10.0 * DEG, 10.0 * DEG)?;
        check_color("a_r", a_r)?;
        check_color("a_tt", a_tt)?;
        Ok([
            Lobe {
                name: "R",
                color: a_r,
                m: gaussian(self.beta_r, -self.tilt, n),
                n: Azimuthal::Uniform,
            },
            Lobe {
                name: "TT",
                color: a_tt,
                m: gaussian(self.beta_tt, 0.5 * self.tilt, n),
                n: Azimuthal::VonMises(VonMises::new(self.gamma_tt)),
            },
        ])
    }
}

/// Parameters of the Huang model (c).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HuangParams {
    /// R colour.
    pub a_r: [f64; 3],
    /// TT colour.
    pub a_tt: [f64; 3],
    /// D (diffuse cylinder) colour.
    pub a_d: [f64; 3],
    /// Widths and tilt of the R and TT lobes.
    pub shape: RtShape,
}

impl Default for HuangParams {
    fn default() -> Self {
        HuangParams { a_r: [0.15; 3], a_tt: [0.45; 3], a_d: [0.4; 3], shape: RtShape::default() }
    }
}

fn check(name: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Error::Invalid(format!(
            "bcsdf: {name} = {v} rad ({:.3}°) outside [{:.3}°, {:.3}°]",
            v / DEG,
            lo / DEG,
            hi / DEG
        )))
    }
}

fn check_color(name: &str, c: [f64; 3]) -> Result<()> {
    if c.iter().all(|x| x.is_finite() && *x >= 0.0) {
        Ok(())
    } else {
        Err(Error::Invalid(format!("bcsdf: colour {name} = {c:?} must be finite and ≥ 0")))
    }
}

fn gaussian(beta: f64, shift: f64, n: Normalization) -> Longitudinal {
    Longitudinal::Gaussian(GaussianLobe::new(beta, shift, n))
}

impl FiberBcsdf {
    /// Model (a): [W19 eq. 5] + diffuse.
    pub fn simple(p: &SimpleParams) -> Result<Self> {
        check("beta", p.beta, DEG, 60.0 * DEG)?;
        check_color("kd", p.kd)?;
        check_color("ks", p.ks)?;
        Ok(FiberBcsdf {
            lobes: vec![
                Lobe {
                    name: "diffuse",
                    color: p.kd,
                    m: Longitudinal::Constant,
                    n: Azimuthal::Uniform,
                },
                Lobe {
                    name: "specular",
                    color: p.ks,
                    m: gaussian(p.beta, 0.0, Normalization::EnergyConserving),
                    n: Azimuthal::HalfCos,
                },
            ],
        })
    }

    /// Model (b): Khungurn R + TT [W19 eq. 6–10] + diffuse.
    pub fn khungurn(p: &KhungurnParams) -> Result<Self> {
        check_color("kd", p.kd)?;
        let [r, tt] = p.shape.lobes(p.a_r, p.a_tt, p.normalization)?;
        let diffuse =
            Lobe { name: "diffuse", color: p.kd, m: Longitudinal::Constant, n: Azimuthal::Uniform };
        Ok(FiberBcsdf { lobes: vec![r, tt, diffuse] })
    }

    /// Model (c): R + TT + D for [H25 eq. 7].
    pub fn huang(p: &HuangParams) -> Result<Self> {
        check_color("a_d", p.a_d)?;
        let [r, tt] = p.shape.lobes(p.a_r, p.a_tt, Normalization::EnergyConserving)?;
        let d = Lobe { name: "D", color: p.a_d, m: Longitudinal::Constant, n: Azimuthal::Cylinder };
        Ok(FiberBcsdf { lobes: vec![r, tt, d] })
    }
}
