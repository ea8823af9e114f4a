//! Signatures and the common header of the UBO2014 binary `.btf` files: measurement
//! metadata (versions 1–4: cosine flag, XML text, channel names), the bidirectional
//! sampling (per view `θ, φ` in radians and its light list), the texture size and the
//! optional per-direction 3×3 rotation matrices. Readers and writers of the same layout.

use super::bytes::{ByteReader, put_f32s, put_text, put_u32};
use crate::Result;
use std::io::{Read, Seek, Write};

/// The four payload kinds of a UBO2014 file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Payload {
    /// One truncated SVD of the whole BTF matrix.
    Fmf,
    /// One SVD per decorrelated colour channel.
    Dfmf,
    /// Per-view PCA (Sattler et al. 2003).
    Pvf,
    /// Uncompressed, ABRDF-major.
    Bdi,
}

/// A known file signature and what it implies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Signature {
    /// The literal text at the start of the file.
    pub text: &'static str,
    /// Payload kind.
    pub payload: Payload,
    /// Rotation matrices follow the header.
    pub rotations: bool,
    /// FMF: a header-version byte follows; BDI: a compression byte follows.
    pub extended: bool,
}

const fn sig(text: &'static str, payload: Payload, rotations: bool, extended: bool) -> Signature {
    Signature { text, payload, rotations, extended }
}

/// `(θ, φ)` pairs in radians, in file order.
pub type Directions = Vec<[f32; 2]>;

/// Every signature this reader knows.
pub const SIGNATURES: [Signature; 7] = [
    sig("!DFMF08FCR", Payload::Dfmf, true, false),
    sig("!FMF12FCER", Payload::Fmf, true, true),
    sig("!FMF06FCR", Payload::Fmf, true, false),
    sig("!FMF06FC", Payload::Fmf, false, false),
    sig("!PVF06FCR", Payload::Pvf, true, false),
    sig("!PVF06FC", Payload::Pvf, false, false),
    sig("!BDIF06R2!", Payload::Bdi, true, true),
];

/// Measurement metadata of the common header.
#[derive(Debug, Clone, PartialEq)]
pub struct MetaData {
    /// Header structure version (1–4).
    pub version: u32,
    /// Free text, 80 bytes on disk.
    pub measurement_setup: String,
    /// Free text, 80 bytes on disk.
    pub image_sensor: String,
    /// Free text, 80 bytes on disk.
    pub light_source: String,
    /// Resolution, texels per millimetre.
    pub ppmm: f32,
    /// Per-channel scale factor of the RGB values.
    pub rgb_scale: [f32; 3],
    /// True when `cos θ_light` is already multiplied into the data (version > 1).
    pub cosine_flag: bool,
    /// The measurement XML (version > 2).
    pub xml: String,
    /// Channel names (version > 3; otherwise R, G, B). Non-RGB names are wavelengths.
    pub channel_names: Vec<String>,
}

impl Default for MetaData {
    fn default() -> Self {
        MetaData {
            version: 4,
            measurement_setup: String::new(),
            image_sensor: String::new(),
            light_source: String::new(),
            ppmm: 0.0,
            rgb_scale: [1.0; 3],
            cosine_flag: true,
            xml: String::new(),
            channel_names: ["R", "G", "B"].map(String::from).to_vec(),
        }
    }
}

/// The header shared by FMF, DFMF and PVF (BDI reads the same parts in its own order).
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// The signature found.
    pub signature: Signature,
    /// Measurement metadata.
    pub meta: MetaData,
    /// View directions `(θ, φ)` in radians, in file order.
    pub views: Vec<[f32; 2]>,
    /// Light directions `(θ, φ)` in radians (the same for every view), in file order.
    pub lights: Vec<[f32; 2]>,
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major 3×3 rotation matrices of the local frames (signatures ending in `R`).
    pub rotations: Vec<[f32; 9]>,
}

impl Header {
    /// Number of colour channels.
    pub fn channels(&self) -> usize {
        self.meta.channel_names.len()
    }
}

