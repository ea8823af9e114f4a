//! FMF and DFMF payloads: truncated SVDs of the whole BTF matrix (Bonn UBO2014).
//!
//! FMF holds one SVD `B ≈ U · (S·V)ᵀ` of the matrix whose rows are `(channel, light, view)`
//! (channel fastest) and whose columns are texels (`x` fastest), or of its transpose
//! (rows `(channel, texel)`, columns `(light, view)`). DFMF holds one SVD per decorrelated
//! colour channel, with rows `(light, view)` and columns texels (or transposed), and a
//! colour model that maps the decorrelated channels back to RGB:
//! 0 RGB, 1 YUV, 3 PCA (`rgb = c·M + mean`), 4 YCoCg, 9 `Y = exp(Y') − ε` then YUV,
//! 10 log-magnitude U and V as well, 11 `U = U'·(Y+ε)`, `V = V'·(Y+ε)` then YUV,
//! 12 `rgb = exp(c) − ε`, with ε = 1e-5. FMF's dynamic-range reduction (`drr ≠ 0`) stores
//! `log(x + ε)` and is undone the same way.

use super::bytes::ByteReader;
use super::header::Header;
use crate::{Error, Result};
use std::io::{Read, Seek};

/// The ε of the logarithmic colour models and dynamic-range reduction.
pub const LOG_EPS: f32 = 1e-5;

/// One truncated SVD: `rows × P` left factors and `cols × P` right factors times `S`.
#[derive(Debug, Clone, PartialEq)]
pub struct Svd {
    /// Rows of the factorised matrix.
    pub rows: usize,
    /// Columns of the factorised matrix.
    pub cols: usize,
    /// Components `P`.
    pub components: usize,
    /// Singular values (informational: already multiplied into `sxv`).
    pub singular_values: Vec<f32>,
    /// Left singular vectors, `rows × P`, row-major.
    pub u: Vec<f32>,
    /// Right singular vectors times singular values, `cols × P`, row-major.
    pub sxv: Vec<f32>,
}

impl Svd {
    /// Entry `(row, col)` of the reconstructed matrix.
    pub fn at(&self, row: usize, col: usize) -> f32 {
        let p = self.components;
        let a = &self.u[row * p..(row + 1) * p];
        let b = &self.sxv[col * p..(col + 1) * p];
        a.iter().zip(b).map(|(x, y)| x * y).sum()
    }
}

/// An FMF payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Fmf {
    /// Header version byte of `!FMF12FCER` files (0 otherwise).
    pub header_version: u8,
    /// Dynamic-range reduction method (0 none, else `log(x + ε)` stored).
    pub dynamic_range_reduction: u32,
    /// Optional height map `(rows, cols, values)` (header version ≥ 2).
    pub height_map: Option<(usize, usize, Vec<f32>)>,
    /// The factorisation.
    pub svd: Svd,
}

/// A DFMF payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Dfmf {
    /// Colour model code.
    pub color_model: i32,
    /// Colour mean (PCA model).
    pub color_mean: [f32; 3],
    /// Colour transform, row-major (PCA model).
    pub color_transform: [f32; 9],
    /// One factorisation per channel.
    pub channels: Vec<Svd>,
}

fn read_svd<R: Read + Seek>(
    r: &mut ByteReader<R>,
    size: u8,
    p: u32,
    rows: u32,
    cols: u32,
) -> Result<Svd> {
    if p == 0 || p > 1 << 20 {
        return Err(r.invalid("num_components", format!("{p} is not in 1..=1048576")));
    }
    let (p, rows, cols) = (p as u64, rows as u64, cols as u64);
    // Check the whole payload's size up front, then each factor as it is read.
    let total = rows.saturating_mul(p).saturating_add(cols.saturating_mul(p)).saturating_add(p);
    r.need(total.saturating_mul(size as u64), "svd payload")?;
    let singular_values = r.scalars(p, size, "singular_values")?;
    let u = r.scalars(rows * p, size, "U")?;
    let sxv = r.scalars(cols * p, size, "SxV")?;
    Ok(Svd {
        rows: rows as usize,
        cols: cols as usize,
        components: p as usize,
        singular_values,
        u,
        sxv,
    })
}

