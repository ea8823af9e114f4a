//! The BTF store: normtextures `[view][light][y][x][rgb]` in a Zarr v3 group, one chunk
//! per (view slot, light) image (compressed since issue #25: zstd, then blosc = byte
//! shuffle + zstd, [`crate::zarr::Compression`]), linear values in `f16`
//! or `f32`, with the (θ, φ) of every view slot and light beside them ([`crate::axes`]).
//!
//! A store is written into `NAME.partial/` and renamed to `NAME` only when every chunk is
//! in place, so an interrupted run leaves any previous output untouched; running the same
//! job again with `resume` keeps the chunks already written. The group attributes record
//! the samplings, colour space, units and provenance (see [`BtfMeta`]).

use crate::sampling::Sampling;
use crate::zarr::{self, ArrayMeta, DType, Limits, ZarrArray};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::fs;
use std::path::{Path, PathBuf};

/// What a BTF store holds, recorded in its group attributes under `"btf"`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BtfMeta {
    /// `"btf"` for normtextures, `"eigen"` for a compressed store.
    pub kind: String,
    /// Sampling of the view slots.
    pub view_sampling: Sampling,
    /// Sampling of the light directions.
    pub light_sampling: Sampling,
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Colour space of the linear RGB values.
    pub color_space: String,
    /// What one unit means.
    pub units: String,
    /// Free-form provenance (generator, parameters, source files).
    pub provenance: Value,
}

impl BtfMeta {
    /// Metadata for a new store with the usual colour space and units.
    pub fn new(
        view_sampling: Sampling,
        light_sampling: Sampling,
        width: usize,
        height: usize,
    ) -> Self {
        BtfMeta {
            kind: "btf".into(),
            view_sampling,
            light_sampling,
            width,
            height,
            color_space: "linear sRGB (Rec. 709 primaries)".into(),
            units: "radiance per unit irradiance perpendicular to the light (1/sr); includes cos(theta_light)".into(),
            provenance: json!({}),
        }
    }

    /// Number of view slots.
    pub fn n_views(&self) -> usize {
        self.view_sampling.len()
    }
    /// Number of light directions.
    pub fn n_lights(&self) -> usize {
        self.light_sampling.len()
    }
    /// Floats per image (`height · width · 3`).
    pub fn texel_values(&self) -> usize {
        self.width * self.height * 3
    }

    pub(crate) fn validate(mut self, path: &Path) -> Result<Self> {
        self.view_sampling = self.view_sampling.validated()?;
        self.light_sampling = self.light_sampling.validated()?;
        if self.width == 0 || self.height == 0 || self.width > 1 << 16 || self.height > 1 << 16 {
            return Err(Error::Invalid(format!(
                "{}: texture size {}x{} is outside 1..=65536",
                path.display(),
                self.width,
                self.height
            )));
        }
        Ok(self)
    }
}

/// Reads a store's group metadata (shared by BTF and eigen stores).
pub fn read_meta(path: &Path) -> Result<BtfMeta> {
    let attrs = zarr::read_group(path)?;
    let m: BtfMeta = serde_json::from_value(attrs["btf"].clone())
        .map_err(|source| Error::Json { path: path.join("zarr.json"), source })?;
    if attrs["complete"] != json!(true) {
        return Err(Error::Invalid(format!(
            "{}: store is incomplete (an interrupted write?)",
            path.display()
        )));
    }
    m.validate(path)
}

/// [`read_meta`] of a store that must be of `kind` (`"btf"` or `"eigen"`); `hint` follows
/// the refusal of any other kind.
pub fn read_meta_of_kind(path: &Path, kind: &str, hint: &str) -> Result<BtfMeta> {
    let meta = read_meta(path)?;
    if meta.kind != kind {
        let article = if kind.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" };
        let name = if kind == "btf" { "BTF" } else { kind };
        return Err(Error::Invalid(format!(
            "{}: a '{}' store, not {article} {name} store{hint}",
            path.display(),
            meta.kind
        )));
    }
    Ok(meta)
}

/// A store folder being written: `NAME.partial` until [`StoreTxn::commit`].
#[derive(Debug)]
pub struct StoreTxn {
    final_path: PathBuf,
    partial: PathBuf,
    job: Value,
}

/// Where a committing writer keeps its job while the partial holds the final attributes:
/// beside the partial (`NAME.partial.job`), so that nothing of it travels into the store.
fn job_sidecar(partial: &Path) -> PathBuf {
    let mut name = partial.file_name().unwrap_or_default().to_os_string();
    name.push(".job");
    partial.with_file_name(name)
}

impl StoreTxn {
    /// Starts (or, with `resume`, continues) writing a store at `path` for `job` (what made
    /// it: the metadata, parameters and input identity). The partial's `zarr.json` records
    /// the job from the start, so the partial is a valid Zarr group at every instant and a
    /// resume by a different job is refused, naming the first field that differs.
    pub fn begin(path: &Path, resume: bool, job: &Value) -> Result<Self> {
        let name = path
            .file_name()
            .ok_or_else(|| Error::Invalid(format!("{}: not a file name", path.display())))?;
        crate::fs::check_replaceable(path, crate::fs::OutputKind::Store)?;
        let partial = path.with_file_name(format!("{}.partial", name.to_string_lossy()));
        let sidecar = job_sidecar(&partial);
        if sidecar.exists() && !partial.exists() {
            // Left by a writer killed just after its commit's rename: the store is whole.
            fs::remove_file(&sidecar).map_err(|e| Error::io(&sidecar, e))?;
        }
        if sidecar.exists() && partial.exists() {
            // Killed after the commit's exchange swapped the new store in: `path` holds the
            // attributes the sidecar recorded, and the partial is the old store (or what
            // its removal left). The commit is done; what remains is to clear up.
            let committed = read_sidecar(&sidecar).map(|(_, attrs)| attrs);
            if committed.is_some() && zarr::read_group(path).ok() == committed {
                fs::remove_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
                fs::remove_file(&sidecar).map_err(|e| Error::io(&sidecar, e))?;
            }
        }
        if partial.exists() && resume && !partial.join("zarr.json").exists() {
            // Killed between creating the folder and recording the job: nothing was
            // written yet (the record comes before any chunk), so start afresh.
            fs::remove_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
        }
        if partial.exists() && resume {
            // A writer killed inside its commit left the final attributes in the partial and
            // its job in the sidecar; it resumes (and commits) like any other.
            let sidecar_job = || read_sidecar(&sidecar).map(|(job, _)| job);
            let recorded = zarr::read_group(&partial)
                .ok()
                .and_then(|a| a.get("partial_job").cloned())
                .or_else(sidecar_job);
            match recorded {
                Some(r) if &r == job => {}
                Some(r) => {
                    return Err(Error::Invalid(format!(
                        "{} was begun by a different job ({}); it cannot be resumed by this \
                         one: run without --resume to start over",
                        partial.display(),
                        first_difference(&r, job, "")
                    )));
                }
                None => {
                    return Err(Error::Invalid(format!(
                        "{} records no job, so it cannot be told apart from another job's; \
                         run without --resume to start over",
                        partial.display()
                    )));
                }
            }
        } else if partial.exists() {
            if !partial.is_dir()
                || !crate::fs::is_toolkit_store(&partial) && !is_empty_dir(&partial)
            {
                return Err(Error::Invalid(format!(
                    "{} exists and is not a partial store this toolkit began; refusing to \
                     remove it",
                    partial.display()
                )));
            }
            fs::remove_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
            if sidecar.exists() {
                fs::remove_file(&sidecar).map_err(|e| Error::io(&sidecar, e))?;
            }
        }
        fs::create_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
        if !partial.join("zarr.json").exists() {
            zarr::write_group(&partial, &json!({ "partial_job": job }))?;
        }
        Ok(StoreTxn { final_path: path.to_owned(), partial, job: job.clone() })
    }

