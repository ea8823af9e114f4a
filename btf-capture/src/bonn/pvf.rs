//! PVF payloads: per-view PCA, the representation of Sattler et al. 2003 ([S03 eq. 1–2]), read
//! slot by slot so that a large file never has to fit in memory, and written from our
//! eigen stores (no public tool writes PVF).
//!
//! After the common header: `u32 components`, `u32 num_view_slots` (a legacy layout is
//! flagged by the magic `301074` right after the signature: `u32 components, width,
//! height, num_view_slots`, then the sampling, no metadata). Per slot: `u8 scalar_size`,
//! `u32 P`, `u32 num_weights`, `u32 dimension`, eigenvalues (`P`), mean (`dimension`),
//! components (`dimension × P`, row-major) and weights (`num_weights × P`). Either the
//! components are eigentextures (`dimension = nC·h·w`, channel fastest, `x` next) with
//! per-light weights (`num_weights = nL`) — our layout — or they are per-light colour rows
//! (`dimension = nC·nL`) with per-texel weights (`num_weights = w·h`). A texture is
//! `mean + components · weightsᵀ` in either case.

use super::bytes::{ByteReader, put_scalars, put_u32};
use super::header::{
    Header, MetaData, read_header, read_sampling, read_side, read_signature, write_header,
};
use crate::{Error, Result};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The magic number of the legacy PVF layout.
pub const LEGACY_MAGIC: i32 = 301_074;

/// How a slot's matrices are arranged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PvfLayout {
    /// Components are eigentextures (`nC·h·w × P`), weights per light (`nL × P`).
    Eigentextures,
    /// Components are per-light colours (`nC·nL × P`), weights per texel (`w·h × P`).
    LightRows,
}

/// One view slot of a PVF file.
#[derive(Debug, Clone, PartialEq)]
pub struct PvfSlot {
    /// Components `P`.
    pub components: usize,
    /// Matrix arrangement.
    pub layout: PvfLayout,
    /// Eigenvalues, `P`.
    pub eigenvalues: Vec<f32>,
    /// Mean, `dimension`.
    pub mean: Vec<f32>,
    /// Components, `dimension × P`, row-major.
    pub basis: Vec<f32>,
    /// Weights, `num_weights × P`, row-major.
    pub weights: Vec<f32>,
}

impl PvfSlot {
    /// Decodes the texture of light `light` (file index) into `out` (`h·w·nC`).
    pub fn decode(&self, light: usize, n_channels: usize, out: &mut [f32]) {
        let p = self.components;
        let dot = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f32>();
        match self.layout {
            PvfLayout::Eigentextures => {
                let w = &self.weights[light * p..(light + 1) * p];
                for (i, v) in out.iter_mut().enumerate() {
                    *v = self.mean[i] + dot(&self.basis[i * p..(i + 1) * p], w);
                }
            }
            PvfLayout::LightRows => {
                for (t, px) in out.chunks_exact_mut(n_channels).enumerate() {
                    let w = &self.weights[t * p..(t + 1) * p];
                    for (c, v) in px.iter_mut().enumerate() {
                        let row = c + n_channels * light;
                        *v = self.mean[row] + dot(&self.basis[row * p..(row + 1) * p], w);
                    }
                }
            }
        }
    }
}

/// A PVF file opened for slot-by-slot reading.
#[derive(Debug)]
pub struct PvfReader<R> {
    /// The header (metadata defaulted for the legacy layout).
    pub header: Header,
    /// True for the legacy layout.
    pub legacy: bool,
    /// Components declared in the header.
    pub components: usize,
    r: ByteReader<R>,
    next: usize,
}

impl<R: Read + Seek> PvfReader<R> {
    /// Reads the header from the start of the file.
    pub fn new(mut r: ByteReader<R>) -> Result<Self> {
        let signature = read_signature(&mut r)?;
        let at = r.pos();
        let legacy = r.remaining() >= 4 && r.i32("pvf.magic")? == LEGACY_MAGIC;
        let (header, components, slots);
        if legacy {
            components = r.u32("pvf.num_components")? as usize;
            let width = read_side(&mut r, "width")?;
            let height = read_side(&mut r, "height")?;
            slots = r.u32("pvf.num_view_slots")? as usize;
            let (views, lights) = read_sampling(&mut r)?;
            let meta = MetaData { version: 0, cosine_flag: false, ..MetaData::default() };
            header =
                Header { signature, meta, views, lights, width, height, rotations: Vec::new() };
        } else {
            r.seek_to(at - signature.text.len() as u64, "signature")?;
            header = read_header(&mut r)?;
            components = r.u32("pvf.num_components")? as usize;
            slots = r.u32("pvf.num_view_slots")? as usize;
        }
        if slots != header.views.len() {
            return Err(r.invalid(
                "pvf.num_view_slots",
                format!("{slots}, but the sampling has {} views", header.views.len()),
            ));
        }
        Ok(PvfReader { header, legacy, components, r, next: 0 })
    }

