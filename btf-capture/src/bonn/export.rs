//! Our stores in Bonn formats: an eigen store as a PVF file (eigentexture slots, `f32`,
//! views and lights in our order, cosine flag 1) and a BTF store as a UBO2003-style image
//! folder (`tvTTT_pvPPP/NAME_NNNNN_tlTTT_plPPP_tvTTT_pvPPP.EXT`).
//!
//! 8/16-bit images are sRGB-encoded after dividing by a scale (the store's largest value,
//! or 1 when everything is ≤ 1) written to `btf-export.json`, which our importer applies
//! back; EXR images hold the linear `f32` values unchanged. Precision of the folder route:
//! 8-bit PNG/JPEG within `srgb::MAX_ERR_8BIT · scale` (PNG; JPEG adds its own loss),
//! 16-bit PNG within `srgb::MAX_ERR_16BIT · scale`, EXR exact. Both outputs are written
//! under a temporary name and renamed when complete.

use super::directions::sampling_radians;
use super::header::{Header, MetaData, signature};
use super::pvf::{PvfLayout, PvfSlot, PvfWriter};
use crate::{Error, Result};
use btf_core::eigen::EigenStore;
use btf_core::store::BtfStore;
use btf_image::color::srgb_encode;
use serde_json::json;
use std::path::Path;

/// Image encoding of an exported folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageEncoding {
    /// 8-bit sRGB PNG.
    Png8,
    /// 16-bit sRGB PNG.
    Png16,
    /// 8-bit sRGB JPEG at the given quality.
    Jpeg(u8),
    /// 32-bit float linear OpenEXR.
    Exr,
}

impl ImageEncoding {
    /// File extension.
    pub fn extension(self) -> &'static str {
        match self {
            ImageEncoding::Png8 | ImageEncoding::Png16 => "png",
            ImageEncoding::Jpeg(_) => "jpg",
            ImageEncoding::Exr => "exr",
        }
    }
}

/// Writes an eigen store as a PVF file at `path`.
pub fn export_pvf(store: &EigenStore, path: &Path) -> Result<()> {
    let m = store.meta();
    let b = &m.btf;
    let header = Header {
        signature: signature("!PVF06FC").expect("known signature"),
        meta: MetaData {
            measurement_setup: "btf toolkit eigen store".into(),
            xml: serde_json::to_string(&json!({"view_sampling": b.view_sampling, "light_sampling": b.light_sampling, "provenance": b.provenance})).unwrap_or_default(),
            ..MetaData::default()
        },
        views: sampling_radians(&b.view_sampling),
        lights: sampling_radians(&b.light_sampling),
        width: b.width,
        height: b.height,
        rotations: Vec::new(),
    };
    let c = m.components;
    let mut w = PvfWriter::create(path, header, c)?;
    for v in 0..b.n_views() {
        let s = store.read_slot(v)?;
        let n = s.mean.len();
        let mut basis = vec![0f32; n * c];
        for k in 0..c {
            for (i, x) in s.basis_row(k).iter().enumerate() {
                basis[i * c + k] = *x;
            }
        }
        let mut eigenvalues: Vec<f32> = s.eigenvalues.iter().take(c).map(|&e| e as f32).collect();
        eigenvalues.resize(c, 0.0);
        w.write_slot(&PvfSlot {
            components: c,
            layout: PvfLayout::Eigentextures,
            eigenvalues,
            mean: s.mean,
            basis,
            weights: s.weights,
        })?;
    }
    w.finish()
}

/// An angle as it appears in names: three digits, with one decimal when not whole.
pub fn angle_tag(deg: f64) -> String {
    let r = (deg * 10.0).round() / 10.0;
    if r.fract() == 0.0 { format!("{:03}", r as i64) } else { format!("{r:05.1}") }
}

fn encode_image(
    path: &Path,
    w: usize,
    h: usize,
    px: &[f32],
    scale: f32,
    enc: ImageEncoding,
) -> Result<()> {
    let bad = |e: &dyn std::fmt::Display| Error::Image {
        file: path.display().to_string(),
        what: e.to_string(),
    };
    let (w32, h32) = (w as u32, h as u32);
    match enc {
        ImageEncoding::Png8 | ImageEncoding::Jpeg(_) => {
            let raw: Vec<u8> =
                px.iter().map(|v| (srgb_encode(v / scale) * 255.0).round() as u8).collect();
            let img = image::RgbImage::from_raw(w32, h32, raw).expect("size matches");
            let mut bytes = Vec::new();
            if let ImageEncoding::Jpeg(q) = enc {
                let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, q);
                enc.encode_image(&img).map_err(|e| bad(&e))?;
            } else {
                img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
                    .map_err(|e| bad(&e))?;
            }
            btf_core::fs::write_atomic_unsynced(path, &bytes).map_err(Error::from)
        }
        ImageEncoding::Png16 => {
            let raw: Vec<u16> =
                px.iter().map(|v| (srgb_encode(v / scale) * 65535.0).round() as u16).collect();
            let img = image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(w32, h32, raw)
                .expect("size matches");
            let mut bytes = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
                .map_err(|e| bad(&e))?;
            btf_core::fs::write_atomic_unsynced(path, &bytes).map_err(Error::from)
        }
        ImageEncoding::Exr => {
            let get = |x: usize, y: usize| {
                let i = (y * w + x) * 3;
                (px[i], px[i + 1], px[i + 2])
            };
            use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
            let mut bytes = std::io::Cursor::new(Vec::new());
            Image::from_channels((w, h), SpecificChannels::rgb(|p: Vec2<usize>| get(p.0, p.1)))
                .write()
                .to_buffered(&mut bytes)
                .map_err(|e| bad(&e))?;
            btf_core::fs::write_atomic_unsynced(path, bytes.get_ref()).map_err(Error::from)
        }
    }
}