    /// Joins the partial store at `path` as one of several concurrent writers (the shards
    /// of a job, issue #23): creates `NAME.partial` and records `job` in it if nobody has
    /// ([`crate::fs::write_new`]: once, by whoever comes first), or checks that the job
    /// recorded there is `job`, refusing with the first differing field named before
    /// anything is written. Never removes anything; the store is committed later by the
    /// finaliser ([`StoreTxn::reopen`]).
    pub fn join(path: &Path, job: &Value) -> Result<Self> {
        let name = path
            .file_name()
            .ok_or_else(|| Error::Invalid(format!("{}: not a file name", path.display())))?;
        crate::fs::check_replaceable(path, crate::fs::OutputKind::Store)?;
        let partial = path.with_file_name(format!("{}.partial", name.to_string_lossy()));
        if partial.exists() && !partial.is_dir() {
            return Err(Error::Invalid(format!(
                "{} exists and is not a partial store folder; refusing to write into it",
                partial.display()
            )));
        }
        let doc =
            json!({"zarr_format": 3, "node_type": "group", "attributes": {"partial_job": job}});
        let text = serde_json::to_string_pretty(&doc).unwrap_or_default();
        let meta = partial.join("zarr.json");
        // Another shard creating the record leaves only its temporary here meanwhile; and
        // every other file of a job comes after its record, so the record is looked for
        // after the listing.
        let foreign = || partial.is_dir() && !holds_only_temporaries(&partial) && !meta.exists();
        // A folder of files without a record may be another shard's record in flight (a
        // file system may list a directory being changed loosely): look again for up to
        // 2 s before refusing it.
        let mut tries = 0;
        while foreign() && tries < 100 {
            std::thread::sleep(std::time::Duration::from_millis(20));
            tries += 1;
        }
        if foreign() {
            let names: Vec<String> = fs::read_dir(&partial)
                .map(|d| {
                    d.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect()
                })
                .unwrap_or_default();
            return Err(Error::Invalid(format!(
                "{} exists, holds files ({}) and records no job; refusing to write into it",
                partial.display(),
                names.join(", ")
            )));
        }
        fs::create_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
        if !crate::fs::write_new(&meta, text.as_bytes())? {
            let attrs = zarr::read_group(&partial)?;
            match attrs.get("partial_job") {
                Some(r) if r == job => {}
                Some(r) => {
                    return Err(Error::Invalid(format!(
                        "{} was begun by a different job ({}); every shard of one output \
                         must be given the same input and parameters — refusing before \
                         writing anything",
                        partial.display(),
                        first_difference(r, job, "")
                    )));
                }
                None => {
                    return Err(Error::Invalid(format!(
                        "{} records no job (is it being finalised?); refusing to write into it",
                        partial.display()
                    )));
                }
            }
        }
        Ok(StoreTxn { final_path: path.to_owned(), partial, job: job.clone() })
    }

    /// The job recorded in the partial store of `path` (by [`StoreTxn::begin`] or
    /// [`StoreTxn::join`]; or, for a commit that was interrupted, beside it), if any.
    pub fn recorded_job(path: &Path) -> Option<Value> {
        let name = path.file_name()?.to_string_lossy().into_owned();
        let partial = path.with_file_name(format!("{name}.partial"));
        zarr::read_group(&partial)
            .ok()
            .and_then(|a| a.get("partial_job").cloned())
            .or_else(|| read_sidecar(&job_sidecar(&partial)).map(|(job, _)| job))
    }

    /// The partial store of `path` and its job, for reading only (a status report):
    /// nothing is created, resumed or removed.
    pub fn peek(path: &Path) -> Option<(Self, Value)> {
        let job = Self::recorded_job(path)?;
        let name = path.file_name()?.to_string_lossy().into_owned();
        let partial = path.with_file_name(format!("{name}.partial"));
        Some((StoreTxn { final_path: path.to_owned(), partial, job: job.clone() }, job))
    }

    /// Reopens the partial store of `path` to commit it (the finaliser of a sharded job):
    /// the job it records is resumed as [`StoreTxn::begin`] resumes one, which also
    /// completes a commit that a killed finaliser left half done.
    pub fn reopen(path: &Path) -> Result<(Self, Value)> {
        let job = Self::recorded_job(path).ok_or_else(|| {
            Error::Invalid(format!(
                "{}: no partial store of a job to finalise beside it",
                path.display()
            ))
        })?;
        Ok((Self::begin(path, true, &job)?, job))
    }

    /// The folder being written.
    pub fn dir(&self) -> &Path {
        &self.partial
    }

