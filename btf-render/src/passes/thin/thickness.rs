//! The optical thickness of a thin-cloth material per texel (`[TC eq. 7–9]` read `τ₁` per
//! fragment): a constant, the luminance of the BTF's frontal mean texture, or a grey image;
//! and the slab parameters of its environment tables (`btf_light::thin_tables`).

use crate::material::MaterialData;
use crate::scene::{TauTexture, TransmissionDesc};
use crate::{Error, Result};
use btf_light::thin_tables::SlabParams;
use half::f16;

/// The τ texture of a material (1×1 of ones without `tau_texture`): width, height, texels.
pub(crate) fn tau_texels(
    desc: &TransmissionDesc,
    data: &MaterialData,
) -> Result<(u32, u32, Vec<f16>)> {
    Ok(match &desc.tau_texture {
        None => (1, 1, vec![f16::ONE]),
        Some(TauTexture::BtfMean) => btf_mean_thickness(data),
        Some(TauTexture::Image(p)) => image_thickness(p)?,
    })
}

/// Luminance of the frontal view slot's mean texture, divided by its average (all ones
/// for a black mean).
pub(crate) fn btf_mean_thickness(data: &MaterialData) -> (u32, u32, Vec<f16>) {
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
pub(crate) fn image_thickness(path: &std::path::Path) -> Result<(u32, u32, Vec<f16>)> {
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
pub(crate) fn slab_params(desc: &TransmissionDesc, max_texel: f32) -> SlabParams {
    let textured = desc.tau_texture.is_some();
    let scale = if textured { max_texel.max(1.0) as f64 } else { 1.0 };
    SlabParams {
        tau: desc.tau as f64 * scale,
        textured,
        albedo: desc.albedo.rgb().map(|a| a as f64),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Albedo, PhaseDesc};

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
