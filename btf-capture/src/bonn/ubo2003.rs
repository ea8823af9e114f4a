//! UBO2003/ATRIUM image sets: one image per (view, light), in per-view folders or a zip,
//! named with the angles as tags `tlTTT plPPP tvTTT pvPPP` (degrees) anywhere in the name,
//! separated by spaces or underscores, e.g. `tv030_pv030/00008 tl000 pl000 tv030 pv030.jpg`.
//!
//! Images are decoded (JPEG, PNG 8/16-bit, BMP: sRGB, linearised; Radiance `.hdr` and
//! OpenEXR: linear), the view and light directions are mapped onto a sampling
//! ([`super::directions`]) and written into a BTF store. Row 0 of an image is its top row,
//! which is our row 0. A `btf-export.json` beside the images (written by our exporter)
//! supplies a scale that undoes the normalisation applied on export.

use super::directions::{DirectionMap, map_directions};
use crate::{Error, Result};
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use btf_image::color::{srgb_decode, srgb_table8};
use serde_json::json;
use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};

/// The four angles of an image, degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    /// Light θ.
    pub theta_light: f64,
    /// Light φ.
    pub phi_light: f64,
    /// View θ.
    pub theta_view: f64,
    /// View φ.
    pub phi_view: f64,
}

/// Image file extensions recognised.
pub const IMAGE_EXTENSIONS: [&str; 6] = ["jpg", "jpeg", "png", "bmp", "hdr", "exr"];

/// Name of the sidecar our exporter writes.
pub const SIDECAR: &str = "btf-export.json";

/// Largest image file read, bytes (a zip entry may claim any size).
pub const MAX_IMAGE_BYTES: u64 = 256 << 20;

/// Parses the `tl/pl/tv/pv` tags of a file name (any folder part is ignored).
pub fn parse_name(name: &str) -> Result<Angles> {
    let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
    let stem = base.rsplit_once('.').map(|(s, _)| s).unwrap_or(base);
    let mut vals: [Option<f64>; 4] = [None; 4];
    for tok in stem.split([' ', '_']) {
        let Some(k) =
            ["tl", "pl", "tv", "pv"].iter().position(|t| tok.len() > 2 && tok.starts_with(t))
        else {
            continue;
        };
        let num = &tok[2..];
        let Ok(v) = num.parse::<f64>() else { continue };
        if !num.bytes().all(|b| b.is_ascii_digit() || b == b'.') || !v.is_finite() {
            continue;
        }
        if vals[k].replace(v).is_some() {
            return Err(Error::invalid(name, ["tl", "pl", "tv", "pv"][k], "tag appears twice"));
        }
    }
    let get = |k: usize| {
        vals[k].ok_or_else(|| {
            Error::invalid(
                name,
                ["tl", "pl", "tv", "pv"][k],
                "angle tag missing from the file name",
            )
        })
    };
    Ok(Angles { theta_light: get(0)?, phi_light: get(1)?, theta_view: get(2)?, phi_view: get(3)? })
}

/// Where the images come from.
enum Source {
    Dir(Vec<PathBuf>),
    Zip(zip::ZipArchive<std::fs::File>),
}

fn is_image(name: &str) -> bool {
    let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
    IMAGE_EXTENSIONS.contains(&ext.as_str())
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>, depth: usize) -> Result<()> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    for e in rd {
        let p = e.map_err(|e| Error::io(dir, e))?.path();
        if p.is_dir() && depth < 4 {
            walk(&p, out, depth + 1)?;
        } else if is_image(&p.to_string_lossy()) {
            out.push(p);
        }
    }
    Ok(())
}

