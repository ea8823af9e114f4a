//! Environment maps for image-based lighting (Sattler et al. 2003, §5.3, the `L_env` of
//! eq. 9–10): equirectangular linear HDR images loaded from `.hdr`/`.exr`, and their
//! filtered cube-map form that the hemicube pixels look up.
//!
//! Convention (shared with the `datasets` crate): world `+z` is up; pixel `(col, row)` of a
//! `W × H` map covers `θ ∈ [π·row/H, π·(row+1)/H]` from `+z` and `φ ∈ [2π·col/W, …]` from
//! `+x` towards `+y`. Non-finite and negative pixels are refused, naming file and pixel.
//!
//! Filtering. A hemicube pixel stands for `~(2/res)²` sr; a sun of 1e-5 sr must neither be
//! missed (aliasing: it falls between pixel centres) nor counted twice. Rather than looking
//! the map up at pixel centres, [`EnvCube::new`] bins it into cube texels about as large as
//! the hemicube pixels, each kept as a directional source carrying the texel's exact power
//! `Σ L dω` at the power-weighted centroid of its directions; the gather then drops every
//! source into the one hemicube pixel it falls in. Energy is conserved exactly, a sun keeps
//! its direction, and what remains is the hemicube's own quantisation of directions.
//!

use crate::{Error, Result};
use std::f64::consts::PI;
use std::path::Path;

/// Largest accepted map (pixels), checked before allocating.
pub const MAX_PIXELS: usize = 1 << 27;

/// An equirectangular map of linear RGB radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major pixels.
    pub pixels: Vec<[f32; 3]>,
}

impl EnvMap {
    /// A map from pixels; refuses sizes that do not match and non-finite or negative values
    /// (`name` is used in errors).
    pub fn new(width: usize, height: usize, pixels: Vec<[f32; 3]>, name: &str) -> Result<EnvMap> {
        if width == 0 || height == 0 || width.saturating_mul(height) != pixels.len() {
            return Err(Error::Invalid(format!(
                "{name}: {width}×{height} map with {} pixels",
                pixels.len()
            )));
        }
        for (i, p) in pixels.iter().enumerate() {
            if let Some(c) =
                p.iter().position(|v| !v.is_finite() || *v < 0.0 || *v > btf_core::MAX_RADIANCE)
            {
                let what = if !p[c].is_finite() {
                    "non-finite"
                } else if p[c] < 0.0 {
                    "negative"
                } else {
                    "beyond the radiance limit of 1e12 (btf_core::MAX_RADIANCE)"
                };
                return Err(Error::Invalid(format!(
                    "{name}: environment pixel x={}, y={} channel {} is {what} ({}); environment maps must hold finite radiance ≥ 0",
                    i % width,
                    i / width,
                    ["R", "G", "B"][c],
                    p[c]
                )));
            }
        }
        Ok(EnvMap { width, height, pixels })
    }

    /// A map of constant radiance.
    pub fn constant(width: usize, rgb: [f32; 3]) -> Result<EnvMap> {
        EnvMap::new(width, width / 2, vec![rgb; width * (width / 2)], "constant environment")
    }

    /// Evaluates `radiance(direction)` at every pixel centre.
    pub fn from_fn(width: usize, radiance: impl Fn([f64; 3]) -> [f32; 3]) -> Result<EnvMap> {
        let h = width / 2;
        let pixels =
            (0..width * h).map(|i| radiance(pixel_dir(width, h, i % width, i / width))).collect();
        EnvMap::new(width, h, pixels, "generated environment")
    }

