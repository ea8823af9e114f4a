//! UBO2014 `.btf` files: recognises the payload from the signature and turns any of the
//! four (FMF, DFMF, PVF, BDI) into our BTF store, texture by texture; a PVF file whose
//! slots hold eigentextures can go straight into an eigen store (no re-compression).
//!
//! Directions are mapped onto our samplings by [`super::directions`]; `cos θ_light` is
//! multiplied in when the file's cosine flag says it is absent (see the module docs of
//! [`super`]).

use super::bdi::BdiReader;
use super::bytes::{ByteReader, Limits};
use super::directions::{DirectionMap, map_directions, radians_to_degrees};
use super::header::{Header, Payload, read_header, read_signature};
use super::pvf::{PvfLayout, PvfReader};
use super::svd::{Dfmf, Fmf, Layout, decode_dfmf, decode_fmf, read_dfmf, read_fmf};
use crate::{Error, Result};
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use serde_json::json;
use std::io::{BufReader, Cursor, Read, Seek};
use std::path::Path;

/// An opened UBO2014 file: compressed payloads in memory, PVF and BDI streamed.
#[derive(Debug)]
pub enum Ubo2014<R> {
    /// Full-matrix factorisation.
    Fmf(Header, Fmf, Layout),
    /// Decorrelated full-matrix factorisation.
    Dfmf(Header, Dfmf, Layout),
    /// Per-view factorisation (slots read on demand).
    Pvf(PvfReader<R>),
    /// Uncompressed (chunks read on demand).
    Bdi(BdiReader<R>),
}

/// Opens `path` as a UBO2014 file.
pub fn open(path: &Path, limits: Limits) -> Result<Ubo2014<BufReader<std::fs::File>>> {
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = f.metadata().map_err(|e| Error::io(path, e))?.len();
    let r = ByteReader::new(
        BufReader::with_capacity(1 << 20, f),
        len,
        path.display().to_string(),
        limits,
    );
    open_reader(r)
}

/// Parses UBO2014 bytes held in memory (`name` appears in errors).
pub fn open_bytes<'a>(
    bytes: &'a [u8],
    name: &str,
    limits: Limits,
) -> Result<Ubo2014<Cursor<&'a [u8]>>> {
    open_reader(ByteReader::new(Cursor::new(bytes), bytes.len() as u64, name, limits))
}

fn open_reader<R: Read + Seek>(mut r: ByteReader<R>) -> Result<Ubo2014<R>> {
    let sig = read_signature(&mut r)?;
    r.seek_to(0, "signature")?;
    Ok(match sig.payload {
        Payload::Pvf => Ubo2014::Pvf(PvfReader::new(r)?),
        Payload::Bdi => Ubo2014::Bdi(BdiReader::new(r)?),
        Payload::Fmf => {
            let h = read_header(&mut r)?;
            let (f, lay) = read_fmf(&mut r, &h)?;
            Ubo2014::Fmf(h, f, lay)
        }
        Payload::Dfmf => {
            let h = read_header(&mut r)?;
            let (d, lay) = read_dfmf(&mut r, &h)?;
            Ubo2014::Dfmf(h, d, lay)
        }
    })
}

impl<R: Read + Seek> Ubo2014<R> {
    /// The header.
    pub fn header(&self) -> &Header {
        match self {
            Ubo2014::Fmf(h, ..) | Ubo2014::Dfmf(h, ..) => h,
            Ubo2014::Pvf(p) => &p.header,
            Ubo2014::Bdi(b) => &b.header,
        }
    }
}

/// What an import produced.
#[derive(Debug, Clone)]
pub struct ImportReport {
    /// Signature of the source.
    pub signature: String,
    /// View and light sampling names.
    pub samplings: (String, String),
    /// Texture size `(width, height)`.
    pub size: (usize, usize),
    /// Images (or eigen slots) written.
    pub written: usize,
}

