//! Equirectangular environment maps: the `L_env` of image-based lighting `[S03 eq. 9–10]`,
//! loaded from users' `.hdr` (Radiance RGBE) and `.exr` files or generated procedurally,
//! written as EXR. This is the toolkit's only environment-map type: `btf demo`, `btf
//! render`, `btf relight`, `btf view` and the synthetic environments all take the same
//! files with the same checks.
//!
//! **Convention.** World `+z` is up. Pixel `(col, row)` of a `W × H` map covers the polar
//! angle `θ ∈ [π·row/H, π·(row+1)/H]` from `+z` (row 0 touches the zenith, the last row the
//! nadir) and the longitude `φ ∈ [2π·col/W, 2π·(col+1)/W]` measured from `+x` towards `+y`;
//! its centre direction is `(sin θ cos φ, sin θ sin φ, cos θ)` and its solid angle
//! `(2π/W)(cos θ_top − cos θ_bottom)` (they sum to 4π). Values are linear Rec. 709 RGB
//! radiance.
//!
//! **Only 2:1 maps.** An equirectangular map spans 2π in longitude and π in latitude, so
//! its pixels are square only when `W = 2H`. A map of another aspect is almost always a
//! cube-cross, a mirror ball or a cropped panorama read as if it were equirectangular,
//! which would light the scene from the wrong directions without any visible error — so it
//! is refused, naming the file and its size, rather than silently stretched.
//!
//! **Hard cases.** Sizes are checked against [`MAX_PIXELS`] from the header, before
//! anything is allocated (EXR rows are allocated as they are decoded, so a small file
//! claiming a huge map costs only what it holds). Non-finite, negative and absurd values
//! (above `btf_core::MAX_RADIANCE`) are refused with the file, pixel and channel named.
//! Integrals are summed in `f64`, so maps near the limit do not overflow.

use crate::{Error, Result};
use std::f64::consts::PI;
use std::path::Path;

/// Largest accepted map (pixels), checked before the pixel data is allocated.
pub const MAX_PIXELS: usize = 1 << 27;

/// An equirectangular map of linear RGB radiance (see the module docs for the convention).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    /// Pixels per row (`2 × height`).
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major pixels `[row][col]`, top (zenith) row first.
    pub pixels: Vec<[f32; 3]>,
}

impl EnvMap {
    /// A map from pixels. Refuses a pixel count that does not match the size, a map that is
    /// not 2:1, and non-finite, negative or absurd values (`name` is used in errors).
    pub fn new(width: usize, height: usize, pixels: Vec<[f32; 3]>, name: &str) -> Result<EnvMap> {
        check_size(name, width, height)?;
        if width.saturating_mul(height) != pixels.len() {
            return Err(Error::Invalid(format!(
                "{name}: {width}×{height} map with {} pixels",
                pixels.len()
            )));
        }
        let map = EnvMap { width, height, pixels };
        map.check_pixels(name)?;
        Ok(map)
    }

    /// A `width × width/2` map of constant radiance.
    pub fn constant(width: usize, rgb: [f32; 3]) -> Result<EnvMap> {
        EnvMap::new(width, width / 2, vec![rgb; width * (width / 2)], "constant environment")
    }

    /// A `width × width/2` map with `radiance(direction)` evaluated at every pixel centre
    /// (in parallel); negative values are clamped to 0. `width` must be even, 8…32768.
    pub fn from_fn(width: usize, radiance: impl Fn([f64; 3]) -> [f64; 3] + Sync) -> Result<Self> {
        use rayon::prelude::*;
        if !(8..=32768).contains(&width) || !width.is_multiple_of(2) {
            return Err(Error::Invalid(format!(
                "environment width {width} must be even and in 8..=32768"
            )));
        }
        let h = width / 2;
        let pixels = (0..width * h)
            .into_par_iter()
            .map(|i| {
                radiance(pixel_direction(width, h, i % width, i / width)).map(|c| c.max(0.0) as f32)
            })
            .collect();
        EnvMap::new(width, h, pixels, "generated environment")
    }

    /// Loads an equirectangular `.hdr` or `.exr` file (linear RGB; EXR's first RGBA layer).
    pub fn load(path: &Path) -> Result<EnvMap> {
        let name = path.display().to_string();
        let (w, h, pixels) = read_linear_rgb(path)?;
        EnvMap::new(w, h, pixels, &name)
    }