    /// Marks the store complete and moves it into place, replacing any previous store.
    pub fn commit(self, attributes: Value) -> Result<()> {
        let mut attrs = attributes;
        attrs["complete"] = json!(true);
        // A killed writer's temporary files must not travel into the finished store.
        crate::fs::sweep_temps(&self.partial)?;
        // The final attributes replace the job record: keep the job beside the partial until
        // the store is in place, so a writer killed in between can still be resumed.
        let sidecar = job_sidecar(&self.partial);
        let record = json!({ "job": self.job, "attributes": attrs });
        crate::fs::write_atomic(&sidecar, record.to_string().as_bytes())?;
        zarr::write_group(&self.partial, &attrs)?;
        if self.final_path.exists() && exchange(&self.partial, &self.final_path).is_ok() {
            // One atomic step swapped the new store in; the old one now sits at `partial`.
            let p = &self.partial;
            let _ = if p.is_dir() { fs::remove_dir_all(p) } else { fs::remove_file(p) };
        } else if self.final_path.exists() {
            // No atomic exchange here (another OS, or a file system without it): two
            // renames, with the old store kept under a side name until the new one is in.
            let old = self.final_path.with_file_name(format!(
                "{}.old-{}",
                self.final_path.file_name().unwrap().to_string_lossy(),
                std::process::id()
            ));
            fs::rename(&self.final_path, &old).map_err(|e| Error::io(&self.final_path, e))?;
            fs::rename(&self.partial, &self.final_path)
                .map_err(|e| Error::io(&self.final_path, e))?;
            let _ = if old.is_dir() { fs::remove_dir_all(&old) } else { fs::remove_file(&old) };
        } else {
            fs::rename(&self.partial, &self.final_path)
                .map_err(|e| Error::io(&self.final_path, e))?;
        }
        fs::remove_file(&sidecar).map_err(|e| Error::io(&sidecar, e))?;
        Ok(())
    }
}

/// The job and the final attributes a commit recorded beside its partial (`None` when
/// unreadable: a sidecar killed mid-write is never renamed into place, so that means absent).
fn read_sidecar(sidecar: &Path) -> Option<(Value, Value)> {
    let v: Value = serde_json::from_slice(&fs::read(sidecar).ok()?).ok()?;
    Some((v.get("job")?.clone(), v.get("attributes")?.clone()))
}

fn holds_only_temporaries(p: &Path) -> bool {
    fs::read_dir(p).is_ok_and(|mut d| {
        d.all(|e| e.is_ok_and(|e| e.file_name().to_str().is_some_and(crate::fs::is_temp_name)))
    })
}

fn is_empty_dir(p: &Path) -> bool {
    fs::read_dir(p).map(|mut d| d.next().is_none()).unwrap_or(false)
}

/// The first place where two job records differ, as `field: was A, now B`.
pub fn first_difference(was: &Value, now: &Value, at: &str) -> String {
    match (was, now) {
        (Value::Object(a), Value::Object(b)) => {
            let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
            keys.sort();
            keys.dedup();
            for k in keys {
                let (x, y) = (a.get(k).unwrap_or(&Value::Null), b.get(k).unwrap_or(&Value::Null));
                if x != y {
                    let path = if at.is_empty() { k.clone() } else { format!("{at}.{k}") };
                    return first_difference(x, y, &path);
                }
            }
            format!("{}: no difference", if at.is_empty() { "job" } else { at })
        }
        (Value::String(a), Value::String(b)) if a.contains('\n') || b.contains('\n') => {
            // Text (a TOML of parameters, say): name the first line that differs, so the
            // message does not end in a shared prefix cut short.
            let (mut la, mut lb) = (a.lines(), b.lines());
            let mut line = 1;
            loop {
                match (la.next(), lb.next()) {
                    (Some(x), Some(y)) if x == y => line += 1,
                    (x, y) => {
                        let show =
                            |l: Option<&str>| l.map_or("(no line)".into(), |l| format!("{l:?}"));
                        return format!(
                            "{}, line {line}: was {}, now {}",
                            if at.is_empty() { "job" } else { at },
                            show(x),
                            show(y)
                        );
                    }
                }
            }
        }
        _ => {
            let short = |v: &Value| {
                let s = v.to_string();
                if s.chars().count() > 80 {
                    format!("{}…", s.chars().take(80).collect::<String>())
                } else {
                    s
                }
            };
            format!(
                "{}: was {}, now {}",
                if at.is_empty() { "job" } else { at },
                short(was),
                short(now)
            )
        }
    }
}

/// Swaps the names `a` and `b` atomically (Linux `renameat2(RENAME_EXCHANGE)`), so a store
/// being replaced is never absent, not even for the instant between two renames.
#[cfg(any(target_os = "linux", target_os = "android"))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::ErrorKind::Unsupported.into())
}

/// Checks that every value is finite; names the slot, light and texel otherwise.
pub fn check_finite(values: &[f32], view: usize, light: usize, width: usize) -> Result<()> {
    // Fast path: `v · 0` is 0 for finite values and NaN otherwise; eight lanes vectorise.
    let mut acc = [0f32; 8];
    for c in values.chunks(8) {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v * 0.0;
        }
    }
    if acc.iter().all(|a| *a == 0.0) {
        return Ok(());
    }
    if let Some(pos) = values.iter().position(|v| !v.is_finite()) {
        let texel = pos / 3;
        let (y, x) = texel.checked_div(width).map_or((0, texel), |y| (y, texel % width));
        return Err(Error::NonFinite {
            view,
            light,
            at: Some(format!("texel y={y}, x={x}, channel {}", pos % 3)),
        });
    }
    Ok(())
}

/// Checks that every value stays finite when rounded to `f16` (magnitude below 65520, where
/// rounding to nearest reaches infinity); names the slot, light and texel otherwise.
fn check_f16_range(values: &[f32], view: usize, light: usize, width: usize) -> Result<()> {
    const F16_OVERFLOW: f32 = 65520.0;
    let Some(pos) = values.iter().position(|v| v.abs() >= F16_OVERFLOW) else { return Ok(()) };
    let texel = pos / 3;
    let (y, x) = texel.checked_div(width).map_or((0, texel), |y| (y, texel % width));
    Err(Error::Invalid(format!(
        "image (view slot {view}, light {light}): value {} at texel y={y}, x={x}, channel {} \
         is beyond the f16 range (store it as f32)",
        values[pos],
        pos % 3
    )))
}

/// Writer of a BTF store, one image at a time, in any order, resumable.
#[derive(Debug)]
pub struct BtfWriter {
    txn: StoreTxn,
    meta: BtfMeta,
    arr: ZarrArray,
}

fn normtexture_array(meta: &BtfMeta, dtype: DType) -> ArrayMeta {
    let (h, w) = (meta.height as u64, meta.width as u64);
    ArrayMeta::new(
        vec![meta.n_views() as u64, meta.n_lights() as u64, h, w, 3],
        vec![1, 1, h, w, 3],
        dtype,
        &["view", "light", "y", "x", "channel"],
    )
}

impl BtfWriter {
    /// Starts a store at `path` with element type `dtype` (`F16` or `F32`). The job that a
    /// resume must match is the metadata (with its provenance) and the element type.
    pub fn create(path: &Path, meta: BtfMeta, dtype: DType, resume: bool) -> Result<Self> {
        Self::create_for_job(path, meta, dtype, resume, Value::Null)
    }

