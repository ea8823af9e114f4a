//! Contact sheets: a row of normtextures of a BTF store at a few characteristic
//! (view, light) pairs, tone-mapped and sRGB-encoded into one PNG for a quick look.
//!
//! One exposure is used for the whole sheet (so relative brightness between tiles is kept):
//! values are scaled so that the sheet's 95th percentile maps to 0.6 after the tone curve
//! `1 − exp(−x)`, then encoded with the sRGB transfer function.

use crate::{Error, Result};
use btf_core::Direction;
use btf_core::store::BtfStore;
use std::path::{Path, PathBuf};

/// The (view θ, view φ, light θ, light φ) pairs shown, in degrees; each is snapped to the
/// nearest direction of the store's sampling.
pub const PREVIEW_PAIRS: [(f64, f64, f64, f64); 6] = [
    (0.0, 0.0, 0.0, 0.0),
    (0.0, 0.0, 45.0, 0.0),
    (0.0, 0.0, 75.0, 0.0),
    (0.0, 0.0, 75.0, 90.0),
    (60.0, 0.0, 30.0, 180.0),
    (60.0, 90.0, 60.0, 270.0),
];

fn nearest_index(dirs: &[Direction], want: Direction) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, d) in dirs.iter().enumerate() {
        let a = d.angle_to_deg(want);
        if a < best.0 {
            best = (a, i);
        }
    }
    best.1
}

/// Writes `DIR/NAME.png`: the normtextures of [`PREVIEW_PAIRS`] side by side, each tile
/// enlarged (nearest neighbour) to at least 128 pixels. Returns the file written.
pub fn write_contact_sheet(store: &BtfStore, dir: &Path, name: &str) -> Result<PathBuf> {
    let meta = store.meta();
    let (w, h) = (meta.width, meta.height);
    let views = meta.view_sampling.directions();
    let lights = meta.light_sampling.directions();
    let mut tiles = Vec::new();
    for &(vt, vp, lt, lp) in &PREVIEW_PAIRS {
        let v = nearest_index(&views, Direction::new(vt, vp));
        let l = nearest_index(&lights, Direction::new(lt, lp));
        tiles.push(store.read_image(v, l)?);
    }
    let mut lum: Vec<f32> = tiles.iter().flatten().copied().collect();
    lum.sort_by(f32::total_cmp);
    let p95 = lum[(lum.len() * 95 / 100).min(lum.len() - 1)].max(1e-6) as f64;
    let exposure = -(1.0f64 - 0.6).ln() / p95;
    let zoom = (128usize).div_ceil(w.max(h)).max(1);
    let (tw, th, gap) = (w * zoom, h * zoom, 4);
    let sheet_w = tiles.len() * (tw + gap) - gap;
    let mut img = image::RgbImage::from_pixel(sheet_w as u32, th as u32, image::Rgb([32, 32, 32]));
    for (k, tile) in tiles.iter().enumerate() {
        for y in 0..th {
            for x in 0..tw {
                let src = ((y / zoom) * w + x / zoom) * 3;
                let px: [u8; 3] = std::array::from_fn(|c| {
                    let t = 1.0 - (-(tile[src + c] as f64) * exposure).exp();
                    btf_image::color::srgb_encode8(t as f32)
                });
                img.put_pixel((k * (tw + gap) + x) as u32, y as u32, image::Rgb(px));
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let path = dir.join(format!("{name}.png"));
    btf_image::write::write_png(&path, &img)?;
    Ok(path)
}