fn maps(file: &str, h: &Header) -> Result<(DirectionMap, DirectionMap)> {
    if h.channels() != 3 {
        return Err(Error::unsupported(
            file,
            format!(
                "{} channels ({}); our stores hold RGB",
                h.channels(),
                h.meta.channel_names.join(", ")
            ),
        ));
    }
    let v = map_directions(&radians_to_degrees(&h.views), file, "views")?;
    let l = map_directions(&radians_to_degrees(&h.lights), file, "lights")?;
    Ok((v, l))
}

fn store_meta(file: &str, h: &Header, v: &DirectionMap, l: &DirectionMap) -> BtfMeta {
    let mut m = BtfMeta::new(v.sampling.clone(), l.sampling.clone(), h.width, h.height);
    m.provenance = json!({
        "source": file, "format": h.signature.text, "meta_version": h.meta.version,
        "measurement_setup": h.meta.measurement_setup, "image_sensor": h.meta.image_sensor,
        "light_source": h.meta.light_source, "ppmm": h.meta.ppmm,
        "rgb_scale_factor_not_applied": h.meta.rgb_scale, "cosine_flag": h.meta.cosine_flag,
        "rotations": h.rotations.len(), "xml_bytes": h.meta.xml.len(),
    });
    m
}

/// Multiplies `cos θ_light` into `img` unless the file already contains it.
fn apply_cosine(h: &Header, light: usize, img: &mut [f32]) {
    if !h.meta.cosine_flag {
        let c = h.lights[light][0].cos().max(0.0);
        img.iter_mut().for_each(|v| *v *= c);
    }
}

/// Imports any UBO2014 file into a BTF store at `out`. `budget_bytes` bounds the BDI view
/// buffers.
pub fn import_to_store(
    path: &Path,
    out: &Path,
    dtype: DType,
    budget_bytes: u64,
) -> Result<ImportReport> {
    let file = path.display().to_string();
    let mut src = open(path, Limits::default())?;
    let h = src.header().clone();
    let (vm, lm) = maps(&file, &h)?;
    let w = BtfWriter::create(out, store_meta(&file, &h, &vm, &lm), dtype, false)?;
    let n = h.width * h.height * 3;
    let mut img = vec![0f32; n];
    let put = |v: usize, l: usize, img: &mut [f32]| -> Result<()> {
        apply_cosine(&h, l, img);
        Ok(w.write_image(vm.ours[v], lm.ours[l], img)?)
    };
    match &mut src {
        Ubo2014::Fmf(h, f, lay) => {
            for v in 0..h.views.len() {
                for l in 0..h.lights.len() {
                    decode_fmf(h, f, *lay, v, l, &mut img);
                    put(v, l, &mut img)?;
                }
            }
        }
        Ubo2014::Dfmf(h, d, lay) => {
            for v in 0..h.views.len() {
                for l in 0..h.lights.len() {
                    decode_dfmf(h, d, *lay, v, l, &mut img);
                    put(v, l, &mut img)?;
                }
            }
        }
        Ubo2014::Pvf(p) => {
            let mut v = 0;
            while let Some(slot) = p.next_slot()? {
                for l in 0..h.lights.len() {
                    slot.decode(l, 3, &mut img);
                    put(v, l, &mut img)?;
                }
                v += 1;
            }
        }
        Ubo2014::Bdi(b) => {
            let per_view = (h.lights.len() * n * 4) as u64;
            let group = (budget_bytes / per_view.max(1)).clamp(1, h.views.len() as u64) as usize;
            let all: Vec<usize> = (0..h.views.len()).collect();
            for views in all.chunks(group) {
                let bufs = b.read_views(views)?;
                for (&v, buf) in views.iter().zip(bufs) {
                    for (l, chunk) in buf.chunks_exact(n).enumerate() {
                        img.copy_from_slice(chunk);
                        put(v, l, &mut img)?;
                    }
                }
            }
        }
    }
    w.finish()?;
    let written = h.views.len() * h.lights.len();
    Ok(ImportReport {
        signature: h.signature.text.into(),
        samplings: (vm.sampling.name, lm.sampling.name),
        size: (h.width, h.height),
        written,
    })
}