    /// [`BtfWriter::create`] for a job with more to it than the metadata says (the identity
    /// of its input, options that shape the result): `job` is recorded in the partial and a
    /// resume must match it too.
    pub fn create_for_job(
        path: &Path,
        meta: BtfMeta,
        dtype: DType,
        resume: bool,
        job: Value,
    ) -> Result<Self> {
        Self::create_compressed(path, meta, dtype, resume, job, zarr::Compression::DEFAULT)
    }

    /// [`BtfWriter::create_for_job`] with the chunks' compression chosen:
    /// [`zarr::Compression::None`] writes the pre-#25 layout, whose chunks the PCA maps in
    /// place ([`BtfStore::map_slot`]).
    pub fn create_compressed(
        path: &Path,
        meta: BtfMeta,
        dtype: DType,
        resume: bool,
        job: Value,
        compression: zarr::Compression,
    ) -> Result<Self> {
        if !matches!(dtype, DType::F16 | DType::F32) {
            return Err(Error::Unsupported(format!(
                "normtexture dtype {dtype:?} (use f16 or f32)"
            )));
        }
        let meta = meta.validate(path)?;
        let record = json!({"store": "btf", "meta": meta, "dtype": dtype.zarr_name(), "job": job});
        let txn = StoreTxn::begin(path, resume, &record)?;
        let array = ArrayMeta { compression, ..normtexture_array(&meta, dtype) };
        let arr = ZarrArray::create(&txn.dir().join("normtextures"), array)?;
        Ok(BtfWriter { txn, meta, arr })
    }

    /// [`BtfWriter::create_for_job`] for one shard of several filling one store at once
    /// ([`StoreTxn::join`]): the first creates the partial store and its job record, the
    /// others check that they agree (metadata with its provenance, element type, `job`)
    /// before writing anything. Nothing is committed: the finaliser does that
    /// ([`finalize_sharded`]).
    pub fn join_for_job(path: &Path, meta: BtfMeta, dtype: DType, job: Value) -> Result<Self> {
        Self::join_for_job_compressed(path, meta, dtype, job, zarr::Compression::DEFAULT)
    }

    /// [`BtfWriter::join_for_job`] with the chunks' compression chosen, as
    /// [`BtfWriter::create_compressed`] (the shard that creates the store chooses; the others
    /// keep its codec).
    pub fn join_for_job_compressed(
        path: &Path,
        meta: BtfMeta,
        dtype: DType,
        job: Value,
        compression: zarr::Compression,
    ) -> Result<Self> {
        if !matches!(dtype, DType::F16 | DType::F32) {
            return Err(Error::Unsupported(format!(
                "normtexture dtype {dtype:?} (use f16 or f32)"
            )));
        }
        let meta = meta.validate(path)?;
        let record = json!({"store": "btf", "meta": meta, "dtype": dtype.zarr_name(), "job": job});
        let txn = StoreTxn::join(path, &record)?;
        let array = ArrayMeta { compression, ..normtexture_array(&meta, dtype) };
        let arr = ZarrArray::create(&txn.dir().join("normtextures"), array)?;
        Ok(BtfWriter { txn, meta, arr })
    }

    /// The partial BTF store of `path` with its job record, opened to read its state
    /// (`commit = false`: nothing is created or removed) or to commit it.
    fn open_partial(path: &Path, commit: bool) -> Result<(Self, Value)> {
        let (txn, record) = if commit {
            StoreTxn::reopen(path)?
        } else {
            StoreTxn::peek(path).ok_or_else(|| {
                Error::Invalid(format!("{}: no partial store beside it", path.display()))
            })?
        };
        if record.get("store") != Some(&json!("btf")) {
            return Err(Error::Invalid(format!(
                "{}: the partial store beside it is not a BTF store",
                path.display()
            )));
        }
        let meta: BtfMeta = serde_json::from_value(record["meta"].clone())
            .map_err(|source| Error::Json { path: txn.dir().join("zarr.json"), source })?;
        let meta = meta.validate(txn.dir())?;
        let arr = ZarrArray::open(&txn.dir().join("normtextures"), &Limits::default())?;
        Ok((BtfWriter { txn, meta, arr }, record))
    }

    /// The partial BTF store of `path` reopened to commit it (the finaliser of a sharded
    /// job that has more to record than the images), with its job record; `None` when no
    /// partial store is beside `path`.
    pub fn reopen_for_commit(path: &Path) -> Result<Option<(Self, Value)>> {
        if StoreTxn::recorded_job(path).is_none() {
            return Ok(None);
        }
        Self::open_partial(path, true).map(Some)
    }

    /// Refuses, listing them, while view slots of the store being written are missing or
    /// corrupt.
    pub fn check_complete(&self, output: &Path) -> Result<()> {
        let states = (0..self.meta.n_views()).map(|v| self.slot_state(v)).collect();
        ShardedStatus::of("btf", &self.txn.job["job"], states).require_complete(output)
    }

    /// The state of view slot `view`: every light image present with a valid checksum,
    /// some image missing, or an image failing its check (the file named).
    pub fn slot_state(&self, view: usize) -> SlotState {
        let n_l = self.meta.n_lights();
        let idx = |l: usize| [view as u64, l as u64, 0, 0, 0];
        if (0..n_l).any(|l| !self.arr.chunk_path(&idx(l)).exists()) {
            return SlotState::Missing;
        }
        for l in 0..n_l {
            if let Err(e) = self.arr.verify_chunk(&idx(l)) {
                return SlotState::Corrupt(e.to_string());
            }
        }
        SlotState::Done
    }

    /// The metadata being written.
    pub fn meta(&self) -> &BtfMeta {
        &self.meta
    }

    /// The folder being written (`NAME.partial`), for side files that travel with the
    /// store (they are moved into place by [`BtfWriter::finish`]).
    pub fn dir(&self) -> &Path {
        self.txn.dir()
    }

    /// Replaces the provenance recorded at [`BtfWriter::finish`] (e.g. results known only
    /// at the end of a run).
    pub fn set_provenance(&mut self, provenance: Value) {
        self.meta.provenance = provenance;
    }

    /// True when image `(view, light)` is written and passes its size and checksum check
    /// (what a shard keeps of an earlier run; a damaged image is written again).
    pub fn has_sound_image(&self, view: usize, light: usize) -> bool {
        self.arr.verify_chunk(&[view as u64, light as u64, 0, 0, 0]).is_ok()
    }