    /// Loads an `.hdr` or `.exr` file.
    pub fn load(path: &Path) -> Result<EnvMap> {
        let name = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let img_err = |what: String| Error::Image { path: path.to_owned(), what };
        let (w, h, pixels) = match ext.as_str() {
            "exr" => {
                let meta = exr::meta::MetaData::read_from_file(path, false)
                    .map_err(|e| img_err(e.to_string()))?;
                if meta.headers.is_empty() {
                    return Err(img_err("no layer".into()));
                }
                for h in &meta.headers {
                    check_size(&name, h.layer_size.width(), h.layer_size.height())?;
                }
                // Rows are allocated as they are decoded: a small file claiming a large
                // map costs what it holds, not what its header claims.
                let img = exr::prelude::read_first_rgba_layer_from_file(
                    path,
                    |res, _| btf_core::memory::LazyRows::<[f32; 3]>::new(res.width(), res.height()),
                    |m: &mut btf_core::memory::LazyRows<[f32; 3]>,
                     pos,
                     (r, g, b, _a): (f32, f32, f32, f32)| {
                        m.set(pos.x(), pos.y(), [r, g, b])
                    },
                )
                .map_err(|e| img_err(e.to_string()))?;
                let size = img.layer_data.size;
                let pixels = img
                    .layer_data
                    .channel_data
                    .pixels
                    .into_vec()
                    .map_err(|y| img_err(format!("pixel row {y} is missing")))?;
                (size.width(), size.height(), pixels)
            }
            "hdr" => {
                let open = || {
                    image::ImageReader::open(path)
                        .map_err(|e| Error::io(path, e))?
                        .with_guessed_format()
                        .map_err(|e| Error::io(path, e))
                };
                let (w, h) = open()?.into_dimensions().map_err(|e| img_err(e.to_string()))?;
                check_size(&name, w as usize, h as usize)?;
                let img = open()?.decode().map_err(|e| img_err(e.to_string()))?.into_rgb32f();
                (w as usize, h as usize, img.pixels().map(|p| p.0).collect())
            }
            _ => {
                return Err(Error::Unsupported(format!(
                    "{name}: environment maps must be .hdr or .exr"
                )));
            }
        };
        EnvMap::new(w, h, pixels, &name)
    }

    /// Solid angle of a pixel in `row`.
    pub fn pixel_solid_angle(&self, row: usize) -> f64 {
        let (t0, t1) =
            (PI * row as f64 / self.height as f64, PI * (row + 1) as f64 / self.height as f64);
        2.0 * PI / self.width as f64 * (t0.cos() - t1.cos())
    }

    /// `∫ L dω` per channel.
    pub fn integral(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        for (i, p) in self.pixels.iter().enumerate() {
            let w = self.pixel_solid_angle(i / self.width);
            (0..3).for_each(|c| s[c] += p[c] as f64 * w);
        }
        s
    }
}

fn check_size(name: &str, w: usize, h: usize) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::Limit(format!(
            "{name}: {w}×{h} pixels is empty or beyond {MAX_PIXELS}"
        )));
    }
    Ok(())
}

fn pixel_dir(w: usize, h: usize, col: usize, row: usize) -> [f64; 3] {
    let theta = PI * (row as f64 + 0.5) / h as f64;
    let phi = 2.0 * PI * (col as f64 + 0.5) / w as f64;
    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
}

/// Face and face coordinates `(a, b) ∈ [−1, 1]²` of a direction on the unit cube.
fn cube_coords(d: [f32; 3]) -> (usize, f32, f32) {
    let [x, y, z] = d;
    let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
    if ax >= ay && ax >= az {
        let m = ax.max(f32::MIN_POSITIVE);
        (if x > 0.0 { 0 } else { 1 }, y / m, z / m)
    } else if ay >= az {
        (if y > 0.0 { 2 } else { 3 }, x / ay, z / ay)
    } else {
        (if z > 0.0 { 4 } else { 5 }, x / az, y / az)
    }
}

/// An environment binned into the texels of a cube map, each kept as a directional
/// source: its power `Σ L dω` (exact: every pixel lands in exactly one texel) at the
/// power-weighted centroid of its directions. Texels without power are dropped.
#[derive(Debug, Clone)]
pub struct EnvCube {
    /// Texels per face side.
    pub res: usize,
    /// Unit direction of every kept texel (world, before rotation).
    pub dirs: Vec<[f32; 3]>,
    /// RGB power `∫ L dω` of every kept texel, W·sr-normalised radiance units × sr.
    pub power: Vec<[f32; 3]>,
}