/// Which way round a factorised matrix is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// Rows are directions (with channels for FMF), columns texels.
    DirectionRows,
    /// Rows are texels (with channels for FMF), columns directions.
    TexelRows,
}

/// The layout of `s`: `(dir_rows, texels)` or `(texel_rows, dirs)`.
fn layout(
    file: &str,
    s: &Svd,
    dir_rows: usize,
    texels: usize,
    texel_rows: usize,
    dirs: usize,
    field: &str,
) -> Result<Layout> {
    if (s.rows, s.cols) == (dir_rows, texels) {
        Ok(Layout::DirectionRows)
    } else if (s.rows, s.cols) == (texel_rows, dirs) {
        Ok(Layout::TexelRows)
    } else {
        Err(Error::invalid(
            file,
            field,
            format!(
                "matrix is {} x {}; the header's sampling and size need {dir_rows} x {texels} or {texel_rows} x {dirs}",
                s.rows, s.cols
            ),
        ))
    }
}

/// Reads the FMF payload that follows the common header.
pub fn read_fmf<R: Read + Seek>(r: &mut ByteReader<R>, h: &Header) -> Result<(Fmf, Layout)> {
    let header_version = if h.signature.extended { r.u8("fmf.header_version")? } else { 0 };
    if header_version >= 3 {
        return Err(Error::unsupported(r.file(), format!("FMF header version {header_version}")));
    }
    let dynamic_range_reduction =
        if header_version >= 1 { r.u32("fmf.dynamic_range_reduction")? } else { 0 };
    let mut height_map = None;
    if header_version >= 2 {
        let rows = r.u32("height_map.rows")? as u64;
        let cols = r.u32("height_map.cols")? as u64;
        let n =
            rows.checked_mul(cols).ok_or_else(|| r.invalid("height_map.rows", "size overflows"))?;
        if n > 0 {
            height_map = Some((rows as usize, cols as usize, r.scalars(n, 2, "height_map")?));
        }
    }
    let _ = r.u32("fmf.num_components")?;
    let size = r.u8("fmf.scalar_size")?;
    let p = r.u32("fmf.num_components")?;
    let rows = r.u32("fmf.rows")?;
    let cols = r.u32("fmf.cols")?;
    let svd = read_svd(r, size, p, rows, cols)?;
    let (nc, texels, dirs) = (h.channels(), h.width * h.height, h.views.len() * h.lights.len());
    let lay = layout(r.file(), &svd, nc * dirs, texels, nc * texels, dirs, "fmf.rows")?;
    Ok((Fmf { header_version, dynamic_range_reduction, height_map, svd }, lay))
}

/// Reads the DFMF payload that follows the common header.
pub fn read_dfmf<R: Read + Seek>(r: &mut ByteReader<R>, h: &Header) -> Result<(Dfmf, Layout)> {
    let _ = r.u32("dfmf.num_components")?;
    let color_model = r.i32("dfmf.color_model")?;
    if !matches!(color_model, 0 | 1 | 3 | 4 | 9 | 10 | 11 | 12) {
        return Err(Error::unsupported(r.file(), format!("DFMF colour model {color_model}")));
    }
    if color_model != 0 && color_model != 12 && h.channels() != 3 {
        return Err(r.invalid(
            "dfmf.color_model",
            format!("model {color_model} needs 3 channels, header has {}", h.channels()),
        ));
    }
    let mut color_mean = [0f32; 3];
    for (c, v) in r.scalars(3, 4, "dfmf.color_mean")?.into_iter().enumerate() {
        color_mean[c] = v;
    }
    let mut color_transform = [0f32; 9];
    color_transform.copy_from_slice(&r.scalars(9, 4, "dfmf.color_transform")?);
    let (texels, dirs) = (h.width * h.height, h.views.len() * h.lights.len());
    let mut channels = Vec::with_capacity(h.channels());
    let mut lay = Layout::DirectionRows;
    for c in 0..h.channels() {
        let size = r.u8("dfmf.scalar_size")?;
        let p = r.u32("dfmf.num_components")?;
        let rows = r.u32("dfmf.rows")?;
        let cols = r.u32("dfmf.cols")?;
        let svd = read_svd(r, size, p, rows, cols)?;
        let l = layout(r.file(), &svd, dirs, texels, texels, dirs, "dfmf.rows")?;
        if c > 0 && l != lay {
            return Err(r.invalid("dfmf.rows", "channels disagree on the matrix layout"));
        }
        lay = l;
        channels.push(svd);
    }
    Ok((Dfmf { color_model, color_mean, color_transform, channels }, lay))
}