/// True when the 8 bytes at `at` look like the start of a metadata block (size ≥ 264,
/// version 1–4) or of the legacy PVF layout.
fn plausible_meta(head: &[u8], at: usize) -> bool {
    let word =
        |i: usize| head.get(i..i + 4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")));
    match (word(at), word(at + 4)) {
        (Some(size), Some(version)) => {
            (size >= 264 && (1..=4).contains(&version)) || size == 301_074
        }
        _ => false,
    }
}

/// Reads the signature. When several known signatures prefix the file (`!FMF06FC` and
/// `!FMF06FCR`: a metadata size whose low byte is `R` makes them collide), the longest one
/// followed by a plausible metadata block wins, else the longest.
pub fn read_signature<R: Read + Seek>(r: &mut ByteReader<R>) -> Result<Signature> {
    let n = r.remaining().min(18);
    let head = r.bytes(n, "signature")?;
    let mut found: Vec<Signature> =
        SIGNATURES.iter().filter(|s| head.starts_with(s.text.as_bytes())).copied().collect();
    found.sort_by_key(|s| std::cmp::Reverse(s.text.len()));
    let best =
        found.iter().find(|s| plausible_meta(&head, s.text.len())).or(found.first()).copied();
    let Some(s) = best else {
        let shown: String = head[..head.len().min(10)]
            .iter()
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '.' })
            .collect();
        let known: Vec<&str> = SIGNATURES.iter().map(|s| s.text).collect();
        return Err(r.invalid(
            "signature",
            format!("'{shown}' is not a Bonn BTF signature (known: {})", known.join(", ")),
        ));
    };
    r.seek_to(s.text.len() as u64, "signature")?;
    Ok(s)
}

/// Reads the metadata block and checks its declared size.
pub fn read_meta<R: Read + Seek>(r: &mut ByteReader<R>) -> Result<MetaData> {
    let start = r.pos();
    let size = r.u32("meta.size")? as u64;
    let version = r.u32("meta.version")?;
    if !(1..=4).contains(&version) {
        return Err(r.invalid("meta.version", format!("{version} is not in 1..=4")));
    }
    let mut m = MetaData { version, ..MetaData::default() };
    m.measurement_setup = r.text(80, "meta.measurement_setup")?;
    m.image_sensor = r.text(80, "meta.image_sensor")?;
    m.light_source = r.text(80, "meta.light_source")?;
    m.ppmm = r.f32("meta.ppmm")?;
    for c in &mut m.rgb_scale {
        *c = r.f32("meta.rgb_scale_factor")?;
    }
    m.cosine_flag = version > 1 && r.u32("meta.cosine_flag")? != 0;
    if version > 2 {
        let n = r.u32("meta.xml_len")?;
        m.xml = r.text(n as u64, "meta.xml")?;
    }
    if version > 3 {
        let n = r.u32("meta.num_channels")?;
        if n == 0 || n > 1024 {
            return Err(r.invalid("meta.num_channels", format!("{n} is not in 1..=1024")));
        }
        r.check_alloc(n as u64, 4, "meta.num_channels")?;
        m.channel_names = Vec::with_capacity(n as usize);
        for _ in 0..n {
            let len = r.u32("meta.channel_name_len")?;
            m.channel_names.push(r.text(len as u64, "meta.channel_name")?);
        }
    }
    if r.pos() - start != size {
        return Err(r.invalid(
            "meta.size",
            format!(
                "declares {size} bytes but the version-{version} block has {}",
                r.pos() - start
            ),
        ));
    }
    Ok(m)
}

/// Reads the bidirectional sampling: views, each with its light list (all alike).
pub fn read_sampling<R: Read + Seek>(r: &mut ByteReader<R>) -> Result<(Directions, Directions)> {
    let max = r.limits.max_directions as u64;
    let n_v = r.u32("num_views")? as u64;
    if n_v == 0 || n_v > max {
        return Err(r.invalid("num_views", format!("{n_v} is not in 1..={max}")));
    }
    r.check_alloc(n_v, 12, "num_views")?;
    let mut views = Vec::with_capacity(n_v as usize);
    let mut lights: Vec<[f32; 2]> = Vec::new();
    for v in 0..n_v {
        views.push([r.f32("view.theta")?, r.f32("view.phi")?]);
        let n_l = r.u32("num_lights")? as u64;
        if n_l == 0 || n_l > max {
            return Err(r.invalid("num_lights", format!("view {v}: {n_l} is not in 1..={max}")));
        }
        r.check_alloc(n_l, 8, "num_lights")?;
        if v == 0 {
            for _ in 0..n_l {
                lights.push([r.f32("light.theta")?, r.f32("light.phi")?]);
            }
        } else if n_l as usize != lights.len() {
            return Err(crate::Error::unsupported(
                r.file(),
                format!(
                    "view {v} has {n_l} lights, view 0 has {} (only a fixed light set is supported)",
                    lights.len()
                ),
            ));
        } else {
            r.skip(n_l * 8, "light directions")?;
        }
    }
    Ok((views, lights))
}

