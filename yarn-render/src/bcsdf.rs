//! A `yarn::bcsdf::FiberBcsdf` (any lobe sum `Σ A_p M_p N_p`: simple [W19 eq. 5] +
//! diffuse, Khungurn R + TT [W19 eq. 6] + diffuse, R + TT + D [H25 eq. 7]) as lobe records
//! and the Sinkhorn scaling nodes of its energy-conserving Gaussians, for
//! `shaders/fiber_draw.wgsl`, which evaluates exactly what `FiberBcsdf::eval` does (f32).

use crate::{Error, Result};
use yarn::bcsdf::{Azimuthal, FiberBcsdf, Longitudinal, Normalization};

/// One lobe as the shaders read it (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LobeRaw {
    /// Colour `A_p`.
    pub color: [f32; 4],
    /// β, shift, scale of the Gaussian; κ of the von Mises lobe.
    pub shape: [f32; 4],
    /// M kind, N kind, first q node, unused.
    pub kinds: [u32; 4],
    /// von Mises normalisation.
    pub extra: [f32; 4],
}

/// The most lobes a BCSDF may have here.
pub const MAX_LOBES: usize = 8;

/// Lobes and q nodes (256 per Gaussian lobe; one unused node set when there are none).
pub fn pack(b: &FiberBcsdf) -> Result<(Vec<LobeRaw>, Vec<f32>)> {
    if b.lobes.is_empty() || b.lobes.len() > MAX_LOBES {
        return Err(Error::Invalid(format!(
            "fiber BCSDF with {} lobes (1..={MAX_LOBES})",
            b.lobes.len()
        )));
    }
    let mut lobes = Vec::new();
    let mut q = Vec::new();
    for l in &b.lobes {
        let mut raw = LobeRaw {
            color: [l.color[0] as f32, l.color[1] as f32, l.color[2] as f32, 0.0],
            ..Default::default()
        };
        match &l.m {
            Longitudinal::Constant => raw.kinds[0] = 0,
            Longitudinal::Gaussian(g) => {
                raw.kinds[0] = 1;
                raw.shape[0] = g.beta as f32;
                raw.shape[1] = g.shift as f32;
                raw.kinds[2] = q.len() as u32;
                match g.normalization {
                    Normalization::EnergyConserving => {
                        raw.shape[2] = 1.0;
                        q.extend(g.q_nodes().iter().map(|&x| x as f32));
                    }
                    Normalization::Paper => {
                        raw.shape[2] = (1.0 / (g.beta * std::f64::consts::TAU.sqrt())) as f32;
                        q.extend(std::iter::repeat_n(1.0f32, 256));
                    }
                }
            }
        }
        match &l.n {
            Azimuthal::Uniform => raw.kinds[1] = 0,
            Azimuthal::HalfCos => raw.kinds[1] = 1,
            Azimuthal::VonMises(v) => {
                raw.kinds[1] = 2;
                raw.shape[3] = v.kappa as f32;
                raw.extra[0] = v.norm() as f32;
            }
            Azimuthal::Cylinder => raw.kinds[1] = 3,
        }
        lobes.push(raw);
    }
    if q.is_empty() {
        q.resize(256, 1.0);
    }
    Ok((lobes, q))
}
