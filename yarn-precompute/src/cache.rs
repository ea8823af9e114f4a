//! `Precomputed`: everything the GPU fiber renderer needs per yarn type — the core texture,
//! the self-shadow volume, the AO texture and cubic, and the ambient integral tables of the
//! fiber model ([W19 eq. 8–10], `yarn::bcsdf::ambient`, reused as is) — baked once and
//! cached on disk by a hash of the yarn parameters and the bake settings.
//!
//! **File** (`<name>-<hash>.ypc`, little-endian, written with `btf_core::fs::write_atomic`):
//! magic `YPRECMP\0`, format version u32, key length u32, the key (UTF-8: format version,
//! the parameters' TOML, the settings' `Debug` text, which prints every float exactly),
//! payload length u64, CRC-32C of the payload u32, payload. A file whose magic, version,
//! key, length or checksum disagree, or whose payload does not parse within its declared
//! sizes, is never trusted: it is baked again and replaced. Sizes are checked against the
//! bytes that remain before anything is allocated.

use crate::ao::{AoCubic, AoTexture};
use crate::core_texture::{CoreTexture, check_sizes};
use crate::self_shadow::SelfShadowVolume;
use crate::settings::{BakeSettings, ShadingModel};
use crate::sigma::field_for;
use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;
use yarn::YarnParams;
use yarn::bcsdf::{AmbientTable, FiberBcsdf};

const MAGIC: &[u8; 8] = b"YPRECMP\0";
/// Version of the file format and of the bake (part of the key: a change of either
/// invalidates every cache file).
pub const FORMAT_VERSION: u32 = 1;

/// Seconds spent per part of a bake (zero when loaded from the cache).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BakeTimes {
    /// Cross-section density and σ field.
    pub density_s: f64,
    /// Core texture.
    pub core_s: f64,
    /// Self-shadow volume.
    pub shadow_s: f64,
    /// AO texture and cubic.
    pub ao_s: f64,
    /// Ambient tables.
    pub ambient_s: f64,
}

/// The whole precomputation of one yarn type.
#[derive(Debug, Clone, PartialEq)]
pub struct Precomputed {
    /// Core-fiber texture.
    pub core: CoreTexture,
    /// Self-shadow volume.
    pub self_shadow: SelfShadowVolume,
    /// AO texture.
    pub ao_texture: AoTexture,
    /// AO cubic fitted to the texture.
    pub ao_cubic: AoCubic,
    /// `∫ f cos θ_i dω_i` over θ_o ([W19 eq. 8–10]).
    pub ambient: AmbientTable,
    /// Where the time went.
    pub times: BakeTimes,
    /// Loaded from a valid cache file.
    pub from_cache: bool,
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

impl Precomputed {
    /// Bakes everything (no cache).
    pub fn bake(params: &YarnParams, settings: &BakeSettings) -> Result<Self> {
        params.validate()?;
        settings.validate()?;
        let mut times = BakeTimes::default();
        let t = Instant::now();
        let field = field_for(params, settings)?;
        let plain = field.symmetrized();
        times.density_s = secs(t);
        let t = Instant::now();
        let core = CoreTexture::bake(params, settings.seed, &settings.core)?;
        times.core_s = secs(t);
        let t = Instant::now();
        let self_shadow =
            SelfShadowVolume::bake(&field, params.ply_count as usize, &settings.shadow);
        times.shadow_s = secs(t);
        let t = Instant::now();
        let ao_texture = AoTexture::bake(&plain, &settings.ao, settings.seed);
        let ao_cubic = AoCubic::fit(&ao_texture, params.yarn_radius(), settings.ao.radial_bins);
        times.ao_s = secs(t);
        let t = Instant::now();
        let bcsdf = match &settings.shading {
            ShadingModel::Simple(p) => FiberBcsdf::simple(p)?,
            ShadingModel::Khungurn(p) => FiberBcsdf::khungurn(p)?,
            ShadingModel::Huang(p) => FiberBcsdf::huang(p)?,
        };
        let ambient = AmbientTable::build(&bcsdf, settings.ambient_entries);
        times.ambient_s = secs(t);
        Ok(Precomputed {
            core,
            self_shadow,
            ao_texture,
            ao_cubic,
            ambient,
            times,
            from_cache: false,
        })
    }