/// Reads a texture side length.
pub fn read_side<R: Read + Seek>(r: &mut ByteReader<R>, field: &str) -> Result<usize> {
    let v = r.u32(field)? as usize;
    if v == 0 || v > r.limits.max_side {
        return Err(r.invalid(field, format!("{v} is not in 1..={}", r.limits.max_side)));
    }
    Ok(v)
}

/// Reads `u32 count` and that many row-major 3×3 `f32` matrices.
pub fn read_rotations<R: Read + Seek>(r: &mut ByteReader<R>) -> Result<Vec<[f32; 9]>> {
    let n = r.u32("num_rotations")? as u64;
    r.check_alloc(n, 36, "num_rotations")?;
    let flat = r.scalars(n * 9, 4, "rotations")?;
    Ok(flat.chunks_exact(9).map(|c| c.try_into().expect("9 floats")).collect())
}

/// Reads the common header of FMF, DFMF and PVF files, from the start of the file.
pub fn read_header<R: Read + Seek>(r: &mut ByteReader<R>) -> Result<Header> {
    let signature = read_signature(r)?;
    let meta = read_meta(r)?;
    let (views, lights) = read_sampling(r)?;
    let width = read_side(r, "width")?;
    let height = read_side(r, "height")?;
    let rotations = if signature.rotations { read_rotations(r)? } else { Vec::new() };
    Ok(Header { signature, meta, views, lights, width, height, rotations })
}

/// Writes the metadata block in its own `meta.version` layout.
pub fn write_meta(w: &mut impl Write, m: &MetaData) -> std::io::Result<()> {
    let mut body = Vec::new();
    put_u32(&mut body, m.version)?;
    put_text(&mut body, &m.measurement_setup, 80)?;
    put_text(&mut body, &m.image_sensor, 80)?;
    put_text(&mut body, &m.light_source, 80)?;
    put_f32s(&mut body, &[m.ppmm])?;
    put_f32s(&mut body, &m.rgb_scale)?;
    if m.version > 1 {
        put_u32(&mut body, m.cosine_flag as u32)?;
    }
    if m.version > 2 {
        put_u32(&mut body, m.xml.len() as u32)?;
        body.extend_from_slice(m.xml.as_bytes());
    }
    if m.version > 3 {
        put_u32(&mut body, m.channel_names.len() as u32)?;
        for n in &m.channel_names {
            put_u32(&mut body, n.len() as u32)?;
            body.extend_from_slice(n.as_bytes());
        }
    }
    put_u32(w, body.len() as u32 + 4)?;
    w.write_all(&body)
}

/// Writes the bidirectional sampling (every view with the same lights).
pub fn write_sampling(
    w: &mut impl Write,
    views: &[[f32; 2]],
    lights: &[[f32; 2]],
) -> std::io::Result<()> {
    put_u32(w, views.len() as u32)?;
    for v in views {
        put_f32s(w, v)?;
        put_u32(w, lights.len() as u32)?;
        for l in lights {
            put_f32s(w, l)?;
        }
    }
    Ok(())
}

/// Writes the common header of FMF, DFMF and PVF files (signature included).
pub fn write_header(w: &mut impl Write, h: &Header) -> std::io::Result<()> {
    w.write_all(h.signature.text.as_bytes())?;
    write_meta(w, &h.meta)?;
    write_sampling(w, &h.views, &h.lights)?;
    put_u32(w, h.width as u32)?;
    put_u32(w, h.height as u32)?;
    if h.signature.rotations {
        put_u32(w, h.rotations.len() as u32)?;
        for m in &h.rotations {
            put_f32s(w, m)?;
        }
    }
    Ok(())
}

/// The signature entry for a literal signature text.
pub fn signature(text: &str) -> Option<Signature> {
    SIGNATURES.iter().find(|s| s.text == text).copied()
}
