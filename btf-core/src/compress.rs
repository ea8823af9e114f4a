//! Compression of a whole BTF store into an eigen store: the per-slot PCA of [S03 eq. 1] run over
//! all view slots in parallel, one slot in memory per worker, with per-slot statistics kept
//! beside the arrays so an interrupted run resumes where it stopped.

use crate::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot};
use crate::metrics::{psnr_db, rel_rmse_from};
use crate::pca::{GramPrecision, PcaScratch, SlotRows, max_components, pca_rows_in, pca_slot_in};
use crate::shard::Shard;
use crate::store::{BtfStore, ShardedStatus, SlotData};
use crate::zarr::{Compression, DType};
use crate::{Error, Result};
use half::f16;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, mpsc};
use std::time::Instant;

/// Parameters of [`compress`].
#[derive(Debug, Clone, Copy)]
pub struct CompressParams {
    /// Components wanted per slot (clamped to what the data allows, with a warning).
    pub components: usize,
    /// Storage of the eigentextures.
    pub quantization: Quantization,
    /// Keep slots already written by an interrupted run.
    pub resume: bool,
    /// The Gram matrix's arithmetic (by default `f32` lanes for `f16` stores, `f64` else).
    pub gram: GramPrecision,
    /// The chunk codec of the means and eigentextures ([`Compression::FAST`] by default;
    /// [`Compression::None`]: no encoding, a larger store — BENCHMARKS.md, "Session 29").
    pub codec: Compression,
}

impl Default for CompressParams {
    fn default() -> Self {
        CompressParams {
            components: 16,
            quantization: Quantization::F16,
            resume: false,
            gram: GramPrecision::Auto,
            codec: Compression::FAST,
        }
    }
}

/// Statistics of one slot.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SlotReport {
    /// View slot index.
    pub view: usize,
    /// Squared error of the exact `c`-component PCA, measured from the data.
    pub sse: f64,
    /// Squared error of what is stored (after quantisation).
    pub sse_stored: f64,
    /// Sum of the discarded eigenvalues.
    pub discarded_eigen_sum: f64,
    /// `Σ ‖x‖²` of the slot's images.
    pub energy: f64,
    /// Largest input value in the slot.
    pub peak: f32,
    /// Components with non-zero eigenvalue.
    pub effective_components: usize,
    /// Wall-clock seconds spent on the slot (reading included; the writing is the writer
    /// thread's).
    pub seconds: f64,
}

/// Result of [`compress`].
#[derive(Debug, Clone, Serialize)]
pub struct CompressReport {
    /// Components stored per slot.
    pub components: usize,
    /// Components asked for.
    pub requested_components: usize,
    /// Storage of the eigentextures.
    pub quantization: Quantization,
    /// Relative RMSE of the stored representation over the whole BTF.
    pub rel_rmse: f64,
    /// PSNR of the stored representation (peak = largest input value), dB.
    pub psnr_db: f64,
    /// Relative RMSE of the exact (unquantised) PCA.
    pub rel_rmse_exact: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// The kernel path the PCA ran on (`BTF_SIMD`, or the best the CPU has).
    pub simd: &'static str,
    /// The Gram matrix's arithmetic: `"f64"` or `"f32"` ([`GramPrecision`]).
    pub gram: &'static str,
    /// Bytes of the input store's chunks.
    pub input_bytes: u64,
    /// Bytes of the output store's chunks.
    pub output_bytes: u64,
    /// Slots taken from an interrupted run instead of recomputed.
    pub resumed_slots: usize,
    /// Warnings for the user (clamped components, rank deficiency).
    pub warnings: Vec<String>,
    /// Per-slot statistics.
    pub slots: Vec<SlotReport>,
}