    /// True when image `(view, light)` is already written (for resuming).
    pub fn has_image(&self, view: usize, light: usize) -> bool {
        self.arr.has_chunk(&[view as u64, light as u64, 0, 0, 0])
    }

    /// Writes one normtexture (`height · width · 3` linear values, row-major, RGB).
    pub fn write_image(&self, view: usize, light: usize, values: &[f32]) -> Result<()> {
        if view >= self.meta.n_views() || light >= self.meta.n_lights() {
            return Err(Error::Invalid(format!("image ({view}, {light}) is outside the sampling")));
        }
        if values.len() != self.meta.texel_values() {
            return Err(Error::Invalid(format!(
                "image ({view}, {light}) has {} values, {} expected",
                values.len(),
                self.meta.texel_values()
            )));
        }
        check_finite(values, view, light, self.meta.width)?;
        if self.arr.meta().dtype == DType::F16 {
            check_f16_range(values, view, light, self.meta.width)?;
        }
        self.arr.write_chunk(
            &[view as u64, light as u64, 0, 0, 0],
            &zarr::encode_f32(values, self.arr.meta().dtype),
        )
    }

    /// Checks that every image is present and moves the store into place.
    pub fn finish(self) -> Result<()> {
        for v in 0..self.meta.n_views() {
            for l in 0..self.meta.n_lights() {
                if !self.has_image(v, l) {
                    return Err(Error::Invalid(format!(
                        "image (view {v}, light {l}) was never written"
                    )));
                }
            }
        }
        crate::axes::write(self.txn.dir(), &self.meta)?;
        let attrs = json!({"btf": self.meta});
        self.txn.commit(attrs)
    }
}

/// The state of one view slot of a store being written (by shards, issue #23).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SlotState {
    /// Every chunk present and checked (and, for an eigen slot, its statistics recorded).
    Done,
    /// Some chunk (or the statistics) not written yet.
    Missing,
    /// A chunk fails its size or checksum check: what is wrong, with the file named.
    Corrupt(String),
}

/// What the shards of a job have written into a store at `output` (a BTF or eigen store,
/// still `OUTPUT.partial` or already committed).
#[derive(Debug, Clone, serde::Serialize)]
pub struct ShardedStatus {
    /// `"btf"` or `"eigen"`.
    pub store: String,
    /// Shards the job was split into (1 when it was not sharded).
    pub shards: usize,
    /// State of every view slot: `"done"`, `"missing"` or `"corrupt: …"`.
    pub slots: Vec<String>,
    /// True when the store has been committed (finalised).
    pub finalised: bool,
}

impl ShardedStatus {
    /// View slots whose state starts with `state` (`"done"`, `"missing"`, `"corrupt"`).
    pub fn views(&self, state: &str) -> Vec<usize> {
        (0..self.slots.len()).filter(|&v| self.slots[v].starts_with(state)).collect()
    }

    pub(crate) fn of(store: &str, job: &Value, states: Vec<SlotState>) -> Self {
        let slots = states
            .into_iter()
            .map(|s| match s {
                SlotState::Done => "done".to_string(),
                SlotState::Missing => "missing".to_string(),
                SlotState::Corrupt(why) => format!("corrupt: {why}"),
            })
            .collect();
        ShardedStatus {
            store: store.into(),
            shards: job["shards"].as_u64().unwrap_or(1) as usize,
            slots,
            finalised: false,
        }
    }

    /// Refuses (listing them) when slots are missing or corrupt.
    pub(crate) fn require_complete(&self, output: &Path) -> Result<()> {
        let (missing, corrupt) = (self.views("missing"), self.views("corrupt"));
        if missing.is_empty() && corrupt.is_empty() {
            return Ok(());
        }
        let why: Vec<&str> = corrupt.iter().map(|&v| self.slots[v].as_str()).collect();
        Err(Error::Invalid(format!(
            "{}: cannot finalise: {} of {} view slots missing ({}), {} corrupt{}{}",
            output.display(),
            missing.len(),
            self.slots.len(),
            list_units(&missing),
            corrupt.len(),
            if why.is_empty() { "" } else { ": " },
            why.join("; ")
        )))
    }
}

/// `0-3, 7, 9-12`.
pub fn list_units(units: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < units.len() {
        let mut j = i;
        while j + 1 < units.len() && units[j + 1] == units[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            units[i].to_string()
        } else {
            format!("{}-{}", units[i], units[j])
        });
        i = j + 1;
    }
    parts.join(", ")
}

/// Which kind of store (`"btf"`, `"eigen"`) the job beside `output` is writing, or the
/// committed store at `output` is; `None` for neither.
pub fn store_kind(output: &Path) -> Option<String> {
    if let Some(job) = StoreTxn::recorded_job(output) {
        return job["store"].as_str().map(String::from);
    }
    read_meta(output).ok().map(|m| m.kind)
}

/// The state of every view slot of the BTF store that shards are writing at `output`
/// (or of the committed store).
pub fn sharded_status(output: &Path) -> Result<ShardedStatus> {
    if StoreTxn::recorded_job(output).is_none() {
        let store = BtfStore::open(output)?;
        let n = store.meta().n_views();
        return Ok(ShardedStatus {
            store: "btf".into(),
            shards: 1,
            slots: vec!["done".into(); n],
            finalised: true,
        });
    }
    let (w, record) = BtfWriter::open_partial(output, false)?;
    let states = (0..w.meta.n_views()).map(|v| w.slot_state(v)).collect();
    Ok(ShardedStatus::of("btf", &record["job"], states))
}

/// Commits the BTF store that shards filled at `output` once every image is in and sound;
/// `Ok(true)` when it was committed already (safe to run twice).
pub fn finalize_sharded(output: &Path) -> Result<bool> {
    if StoreTxn::recorded_job(output).is_none() {
        BtfStore::open(output)?;
        return Ok(true);
    }
    let (w, record) = BtfWriter::open_partial(output, true)?;
    let states = (0..w.meta.n_views()).map(|v| w.slot_state(v)).collect();
    ShardedStatus::of("btf", &record["job"], states).require_complete(output)?;
    w.finish()?;
    Ok(false)
}

/// The light images of one view slot: `n_lights` rows of `texel_values` floats.
#[derive(Debug, Clone)]
pub struct SlotData {
    /// View slot index.
    pub view: usize,
    /// Number of rows (lights).
    pub n_lights: usize,
    /// Floats per row.
    pub texel_values: usize,
    /// Row-major data, `n_lights × texel_values`.
    pub data: Vec<f32>,
}

impl SlotData {
    /// Row `light`.
    pub fn row(&self, light: usize) -> &[f32] {
        &self.data[light * self.texel_values..(light + 1) * self.texel_values]
    }
}