    /// Reads the next view slot (file order), or `None` after the last.
    pub fn next_slot(&mut self) -> Result<Option<PvfSlot>> {
        if self.next == self.header.views.len() {
            return Ok(None);
        }
        let r = &mut self.r;
        let size = r.u8("slot.scalar_size")?;
        let p = r.u32("slot.num_components")? as u64;
        let nw = r.u32("slot.num_weights")? as u64;
        let dim = r.u32("slot.dimension")? as u64;
        let h = &self.header;
        let (nc, nl, texels) =
            ((h.channels()) as u64, h.lights.len() as u64, (h.width * h.height) as u64);
        let layout = if (dim, nw) == (nc * texels, nl) {
            PvfLayout::Eigentextures
        } else if (dim, nw) == (nc * nl, texels) {
            PvfLayout::LightRows
        } else {
            return Err(r.invalid(
                "slot.dimension",
                format!(
                    "slot {}: dimension {dim} with {nw} weights fits neither {} x {nl} nor {} x {texels}",
                    self.next,
                    nc * texels,
                    nc * nl
                ),
            ));
        };
        if p == 0 || p > dim.min(1 << 20) {
            return Err(r.invalid(
                "slot.num_components",
                format!("slot {}: {p} is not in 1..={dim}", self.next),
            ));
        }
        let total =
            (p + dim).saturating_add(dim.saturating_mul(p)).saturating_add(nw.saturating_mul(p));
        r.need(total.saturating_mul(size as u64), "slot payload")?;
        let eigenvalues = r.scalars(p, size, "slot.eigenvalues")?;
        let mean = r.scalars(dim, size, "slot.mean")?;
        let basis = r.scalars(dim * p, size, "slot.components")?;
        let weights = r.scalars(nw * p, size, "slot.weights")?;
        self.next += 1;
        Ok(Some(PvfSlot { components: p as usize, layout, eigenvalues, mean, basis, weights }))
    }

    /// The file name used in errors.
    pub fn file(&self) -> &str {
        self.r.file()
    }
}

/// Writes a PVF file slot by slot through one [`btf_core::fs::AtomicFile`], moved into
/// place by [`PvfWriter::finish`]; a writer dropped before that removes its temporary, so a
/// failed export leaves nothing behind.
pub struct PvfWriter {
    out: btf_core::fs::AtomicFile,
    path: PathBuf,
    header: Header,
    left: usize,
}

impl PvfWriter {
    /// Starts a file with `header` (signature `!PVF06FC` or `!PVF06FCR`) and `components`.
    pub fn create(path: &Path, header: Header, components: usize) -> Result<Self> {
        let mut out = btf_core::fs::AtomicFile::create(path)?;
        let io = |e| Error::io(path, e);
        write_header(&mut out, &header).map_err(io)?;
        put_u32(&mut out, components as u32).map_err(io)?;
        put_u32(&mut out, header.views.len() as u32).map_err(io)?;
        let left = header.views.len();
        Ok(PvfWriter { out, path: path.to_owned(), header, left })
    }

    /// Appends the next slot (file order = the header's view order), as `f32`.
    pub fn write_slot(&mut self, s: &PvfSlot) -> Result<()> {
        let h = &self.header;
        let (dim, nw) = match s.layout {
            PvfLayout::Eigentextures => (h.channels() * h.width * h.height, h.lights.len()),
            PvfLayout::LightRows => (h.channels() * h.lights.len(), h.width * h.height),
        };
        let p = s.components;
        if self.left == 0
            || s.mean.len() != dim
            || s.basis.len() != dim * p
            || s.weights.len() != nw * p
            || s.eigenvalues.len() != p
        {
            return Err(Error::invalid(
                &self.path.display().to_string(),
                "slot",
                "slot shape disagrees with the header",
            ));
        }
        for part in [&s.eigenvalues, &s.mean, &s.basis, &s.weights] {
            if let Some(i) = part.iter().position(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    &self.path.display().to_string(),
                    "slot",
                    format!("non-finite value at element {i} of a slot; refusing to write it"),
                ));
            }
        }
        let io = |e| Error::io(&self.path, e);
        let out = &mut self.out;
        out.write_all(&[4]).map_err(io)?;
        for v in [p, nw, dim] {
            put_u32(out, v as u32).map_err(io)?;
        }
        for part in [&s.eigenvalues, &s.mean, &s.basis, &s.weights] {
            put_scalars(out, part, 4).map_err(io)?;
        }
        self.left -= 1;
        Ok(())
    }

    /// Checks every slot was written, flushes and moves the file into place.
    pub fn finish(self) -> Result<()> {
        if self.left != 0 {
            return Err(Error::invalid(
                &self.path.display().to_string(),
                "slot",
                format!("{} slots never written", self.left),
            ));
        }
        Ok(self.out.commit(true)?)
    }
}