/// Imports a PVF file with eigentexture slots straight into an eigen store at `out`.
pub fn import_pvf_to_eigen(
    path: &Path,
    out: &Path,
    quantization: Quantization,
) -> Result<ImportReport> {
    let file = path.display().to_string();
    let Ubo2014::Pvf(mut p) = open(path, Limits::default())? else {
        return Err(Error::unsupported(
            &file,
            "only PVF files hold per-view eigentextures; import into a BTF store instead",
        ));
    };
    let h = p.header.clone();
    if !h.meta.cosine_flag {
        return Err(Error::unsupported(
            &file,
            "cosine flag 0: cos(theta_light) must be multiplied in per light, which an eigen store cannot hold; import into a BTF store instead",
        ));
    }
    let (vm, lm) = maps(&file, &h)?;
    let c = p.components;
    if c == 0 || c > h.lights.len() {
        return Err(Error::invalid(
            &file,
            "pvf.num_components",
            format!("{c} is not in 1..={}", h.lights.len()),
        ));
    }
    let meta = EigenMeta { btf: store_meta(&file, &h, &vm, &lm), components: c, quantization };
    let w = EigenWriter::create(out, meta, false)?;
    let n = h.width * h.height * 3;
    let mut v = 0;
    while let Some(s) = p.next_slot()? {
        if s.layout != PvfLayout::Eigentextures || s.components != c {
            return Err(Error::unsupported(
                &file,
                format!(
                    "slot {v}: per-texel weights or {} components instead of {c}; import into a BTF store instead",
                    s.components
                ),
            ));
        }
        let mut basis = vec![0f32; c * n];
        for i in 0..n {
            for k in 0..c {
                basis[k * n + i] = s.basis[i * c + k];
            }
        }
        let mut weights = vec![0f32; s.weights.len()];
        for l in 0..h.lights.len() {
            weights[lm.ours[l] * c..(lm.ours[l] + 1) * c]
                .copy_from_slice(&s.weights[l * c..(l + 1) * c]);
        }
        let (eigentextures, scale_offset) = quantize(&basis, c, quantization);
        let eigenvalues = s.eigenvalues.iter().map(|&e| e as f64).collect();
        w.write_slot(
            vm.ours[v],
            &QuantizedSlot { mean: s.mean, eigentextures, scale_offset, weights, eigenvalues },
        )?;
        v += 1;
    }
    w.finish()?;
    Ok(ImportReport {
        signature: h.signature.text.into(),
        samplings: (vm.sampling.name, lm.sampling.name),
        size: (h.width, h.height),
        written: v,
    })
}

/// Parses every part of a UBO2014 file held in memory and decodes its first texture: the
/// fuzzing entry point. Returns the number of values decoded.
pub fn parse_all(bytes: &[u8]) -> Result<usize> {
    let limits = Limits { max_alloc_bytes: 64 << 20, ..Limits::default() };
    let mut src = open_bytes(bytes, "input", limits)?;
    let h = src.header().clone();
    let n = h.width * h.height * h.channels();
    if n > 1 << 22 {
        return Err(Error::limit("input", "width", "texture too large to decode here"));
    }
    let mut img = vec![0f32; n];
    match &mut src {
        Ubo2014::Fmf(h, f, lay) => decode_fmf(h, f, *lay, 0, 0, &mut img),
        Ubo2014::Dfmf(h, d, lay) => decode_dfmf(h, d, *lay, 0, 0, &mut img),
        Ubo2014::Pvf(p) => {
            while let Some(s) = p.next_slot()? {
                s.decode(0, h.channels(), &mut img);
            }
        }
        Ubo2014::Bdi(b) => {
            let v = b.read_views(&[0])?;
            img.copy_from_slice(&v[0][..n]);
        }
    }
    Ok(img.len())
}