/// A BTF store opened for reading.
#[derive(Debug, Clone)]
pub struct BtfStore {
    path: PathBuf,
    meta: BtfMeta,
    arr: ZarrArray,
}

impl BtfStore {
    /// Opens a store, checking its metadata and limits before reading any chunk.
    pub fn open(path: &Path) -> Result<Self> {
        let meta = read_meta_of_kind(path, "btf", "")?;
        let arr = ZarrArray::open(&path.join("normtextures"), &Limits::default())?;
        let expect = ArrayMeta {
            compression: arr.meta().compression,
            ..normtexture_array(&meta, arr.meta().dtype)
        };
        crate::axes::check(path, &meta)?;
        if arr.meta() != &expect {
            return Err(Error::Corrupt {
                path: path.join("normtextures/zarr.json"),
                what: "array shape disagrees with the store's sampling and size".into(),
            });
        }
        Ok(BtfStore { path: path.to_owned(), meta, arr })
    }

    /// The store's metadata.
    pub fn meta(&self) -> &BtfMeta {
        &self.meta
    }
    /// The store's folder.
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Element type on disk.
    pub fn dtype(&self) -> DType {
        self.arr.meta().dtype
    }
    /// Bytes of all chunks on disk.
    pub fn bytes(&self) -> u64 {
        (self.meta.n_views() * self.meta.n_lights()) as u64
            * self.arr.meta().chunk_bytes().unwrap_or(0)
    }

    /// Reads one normtexture into `out` (`texel_values` floats), refusing non-finite data.
    pub fn read_image_into(&self, view: usize, light: usize, out: &mut [f32]) -> Result<()> {
        self.read_image_buffered(view, light, out, &mut Vec::new(), true)
    }

    fn read_image_buffered(
        &self,
        view: usize,
        light: usize,
        out: &mut [f32],
        raw: &mut Vec<u8>,
        check: bool,
    ) -> Result<()> {
        if view >= self.meta.n_views() || light >= self.meta.n_lights() {
            return Err(Error::Invalid(format!("image ({view}, {light}) is outside the sampling")));
        }
        let idx = [view as u64, light as u64, 0, 0, 0];
        let name = |e| match e {
            Error::Corrupt { path, what } => {
                Error::Corrupt { path, what: format!("view slot {view}, light {light}: {what}") }
            }
            other => other,
        };
        if self.dtype() == DType::F32 && cfg!(target_endian = "little") {
            // Little-endian f32 on disk is the in-memory layout: read straight into `out`.
            self.arr.read_chunk_to(&idx, bytemuck::cast_slice_mut(out)).map_err(name)?;
        } else {
            self.arr.read_chunk_into(&idx, raw).map_err(name)?;
            zarr::decode_to_f32(raw, self.dtype(), out);
        }
        if check { check_finite(out, view, light, self.meta.width) } else { Ok(()) }
    }

    /// Checks, before anything is allocated for them, that the chunks of `lights` in view
    /// slot `view` are on disk with the size the metadata claims and that `values` floats
    /// fit in memory: a store whose metadata claims more than its files hold is refused by
    /// name instead of aborting on the allocation.
    fn check_claim(&self, view: usize, lights: std::ops::Range<usize>, values: u64) -> Result<()> {
        if view >= self.meta.n_views() || lights.end > self.meta.n_lights() {
            return Err(Error::Invalid(format!(
                "{}: view slot {view}, lights {lights:?} are outside the sampling",
                self.path.display()
            )));
        }
        for l in lights {
            self.arr.check_chunk_file(&[view as u64, l as u64, 0, 0, 0]).map_err(|e| match e {
                Error::Corrupt { path, what } => {
                    Error::Corrupt { path, what: format!("view slot {view}, light {l}: {what}") }
                }
                other => other,
            })?;
        }
        crate::memory::check_alloc(
            values.checked_mul(4),
            &format!(
                "{}: btf.width x btf.height = {} x {} texels",
                self.path.join("zarr.json").display(),
                self.meta.width,
                self.meta.height
            ),
        )
    }

    /// Reads one normtexture.
    pub fn read_image(&self, view: usize, light: usize) -> Result<Vec<f32>> {
        self.check_claim(view, light..light + 1, self.meta.texel_values() as u64)?;
        let mut out = vec![0f32; self.meta.texel_values()];
        self.read_image_into(view, light, &mut out)?;
        Ok(out)
    }

    /// Reads all light images of view slot `view`.
    pub fn read_slot(&self, view: usize) -> Result<SlotData> {
        let mut slot = SlotData { view, n_lights: 0, texel_values: 0, data: Vec::new() };
        self.read_slot_into(view, &mut slot, &mut Vec::new())?;
        Ok(slot)
    }

    /// Reads all light images of view slot `view` into reusable buffers (`raw` holds one
    /// chunk's bytes), so streaming the slots of a large BTF allocates nothing per slot.
    pub fn read_slot_into(
        &self,
        view: usize,
        slot: &mut SlotData,
        raw: &mut Vec<u8>,
    ) -> Result<()> {
        self.read_slot_checked(view, slot, raw, true)
    }

