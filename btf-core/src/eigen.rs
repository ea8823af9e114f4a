//! The eigen store: per view slot `j`, the mean texture `μ_j`, `c` eigentextures `B_kj`, the
//! per-light weights `p_ikj` and all eigenvalues ([S03 eq. 1]), in a Zarr v3
//! group chunked per view slot.
//!
//! Eigentextures are stored quantised, `f16` (default) or `u8`, each component with its own
//! `(scale, offset)`: the value is `stored · scale + offset`. For `f16` the scale is the
//! power of two at or above the component's largest magnitude ([`f16_scale`]), so the
//! stored values lie in `[-1, 1]` where half precision is densest and a store re-quantised
//! after a round trip (export, import) keeps its bits; for `u8` the range `[min, max]` maps
//! onto 0‥255. Means and weights are `f32`, eigenvalues `f64`.

use crate::sampling::Sampling;
pub use crate::store::SlotState;
use crate::store::{BtfMeta, StoreTxn, read_meta_of_kind};
use crate::zarr::{self, ArrayMeta, Compression, DType, Limits, ZarrArray};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};

/// How eigentextures are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Quantization {
    /// Half precision, scaled to `[-1, 1]` per component.
    #[default]
    F16,
    /// 8 bits per value with a per-component scale and offset.
    U8,
}

impl Quantization {
    /// Element type on disk.
    pub fn dtype(self) -> DType {
        match self {
            Quantization::F16 => DType::F16,
            Quantization::U8 => DType::U8,
        }
    }
    /// Name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Quantization::F16 => "f16",
            Quantization::U8 => "u8",
        }
    }
}

impl std::str::FromStr for Quantization {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "f16" => Ok(Quantization::F16),
            "u8" => Ok(Quantization::U8),
            o => Err(Error::Invalid(format!("unknown quantisation '{o}' (f16|u8)"))),
        }
    }
}

/// Metadata of an eigen store (group attributes `"btf"` and `"eigen"`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EigenMeta {
    /// Samplings, size, colour space, units and provenance of the compressed BTF.
    pub btf: BtfMeta,
    /// Components kept per slot.
    pub components: usize,
    /// Storage of the eigentextures.
    pub quantization: Quantization,
}

/// One view slot, dequantised, ready for CPU reconstruction.
#[derive(Debug, Clone)]
pub struct EigenSlot {
    /// View slot index.
    pub view: usize,
    /// Mean texture, `texel_values` floats.
    pub mean: Vec<f32>,
    /// Eigentextures, `components × texel_values`, row-major, dequantised.
    pub basis: Vec<f32>,
    /// Weights `p_ik`, `n_lights × components`, row-major.
    pub weights: Vec<f32>,
    /// All eigenvalues of the slot's centred Gram matrix, descending.
    pub eigenvalues: Vec<f64>,
    /// Components per slot.
    pub components: usize,
}

impl EigenSlot {
    /// Eigentexture `k`.
    pub fn basis_row(&self, k: usize) -> &[f32] {
        let n = self.mean.len();
        &self.basis[k * n..(k + 1) * n]
    }
    /// Weights of light `i`.
    pub fn weights_of(&self, light: usize) -> &[f32] {
        &self.weights[light * self.components..(light + 1) * self.components]
    }
}

/// One view slot as stored: quantised eigentextures and their dequantisation parameters —
/// what a GPU uploads without re-encoding.
#[derive(Debug, Clone)]
pub struct QuantizedSlot {
    /// Mean texture (`f32`).
    pub mean: Vec<f32>,
    /// Raw little-endian eigentexture bytes, `components × texel_values` elements.
    pub eigentextures: Vec<u8>,
    /// `(scale, offset)` per component.
    pub scale_offset: Vec<[f32; 2]>,
    /// Weights, `n_lights × components`.
    pub weights: Vec<f32>,
    /// Eigenvalues, descending.
    pub eigenvalues: Vec<f64>,
}

struct Arrays {
    mean: ZarrArray,
    eig: ZarrArray,
    scale: ZarrArray,
    weights: ZarrArray,
    values: ZarrArray,
}