    /// Writes the map as a 32-bit float RGB EXR, atomically.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        self.check_pixels(&path.display().to_string())?;
        let rgb: Vec<f32> = self.pixels.iter().flatten().copied().collect();
        crate::write::write_exr_rgb(path, self.width, self.height, &rgb)
    }

    /// The unit direction of the centre of pixel `(col, row)`.
    pub fn direction(&self, col: usize, row: usize) -> [f64; 3] {
        pixel_direction(self.width, self.height, col, row)
    }

    /// The pixel `(col, row)` containing unit direction `d`.
    pub fn pixel_of(&self, d: [f64; 3]) -> (usize, usize) {
        let theta = d[2].clamp(-1.0, 1.0).acos();
        let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
        let row = ((theta / PI * self.height as f64) as usize).min(self.height - 1);
        let col = ((phi / (2.0 * PI) * self.width as f64) as usize).min(self.width - 1);
        (col, row)
    }

    /// Solid angle (sr) of a pixel in `row`.
    pub fn pixel_solid_angle(&self, row: usize) -> f64 {
        let (t0, t1) =
            (PI * row as f64 / self.height as f64, PI * (row + 1) as f64 / self.height as f64);
        2.0 * PI / self.width as f64 * (t0.cos() - t1.cos())
    }

    /// `∫ L dω` per channel over the sphere (pixel sums weighted by solid angle, in `f64`).
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

    /// Irradiance `E = ∫ L max(0, n·ω) dω` per channel on a surface with unit normal `n`
    /// (pixel-centre quadrature, `f64`).
    pub fn irradiance(&self, n: [f64; 3]) -> [f64; 3] {
        let mut e = [0.0; 3];
        for row in 0..self.height {
            let om = self.pixel_solid_angle(row);
            for col in 0..self.width {
                let d = self.direction(col, row);
                let c = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
                if c <= 0.0 {
                    continue;
                }
                let p = self.pixels[row * self.width + col];
                (0..3).for_each(|k| e[k] += p[k] as f64 * c * om);
            }
        }
        e
    }

    /// The exposure `1 / E_h` that gives a horizontal surface (normal `+z`) unit irradiance,
    /// `E_h` the mean of the channels of [`EnvMap::irradiance`]; 1 for a black upper
    /// hemisphere.
    pub fn unit_irradiance_exposure(&self) -> f64 {
        let e = self.irradiance([0.0, 0.0, 1.0]);
        let mean = (e[0] + e[1] + e[2]) / 3.0;
        if mean > 0.0 { 1.0 / mean } else { 1.0 }
    }

    fn check_pixels(&self, name: &str) -> Result<()> {
        for (i, p) in self.pixels.iter().enumerate() {
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
                    i % self.width,
                    i / self.width,
                    ["R", "G", "B"][c],
                    p[c]
                )));
            }
        }
        Ok(())
    }
}

/// Refuses empty, oversized (before allocating) and non-2:1 maps, naming the file.
/// Reads a linear RGB image (`.exr`: the first RGBA layer; `.hdr`) of at most
/// `MAX_PIXELS` pixels, any aspect: `(width, height, pixels)`, rows top first. Headers are
/// checked before anything is allocated; rows are allocated as they are decoded.
pub fn read_linear_rgb(path: &Path) -> Result<(usize, usize, Vec<[f32; 3]>)> {
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
                check_pixels(&name, h.layer_size.width(), h.layer_size.height())?;
                crate::exr_limits::check_header(h)
                    .map_err(|(field, what)| Error::Limit(format!("{name}: {field}: {what}")))?;
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
                .map_err(|y| Error::Invalid(format!("{name}: pixel row {y} is missing")))?;
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
            check_pixels(&name, w as usize, h as usize)?;
            let img = open()?.decode().map_err(|e| img_err(e.to_string()))?.into_rgb32f();
            (w as usize, h as usize, img.pixels().map(|p| p.0).collect())
        }
        _ => {
            return Err(Error::Unsupported(format!("{name}: linear images must be .hdr or .exr")));
        }
    };
    Ok((w, h, pixels))
}

fn check_pixels(name: &str, w: usize, h: usize) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::Limit(format!(
            "{name}: {w}×{h} pixels is empty or beyond {MAX_PIXELS}"
        )));
    }
    Ok(())
}

fn check_size(name: &str, w: usize, h: usize) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::Limit(format!(
            "{name}: {w}×{h} pixels is empty or beyond {MAX_PIXELS}"
        )));
    }
    if w != 2 * h {
        return Err(Error::Invalid(format!(
            "{name}: {w}×{h} is not an equirectangular (2:1) environment map"
        )));
    }
    Ok(())
}