    /// Maps the chunks of view slot `view` read-only when they hold little-endian `f32` or
    /// `f16` (in-memory layouts the PCA's loads widen in place), for a caller that reads
    /// the slot several times and checks the checksums itself ([`crate::mapped`]); `None`
    /// for a dtype or a compression that must be decoded.
    pub fn map_slot(&self, view: usize) -> Result<Option<crate::mapped::MappedSlot>> {
        if !matches!(self.dtype(), DType::F32 | DType::F16)
            || !cfg!(target_endian = "little")
            || self.arr.meta().compression != zarr::Compression::None
        {
            return Ok(None);
        }
        if view >= self.meta.n_views() {
            return Err(Error::Invalid(format!("view slot {view} is outside the sampling")));
        }
        let chunks = (0..self.meta.n_lights())
            .map(|l| {
                self.arr.map_chunk(&[view as u64, l as u64, 0, 0, 0]).map_err(|e| match e {
                    Error::Corrupt { path, what } => Error::Corrupt {
                        path,
                        what: format!("view slot {view}, light {l}: {what}"),
                    },
                    other => other,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Some(crate::mapped::MappedSlot::new(view, chunks)))
    }

    /// [`BtfStore::read_slot_into`] without the finiteness check (checksums are still
    /// verified), for a caller that checks every value itself before using any: the PCA
    /// does, in its first pass.
    pub fn read_slot_into_unchecked(
        &self,
        view: usize,
        slot: &mut SlotData,
        raw: &mut Vec<u8>,
    ) -> Result<()> {
        self.read_slot_checked(view, slot, raw, false)
    }

    /// Reads the light images of view slot `view` as the `f16` values the store holds, row
    /// after row into `halves` (reused from slot to slot), checksums verified and values
    /// not checked (the PCA checks every one in its first pass): half the memory of the
    /// `f32` slot of [`BtfStore::read_slot_into`], so half the pages each process faults
    /// in, and no widening pass. `Ok(false)`, nothing read, unless the store holds
    /// little-endian `f16`.
    pub fn read_slot_f16_into(&self, view: usize, halves: &mut Vec<half::f16>) -> Result<bool> {
        if self.dtype() != DType::F16 || !cfg!(target_endian = "little") {
            return Ok(false);
        }
        let n = self.meta.texel_values();
        let n_l = self.meta.n_lights();
        self.check_claim(view, 0..n_l, (n as u64).saturating_mul(n_l as u64))?;
        halves.resize(n * n_l, half::f16::ZERO);
        for (l, row) in halves.chunks_exact_mut(n).enumerate() {
            let idx = [view as u64, l as u64, 0, 0, 0];
            self.arr.read_chunk_to(&idx, bytemuck::cast_slice_mut(row)).map_err(|e| match e {
                Error::Corrupt { path, what } => {
                    Error::Corrupt { path, what: format!("view slot {view}, light {l}: {what}") }
                }
                other => other,
            })?;
        }
        Ok(true)
    }

    fn read_slot_checked(
        &self,
        view: usize,
        slot: &mut SlotData,
        raw: &mut Vec<u8>,
        check: bool,
    ) -> Result<()> {
        let n = self.meta.texel_values();
        let n_l = self.meta.n_lights();
        self.check_claim(view, 0..n_l, (n as u64).saturating_mul(n_l as u64))?;
        slot.view = view;
        slot.n_lights = self.meta.n_lights();
        slot.texel_values = n;
        slot.data.resize(n * slot.n_lights, 0.0);
        for (l, row) in slot.data.chunks_exact_mut(n).enumerate() {
            self.read_image_buffered(view, l, row, raw, check)?;
        }
        Ok(())
    }
}

/// Rewrites a store's metadata to claim `w × h` texels consistently (group attributes and
/// the `y`/`x` dimensions of every array's shape and chunk shape), chunk files untouched:
/// the hostile store of issue #26, class 3.
#[cfg(test)]
pub(crate) fn claim_texels(store: &Path, w: u64, h: u64) {
    let group = store.join("zarr.json");
    let mut g: Value = serde_json::from_slice(&fs::read(&group).unwrap()).unwrap();
    g["attributes"]["btf"]["width"] = json!(w);
    g["attributes"]["btf"]["height"] = json!(h);
    fs::write(&group, serde_json::to_vec(&g).unwrap()).unwrap();
    for e in fs::read_dir(store).unwrap() {
        let meta = e.unwrap().path().join("zarr.json");
        let Ok(bytes) = fs::read(&meta) else { continue };
        let mut a: Value = serde_json::from_slice(&bytes).unwrap();
        // Groups (stats/, registration/) have no dimensions.
        let Ok(names) = serde_json::from_value::<Vec<String>>(a["dimension_names"].clone()) else {
            continue;
        };
        for (i, n) in names.iter().enumerate() {
            let v = match n.as_str() {
                "y" => h,
                "x" => w,
                _ => continue,
            };
            a["shape"][i] = json!(v);
            a["chunk_grid"]["configuration"]["chunk_shape"][i] = json!(v);
        }
        fs::write(&meta, serde_json::to_vec(&a).unwrap()).unwrap();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_difference_inside_a_text_names_the_line() {
        let was =
            serde_json::json!({"yarn": {"params": "name = \"a\"\nply_count = 2\nfibers = 80\n"}});
        let now =
            serde_json::json!({"yarn": {"params": "name = \"a\"\nply_count = 3\nfibers = 80\n"}});
        assert_eq!(
            first_difference(&was, &now, ""),
            "yarn.params, line 2: was \"ply_count = 2\", now \"ply_count = 3\""
        );
        let shorter = serde_json::json!({"yarn": {"params": "name = \"a\"\n"}});
        assert!(first_difference(&was, &shorter, "").ends_with("now (no line)"));
    }

    #[test]
    fn metadata_claiming_8192_squared_texels_is_refused_before_allocating() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        write_store(&p, 1.0);
        claim_texels(&p, 8192, 8192);
        // Consistent metadata opens; reading refuses by naming the chunk file and the claim
        // (the decoded size its blosc frame records against the claim) instead of
        // allocating 4 × 805 MB for the slot.
        let s = BtfStore::open(&p).unwrap();
        assert_eq!((s.meta().width, s.meta().height), (8192, 8192));
        for e in [s.read_slot(1).unwrap_err(), s.read_image(1, 2).unwrap_err()] {
            assert!(matches!(e, Error::Corrupt { .. }), "{e}");
            let e = e.to_string();
            assert!(e.contains("normtextures/c.1.") && e.contains("view slot 1"), "{e}");
            assert!(e.contains("claims 805306368"), "{e}");
        }
        // Compressed chunks are decoded, never mapped.
        assert!(s.map_slot(1).unwrap().is_none());
    }

    fn tiny_meta() -> BtfMeta {
        let s = Sampling::new(
            "custom",
            vec![
                crate::Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 },
                crate::Ring { theta_deg: 40.0, count: 3, phi_offset_deg: 0.0 },
            ],
        )
        .unwrap();
        BtfMeta::new(s.clone(), s, 3, 2)
    }

    fn write_store(path: &Path, scale: f32) {
        let w = BtfWriter::create(path, tiny_meta(), DType::F32, false).unwrap();
        for v in 0..4 {
            for l in 0..4 {
                let img: Vec<f32> =
                    (0..18).map(|k| scale * (v * 100 + l * 10 + k) as f32).collect();
                w.write_image(v, l, &img).unwrap();
            }
        }
        w.finish().unwrap();
    }

    #[test]
    fn round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        write_store(&p, 1.0);
        let s = BtfStore::open(&p).unwrap();
        assert_eq!(s.read_image(2, 3).unwrap()[5], 235.0);
        let slot = s.read_slot(1).unwrap();
        assert_eq!(slot.row(2)[0], 120.0);
    }

    #[test]
    fn interrupted_write_leaves_previous_store_and_resume_works() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        write_store(&p, 1.0);
        // An interrupted second write: half the images, no finish.
        {
            let w = BtfWriter::create(&p, tiny_meta(), DType::F32, false).unwrap();
            w.write_image(0, 0, &[2.0; 18]).unwrap();
        }
        assert_eq!(BtfStore::open(&p).unwrap().read_image(0, 0).unwrap()[1], 1.0);
        // Resuming keeps the written image; finishing fails while images are missing.
        let w = BtfWriter::create(&p, tiny_meta(), DType::F32, true).unwrap();
        assert!(w.has_image(0, 0) && !w.has_image(0, 1));
        let err = w.finish().unwrap_err().to_string();
        assert!(err.contains("never written"), "{err}");
        assert_eq!(BtfStore::open(&p).unwrap().read_image(0, 0).unwrap()[1], 1.0);
    }