/// The arrays of an eigen store, the means and eigentextures chunked with `bulk`.
fn array_metas(m: &EigenMeta, bulk: Compression) -> [(&'static str, ArrayMeta); 5] {
    let (v, l, h, w, c) = (
        m.btf.n_views() as u64,
        m.btf.n_lights() as u64,
        m.btf.height as u64,
        m.btf.width as u64,
        m.components as u64,
    );
    [
        (
            "mean",
            ArrayMeta {
                compression: bulk,
                ..ArrayMeta::new(
                    vec![v, h, w, 3],
                    vec![1, h, w, 3],
                    DType::F32,
                    &["view", "y", "x", "channel"],
                )
            },
        ),
        (
            "eigentextures",
            ArrayMeta {
                attributes: json!({
                    "description": "unit-norm eigentextures B_kj, quantised: value = stored * scale_offset[view, component, 0] + scale_offset[view, component, 1]",
                }),
                compression: bulk,
                ..ArrayMeta::new(
                    vec![v, c, h, w, 3],
                    vec![1, c, h, w, 3],
                    m.quantization.dtype(),
                    &["view", "component", "y", "x", "channel"],
                )
            },
        ),
        (
            "scale_offset",
            ArrayMeta {
                attributes: json!({
                    "description": "per (view, component): [scale, offset]; eigentexture value = stored * scale + offset",
                }),
                ..ArrayMeta::new(
                    vec![v, c, 2],
                    vec![1, c, 2],
                    DType::F32,
                    &["view", "component", "scale_offset"],
                )
            },
        ),
        (
            "weights",
            ArrayMeta::new(
                vec![v, l, c],
                vec![1, l, c],
                DType::F32,
                &["view", "light", "component"],
            ),
        ),
        ("eigenvalues", ArrayMeta::new(vec![v, l], vec![1, l], DType::F64, &["view", "index"])),
    ]
}

fn open_arrays(dir: &Path, m: &EigenMeta, create: bool, bulk: Compression) -> Result<Arrays> {
    let mut it = array_metas(m, bulk).into_iter().map(|(name, meta)| {
        let p = dir.join(name);
        if create {
            ZarrArray::create(&p, meta)
        } else {
            let a = ZarrArray::open(&p, &Limits::default())?;
            // Stores before issue #25 are uncompressed: any codec chain we read is fine.
            let meta = ArrayMeta { compression: a.meta().compression, ..meta };
            if a.meta() != &meta {
                return Err(Error::Corrupt {
                    path: p.join("zarr.json"),
                    what: "array shape disagrees with the store metadata".into(),
                });
            }
            Ok(a)
        }
    });
    let mut next = || it.next().unwrap();
    let (mean, eig) = (next()?, next()?);
    // The means and eigentextures are almost all of a store's bytes, and a compression run
    // never reads them back: written by direct I/O, they cost the disk's time, not a core's.
    let (mean, eig) =
        if create { (mean.with_direct_writes(), eig.with_direct_writes()) } else { (mean, eig) };
    Ok(Arrays { mean, eig, scale: next()?, weights: next()?, values: next()? })
}

/// Quantises `basis` (`components × n` floats) per component; returns raw bytes and
/// `(scale, offset)` pairs.
pub fn quantize(basis: &[f32], components: usize, q: Quantization) -> (Vec<u8>, Vec<[f32; 2]>) {
    let n = basis.len().checked_div(components).unwrap_or(0);
    let mut raw = Vec::with_capacity(basis.len() * q.dtype().size());
    let mut so = Vec::with_capacity(components);
    for k in 0..components {
        let row = &basis[k * n..(k + 1) * n];
        match q {
            Quantization::F16 => {
                let m = row.iter().fold(0f32, |a, v| a.max(v.abs()));
                let scale = f16_scale(m);
                let scaled: Vec<f32> = row.iter().map(|v| v / scale).collect();
                // The slice conversion (F16C where the CPU has it), little-endian bytes.
                let mut halves = vec![half::f16::ZERO; row.len()];
                half::slice::HalfFloatSliceExt::convert_from_f32_slice(&mut halves[..], &scaled);
                if cfg!(target_endian = "little") {
                    raw.extend_from_slice(bytemuck::cast_slice(&halves));
                } else {
                    raw.extend(halves.iter().flat_map(|h| h.to_le_bytes()));
                }
                so.push([scale, 0.0]);
            }
            Quantization::U8 => {
                let (lo, hi) =
                    row.iter().fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
                let scale = if hi > lo { (hi - lo) / 255.0 } else { 1.0 };
                raw.extend(row.iter().map(|v| ((v - lo) / scale).round().clamp(0.0, 255.0) as u8));
                so.push([scale, lo]);
            }
        }
    }
    (raw, so)
}

/// The `f16` scale of a component whose largest magnitude is `largest`: the power of two
/// at or above it (1 for an all-zero component). Dividing by it is exact, so quantising
/// what [`dequantize`] returns gives back the same halves, and the compressor's fused pass
/// (which rounds first and rescales after) stores exactly what this would.
pub fn f16_scale(largest: f32) -> f32 {
    if largest > 0.0 && largest.is_finite() { 2f32.powi(largest.log2().ceil() as i32) } else { 1.0 }
}

/// Inverse of [`quantize`].
pub fn dequantize(raw: &[u8], scale_offset: &[[f32; 2]], q: Quantization) -> Vec<f32> {
    let mut out = vec![0f32; raw.len() / q.dtype().size()];
    zarr::decode_to_f32(raw, q.dtype(), &mut out);
    let c = scale_offset.len().max(1);
    let n = out.len() / c;
    for (k, row) in out.chunks_mut(n.max(1)).enumerate() {
        let [s, o] = scale_offset[k.min(c - 1)];
        for v in row {
            *v = *v * s + o;
        }
    }
    out
}

/// Writer of an eigen store, one slot at a time, resumable.
pub struct EigenWriter {
    txn: StoreTxn,
    meta: EigenMeta,
    arrays: Arrays,
}

impl EigenWriter {
    /// Starts an eigen store at `path`; a resume must match `meta`.
    pub fn create(path: &Path, meta: EigenMeta, resume: bool) -> Result<Self> {
        Self::create_for_job(path, meta, resume, serde_json::Value::Null)
    }

    /// [`EigenWriter::create`] with more to the job than the metadata (e.g. the identity of
    /// the input store): a resume must match `job` too.
    pub fn create_for_job(
        path: &Path,
        meta: EigenMeta,
        resume: bool,
        job: serde_json::Value,
    ) -> Result<Self> {
        Self::create_for_job_with(path, meta, resume, job, Compression::FAST)
    }

    /// [`EigenWriter::create_for_job`] with the chunks of the means and eigentextures (all
    /// but a few kilobytes of the store) in `bulk` ([`Compression::FAST`] by default;
    /// [`Compression::None`] writes them raw, for a faster compression and a larger store).
    /// A resumed store keeps the codec it was begun with.
    pub fn create_for_job_with(
        path: &Path,
        meta: EigenMeta,
        resume: bool,
        job: serde_json::Value,
        bulk: Compression,
    ) -> Result<Self> {
        if meta.components == 0 || meta.components > meta.btf.n_lights() {
            return Err(Error::Invalid(format!(
                "components {} not in 1..={}",
                meta.components,
                meta.btf.n_lights()
            )));
        }
        let record = serde_json::json!({"store": "eigen", "meta": meta, "job": job});
        let txn = StoreTxn::begin(path, resume, &record)?;
        let arrays = open_arrays(txn.dir(), &meta, true, bulk)?;
        zarr::ensure_record_group(txn.dir(), "stats")?;
        Ok(EigenWriter { txn, meta, arrays })
    }

    /// [`EigenWriter::create_for_job`] for one shard of several writing into one store at
    /// once ([`StoreTxn::join`]): the first creates the partial store and its job record,
    /// the others check that they agree before writing anything. Nothing is committed: the
    /// finaliser does that ([`EigenWriter::reopen`], then [`EigenWriter::finish`]).
    pub fn join_for_job(path: &Path, meta: EigenMeta, job: serde_json::Value) -> Result<Self> {
        Self::join_for_job_with(path, meta, job, Compression::FAST)
    }

    /// [`EigenWriter::join_for_job`] with the means and eigentextures in `bulk`, as
    /// [`EigenWriter::create_for_job_with`] (the shard that creates the store chooses; the
    /// others keep its codec).
    pub fn join_for_job_with(
        path: &Path,
        meta: EigenMeta,
        job: serde_json::Value,
        bulk: Compression,
    ) -> Result<Self> {
        let record = serde_json::json!({"store": "eigen", "meta": meta, "job": job});
        let txn = StoreTxn::join(path, &record)?;
        let arrays = open_arrays(txn.dir(), &meta, true, bulk)?;
        zarr::ensure_record_group(txn.dir(), "stats")?;
        Ok(EigenWriter { txn, meta, arrays })
    }

    /// Reopens the partial eigen store of `path` that shards filled, to check and commit
    /// it; returns the writer and the job (`"job"` of the record) it was begun for.
    pub fn reopen(path: &Path) -> Result<(Self, serde_json::Value)> {
        let (txn, record) = StoreTxn::reopen(path)?;
        if record.get("store") != Some(&json!("eigen")) {
            return Err(Error::Invalid(format!(
                "{}: the partial store beside it is not an eigen store",
                path.display()
            )));
        }
        let mut meta: EigenMeta = serde_json::from_value(record["meta"].clone())
            .map_err(|source| Error::Json { path: txn.dir().join("zarr.json"), source })?;
        meta.btf = meta.btf.validate(txn.dir())?;
        // The arrays exist: each keeps the codec its store was begun with.
        let arrays = open_arrays(txn.dir(), &meta, true, Compression::FAST)?;
        zarr::ensure_record_group(txn.dir(), "stats")?;
        Ok((EigenWriter { txn, meta, arrays }, record["job"].clone()))
    }

    /// The partial eigen store of `path` opened for reading its state only (nothing is
    /// created or removed); returns the writer and the job (`"job"` of the record).
    pub fn open_partial(path: &Path) -> Result<(Self, serde_json::Value)> {
        let (txn, record) = StoreTxn::peek(path).ok_or_else(|| {
            Error::Invalid(format!("{}: no partial store beside it", path.display()))
        })?;
        let mut meta: EigenMeta = serde_json::from_value(record["meta"].clone())
            .map_err(|source| Error::Json { path: txn.dir().join("zarr.json"), source })?;
        meta.btf = meta.btf.validate(txn.dir())?;
        let arrays = open_arrays(txn.dir(), &meta, false, Compression::FAST)?;
        Ok((EigenWriter { txn, meta, arrays }, record["job"].clone()))
    }

    /// The metadata being written.
    pub fn meta(&self) -> &EigenMeta {
        &self.meta
    }

    /// The state of slot `view` in the store being written: every chunk present with a
    /// valid crc32c ([`zarr::ZarrArray::verify_chunk`]) and its statistics recorded, some
    /// chunk missing, or a chunk failing its check (the error names the file).
    pub fn slot_state(&self, view: usize) -> SlotState {
        let v = view as u64;
        let a = &self.arrays;
        let chunks: [(&ZarrArray, Vec<u64>); 5] = [
            (&a.values, vec![v, 0]),
            (&a.mean, vec![v, 0, 0, 0]),
            (&a.eig, vec![v, 0, 0, 0, 0]),
            (&a.weights, vec![v, 0, 0]),
            (&a.scale, vec![v, 0, 0]),
        ];
        for (arr, idx) in &chunks {
            if !arr.chunk_path(idx).exists() {
                return SlotState::Missing;
            }
        }
        for (arr, idx) in &chunks {
            if let Err(e) = arr.verify_chunk(idx) {
                return SlotState::Corrupt(e.to_string());
            }
        }
        if self.read_stats(view).is_none() {
            return SlotState::Missing;
        }
        SlotState::Done
    }

    /// True when slot `view` is fully written (for resuming).
    pub fn has_slot(&self, view: usize) -> bool {
        let v = view as u64;
        self.arrays.values.has_chunk(&[v, 0])
            && self.arrays.mean.has_chunk(&[v, 0, 0, 0])
            && self.arrays.eig.has_chunk(&[v, 0, 0, 0, 0])
            && self.arrays.weights.has_chunk(&[v, 0, 0])
            && self.arrays.scale.has_chunk(&[v, 0, 0])
    }

    /// Writes one slot. The eigenvalues chunk goes last, so its presence marks the slot done.
    pub fn write_slot(&self, view: usize, slot: &QuantizedSlot) -> Result<()> {
        let v = view as u64;
        let c = self.meta.components;
        let n_l = self.meta.btf.n_lights();
        if slot.scale_offset.len() != c
            || slot.weights.len() != n_l * c
            || slot.mean.len() != self.meta.btf.texel_values()
        {
            return Err(Error::Invalid(format!(
                "slot {view}: arrays do not match the store's shape"
            )));
        }
        for (l, w) in slot.weights.chunks(c).enumerate() {
            crate::store::check_finite(w, view, l, 0)?;
        }
        let mut ev = slot.eigenvalues.clone();
        ev.resize(n_l, 0.0);
        let ev_raw: Vec<u8> = ev.iter().flat_map(|x| x.to_le_bytes()).collect();
        let so: Vec<f32> = slot.scale_offset.iter().flatten().copied().collect();
        self.arrays.mean.write_chunk(&[v, 0, 0, 0], &zarr::encode_f32(&slot.mean, DType::F32))?;
        self.arrays.eig.write_chunk(&[v, 0, 0, 0, 0], &slot.eigentextures)?;
        self.arrays.scale.write_chunk(&[v, 0, 0], &zarr::encode_f32(&so, DType::F32))?;
        self.arrays
            .weights
            .write_chunk(&[v, 0, 0], &zarr::encode_f32(&slot.weights, DType::F32))?;
        self.arrays.values.write_chunk(&[v, 0], &ev_raw)
    }

    /// Stores per-slot statistics beside the arrays, as the attributes of the Zarr group
    /// `stats/<view>` ([`zarr::write_record`]); they survive a resume.
    pub fn write_stats(&self, view: usize, stats: &serde_json::Value) -> Result<()> {
        zarr::write_record(self.txn.dir(), "stats", &view.to_string(), stats)
    }

    /// Statistics written for slot `view` by [`EigenWriter::write_stats`], if any.
    pub fn read_stats(&self, view: usize) -> Option<serde_json::Value> {
        zarr::read_record(self.txn.dir(), "stats", &view.to_string())
    }

    /// Checks every slot is present and moves the store into place.
    pub fn finish(self) -> Result<()> {
        for v in 0..self.meta.btf.n_views() {
            if !self.has_slot(v) {
                return Err(Error::Invalid(format!("view slot {v} was never written")));
            }
        }
        let mut btf = self.meta.btf.clone();
        btf.kind = "eigen".into();
        crate::axes::write(self.txn.dir(), &btf)?;
        let attrs = json!({"btf": btf, "eigen": {"components": self.meta.components, "quantization": self.meta.quantization}});
        self.txn.commit(attrs)
    }
}

/// An eigen store opened for reading.
pub struct EigenStore {
    path: PathBuf,
    meta: EigenMeta,
    arrays: Arrays,
}

impl EigenStore {
    /// Opens an eigen store, validating metadata and limits before reading any chunk.
    pub fn open(path: &Path) -> Result<Self> {
        let btf = read_meta_of_kind(path, "eigen", " (run `btf compress` first)")?;
        let attrs = zarr::read_group(path)?;
        let components = attrs["eigen"]["components"].as_u64().unwrap_or(0) as usize;
        let quantization: Quantization =
            serde_json::from_value(attrs["eigen"]["quantization"].clone())
                .map_err(|source| Error::Json { path: path.join("zarr.json"), source })?;
        if components == 0 || components > btf.n_lights() {
            return Err(Error::Corrupt {
                path: path.join("zarr.json"),
                what: format!("components {components} out of range"),
            });
        }
        crate::axes::check(path, &btf)?;
        let meta = EigenMeta { btf, components, quantization };
        let arrays = open_arrays(path, &meta, false, Compression::FAST)?;
        Ok(EigenStore { path: path.to_owned(), meta, arrays })
    }

    /// The store's metadata.
    pub fn meta(&self) -> &EigenMeta {
        &self.meta
    }
    /// The store's folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes of all chunks on disk.
    pub fn bytes(&self) -> u64 {
        let v = self.meta.btf.n_views() as u64;
        [
            &self.arrays.mean,
            &self.arrays.eig,
            &self.arrays.scale,
            &self.arrays.weights,
            &self.arrays.values,
        ]
        .iter()
        .map(|a| a.meta().chunk_bytes().unwrap_or(0) * v)
        .sum()
    }

    fn named<T>(&self, view: usize, r: Result<T>) -> Result<T> {
        r.map_err(|e| match e {
            Error::Corrupt { path, what } => {
                Error::Corrupt { path, what: format!("view slot {view}: {what}") }
            }
            o => o,
        })
    }

    /// Checks that every chunk of every view slot is on disk with the size the metadata
    /// claims (sizes only, not checksums): a reader that allocates for the whole store at
    /// once calls this first, so that metadata claiming more than the files hold is refused
    /// by naming the chunk file instead of aborting on the allocation.
    pub fn check_chunks(&self) -> Result<()> {
        for view in 0..self.meta.btf.n_views() as u64 {
            let a = &self.arrays;
            let checks = [
                a.mean.check_chunk_file(&[view, 0, 0, 0]),
                a.eig.check_chunk_file(&[view, 0, 0, 0, 0]),
                a.scale.check_chunk_file(&[view, 0, 0]),
                a.weights.check_chunk_file(&[view, 0, 0]),
                a.values.check_chunk_file(&[view, 0]),
            ];
            for c in checks {
                self.named(view as usize, c)?;
            }
        }
        Ok(())
    }

    /// Per-slot statistics written at compression time, if present (`stats/<view>` group
    /// attributes; `stats/<view>.json` in stores before issue #25).
    pub fn slot_stats(&self, view: usize) -> Option<serde_json::Value> {
        zarr::read_record(&self.path, "stats", &view.to_string())
    }

    /// Reads slot `view` as stored.
    pub fn read_quantized(&self, view: usize) -> Result<QuantizedSlot> {
        if view >= self.meta.btf.n_views() {
            return Err(Error::Invalid(format!(
                "view slot {view} out of range 0..{}",
                self.meta.btf.n_views()
            )));
        }
        let v = view as u64;
        let f32s = |raw: Vec<u8>| {
            let mut out = vec![0f32; raw.len() / 4];
            zarr::decode_to_f32(&raw, DType::F32, &mut out);
            out
        };
        let mean = f32s(self.named(view, self.arrays.mean.read_chunk(&[v, 0, 0, 0]))?);
        let eigentextures = self.named(view, self.arrays.eig.read_chunk(&[v, 0, 0, 0, 0]))?;
        let so = f32s(self.named(view, self.arrays.scale.read_chunk(&[v, 0, 0]))?);
        let weights = f32s(self.named(view, self.arrays.weights.read_chunk(&[v, 0, 0]))?);
        let eigenvalues =
            zarr::decode_f64(&self.named(view, self.arrays.values.read_chunk(&[v, 0]))?);
        // A valid checksum only says the bytes are as written: refuse non-finite values
        // here, naming the store, array and slot, so no command passes them on.
        self.finite(view, "mean", mean.iter().map(|&x| x as f64))?;
        self.finite(view, "scale_offset", so.iter().map(|&x| x as f64))?;
        self.finite(view, "weights", weights.iter().map(|&x| x as f64))?;
        self.finite(view, "eigenvalues", eigenvalues.iter().copied())?;
        if self.meta.quantization == Quantization::F16 {
            let bits = eigentextures.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]]));
            self.finite(
                view,
                "eigentextures",
                bits.map(|h| if h & 0x7c00 == 0x7c00 { f64::NAN } else { 0.0 }),
            )?;
        }
        let scale_offset = so.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
        Ok(QuantizedSlot { mean, eigentextures, scale_offset, weights, eigenvalues })
    }

    fn finite(&self, view: usize, array: &str, values: impl Iterator<Item = f64>) -> Result<()> {
        for (i, x) in values.enumerate() {
            if !x.is_finite() {
                return Err(Error::Corrupt {
                    path: self.path.join(array),
                    what: format!("non-finite value ({x}) in view slot {view}, element {i}"),
                });
            }
        }
        Ok(())
    }

    /// Reads slot `view`, dequantised.
    pub fn read_slot(&self, view: usize) -> Result<EigenSlot> {
        let q = self.read_quantized(view)?;
        let basis = dequantize(&q.eigentextures, &q.scale_offset, self.meta.quantization);
        Ok(EigenSlot {
            view,
            mean: q.mean,
            basis,
            weights: q.weights,
            eigenvalues: q.eigenvalues,
            components: self.meta.components,
        })
    }

    /// The view sampling.
    pub fn view_sampling(&self) -> &Sampling {
        &self.meta.btf.view_sampling
    }
    /// The light sampling.
    pub fn light_sampling(&self) -> &Sampling {
        &self.meta.btf.light_sampling
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantize_round_trip_error_bounds() {
        let basis: Vec<f32> = (0..2000).map(|i| ((i as f32) * 0.37).sin() * 0.01 - 0.002).collect();
        for (q, tol) in [
            (Quantization::F16, 0.012 * 2f32.powi(-11)),
            (Quantization::U8, 0.02 / 255.0 * 0.5 + 1e-7),
        ] {
            let (raw, so) = quantize(&basis, 2, q);
            let back = dequantize(&raw, &so, q);
            let err = basis.iter().zip(&back).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
            assert!(err <= tol * 1.01, "{q:?}: {err} > {tol}");
            if q == Quantization::F16 {
                // Power-of-two scales: quantising the dequantised values keeps every bit.
                assert!(so.iter().all(|[s, _]| *s == f16_scale(*s)), "{so:?}");
                assert_eq!(quantize(&back, 2, q), (raw, so), "f16 re-quantisation");
            }
        }
    }
}