    /// The cache key of `params` and `settings` (see the module documentation).
    pub fn cache_key(params: &YarnParams, settings: &BakeSettings) -> Result<String> {
        Ok(format!("yarn-precompute v{FORMAT_VERSION}\n{}\n{settings:?}\n", params.to_toml()?))
    }

    /// The cache file of `params` and `settings` inside `dir`.
    pub fn cache_path(dir: &Path, params: &YarnParams, settings: &BakeSettings) -> Result<PathBuf> {
        let key = Self::cache_key(params, settings)?;
        let name: String = params
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' })
            .take(48)
            .collect();
        Ok(dir.join(format!("{name}-{:016x}.ypc", key_hash(key.as_bytes()))))
    }

    /// The precomputation of `params`: read from `cache_dir` when a valid file for exactly
    /// these parameters and settings is there, otherwise baked (and written there).
    pub fn for_params(
        params: &YarnParams,
        settings: &BakeSettings,
        cache_dir: Option<&Path>,
    ) -> Result<Self> {
        params.validate()?;
        settings.validate()?;
        let Some(dir) = cache_dir else {
            return Self::bake(params, settings);
        };
        let key = Self::cache_key(params, settings)?;
        let path = Self::cache_path(dir, params, settings)?;
        if let Ok(bytes) = std::fs::read(&path)
            && let Some(mut p) = decode(&bytes, &key)
        {
            p.from_cache = true;
            return Ok(p);
        }
        let p = Self::bake(params, settings)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        btf_core::fs::write_atomic(&path, &encode(&p, &key))?;
        Ok(p)
    }
}

/// 64-bit key hash (`yarn::hash` over 8-byte chunks and the length).
pub(crate) fn key_hash(bytes: &[u8]) -> u64 {
    yarn::hash::hash_bytes(bytes)
}

/// A cache file: `magic`, `version`, the key (length-prefixed), the payload length and
/// its CRC-32C, the payload. Every bake of this crate writes its payload so.
pub(crate) fn frame(magic: &[u8; 8], version: u32, key: &str, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + key.len() + 32);
    out.extend(magic);
    out.extend(version.to_le_bytes());
    out.extend((key.len() as u32).to_le_bytes());
    out.extend(key.as_bytes());
    out.extend((payload.len() as u64).to_le_bytes());
    out.extend(crc32c::crc32c(payload).to_le_bytes());
    out.extend(payload);
    out
}

/// The payload of a [`frame`]d file if its magic, version and key are exactly these, its
/// length is what it says and its CRC matches (else `None`: the caller rebuilds).
pub(crate) fn unframe<'a>(
    bytes: &'a [u8],
    magic: &[u8; 8],
    version: u32,
    key: &str,
) -> Option<&'a [u8]> {
    let mut r = Reader(bytes);
    if r.take(8)? != magic || u32::from_le_bytes(r.take(4)?.try_into().ok()?) != version {
        return None;
    }
    let klen = u32::from_le_bytes(r.take(4)?.try_into().ok()?) as usize;
    if r.take(klen)? != key.as_bytes() {
        return None;
    }
    let plen = r.u64()?;
    let crc = u32::from_le_bytes(r.take(4)?.try_into().ok()?);
    let payload = r.take(plen)?;
    (r.0.is_empty() && crc32c::crc32c(payload) == crc).then_some(payload)
}

pub(crate) struct Writer(pub(crate) Vec<u8>);

impl Writer {
    pub(crate) fn u64(&mut self, v: usize) {
        self.0.extend((v as u64).to_le_bytes());
    }
    pub(crate) fn f64s(&mut self, v: &[f64]) {
        v.iter().for_each(|x| self.0.extend(x.to_le_bytes()));
    }
    pub(crate) fn f32s(&mut self, v: &[f32]) {
        self.u64(v.len());
        v.iter().for_each(|x| self.0.extend(x.to_le_bytes()));
    }
}

/// Reads what [`Writer`] wrote; every length is checked against the bytes that remain.
pub(crate) struct Reader<'a>(pub(crate) &'a [u8]);