/// Writes a BTF store as a UBO2003-style folder at `dir` with file names `NAME_NNNNN_…`.
/// Returns the scale written to the sidecar.
pub fn export_ubo2003(store: &BtfStore, dir: &Path, name: &str, enc: ImageEncoding) -> Result<f32> {
    export_ubo2003_with_progress(store, dir, name, enc, &|_, _| {})
}

/// [`export_ubo2003`], calling `progress(done, total)` after each image written.
pub fn export_ubo2003_with_progress(
    store: &BtfStore,
    dir: &Path,
    name: &str,
    enc: ImageEncoding,
    progress: &dyn Fn(usize, usize),
) -> Result<f32> {
    let m = store.meta();
    let scale = if enc == ImageEncoding::Exr {
        1.0
    } else {
        let mut peak = 0f32;
        for v in 0..m.n_views() {
            for l in 0..m.n_lights() {
                peak = store.read_image(v, l)?.iter().fold(peak, |a, &x| a.max(x));
            }
        }
        if peak > 1.0 { peak } else { 1.0 }
    };
    // Replace only an earlier export (it carries the sidecar) or an empty folder; never a
    // folder of somebody's files.
    btf_core::fs::check_replaceable(
        dir,
        btf_core::fs::OutputKind::Folder { marker: super::ubo2003::SIDECAR },
    )?;
    let tmp = dir.with_file_name(format!(
        "{}.partial",
        dir.file_name().unwrap_or_default().to_string_lossy()
    ));
    if tmp.exists() {
        btf_core::fs::check_replaceable(
            &tmp,
            btf_core::fs::OutputKind::Folder { marker: super::ubo2003::SIDECAR },
        )
        .or_else(|_| {
            if only_view_folders(&tmp) {
                Ok(())
            } else {
                Err(Error::invalid(
                    &tmp.display().to_string(),
                    "folder",
                    "exists and is not an unfinished export of this toolkit; refusing to remove it",
                ))
            }
        })?;
        std::fs::remove_dir_all(&tmp).map_err(|e| Error::io(&tmp, e))?;
    }
    let written = write_folder(store, &tmp, name, enc, scale, progress);
    if let Err(e) = written {
        // A refusal or a failed write leaves nothing behind.
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if dir.exists() {
        let old = dir.with_file_name(format!(
            ".{}.old-{}",
            dir.file_name().unwrap_or_default().to_string_lossy(),
            std::process::id()
        ));
        std::fs::rename(dir, &old).map_err(|e| Error::io(dir, e))?;
        std::fs::rename(&tmp, dir).map_err(|e| Error::io(dir, e))?;
        let _ = std::fs::remove_dir_all(&old);
    } else {
        std::fs::rename(&tmp, dir).map_err(|e| Error::io(dir, e))?;
    }
    Ok(scale)
}

/// True when `dir` holds nothing but the `tv…_pv…` view folders an export writes and the
/// temporary files of its atomic writes (a writer killed before its sidecar).
fn only_view_folders(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|d| {
        d.flatten().all(|e| {
            e.file_name()
                .to_str()
                .is_some_and(|n| n.starts_with("tv") || btf_core::fs::is_temp_name(n))
        })
    })
}

fn write_folder(
    store: &BtfStore,
    tmp: &Path,
    name: &str,
    enc: ImageEncoding,
    scale: f32,
    progress: &dyn Fn(usize, usize),
) -> Result<()> {
    let m = store.meta();
    let total = m.n_views() * m.n_lights();
    let mut running = 0;
    for v in 0..m.n_views() {
        let vd = m.view_sampling.direction(v);
        let (tv, pv) = (angle_tag(vd.theta_deg), angle_tag(vd.phi_deg));
        let sub = tmp.join(format!("tv{tv}_pv{pv}"));
        std::fs::create_dir_all(&sub).map_err(|e| Error::io(&sub, e))?;
        for l in 0..m.n_lights() {
            let ld = m.light_sampling.direction(l);
            let file = format!(
                "{name}_{running:05}_tl{}_pl{}_tv{tv}_pv{pv}.{}",
                angle_tag(ld.theta_deg),
                angle_tag(ld.phi_deg),
                enc.extension()
            );
            encode_image(&sub.join(file), m.width, m.height, &store.read_image(v, l)?, scale, enc)?;
            running += 1;
            progress(running, total);
        }
    }
    let side = json!({"scale": scale, "encoding": format!("{enc:?}"), "note": "linear value = decoded value x scale",
        "view_sampling": m.view_sampling, "light_sampling": m.light_sampling});
    let sp = tmp.join(super::ubo2003::SIDECAR);
    btf_core::fs::write_atomic(
        &sp,
        serde_json::to_string_pretty(&side).unwrap_or_default().as_bytes(),
    )?;
    Ok(())
}