impl Source {
    fn open(path: &Path) -> Result<(Source, Vec<String>, f32)> {
        if path.is_dir() {
            let mut files = Vec::new();
            walk(path, &mut files, 0)?;
            files.sort();
            let names = files.iter().map(|p| p.display().to_string()).collect();
            let scale = read_sidecar(&path.join(SIDECAR))?;
            return Ok((Source::Dir(files), names, scale));
        }
        let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let mut z = zip::ZipArchive::new(f)
            .map_err(|e| Error::invalid(&path.display().to_string(), "zip", e.to_string()))?;
        let all: Vec<String> =
            z.file_names().filter_map(|n| n.ok().map(|n| n.into_owned())).collect();
        let mut names: Vec<String> = all.iter().filter(|n| is_image(n)).cloned().collect();
        names.sort();
        let mut scale = 1.0;
        if let Some(side) = all.iter().find(|n| n.ends_with(SIDECAR)) {
            let mut e =
                z.by_name(side).map_err(|e| Error::invalid(side, "zip entry", e.to_string()))?;
            let mut s = String::new();
            if e.size() < 1 << 20 && e.read_to_string(&mut s).is_ok() {
                scale = parse_sidecar(&s, SIDECAR)?;
            }
        }
        Ok((Source::Zip(z), names, scale))
    }

    fn read(&mut self, idx: usize, name: &str) -> Result<Vec<u8>> {
        match self {
            Source::Dir(files) => {
                let p = &files[idx];
                let len = p.metadata().map_err(|e| Error::io(p, e))?.len();
                if len > MAX_IMAGE_BYTES {
                    return Err(Error::limit(name, "file size", format!("{len} bytes")));
                }
                std::fs::read(p).map_err(|e| Error::io(p, e))
            }
            Source::Zip(z) => {
                let mut e = z
                    .by_name(name)
                    .map_err(|e| Error::invalid(name, "zip entry", e.to_string()))?;
                if e.size() > MAX_IMAGE_BYTES {
                    return Err(Error::limit(
                        name,
                        "zip entry size",
                        format!("{} bytes", e.size()),
                    ));
                }
                let mut b = Vec::with_capacity(e.size() as usize);
                e.by_ref()
                    .take(MAX_IMAGE_BYTES)
                    .read_to_end(&mut b)
                    .map_err(|e| Error::invalid(name, "zip entry", e.to_string()))?;
                Ok(b)
            }
        }
    }
}

fn parse_sidecar(text: &str, file: &str) -> Result<f32> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| Error::invalid(file, "json", e.to_string()))?;
    let s = v["scale"].as_f64().unwrap_or(1.0) as f32;
    if !(s.is_finite() && s > 0.0) {
        return Err(Error::invalid(file, "scale", format!("{s} is not a positive number")));
    }
    Ok(s)
}

fn read_sidecar(path: &Path) -> Result<f32> {
    match std::fs::read_to_string(path) {
        Ok(t) => parse_sidecar(&t, &path.display().to_string()),
        Err(_) => Ok(1.0),
    }
}

/// Decodes an image file's bytes into `(width, height, linear RGB row-major)`.
pub fn decode_image(bytes: &[u8], name: &str) -> Result<(usize, usize, Vec<f32>)> {
    let bad = |e: &dyn std::fmt::Display| Error::Image { file: name.into(), what: e.to_string() };
    if name.to_ascii_lowercase().ends_with(".exr") {
        return decode_exr(bytes, name);
    }
    let mut rd =
        image::ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| bad(&e))?;
    rd.limits(image::Limits::default());
    let img = crate::decode::decode_image(rd, name, bytes.len() as u64)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    use image::DynamicImage as D;
    let px: Vec<f32> = match &img {
        D::ImageRgb8(_) | D::ImageLuma8(_) | D::ImageRgba8(_) | D::ImageLumaA8(_) => {
            let t = srgb_table8();
            img.to_rgb8().into_raw().into_iter().map(|v| t[v as usize]).collect()
        }
        D::ImageRgb16(_) | D::ImageLuma16(_) | D::ImageRgba16(_) | D::ImageLumaA16(_) => {
            img.to_rgb16().into_raw().into_iter().map(|v| srgb_decode(v as f32 / 65535.0)).collect()
        }
        _ => img.to_rgb32f().into_raw(),
    };
    if let Some(i) = px.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(name, "pixels", format!("non-finite value at texel {}", i / 3)));
    }
    Ok((w, h, px))
}