fn pixel_direction(w: usize, h: usize, col: usize, row: usize) -> [f64; 3] {
    let theta = PI * (row as f64 + 0.5) / h as f64;
    let phi = 2.0 * PI * (col as f64 + 0.5) / w as f64;
    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angles_sum_to_the_sphere_and_pixels_round_trip() {
        let m = EnvMap::constant(64, [1.0; 3]).unwrap();
        assert!((m.integral()[0] - 4.0 * PI).abs() < 1e-9);
        for (col, row) in [(0, 0), (17, 5), (63, 31)] {
            assert_eq!(m.pixel_of(m.direction(col, row)), (col, row));
        }
        // A constant sky of radiance L gives a horizontal surface E = πL (the quadrature
        // error of pixel centres is O(1/H²)).
        let e = m.irradiance([0.0, 0.0, 1.0])[0];
        assert!((e / PI - 1.0).abs() < 2e-3, "{e}");
        assert!((m.unit_irradiance_exposure() * e - 1.0).abs() < 1e-12);
        // Tilted normals see the same constant sky.
        let e45 = m.irradiance([0.0, 0.6, 0.8])[1];
        assert!((e45 / PI - 1.0).abs() < 5e-3, "{e45}");
    }

    #[test]
    fn bad_maps_are_refused_and_named() {
        let mut px = vec![[1.0f32; 3]; 32];
        px[9][2] = f32::NAN;
        let e = EnvMap::new(8, 4, px.clone(), "sky.exr").unwrap_err().to_string();
        assert!(e.contains("sky.exr") && e.contains("x=1, y=1") && e.contains("non-finite"), "{e}");
        px[9][2] = -1.0;
        let e = EnvMap::new(8, 4, px.clone(), "sky.exr").unwrap_err().to_string();
        assert!(e.contains("negative"), "{e}");
        px[9][2] = 3e38;
        let e = EnvMap::new(8, 4, px, "sky.exr").unwrap_err().to_string();
        assert!(e.contains("radiance limit"), "{e}");
        assert!(EnvMap::new(8, 4, vec![[0.0; 3]; 3], "x").is_err());
        let e = EnvMap::new(8, 8, vec![[0.0; 3]; 64], "cube.hdr").unwrap_err().to_string();
        assert!(e.contains("cube.hdr") && e.contains("8×8") && e.contains("2:1"), "{e}");
        let e = EnvMap::new(1 << 16, 1 << 15, vec![], "huge.exr").unwrap_err();
        assert!(matches!(e, Error::Limit(_)), "{e}");
    }

    #[test]
    fn exr_and_hdr_round_trip_and_bad_files_named() {
        let dir = tempfile::tempdir().unwrap();
        let mut m = EnvMap::from_fn(32, |d| [d[2].max(0.0) * 1e5, 1.0, 1e-4]).unwrap();
        let p = dir.path().join("a.exr");
        m.write_exr(&p).unwrap();
        assert_eq!(EnvMap::load(&p).unwrap(), m);
        // A NaN written by another tool is refused on load, naming file and pixel.
        m.pixels[3 * 32 + 5][1] = f32::NAN;
        let bad = dir.path().join("bad.exr");
        exr::prelude::write_rgb_file(&bad, 32, 16, |x, y| {
            let p = m.pixels[y * 32 + x];
            (p[0], p[1], p[2])
        })
        .unwrap();
        let e = EnvMap::load(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.exr") && e.contains("x=5, y=3") && e.contains("non-finite"), "{e}");
        // Writing it is refused too, and nothing is left behind.
        assert!(m.write_exr(&dir.path().join("c.exr")).is_err());
        assert!(!dir.path().join("c.exr").exists());
        // Radiance .hdr files load through the image crate; non-2:1 ones are refused.
        let ok = EnvMap::from_fn(32, |_| [0.5, 2.0, 8.0]).unwrap();
        let hdr = dir.path().join("a.hdr");
        let buf: Vec<image::Rgb<f32>> = ok.pixels.iter().map(|p| image::Rgb(*p)).collect();
        let f = std::fs::File::create(&hdr).unwrap();
        image::codecs::hdr::HdrEncoder::new(f).encode(&buf, 32, 16).unwrap();
        let back = EnvMap::load(&hdr).unwrap();
        assert_eq!((back.width, back.height, back.pixels[40]), (32, 16, [0.5, 2.0, 8.0]));
        let square = dir.path().join("square.hdr");
        let f = std::fs::File::create(&square).unwrap();
        image::codecs::hdr::HdrEncoder::new(f).encode(&buf[..256], 16, 16).unwrap();
        let e = EnvMap::load(&square).unwrap_err().to_string();
        assert!(e.contains("square.hdr") && e.contains("2:1"), "{e}");
        let e = EnvMap::load(&dir.path().join("missing.hdr")).unwrap_err().to_string();
        assert!(e.contains("missing.hdr"), "{e}");
        let e = EnvMap::load(&dir.path().join("x.png")).unwrap_err().to_string();
        assert!(e.contains(".hdr or .exr"), "{e}");
    }
}