/// Compresses `input` into an eigen store at `output`. `progress` is called once per
/// finished slot (from worker threads).
pub fn compress(
    input: &BtfStore,
    output: &Path,
    params: CompressParams,
    progress: &(dyn Fn() + Sync),
) -> Result<CompressReport> {
    let start = Instant::now();
    // A forced kernel path this CPU cannot run is refused before any work.
    let isa = crate::simd::Isa::from_env()?;
    let (emeta, mut warnings) = eigen_meta(input, params)?;
    let job = serde_json::json!({ "input": crate::fs::input_identity(input.path()) });
    let writer = EigenWriter::create_for_job_with(output, emeta, params.resume, job, params.codec)?;
    let views = 0..input.meta().n_views();
    let slots = compress_views(input, &writer, views, params, isa, false, progress)?;
    writer.finish()?;
    let out = crate::eigen::EigenStore::open(output)?;
    let mut r = report_of(input.meta(), params, slots, &mut warnings, out.bytes());
    r.seconds = start.elapsed().as_secs_f64();
    (r.simd, r.input_bytes, r.warnings) = (isa.name(), input.bytes(), warnings);
    r.gram = gram_of(input, params.gram);
    Ok(r)
}

/// The arithmetic `gram` means for `input`'s values (`f16` ones are read as such).
fn gram_of(input: &BtfStore, gram: GramPrecision) -> &'static str {
    gram.resolve(input.dtype() == DType::F16).name()
}

/// The eigen store's metadata for `params` (components clamped to what the lights allow,
/// with a warning).
fn eigen_meta(input: &BtfStore, params: CompressParams) -> Result<(EigenMeta, Vec<String>)> {
    let meta = input.meta().clone();
    let n_l = meta.n_lights();
    let mut warnings = Vec::new();
    if params.components == 0 {
        return Err(Error::Invalid("components must be at least 1".into()));
    }
    let c = params.components.min(max_components(n_l));
    if c < params.components {
        warnings.push(format!(
            "{} components asked for, but {n_l} light images per slot support at most {c}; using {c}",
            params.components
        ));
    }
    Ok((EigenMeta { btf: meta, components: c, quantization: params.quantization }, warnings))
}