    #[test]
    fn a_writer_killed_inside_its_commit_resumes() {
        // The commit writes the final attributes into the partial, then renames it: killed
        // in between, the partial holds no `partial_job`. The job waits in the sidecar, so a
        // resume of the same job finishes it and another job's is refused (both used to be
        // refused as "records no job"); the sidecar never enters the store.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        let job = json!({ "what": "a", "n": 1 });
        let txn = StoreTxn::begin(&p, false, &job).unwrap();
        let partial = txn.dir().to_owned();
        let record = json!({ "job": job, "attributes": { "complete": true } });
        crate::fs::write_atomic(&job_sidecar(&partial), record.to_string().as_bytes()).unwrap();
        zarr::write_group(&partial, &json!({ "complete": true })).unwrap();
        drop(txn);
        let other = json!({ "what": "a", "n": 2 });
        let e = StoreTxn::begin(&p, true, &other).unwrap_err().to_string();
        assert!(e.contains("different job") && e.contains("n"), "{e}");
        let txn = StoreTxn::begin(&p, true, &job).unwrap();
        txn.commit(json!({ "btf": {} })).unwrap();
        let attrs = zarr::read_group(&p).unwrap();
        assert_eq!(attrs, json!({ "btf": {}, "complete": true }));
        let names: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["m.btf"]);
        // Killed just after the rename: the stray sidecar goes with the next writer.
        fs::write(job_sidecar(&partial), "{}").unwrap();
        StoreTxn::begin(&p, false, &job).unwrap().commit(json!({})).unwrap();
        assert!(!job_sidecar(&partial).exists());
    }

    #[test]
    fn a_writer_killed_after_its_exchange_leaves_the_new_store_and_a_clean_resume() {
        // The exchange put the new store at `path` and the old one at the partial's name;
        // killed before the old one was removed (the hostile suite's kill -9 of `compress
        // --resume` met this: the resume then wrote into the old store's arrays and was
        // refused for their different metadata). The next writer clears up and starts anew.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        let old_job = json!({ "c": 2 });
        StoreTxn::begin(&p, false, &old_job).unwrap().commit(json!({ "btf": { "c": 2 } })).unwrap();
        let job = json!({ "c": 3 });
        let txn = StoreTxn::begin(&p, false, &job).unwrap();
        let partial = txn.dir().to_owned();
        let new_attrs = json!({ "btf": { "c": 3 }, "complete": true });
        let record = json!({ "job": job, "attributes": new_attrs });
        crate::fs::write_atomic(&job_sidecar(&partial), record.to_string().as_bytes()).unwrap();
        zarr::write_group(&partial, &new_attrs).unwrap();
        drop(txn);
        // The exchange, then death: the old store sits at the partial's name.
        fs::rename(&p, dir.path().join("old")).unwrap();
        fs::rename(&partial, &p).unwrap();
        fs::rename(dir.path().join("old"), &partial).unwrap();
        let txn = StoreTxn::begin(&p, true, &job).unwrap();
        assert!(!job_sidecar(&partial).exists());
        assert_eq!(zarr::read_group(txn.dir()).unwrap(), json!({ "partial_job": job }));
        txn.commit(json!({ "btf": { "c": 3 } })).unwrap();
        assert_eq!(zarr::read_group(&p).unwrap(), new_attrs);
        assert!(!partial.exists() && !job_sidecar(&partial).exists());
    }

    #[test]
    fn replacing_a_store_swaps_it_in_and_leaves_nothing_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        write_store(&p, 1.0);
        write_store(&p, 2.0);
        assert_eq!(BtfStore::open(&p).unwrap().read_image(2, 3).unwrap()[5], 470.0);
        let names: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["m.btf"]);
        // The exchange itself: both names stay occupied, contents swapped.
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        fs::write(&a, "new").unwrap();
        fs::create_dir(&b).unwrap();
        match exchange(&a, &b) {
            Ok(()) => assert!(a.is_dir() && fs::read_to_string(&b).unwrap() == "new"),
            // ext4, xfs, btrfs and tmpfs all support the exchange on Linux.
            Err(e) if cfg!(target_os = "linux") => panic!("no atomic exchange: {e}"),
            Err(_) => {}
        }
    }

    #[test]
    fn corrupt_chunk_named_and_nan_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.btf");
        write_store(&p, 1.0);
        let chunk = p.join("normtextures/c.2.1.0.0.0");
        let mut b = fs::read(&chunk).unwrap();
        b[10] ^= 1;
        fs::write(&chunk, b).unwrap();
        let err = BtfStore::open(&p).unwrap().read_slot(2).unwrap_err().to_string();
        assert!(err.contains("view slot 2, light 1") && err.contains("checksum"), "{err}");

        let w =
            BtfWriter::create(&dir.path().join("n.btf"), tiny_meta(), DType::F32, false).unwrap();
        let mut img = vec![0.0; 18];
        img[7] = f32::NAN;
        let err = w.write_image(3, 2, &img).unwrap_err().to_string();
        assert!(err.contains("view slot 3, light 2") && err.contains("x=2"), "{err}");
    }

    #[test]
    fn f16_store_refuses_values_that_would_round_to_infinity() {
        let dir = tempfile::tempdir().unwrap();
        let w =
            BtfWriter::create(&dir.path().join("h.btf"), tiny_meta(), DType::F16, false).unwrap();
        // 65519 rounds to the largest f16 (65504); 65520 is the first value that rounds to ∞.
        let mut img = vec![0.5; 18];
        img[4] = -65519.0;
        w.write_image(0, 0, &img).unwrap();
        img[10] = 65520.0;
        let err = w.write_image(1, 3, &img).unwrap_err().to_string();
        assert!(
            err.contains("view slot 1, light 3") && err.contains("y=1, x=0, channel 1"),
            "{err}"
        );
    }
}