impl EnvCube {
    /// Bins `env` into `6 res²` cube texels. Each pixel is split into `s × s` parts
    /// (`s = ⌈4 res / H⌉`) so a coarse map still spreads over the texels it covers.
    pub fn new(env: &EnvMap, res: usize) -> EnvCube {
        let res = res.max(1);
        let s = (4 * res).div_ceil(env.height).clamp(1, 32);
        let (w, h) = (env.width * s, env.height * s);
        let cols: Vec<(f64, f64)> =
            (0..w).map(|c| (2.0 * PI * (c as f64 + 0.5) / w as f64).sin_cos()).collect();
        // Per texel: RGB power, then the luminance-power-weighted direction sum.
        let mut acc = vec![[0f64; 6]; 6 * res * res];
        for row in 0..h {
            let (t0, t1) = (PI * row as f64 / h as f64, PI * (row + 1) as f64 / h as f64);
            let om = 2.0 * PI / w as f64 * (t0.cos() - t1.cos());
            let (st, ct) = (PI * (row as f64 + 0.5) / h as f64).sin_cos();
            let src = &env.pixels[row / s * env.width..(row / s + 1) * env.width];
            for (col, &(sp, cp)) in cols.iter().enumerate() {
                let p = src[col / s];
                let d = [st * cp, st * sp, ct];
                let a = &mut acc[texel_of(res, d.map(|c| c as f32))];
                let lum = (p[0] as f64 + p[1] as f64 + p[2] as f64) * om;
                for c in 0..3 {
                    a[c] += p[c] as f64 * om;
                    a[3 + c] += d[c] * lum;
                }
            }
        }
        let mut cube = EnvCube { res, dirs: vec![], power: vec![] };
        for a in &acc {
            let len = (a[3] * a[3] + a[4] * a[4] + a[5] * a[5]).sqrt();
            if len > 0.0 && a[..3].iter().any(|&x| x > 0.0) {
                cube.dirs.push([a[3], a[4], a[5]].map(|c| (c / len) as f32));
                cube.power.push([a[0] as f32, a[1] as f32, a[2] as f32]);
            }
        }
        cube
    }

    /// Total power per channel (equals [`EnvMap::integral`]).
    pub fn total(&self) -> [f64; 3] {
        let mut t = [0.0; 3];
        for p in &self.power {
            (0..3).for_each(|c| t[c] += p[c] as f64);
        }
        t
    }
}

fn texel_of(res: usize, d: [f32; 3]) -> usize {
    let (face, a, b) = cube_coords(d);
    let i = (((a + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    let j = (((b + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    face * res * res + j * res + i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_pixels_are_refused_and_named() {
        let mut px = vec![[1.0f32; 3]; 32];
        px[9][2] = f32::NAN;
        let e = EnvMap::new(8, 4, px.clone(), "sky.exr").unwrap_err().to_string();
        assert!(e.contains("sky.exr") && e.contains("x=1, y=1") && e.contains("non-finite"), "{e}");
        px[9][2] = -1.0;
        let e = EnvMap::new(8, 4, px, "sky.exr").unwrap_err().to_string();
        assert!(e.contains("negative"), "{e}");
        assert!(EnvMap::new(8, 4, vec![[0.0; 3]; 3], "x").is_err());
    }

    #[test]
    fn cube_keeps_energy_and_finds_the_sun() {
        let sun = [0.6f64, 0.0, 0.8];
        let env = EnvMap::from_fn(256, |d| {
            let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
            [if c > 0.9995 { 1e5 } else { 1.0 }; 3]
        })
        .unwrap();
        for res in [4, 16] {
            let cube = EnvCube::new(&env, res);
            let (got, exact) = (cube.total()[0], env.integral()[0]);
            assert!((got / exact - 1.0).abs() < 1e-5, "{got} vs {exact}");
            // The brightest texel sits at the sun, not at a texel centre.
            let k = (0..cube.power.len())
                .max_by(|&a, &b| cube.power[a][0].total_cmp(&cube.power[b][0]))
                .unwrap();
            let d = cube.dirs[k];
            let cos = d[0] as f64 * sun[0] + d[1] as f64 * sun[1] + d[2] as f64 * sun[2];
            assert!(cos > 0.9995, "res {res}: {d:?}");
        }
        let dark = EnvCube::new(&EnvMap::constant(16, [0.0; 3]).unwrap(), 4);
        assert!(dark.dirs.is_empty());
    }
}