/// Shard `shard` of a compression into one eigen store that every shard fills
/// (issue #23): only the view slots [`Shard::range`] gives it are computed, into the
/// shared partial store (`OUTPUT.partial`), whose job — the eigen metadata (components,
/// quantisation, samplings), the input store's content fingerprint, the shard count and
/// the Gram matrix's arithmetic —
/// is recorded by the first shard and checked by every other before it writes anything.
/// Slots already done (by an earlier, interrupted run of this shard: every chunk there with
/// a valid checksum) are kept, corrupt ones computed again. Nothing is
/// committed: [`finalize`] does that once every slot is in. The report covers this
/// shard's slots.
pub fn compress_shard(
    input: &BtfStore,
    output: &Path,
    params: CompressParams,
    shard: Shard,
    progress: &(dyn Fn() + Sync),
) -> Result<CompressReport> {
    let start = Instant::now();
    let isa = crate::simd::Isa::from_env()?;
    let (emeta, mut warnings) = eigen_meta(input, params)?;
    let views = shard.range(input.meta().n_views());
    let partial = output.with_file_name(format!(
        "{}.partial",
        output.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
    ));
    let job = shard_job(input, shard.count, gram_of(input, params.gram))?;
    if !partial.exists() && crate::store::read_meta(output).is_ok() {
        // Finalised already (a retried shard after the finaliser ran): nothing to compute
        // if the store is this job's.
        let out = crate::eigen::EigenStore::open(output)?;
        // The finished store keeps no job record, but its metadata is the input's (samplings,
        // size, provenance) with the components and quantisation: all must agree.
        let mut was = out.meta().clone();
        was.btf.kind = emeta.btf.kind.clone();
        let (was, now) = (serde_json::json!(was), serde_json::json!(emeta));
        if was != now {
            return Err(Error::Invalid(format!(
                "{} is already finalised for another job ({}); remove it to run this one \
                 into it",
                output.display(),
                crate::store::first_difference(&was, &now, "")
            )));
        }
        let slots = views
            .map(|v| {
                let s = out.slot_stats(v).and_then(|s| serde_json::from_value(s).ok());
                s.map(|s| (s, true)).ok_or_else(|| Error::Corrupt {
                    path: output.join("stats"),
                    what: format!("no statistics for view slot {v}"),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let mut r = report_of(input.meta(), params, slots, &mut warnings, out.bytes());
        (r.simd, r.input_bytes, r.warnings) = (isa.name(), input.bytes(), warnings);
        r.gram = gram_of(input, params.gram);
        return Ok(r);
    }
    let writer = EigenWriter::join_for_job_with(output, emeta, job, params.codec)?;
    let slots = compress_views(input, &writer, views, params, isa, true, progress)?;
    let mut r = report_of(input.meta(), params, slots, &mut warnings, 0);
    r.seconds = start.elapsed().as_secs_f64();
    (r.simd, r.input_bytes, r.warnings) = (isa.name(), input.bytes(), warnings);
    r.gram = gram_of(input, params.gram);
    Ok(r)
}

/// The job every shard of a compression records and checks: the input's content (not its
/// path, which differs between machines), the shard count and the Gram matrix's
/// arithmetic (so that every slot of one store has the same).
fn shard_job(input: &BtfStore, shards: usize, gram: &str) -> Result<serde_json::Value> {
    Ok(serde_json::json!({
        "input": {
            "fingerprint": crate::shard::fingerprint(input.path())?,
            "bytes": input.bytes(),
        },
        "shards": shards,
        "gram": gram,
    }))
}

/// The state of every view slot of the eigen store being written at `output` by the
/// shards of a compression (or of the finished store): done (every chunk present with a
/// valid crc32c and statistics recorded), missing, or corrupt (naming the chunk file).
pub fn status(output: &Path) -> Result<ShardedStatus> {
    if crate::store::StoreTxn::recorded_job(output).is_none() {
        let out = crate::eigen::EigenStore::open(output)?;
        return Ok(ShardedStatus {
            store: "eigen".into(),
            shards: 1,
            slots: vec!["done".into(); out.meta().btf.n_views()],
            finalised: true,
        });
    }
    let (writer, job) = EigenWriter::open_partial(output)?;
    Ok(status_of(&writer, &job))
}

fn status_of(writer: &EigenWriter, job: &serde_json::Value) -> ShardedStatus {
    let states = (0..writer.meta().btf.n_views()).map(|v| writer.slot_state(v)).collect();
    ShardedStatus::of("eigen", job, states)
}

/// Finalises a sharded compression: checks that every view slot of `OUTPUT.partial` is
/// done (chunks present, checksums valid, statistics recorded), commits the store to
/// `output` and returns the report over all slots, built from the statistics the shards
/// recorded (`seconds` is then the sum of the slots' seconds, `simd` this machine's
/// kernel path). Safe to run twice: on a store already finalised it only rebuilds the
/// report. Refuses, listing them, when slots are missing or corrupt.
pub fn finalize(output: &Path) -> Result<(CompressReport, bool)> {
    let isa = crate::simd::Isa::from_env()?;
    let already = crate::store::StoreTxn::recorded_job(output).is_none();
    if !already {
        let (writer, job) = EigenWriter::reopen(output)?;
        status_of(&writer, &job).require_complete(output)?;
        writer.finish()?;
    }
    let out = crate::eigen::EigenStore::open(output)?;
    let m = out.meta();
    let slots = (0..m.btf.n_views())
        .map(|v| {
            let s = out.slot_stats(v).and_then(|s| serde_json::from_value(s).ok());
            s.map(|s| (s, false)).ok_or_else(|| Error::Corrupt {
                path: output.join("stats"),
                what: format!("no statistics for view slot {v}"),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let params = CompressParams {
        components: m.components,
        quantization: m.quantization,
        resume: true,
        ..Default::default()
    };
    let mut warnings = Vec::new();
    let mut r = report_of(&m.btf, params, slots, &mut warnings, out.bytes());
    r.seconds = r.slots.iter().map(|s| s.seconds).sum();
    (r.simd, r.warnings) = (isa.name(), warnings);
    Ok((r, already))
}

/// The report of a run over `slots` (sorted by view; `true` = taken from an earlier run).
fn report_of(
    meta: &crate::store::BtfMeta,
    params: CompressParams,
    slots: Vec<(SlotReport, bool)>,
    warnings: &mut Vec<String>,
    output_bytes: u64,
) -> CompressReport {
    let c = params.components.min(max_components(meta.n_lights()));
    let resumed_slots = slots.iter().filter(|s| s.1).count();
    let slots: Vec<SlotReport> = slots.into_iter().map(|s| s.0).collect();
    let deficient = slots.iter().filter(|s| s.effective_components < c).count();
    if deficient > 0 {
        warnings.push(format!(
            "{deficient} slot(s) have fewer than {c} non-zero eigenvalues (rank-deficient data); their extra components are zero"
        ));
    }
    let sse: f64 = slots.iter().map(|s| s.sse_stored).sum();
    let sse_exact: f64 = slots.iter().map(|s| s.sse).sum();
    let energy: f64 = slots.iter().map(|s| s.energy).sum();
    let peak = slots.iter().map(|s| s.peak).fold(0f32, f32::max) as f64;
    let values = (slots.len() * meta.n_lights() * meta.texel_values()) as f64;
    CompressReport {
        components: c,
        requested_components: params.components,
        quantization: params.quantization,
        rel_rmse: rel_rmse_from(sse, energy),
        psnr_db: psnr_db(sse / values.max(1.0), peak),
        rel_rmse_exact: rel_rmse_from(sse_exact, energy),
        seconds: 0.0,
        simd: "",
        gram: params.gram.name(),
        input_bytes: 0,
        output_bytes,
        resumed_slots,
        warnings: Vec::new(),
        slots,
    }
}

/// Computes (or takes from an earlier run) the view slots `views` into `writer`, slots in
/// parallel; returns their reports sorted by view, each with whether it was resumed.
fn compress_views(
    input: &BtfStore,
    writer: &EigenWriter,
    views: std::ops::Range<usize>,
    params: CompressParams,
    isa: crate::simd::Isa,
    verify: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<(SlotReport, bool)>> {
    let meta = input.meta().clone();
    let c = writer.meta().components;
    // One worker per thread, each with its own slot buffers for the whole run (a slot is
    // 64 MB at 256² in f32, 32 MB in f16: allocating and faulting it in per slot would cost
    // more than reading it; a process faults it in once per worker, a sharded job once per
    // worker of every shard, which is why a compressed f16 slot stays f16).
    // A finished slot goes to the writer thread (its chunks written by direct I/O, which
    // waits for the disk), so the workers go on computing meanwhile.
    let one = |v: usize,
               slot: &mut SlotData,
               halves: &mut Vec<f16>,
               raw: &mut Vec<u8>,
               scratch: &mut PcaScratch|
     -> Result<(SlotReport, Option<QuantizedSlot>)> {
        // A shard checks its finished slots' checksums (a slot `btf status` calls corrupt is
        // computed again); a resume trusts chunks that are there whole.
        let finished = if verify {
            writer.slot_state(v) == crate::store::SlotState::Done
        } else {
            writer.has_slot(v)
        };
        let done = finished.then(|| writer.read_stats(v)).flatten();
        if let Some(r) = done.and_then(|s| serde_json::from_value(s).ok()) {
            progress();
            return Ok((r, None));
        }
        let t0 = Instant::now();
        // The PCA checks every value in its first pass; on a non-finite one, the store's
        // own check of that image names the texel too (or finds the chunk corrupt).
        let name_texel = |e: Error| match &e {
            Error::NonFinite { view, light, .. } => {
                input.read_image(*view, *light).err().unwrap_or(e)
            }
            _ => e,
        };
        let q = params.quantization;
        // f32 and f16 chunks are mapped and read in place (widened to f64 as they are
        // loaded), their checksums folded into the first pass; compressed f16 chunks are
        // decoded into the worker's f16 buffer (widened as they are loaded, the same
        // values), other dtypes into its f32 buffer.
        let m = meta.texel_values();
        let r = if let Some(mapped) = input.map_slot(v)? {
            let check = |crcs: &[u32]| mapped.verify(crcs);
            if input.dtype() == DType::F16 {
                let rows = SlotRows::<f16> { view: v, rows: mapped.rows()?, texel_values: m };
                pca_rows_in(&rows, c, q, scratch, Some(&check))
            } else {
                let rows = SlotRows::<f32> { view: v, rows: mapped.rows()?, texel_values: m };
                pca_rows_in(&rows, c, q, scratch, Some(&check))
            }
        } else if input.read_slot_f16_into(v, halves)? {
            let rows = SlotRows::<f16> {
                view: v,
                rows: halves.chunks_exact(m).collect(),
                texel_values: m,
            };
            pca_rows_in(&rows, c, q, scratch, None)
        } else {
            input.read_slot_into_unchecked(v, slot, raw)?;
            pca_slot_in(slot, c, q, scratch)
        }
        .map_err(name_texel)?;
        let report = SlotReport {
            view: v,
            sse: r.sse,
            sse_stored: r.sse_stored,
            discarded_eigen_sum: r.discarded_eigen_sum,
            energy: r.energy,
            peak: r.peak,
            effective_components: r.effective_components,
            seconds: t0.elapsed().as_secs_f64(),
        };
        Ok((report, Some(r.stored)))
    };
    let (first, n_views) = (views.start, views.end);
    let next = AtomicUsize::new(first);
    let failed = AtomicBool::new(false);
    let workers = rayon::current_num_threads().clamp(1, (n_views - first).max(1));
    // At most two finished slots wait for the writer (a slot's arrays are 7 MB at 256²);
    // the eigentexture bytes it has written come back for the next slots to reuse.
    let (to_writer, queue) = mpsc::sync_channel::<(SlotReport, QuantizedSlot)>(2);
    let spent = Mutex::new(Vec::<Vec<u8>>::new());
    let work = |to_writer: &mpsc::SyncSender<_>| -> Result<Vec<(SlotReport, bool)>> {
        let mut slot = SlotData { view: 0, n_lights: 0, texel_values: 0, data: Vec::new() };
        let (mut halves, mut raw, mut scratch) =
            (Vec::new(), Vec::new(), PcaScratch::for_isa(isa).with_gram(params.gram));
        let mut done = Vec::new();
        loop {
            let v = next.fetch_add(1, Ordering::Relaxed);
            if v >= n_views || failed.load(Ordering::Relaxed) {
                return Ok(done);
            }
            if let Some(bytes) = spent.lock().ok().and_then(|mut p| p.pop()) {
                scratch.recycle(bytes);
            }
            let sent =
                one(v, &mut slot, &mut halves, &mut raw, &mut scratch).and_then(|(r, stored)| {
                    let resumed = stored.is_none();
                    if let Some(stored) = stored {
                        // A refusal means the writer stopped on an error, which it reports.
                        to_writer
                            .send((r.clone(), stored))
                            .map_err(|_| Error::Invalid("the writer stopped".into()))?;
                    }
                    Ok((r, resumed))
                });
            match sent {
                Ok(r) => done.push(r),
                Err(e) => {
                    failed.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
        }
    };
    let (per_worker, written) = std::thread::scope(|scope| {
        let (writer, spent) = (&writer, &spent);
        let write = scope.spawn(move || -> Result<()> {
            for (report, stored) in queue {
                writer.write_slot(report.view, &stored)?;
                writer.write_stats(report.view, &json!(report))?;
                progress();
                if let Ok(mut pool) = spent.lock() {
                    pool.push(stored.eigentextures);
                }
            }
            Ok(())
        });
        let per_worker: Vec<_> = (0..workers).into_par_iter().map(|_| work(&to_writer)).collect();
        drop(to_writer);
        (per_worker, write.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
    });
    written?;
    let mut slots = Vec::with_capacity(n_views - first);
    for w in per_worker {
        slots.extend(w?);
    }
    slots.sort_by_key(|s| s.0.view);
    Ok(slots)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{BtfMeta, BtfWriter};

    fn tiny_store(path: &Path) {
        tiny_store_as(path, DType::F32);
    }

    fn tiny_store_as(path: &Path, dtype: DType) {
        let s = crate::Sampling::new(
            "custom",
            vec![
                crate::Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 },
                crate::Ring { theta_deg: 40.0, count: 4, phi_offset_deg: 0.0 },
            ],
        )
        .unwrap();
        // Uncompressed (the pre-#25 layout): the tests below patch chunk bytes and map slots.
        let meta = BtfMeta::new(s.clone(), s, 4, 3);
        let none = crate::zarr::Compression::None;
        let w =
            BtfWriter::create_compressed(path, meta, dtype, false, serde_json::Value::Null, none)
                .unwrap();
        for v in 0..5 {
            for l in 0..5 {
                let img: Vec<f32> =
                    (0..36).map(|k| 1.0 + ((v * 7 + l * 3 + k) % 11) as f32 * 0.1).collect();
                w.write_image(v, l, &img).unwrap();
            }
        }
        w.finish().unwrap();
    }

    #[test]
    fn stores_claiming_8192_squared_texels_are_refused_before_allocating() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        tiny_store(&p);
        let store = BtfStore::open(&p).unwrap();
        let params = CompressParams { components: 3, ..Default::default() };
        let eig = dir.path().join("a.eig");
        compress(&store, &eig, params, &|| {}).unwrap();
        crate::store::claim_texels(&p, 8192, 8192);
        let big = BtfStore::open(&p).unwrap();
        let e = compress(&big, &dir.path().join("b.eig"), params, &|| {}).unwrap_err();
        assert!(matches!(e, Error::Corrupt { .. }), "{e}");
        assert!(e.to_string().contains("normtextures/c.0.0.0.0.0"), "{e}");
        // An eigen store claiming the same: the whole-store check names a chunk.
        crate::store::claim_texels(&eig, 8192, 8192);
        let e = crate::eigen::EigenStore::open(&eig).unwrap().check_chunks().unwrap_err();
        assert!(matches!(e, Error::Corrupt { .. }), "{e}");
        let e = e.to_string();
        assert!(e.contains("mean/c.0.0.0.0") && e.contains("view slot 0"), "{e}");
        assert!(crate::eigen::EigenStore::open(&eig).unwrap().read_slot(0).is_err());
    }

    #[test]
    fn non_finite_input_is_named_down_to_the_texel_and_scratch_reuse_changes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        tiny_store(&p);
        let store = BtfStore::open(&p).unwrap();
        let params = CompressParams { components: 3, ..Default::default() };
        let r = compress(&store, &dir.path().join("a.eig"), params, &|| {}).unwrap();
        // Same statistics slot by slot as a fresh PCA per slot.
        let mut scratch = crate::pca::PcaScratch::default();
        for s in &r.slots {
            let slot = store.read_slot(s.view).unwrap();
            let fresh = crate::pca::pca_slot(&slot, 3, Quantization::F16).unwrap();
            let reused = pca_slot_in(&slot, 3, Quantization::F16, &mut scratch).unwrap();
            assert_eq!((fresh.sse_stored, fresh.sse), (s.sse_stored, s.sse));
            assert_eq!(fresh.stored.eigentextures, reused.stored.eigentextures);
            assert_eq!(fresh.stored.weights, reused.stored.weights);
        }
        // A NaN with a valid checksum at view 3, light 2, value 17 (texel y=1, x=1, green).
        let chunk = p.join("normtextures/c.3.2.0.0.0");
        let mut raw = std::fs::read(&chunk).unwrap();
        raw.truncate(36 * 4);
        raw[17 * 4..18 * 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let crc = crc32c::crc32c(&raw);
        raw.extend_from_slice(&crc.to_le_bytes());
        std::fs::write(&chunk, &raw).unwrap();
        let store = BtfStore::open(&p).unwrap();
        let err = compress(&store, &dir.path().join("b.eig"), params, &|| {}).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("view slot 3, light 2") && msg.contains("y=1, x=1, channel 2"),
            "{msg}"
        );
        assert!(!dir.path().join("b.eig").exists());
    }

    #[test]
    fn mapped_f32_and_f16_stores_compress_alike_and_truncation_is_named() {
        // The tiny store's values are multiples of 0.1 in [1, 2]: not all f16-exact, so
        // round them through f16 first by writing an f16 store and an f32 copy of it.
        let dir = tempfile::tempdir().unwrap();
        let (p16, p32) = (dir.path().join("h.btf"), dir.path().join("f.btf"));
        tiny_store_as(&p16, DType::F16);
        let h = BtfStore::open(&p16).unwrap();
        let none = crate::zarr::Compression::None;
        let w = BtfWriter::create_compressed(
            &p32,
            h.meta().clone(),
            DType::F32,
            false,
            serde_json::Value::Null,
            none,
        )
        .unwrap();
        for v in 0..5 {
            for l in 0..5 {
                w.write_image(v, l, &h.read_image(v, l).unwrap()).unwrap();
            }
        }
        w.finish().unwrap();
        let f = BtfStore::open(&p32).unwrap();
        // Both are read in place: with the Gram matrix in f64, f16 widened by the same
        // loads as f32, to the same bits; by default (f32 lanes for f16) within the bound.
        assert!(f.map_slot(0).unwrap().is_some() && h.map_slot(0).unwrap().is_some());
        let params = CompressParams { components: 3, ..Default::default() };
        let in_f64 = CompressParams { gram: GramPrecision::F64, ..params };
        let a = compress(&h, &dir.path().join("h.eig"), in_f64, &|| {}).unwrap();
        let b = compress(&f, &dir.path().join("f.eig"), params, &|| {}).unwrap();
        assert_eq!((a.gram, b.gram), ("f64", "f64"));
        for (x, y) in a.slots.iter().zip(&b.slots) {
            assert_eq!((x.sse_stored, x.sse, x.energy), (y.sse_stored, y.sse, y.energy));
        }
        // The means and eigentextures at the fast setting, the rest at the default: blosc,
        // byte shuffle, zstd level 1 both.
        use crate::zarr::Compression;
        for (array, c) in [
            ("mean", Compression::FAST),
            ("eigentextures", Compression::FAST),
            ("weights", Compression::DEFAULT),
        ] {
            let p = dir.path().join("h.eig").join(array);
            let a = crate::zarr::ZarrArray::open(&p, &crate::zarr::Limits::default()).unwrap();
            assert_eq!(a.meta().compression, c, "{array}");
            assert_eq!(c, Compression::Blosc { clevel: 1, shuffle: true });
        }
        let d = compress(&h, &dir.path().join("d.eig"), params, &|| {}).unwrap();
        assert_eq!(d.gram, "f32");
        for (x, y) in d.slots.iter().zip(&b.slots) {
            // The 5 − 3 discarded eigenvalues each within ε·tr(YYᵀ), and tr(YYᵀ) =
            // Σ‖x_i − x₀‖² ≤ 2·energy + 2·5‖x₀‖² ≤ 12·energy.
            let slack = 2.0 * crate::pca::GRAM32_EPS * 12.0 * y.energy;
            assert!((x.sse - y.sse).abs() <= slack, "slot {}: {} vs {}", x.view, x.sse, y.sse);
            assert_eq!(x.energy, y.energy);
        }
        let (ea, eb) = (
            crate::eigen::EigenStore::open(&dir.path().join("h.eig")).unwrap(),
            crate::eigen::EigenStore::open(&dir.path().join("f.eig")).unwrap(),
        );
        for v in 0..5 {
            let (sa, sb) = (ea.read_slot(v).unwrap(), eb.read_slot(v).unwrap());
            assert_eq!(sa.weights, sb.weights, "slot {v}");
            assert_eq!(sa.basis, sb.basis, "slot {v}");
        }
        // A chunk cut short is refused before mapping, with its file, slot and light.
        let chunk = p32.join("normtextures/c.2.1.0.0.0");
        let bytes = std::fs::read(&chunk).unwrap();
        std::fs::write(&chunk, &bytes[..bytes.len() - 6]).unwrap();
        let f = BtfStore::open(&p32).unwrap();
        let msg = compress(&f, &dir.path().join("g.eig"), params, &|| {}).unwrap_err().to_string();
        assert!(
            msg.contains("view slot 2, light 1") && msg.contains("bytes") && msg.contains("c.2.1"),
            "{msg}"
        );
        assert!(!dir.path().join("g.eig").exists());
    }
}