fn decode_exr(bytes: &[u8], name: &str) -> Result<(usize, usize, Vec<f32>)> {
    // The header's size is checked before any pixel is allocated (`crate::decode`).
    let (w, h, rgb) = crate::decode::read_exr_rgb(|| Ok(Cursor::new(bytes)), name)?;
    let px: Vec<f32> = rgb.into_iter().flatten().collect();
    if let Some(i) = px.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(name, "pixels", format!("non-finite value at texel {}", i / 3)));
    }
    Ok((w, h, px))
}

/// What an import found.
#[derive(Debug, Clone)]
pub struct Ubo2003Report {
    /// Images written.
    pub images: usize,
    /// View and light sampling names.
    pub samplings: (String, String),
    /// Texture size `(width, height)`.
    pub size: (usize, usize),
    /// Scale applied from the sidecar.
    pub scale: f32,
}

/// Imports a folder or zip of UBO2003 images at `src` into a BTF store at `out`.
pub fn import(src: &Path, out: &Path, dtype: DType) -> Result<Ubo2003Report> {
    import_with_progress(src, out, dtype, &|_, _| {})
}

/// [`import`], calling `progress(done, total)` after each image stored.
pub fn import_with_progress(
    src: &Path,
    out: &Path,
    dtype: DType,
    progress: &dyn Fn(usize, usize),
) -> Result<Ubo2003Report> {
    let (mut source, names, scale) = Source::open(src)?;
    let src_name = src.display().to_string();
    if names.is_empty() {
        return Err(Error::invalid(
            &src_name,
            "images",
            format!("no image files ({})", IMAGE_EXTENSIONS.join(", ")),
        ));
    }
    let angles: Vec<Angles> = names.iter().map(|n| parse_name(n)).collect::<Result<_>>()?;
    let uniq = |f: &dyn Fn(&Angles) -> (f64, f64)| {
        let mut v: Vec<(f64, f64)> = angles.iter().map(f).collect();
        v.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
        v.dedup();
        v
    };
    let views = uniq(&|a| (a.theta_view, a.phi_view));
    let lights = uniq(&|a| (a.theta_light, a.phi_light));
    let vm = map_directions(&views, &src_name, "tv/pv")?;
    let lm = map_directions(&lights, &src_name, "tl/pl")?;
    let index = |m: &DirectionMap, list: &[(f64, f64)], d: (f64, f64)| {
        m.ours[list.iter().position(|&x| x == d).expect("listed")]
    };
    let (nv, nl) = (vm.sampling.len(), lm.sampling.len());
    let mut slot_of = vec![usize::MAX; nv * nl];
    for (k, a) in angles.iter().enumerate() {
        let (v, l) = (
            index(&vm, &views, (a.theta_view, a.phi_view)),
            index(&lm, &lights, (a.theta_light, a.phi_light)),
        );
        if slot_of[v * nl + l] != usize::MAX {
            return Err(Error::invalid(
                &names[k],
                "tl/pl/tv/pv",
                format!("same angles as {}", names[slot_of[v * nl + l]]),
            ));
        }
        slot_of[v * nl + l] = k;
    }
    if let Some(i) = slot_of.iter().position(|&k| k == usize::MAX) {
        let (v, l) = (vm.sampling.direction(i / nl), lm.sampling.direction(i % nl));
        return Err(Error::invalid(
            &src_name,
            "images",
            format!(
                "no image for view (θ {}, φ {}) under light (θ {}, φ {}): {} of {} present",
                v.theta_deg,
                v.phi_deg,
                l.theta_deg,
                l.phi_deg,
                names.len(),
                nv * nl
            ),
        ));
    }
    let (w0, h0, first) = decode_image(&source.read(0, &names[0])?, &names[0])?;
    let mut meta = BtfMeta::new(vm.sampling.clone(), lm.sampling.clone(), w0, h0);
    meta.provenance =
        json!({"source": src_name, "format": "ubo2003", "images": names.len(), "scale": scale});
    let writer = BtfWriter::create(out, meta, dtype, false)?;
    for (i, &k) in slot_of.iter().enumerate() {
        let (w, h, mut px) = if k == 0 {
            (w0, h0, first.clone())
        } else {
            decode_image(&source.read(k, &names[k])?, &names[k])?
        };
        if (w, h) != (w0, h0) {
            return Err(Error::invalid(
                &names[k],
                "size",
                format!("{w}x{h}, but {} is {w0}x{h0}", names[0]),
            ));
        }
        if scale != 1.0 {
            px.iter_mut().for_each(|v| *v *= scale);
        }
        writer.write_image(i / nl, i % nl, &px)?;
        progress(i + 1, slot_of.len());
    }
    writer.finish()?;
    Ok(Ubo2003Report {
        images: names.len(),
        samplings: (vm.sampling.name, lm.sampling.name),
        size: (w0, h0),
        scale,
    })
}

