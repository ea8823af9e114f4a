//! Reading and writing environment maps: users' `.hdr` (Radiance RGBE, through the `image`
//! crate) and `.exr` (through `exr`) load into the same [`EnvMap`]; non-finite or negative
//! pixels, wrong aspect ratios and absurd sizes are refused with an error naming the file
//! (and the pixel). EXR output is written to a temporary file and renamed into place.

use super::EnvMap;
use crate::{Error, Result};
use std::path::Path;

/// Largest accepted map (pixels), checked before the pixel data is allocated.
pub const MAX_PIXELS: usize = 1 << 27;

fn check_pixels(path: &Path, m: &EnvMap) -> Result<()> {
    for (i, p) in m.pixels.iter().enumerate() {
        if let Some(c) =
            p.iter().position(|v| !v.is_finite() || *v < 0.0 || *v > btf_core::MAX_RADIANCE)
        {
            let what = if !p[c].is_finite() {
                "non-finite"
            } else if p[c] < 0.0 {
                "negative"
            } else {
                "beyond the radiance limit of 1e12 (btf_core::MAX_RADIANCE):"
            };
            return Err(Error::Invalid(format!(
                "{}: {what} value {} at pixel x={}, y={}, channel {}",
                path.display(),
                p[c],
                i % m.width,
                i / m.width,
                ["R", "G", "B"][c]
            )));
        }
    }
    Ok(())
}

fn check_size(path: &Path, w: usize, h: usize) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_PIXELS {
        return Err(Error::Invalid(format!(
            "{}: {w}x{h} pixels is empty or beyond {MAX_PIXELS}",
            path.display()
        )));
    }
    if w != 2 * h {
        return Err(Error::Invalid(format!(
            "{}: {w}x{h} is not an equirectangular (2:1) environment map",
            path.display()
        )));
    }
    Ok(())
}

/// Loads an equirectangular `.hdr` or `.exr` environment map (linear RGB).
pub fn load_env(path: &Path) -> Result<EnvMap> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let img_err = |what: String| Error::Image { path: path.to_owned(), what };
    let map = match ext.as_str() {
        "exr" => {
            let meta = exr::meta::MetaData::read_from_file(path, false)
                .map_err(|e| img_err(e.to_string()))?;
            let size = meta
                .headers
                .first()
                .map(|h| h.layer_size)
                .ok_or_else(|| img_err("no layer".into()))?;
            check_size(path, size.width(), size.height())?;
            for h in &meta.headers {
                check_size(path, h.layer_size.width(), h.layer_size.height())?;
            }
            // Rows are allocated as they are decoded: a small file claiming a large map
            // costs what it holds, not what its header claims.
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
            let pixels = img.layer_data.channel_data.pixels.into_vec().map_err(|y| {
                Error::Invalid(format!("{}: pixel row {y} is missing", path.display()))
            })?;
            EnvMap { width: size.width(), height: size.height(), pixels }
        }
        "hdr" => {
            let reader = image::ImageReader::open(path).map_err(|e| Error::io(path, e))?;
            let reader = reader.with_guessed_format().map_err(|e| Error::io(path, e))?;
            let (w, h) = reader.into_dimensions().map_err(|e| img_err(e.to_string()))?;
            check_size(path, w as usize, h as usize)?;
            let img = image::ImageReader::open(path)
                .map_err(|e| Error::io(path, e))?
                .with_guessed_format()
                .map_err(|e| Error::io(path, e))?
                .decode()
                .map_err(|e| img_err(e.to_string()))?
                .into_rgb32f();
            let pixels = img.pixels().map(|p| p.0).collect();
            EnvMap { width: w as usize, height: h as usize, pixels }
        }
        _ => {
            return Err(Error::Unsupported(format!(
                "{}: environment maps must be .hdr or .exr",
                path.display()
            )));
        }
    };
    check_size(path, map.width, map.height)?;
    check_pixels(path, &map)?;
    Ok(map)
}

/// Writes `map` as a 32-bit float RGB EXR, atomically (temporary file + rename).
pub fn write_exr(map: &EnvMap, path: &Path) -> Result<()> {
    check_pixels(path, map)?;
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let v = map.pixels[p.1 * map.width + p.0];
        (v[0], v[1], v[2])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_channels((map.width, map.height), channels)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| Error::Image { path: path.to_owned(), what: e.to_string() })?;
    Ok(btf_core::fs::write_atomic(path, bytes.get_ref())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_and_bad_pixels_named() {
        let dir = tempfile::tempdir().unwrap();
        let mut m = EnvMap::from_fn(32, |d| [d[2].max(0.0) * 1e5, 1.0, 1e-4]).unwrap();
        let p = dir.path().join("a.exr");
        write_exr(&m, &p).unwrap();
        assert_eq!(load_env(&p).unwrap(), m);
        // A NaN written by another tool is refused on load, naming file and pixel.
        m.pixels[3 * 32 + 5][1] = f32::NAN;
        let bad = dir.path().join("bad.exr");
        exr::prelude::write_rgb_file(&bad, 32, 16, |x, y| {
            let p = m.pixels[y * 32 + x];
            (p[0], p[1], p[2])
        })
        .unwrap();
        let e = load_env(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.exr") && e.contains("x=5, y=3") && e.contains("non-finite"), "{e}");
        // Writing it is refused too, and nothing is left behind.
        assert!(write_exr(&m, &dir.path().join("c.exr")).is_err());
        assert!(!dir.path().join("c.exr").exists());
        // Radiance .hdr files load through the image crate.
        let ok = EnvMap::from_fn(32, |_| [0.5, 2.0, 8.0]).unwrap();
        let hdr = dir.path().join("a.hdr");
        let buf: Vec<image::Rgb<f32>> = ok.pixels.iter().map(|p| image::Rgb(*p)).collect();
        let f = std::fs::File::create(&hdr).unwrap();
        image::codecs::hdr::HdrEncoder::new(f).encode(&buf, 32, 16).unwrap();
        let back = load_env(&hdr).unwrap();
        assert_eq!((back.width, back.height, back.pixels[40]), (32, 16, [0.5, 2.0, 8.0]));
        let e = load_env(&dir.path().join("missing.hdr")).unwrap_err().to_string();
        assert!(e.contains("missing.hdr"), "{e}");
    }
}