impl<'a> Reader<'a> {
    pub(crate) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        if n > self.0.len() {
            return None;
        }
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        Some(a)
    }
    pub(crate) fn u64(&mut self) -> Option<usize> {
        let v = u64::from_le_bytes(self.take(8)?.try_into().ok()?);
        usize::try_from(v).ok()
    }
    pub(crate) fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    pub(crate) fn f32s(&mut self) -> Option<Vec<f32>> {
        let n = self.u64()?;
        let bytes = self.take(n.checked_mul(4)?)?;
        Some(bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect())
    }
}

fn encode(p: &Precomputed, key: &str) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    let c = &p.core;
    w.u64(c.width);
    w.u64(c.height);
    w.u64(c.core_fibers);
    w.f64s(&[c.half_width_circ, c.ellipse[0], c.ellipse[1], c.fiber_pitch, c.ply_pitch]);
    w.f32s(&c.tex_a);
    w.f32s(&c.tex_b);
    let s = &p.self_shadow;
    w.u64(s.res);
    w.u64(s.slices);
    w.u64(s.ply_count);
    w.f64s(&[s.half_width]);
    w.f32s(&s.depth);
    let a = &p.ao_texture;
    w.u64(a.res);
    w.f64s(&[a.half_width]);
    w.f32s(&a.ao);
    let q = &p.ao_cubic;
    w.f64s(&q.coeffs);
    w.f64s(&[q.yarn_radius, q.rms_residual]);
    w.u64(p.ambient.theta_o.len());
    w.f64s(&p.ambient.theta_o);
    p.ambient.values.iter().for_each(|v| w.f64s(v));
    frame(MAGIC, FORMAT_VERSION, key, &w.0)
}

/// The bundle in `bytes` if the header carries exactly `key` and the payload is intact.
fn decode(bytes: &[u8], key: &str) -> Option<Precomputed> {
    let payload = unframe(bytes, MAGIC, FORMAT_VERSION, key)?;
    let p = parse(&mut Reader(payload))?;
    check_sizes(&p.core).ok()?;
    let s = &p.self_shadow;
    let sizes_ok = s.slices >= 2
        && s.res.checked_mul(s.res)?.checked_mul(s.slices)? == s.depth.len()
        && p.ao_texture.res.checked_mul(p.ao_texture.res)? == p.ao_texture.ao.len()
        && p.ambient.theta_o.len() >= 2;
    sizes_ok.then_some(p)
}

fn parse(r: &mut Reader) -> Option<Precomputed> {
    let (width, height, core_fibers) = (r.u64()?, r.u64()?, r.u64()?);
    let [half_width_circ, en, eb, fiber_pitch, ply_pitch] =
        [r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?];
    let (tex_a, tex_b) = (r.f32s()?, r.f32s()?);
    let core = CoreTexture {
        width,
        height,
        tex_a,
        tex_b,
        half_width_circ,
        ellipse: [en, eb],
        fiber_pitch,
        ply_pitch,
        core_fibers,
    };
    let (res, slices, ply_count) = (r.u64()?, r.u64()?, r.u64()?);
    let half_width = r.f64()?;
    let depth = r.f32s()?;
    let self_shadow = SelfShadowVolume { res, slices, ply_count, half_width, depth };
    let ao_res = r.u64()?;
    let ao_half = r.f64()?;
    let ao = r.f32s()?;
    let ao_texture = AoTexture { res: ao_res, half_width: ao_half, ao };
    let coeffs = [r.f64()?, r.f64()?, r.f64()?, r.f64()?];
    let ao_cubic = AoCubic { coeffs, yarn_radius: r.f64()?, rms_residual: r.f64()? };
    let n = r.u64()?;
    if n.checked_mul(32)? > r.0.len() {
        return None;
    }
    let theta_o = (0..n).map(|_| r.f64()).collect::<Option<Vec<_>>>()?;
    let values =
        (0..n).map(|_| Some([r.f64()?, r.f64()?, r.f64()?])).collect::<Option<Vec<_>>>()?;
    let ambient = AmbientTable { theta_o, values };
    r.0.is_empty().then_some(Precomputed {
        core,
        self_shadow,
        ao_texture,
        ao_cubic,
        ambient,
        times: BakeTimes::default(),
        from_cache: false,
    })
}

#[cfg(test)]
mod tests;