#[cfg(test)]
mod tests {
    /// The `ubo2003_image` fuzz target's finding (fuzz/regressions/ubo2003_image-oom-jpeg.bin,
    /// first byte 0 picked `.jpg`): 219 bytes of JPEG claiming a 570 MB image, which the
    /// decoder allocated and the conversion to `f32` then doubled past 1 GiB.
    #[test]
    fn a_tiny_jpeg_claiming_a_huge_image_is_refused_by_its_header() {
        let bytes = include_bytes!("../../../fuzz/regressions/ubo2003_image-oom-jpeg.bin");
        let e = super::decode_image(&bytes[1..], "a.jpg").unwrap_err();
        assert!(matches!(e, crate::Error::Limit { .. }), "{e}");
        let e = e.to_string();
        assert!(e.contains("a.jpg") && e.contains("pixels per byte"), "{e}");
    }

    use super::*;

    #[test]
    fn images_claiming_huge_sizes_are_refused_naming_file_and_field() {
        use crate::decode::crafted::*;
        let cases = [
            (exr_claiming(100_000, 100_000), "tl000_pl000_tv000_pv000.exr", "dataWindow"),
            (png_claiming(100_000, 100_000), "tl000_pl000_tv000_pv000.png", "width x height"),
            (hdr_claiming(100_000, 100_000), "tl000_pl000_tv000_pv000.hdr", "width x height"),
        ];
        for (bytes, name, field) in cases {
            let e = decode_image(&bytes, name).unwrap_err();
            assert!(matches!(e, Error::Limit { .. }), "{name}: {e}");
            let e = e.to_string();
            assert!(e.contains(name) && e.contains(field), "{e}");
        }
    }

    #[test]
    fn names_parse_by_tag_wherever_they_sit() {
        let a = parse_name("tv030_pv030/00008 tl000 pl000 tv030 pv030.jpg").unwrap();
        assert_eq!((a.theta_light, a.phi_light, a.theta_view, a.phi_view), (0.0, 0.0, 30.0, 30.0));
        let b = parse_name("WoolPKNT256_00084_tl015_pl000_tv015_pv120.jpg").unwrap();
        assert_eq!(
            (b.theta_light, b.phi_light, b.theta_view, b.phi_view),
            (15.0, 0.0, 15.0, 120.0)
        );
        let c = parse_name("pv007.5_tv023.5_pl345_tl075.png").unwrap();
        assert_eq!((c.theta_view, c.phi_view, c.theta_light), (23.5, 7.5, 75.0));
        let e = parse_name("dir/x_tl015_pl000_tv015.jpg").unwrap_err().to_string();
        assert!(e.contains("x_tl015_pl000_tv015.jpg") && e.contains("'pv'"), "{e}");
        let e = parse_name("tl1_tl2_pl0_tv0_pv0.jpg").unwrap_err().to_string();
        assert!(e.contains("twice"), "{e}");
    }
}