/// Decodes FMF texture `(view, light)` (file indices) into `out` (`h·w·nC`, channel fastest).
pub fn decode_fmf(h: &Header, f: &Fmf, lay: Layout, view: usize, light: usize, out: &mut [f32]) {
    let nc = h.channels();
    let lv = light + h.lights.len() * view;
    for (t, px) in out.chunks_exact_mut(nc).enumerate() {
        for (c, v) in px.iter_mut().enumerate() {
            let x = match lay {
                Layout::DirectionRows => f.svd.at(c + nc * lv, t),
                Layout::TexelRows => f.svd.at(c + nc * t, lv),
            };
            *v = if f.dynamic_range_reduction != 0 { x.exp() - LOG_EPS } else { x };
        }
    }
}

/// Decodes DFMF texture `(view, light)` (file indices) into `out` (`h·w·nC`).
pub fn decode_dfmf(h: &Header, d: &Dfmf, lay: Layout, view: usize, light: usize, out: &mut [f32]) {
    let nc = h.channels();
    let lv = light + h.lights.len() * view;
    for (t, px) in out.chunks_exact_mut(nc).enumerate() {
        for (c, v) in px.iter_mut().enumerate() {
            *v = match lay {
                Layout::DirectionRows => d.channels[c].at(lv, t),
                Layout::TexelRows => d.channels[c].at(t, lv),
            };
        }
        undecorrelate(d, px);
    }
}

const YUV_TO_RGB: [[f32; 3]; 3] =
    [[1.0, 0.0, 1.139_83], [1.0, -0.394_65, -0.5806], [1.0, 2.032_11, 0.0]];

fn mat3(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|j| m[j][0] * v[0] + m[j][1] * v[1] + m[j][2] * v[2])
}

/// Maps one texel's decorrelated channels back to RGB (in place).
pub fn undecorrelate(d: &Dfmf, px: &mut [f32]) {
    let e = LOG_EPS;
    let out = match d.color_model {
        12 => {
            px.iter_mut().for_each(|v| *v = v.exp() - e);
            return;
        }
        0 => return,
        1 => mat3(&YUV_TO_RGB, [px[0], px[1], px[2]]),
        3 => {
            let m = &d.color_transform;
            [0, 1, 2].map(|j| px[0] * m[j] + px[1] * m[3 + j] + px[2] * m[6 + j] + d.color_mean[j])
        }
        4 => [px[0] + px[1] - px[2], px[0] + px[2], px[0] - px[1] - px[2]],
        9 => mat3(&YUV_TO_RGB, [px[0].exp() - e, px[1], px[2]]),
        10 => {
            let m = |v: f32| v.signum() * (v.abs() + e.ln()).exp();
            mat3(&YUV_TO_RGB, [px[0].exp() - e, m(px[1]), m(px[2])])
        }
        _ => {
            let y = px[0].exp() - e;
            mat3(&YUV_TO_RGB, [y, px[1] * (y + e), px[2] * (y + e)])
        }
    };
    px[..3].copy_from_slice(&out);
}
