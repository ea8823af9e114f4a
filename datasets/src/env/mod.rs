//! HDR environment maps: the equirectangular convention, procedural environments (a
//! physical sky, a photo studio, a room interior), EXR output and the loader for users'
//! `.hdr` / `.exr` files.
//!
//! **Convention.** World `+z` is up. Pixel `(col, row)` of a `W × H` map (`H = W/2`) covers
//! polar angle `θ ∈ [π·row/H, π·(row+1)/H]` from `+z` (row 0 touches the zenith, the last
//! row the nadir) and longitude `φ ∈ [2π·col/W, 2π·(col+1)/W]` measured from `+x` towards
//! `+y`; its centre direction is `(sin θ cos φ, sin θ sin φ, cos θ)` and its solid angle
//! `(2π/W)(cos θ_top − cos θ_bottom)` (they sum to 4π). Values are linear Rec. 709 RGB
//! radiance; the procedural maps use kcd/m² (so a clear sky is ~1–10 and the sun ~1e5–1e6).

pub mod indoor;
pub mod io;
pub mod sky;

pub use io::{load_env, write_exr};

use crate::{Error, Result};
use std::f64::consts::PI;

/// An equirectangular environment map of linear RGB radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    /// Pixels per row.
    pub width: usize,
    /// Rows (`width / 2`).
    pub height: usize,
    /// Row-major pixels `[row][col]`.
    pub pixels: Vec<[f32; 3]>,
}

impl EnvMap {
    /// The unit direction of the centre of pixel `(col, row)`.
    pub fn direction(&self, col: usize, row: usize) -> [f64; 3] {
        let theta = PI * (row as f64 + 0.5) / self.height as f64;
        let phi = 2.0 * PI * (col as f64 + 0.5) / self.width as f64;
        [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
    }

    /// Solid angle (sr) of a pixel in `row`.
    pub fn pixel_solid_angle(&self, row: usize) -> f64 {
        let t0 = PI * row as f64 / self.height as f64;
        let t1 = PI * (row + 1) as f64 / self.height as f64;
        2.0 * PI / self.width as f64 * (t0.cos() - t1.cos())
    }

    /// The pixel `(col, row)` containing unit direction `d`.
    pub fn pixel_of(&self, d: [f64; 3]) -> (usize, usize) {
        let theta = d[2].clamp(-1.0, 1.0).acos();
        let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
        let row = ((theta / PI * self.height as f64) as usize).min(self.height - 1);
        let col = ((phi / (2.0 * PI) * self.width as f64) as usize).min(self.width - 1);
        (col, row)
    }

    /// `∫ L dω` per channel over the sphere (pixel sums weighted by solid angle).
    pub fn integral(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        for row in 0..self.height {
            let w = self.pixel_solid_angle(row);
            for px in &self.pixels[row * self.width..(row + 1) * self.width] {
                (0..3).for_each(|c| s[c] += px[c] as f64 * w);
            }
        }
        s
    }

    /// Fills a map by evaluating `radiance(direction)` at every pixel centre.
    pub fn from_fn(width: usize, radiance: impl Fn([f64; 3]) -> [f64; 3] + Sync) -> Result<Self> {
        use rayon::prelude::*;
        check_width(width)?;
        let mut m =
            EnvMap { width, height: width / 2, pixels: vec![[0.0; 3]; width * (width / 2)] };
        let dirs: Vec<[f64; 3]> =
            (0..m.pixels.len()).map(|i| m.direction(i % width, i / width)).collect();
        m.pixels
            .par_iter_mut()
            .zip(dirs.par_iter())
            .for_each(|(p, &d)| *p = radiance(d).map(|c| c.max(0.0) as f32));
        Ok(m)
    }
}

fn check_width(width: usize) -> Result<()> {
    if !(8..=32768).contains(&width) || !width.is_multiple_of(2) {
        return Err(Error::Invalid(format!(
            "environment width {width} must be even and in 8..=32768"
        )));
    }
    Ok(())
}

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
    check_width(width)?;
    match kind {
        EnvKind::Sky => sky::SkyModel::new(params)?.render(width),
        EnvKind::Studio => indoor::studio(width),
        EnvKind::Interior => indoor::interior(params, width),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
