//! Procedural HDR environments: a physical sky, a photo studio, a room interior, as
//! [`EnvMap`]s (the one map type of `btf_image`, whose docs give the equirectangular
//! convention: `+z` up, row 0 at the zenith, longitude from `+x` toward `+y`). Values are
//! linear Rec. 709 RGB radiance in kcd/m² (a clear sky is ~1–10, the sun ~1e5–1e6).

pub mod indoor;
pub mod sky;

use crate::{Error, Result};
pub use btf_image::EnvMap;

/// The procedural environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EnvKind {
    /// Preetham daylight sky with the sun disc and a diffuse ground.
    Sky,
    /// Dark photo studio with four soft boxes.
    Studio,
    /// A room with a window (showing the sky), a ceiling lamp and walls.
    Interior,
}

impl EnvKind {
    /// Parses `sky`, `studio` or `interior`.
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "sky" => Ok(EnvKind::Sky),
            "studio" => Ok(EnvKind::Studio),
            "interior" => Ok(EnvKind::Interior),
            other => Err(Error::Invalid(format!(
                "unknown environment kind '{other}' (known: sky, studio, interior)"
            ))),
        }
    }
}

/// Parameters of a procedural environment.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnvParams {
    /// Sun elevation above the horizon, degrees (sky and interior).
    pub sun_elevation_deg: f64,
    /// Sun azimuth from `+x` towards `+y`, degrees.
    pub sun_azimuth_deg: f64,
    /// Atmospheric turbidity (2 = very clear … 10 = hazy), Preetham's valid range.
    pub turbidity: f64,
}

impl Default for EnvParams {
    fn default() -> Self {
        EnvParams { sun_elevation_deg: 35.0, sun_azimuth_deg: 30.0, turbidity: 3.0 }
    }
}

/// Synthesises an environment map of `width × width/2` pixels.
pub fn synth_env(kind: EnvKind, params: &EnvParams, width: usize) -> Result<EnvMap> {
    match kind {
        EnvKind::Sky => sky::SkyModel::new(params)?.render(width),
        EnvKind::Studio => indoor::studio(width),
        EnvKind::Interior => indoor::interior(params, width),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use std::f64::consts::PI;

    #[test]
    fn solid_angles_sum_to_4pi_and_pixel_lookup_inverts_direction() {
        let m = EnvMap::from_fn(64, |_| [1.0; 3]).unwrap();
        let s = m.integral();
        assert!((s[0] - 4.0 * PI).abs() < 1e-9, "{s:?}");
        for &(c, r) in &[(0, 0), (17, 9), (63, 31)] {
            assert_eq!(m.pixel_of(m.direction(c, r)), (c, r));
        }
        // Row 0 is around the zenith, column 16 of 64 looks along +y.
        assert!(m.direction(0, 0)[2] > 0.99);
        let d = m.direction(16, 16);
        assert!(d[1] > 0.99 && d[0].abs() < 0.1, "{d:?}");
    }
}
