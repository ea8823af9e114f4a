//! Shards of a batch job (issue #23): which part of a job's work units (frames, view slots)
//! shard `I` of `N` owns, the content fingerprint of an input store that every shard of a
//! job must agree on, and the job records that the first shard writes and every later
//! one checks.
//!
//! - **Partition.** Units are numbered `0..total` in the job's own order and shard `i` of
//!   `n` owns the contiguous block `⌊i·total/n⌋ .. ⌊(i+1)·total/n⌋`: deterministic, the
//!   blocks of any two shards differ by at most one unit (units of one job cost the same:
//!   a frame, a view slot's PCA), and a contiguous block keeps what units share (a relight
//!   environment's gathered weights) inside as few shards as possible.
//! - **Agreement.** A job record (a JSON document) is created once with
//!   [`crate::fs::write_new`] — whoever comes first writes it, nobody replaces it — and every
//!   other writer compares its own record with it before writing anything, refusing with
//!   the first differing field named ([`crate::store::first_difference`]).
//! - **Fingerprint.** A store is identified by its content, not its path or inode (shards on
//!   different machines mount the shared volume at different places): every metadata
//!   document and every file up to 64 KiB whole, every larger chunk's name and length (from
//!   the directory listing), and the stored crc32c (last four bytes) of at most
//!   [`MAX_TAILS`] of the larger chunks, evenly spaced in name order, hashed in name order.
//!   Opening every chunk of a 6 561-image store cost each shard 0.47 s of CPU (+15 % on a
//!   12.6 s compression split four ways); the listing and 256 tails cost a tenth of that.
//!   Two stores of one shape whose chunks differ only outside the sampled tails and keep
//!   their lengths (uncompressed stores) are taken for the same; a job record also names
//!   the parameters, so this is the one case a fingerprint does not catch.

use crate::{Error, Result};
use serde_json::Value;
use std::fs;
use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Shard `index` of `count` (0-based), as `--shard I/N` gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `0..count`.
    pub index: usize,
    /// How many shards the job is split into.
    pub count: usize,
}

/// Environment variables that carry a shard index: Kubernetes Indexed Jobs, Slurm arrays.
pub const INDEX_VARIABLES: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];

impl Shard {
    /// A checked shard: `count ≥ 1` and `index < count`.
    pub fn new(index: usize, count: usize) -> Result<Self> {
        if count == 0 || count > 1_000_000 {
            return Err(Error::Invalid(format!("shard count {count} is not in 1..=1000000")));
        }
        if index >= count {
            return Err(Error::Invalid(format!(
                "shard index {index} is not below the shard count {count} (shards are numbered \
                 0..{count})"
            )));
        }
        Ok(Shard { index, count })
    }

    /// Parses `I/N` (0-based index).
    pub fn parse(text: &str) -> Result<Self> {
        let bad =
            || Error::Invalid(format!("--shard {text:?}: expected I/N with 0 ≤ I < N, e.g. 0/4"));
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let i = i.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        Shard::new(i, n)
    }

    /// Shard of `count` whose index comes from the first of [`INDEX_VARIABLES`] that is set
    /// (`lookup` reads a variable: `std::env::var` in the binary).
    pub fn from_env(count: usize, lookup: impl Fn(&str) -> Option<String>) -> Result<Self> {
        for var in INDEX_VARIABLES {
            if let Some(v) = lookup(var) {
                let index = v.trim().parse().map_err(|_| {
                    Error::Invalid(format!("{var}={v:?}: not a shard index (a whole number)"))
                })?;
                return Shard::new(index, count)
                    .map_err(|e| Error::Invalid(format!("{var}={v}: {e}")));
            }
        }
        Err(Error::Invalid(format!(
            "--shard-count {count} needs the shard index in {} or {} (or give --shard I/N)",
            INDEX_VARIABLES[0], INDEX_VARIABLES[1]
        )))
    }

    /// The units `0..total` this shard owns (see the module docs).
    pub fn range(&self, total: usize) -> Range<usize> {
        let at = |i: usize| (i as u128 * total as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// Which shard of `count` owns unit `unit` of `total`.
    pub fn owner(unit: usize, total: usize, count: usize) -> usize {
        (0..count)
            .find(|&i| Shard { index: i, count }.range(total).contains(&unit))
            .unwrap_or(count - 1)
    }

    /// `I/N`.
    pub fn label(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }
}

/// Writes `record` at `path` if nothing is there yet, or checks that what is there is the
/// same job: `Ok(true)` when this call created it, `Ok(false)` when it agreed, an error
/// naming the file and the first differing field otherwise. Nothing is written on a
/// refusal.
pub fn agree_or_create(path: &Path, record: &Value) -> Result<bool> {
    let text = serde_json::to_string_pretty(record).unwrap_or_default();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty() && !d.exists()) {
        fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    if crate::fs::write_new(path, text.as_bytes())? {
        return Ok(true);
    }
    check_agrees(path, record)?;
    Ok(false)
}

/// Checks that the job recorded at `path` is `record` (see [`agree_or_create`]).
pub fn check_agrees(path: &Path, record: &Value) -> Result<()> {
    let bytes = fs::read(path).map_err(|e| Error::io(path, e))?;
    let was: Value = serde_json::from_slice(&bytes)
        .map_err(|source| Error::Json { path: path.to_owned(), source })?;
    if &was != record {
        return Err(Error::Invalid(format!(
            "{} records a different job ({}); every writer of one output must be given the \
             same inputs and parameters — refusing before writing anything",
            path.display(),
            crate::store::first_difference(&was, record, "")
        )));
    }
    Ok(())
}

/// Files up to this size are hashed whole by [`fingerprint`].
const SMALL_FILE: u64 = 64 << 10;

/// The most large chunks whose stored checksum [`fingerprint`] reads.
pub const MAX_TAILS: usize = 256;

/// The content fingerprint of a store folder (see the module docs), as 16 hex digits.
pub fn fingerprint(store: &Path) -> Result<String> {
    let mut files = Vec::new();
    collect_files(store, store, &mut files)?;
    files.sort();
    let is_small = |(rel, len): &(PathBuf, u64)| {
        let name = rel.file_name().and_then(|n| n.to_str()).unwrap_or("");
        *len <= SMALL_FILE || name.ends_with(".json") && *len <= 64 << 20
    };
    let large = files.iter().filter(|f| !is_small(f)).count();
    let every = large.div_ceil(MAX_TAILS).max(1);
    let mut h = Fnv::new();
    let mut k = 0;
    for f in &files {
        let (rel, len) = f;
        let path = store.join(rel);
        h.eat(rel.to_string_lossy().as_bytes());
        if is_small(f) {
            let bytes = fs::read(&path).map_err(|e| Error::io(&path, e))?;
            h.eat(&bytes);
            continue;
        }
        h.eat(&len.to_le_bytes());
        if k % every == 0 {
            let mut file = fs::File::open(&path).map_err(|e| Error::io(&path, e))?;
            let mut tail = [0u8; 4];
            let n = (*len).min(4);
            file.seek(SeekFrom::Start(len - n)).map_err(|e| Error::io(&path, e))?;
            file.read_exact(&mut tail[..n as usize]).map_err(|e| Error::io(&path, e))?;
            h.eat(&tail);
        }
        k += 1;
    }
    Ok(format!("{:016x}", h.0))
}

fn collect_files(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, u64)>) -> Result<()> {
    for entry in fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let name = entry.file_name();
        if crate::fs::is_temp_name(&name.to_string_lossy()) {
            continue;
        }
        let meta = entry.metadata().map_err(|e| Error::io(&path, e))?;
        if meta.is_dir() {
            collect_files(root, &path, out)?;
        } else {
            out.push((path.strip_prefix(root).unwrap_or(&path).to_owned(), meta.len()));
        }
    }
    Ok(())
}

/// 64-bit FNV-1a.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        // A separator, so that ("ab", "c") and ("a", "bc") differ.
        self.0 = (self.0 ^ 0xff).wrapping_mul(0x0000_0100_0000_01b3);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_cover_every_unit_once_and_differ_by_at_most_one() {
        for total in [0, 1, 7, 81, 200, 1001] {
            for count in 1..=9 {
                let sizes: Vec<usize> =
                    (0..count).map(|i| Shard::new(i, count).unwrap().range(total).len()).collect();
                assert_eq!(sizes.iter().sum::<usize>(), total);
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{total} over {count}: {sizes:?}");
                for u in 0..total {
                    let o = Shard::owner(u, total, count);
                    assert!(Shard::new(o, count).unwrap().range(total).contains(&u));
                }
            }
        }
        assert_eq!(Shard::new(1, 4).unwrap().range(81), 20..40);
        assert_eq!(Shard::new(3, 4).unwrap().range(81), 60..81);
    }

    #[test]
    fn shard_specs_are_parsed_and_checked() {
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["4/4", "1/0", "x/2", "3", "-1/2"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        let env = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "3".to_string());
        assert_eq!(Shard::from_env(4, env).unwrap(), Shard { index: 3, count: 4 });
        let e = Shard::from_env(3, env).unwrap_err().to_string();
        assert!(e.contains("SLURM_ARRAY_TASK_ID=3"), "{e}");
        assert!(Shard::from_env(3, |_| None).unwrap_err().to_string().contains("JOB_COMPLETION"));
    }

    #[test]
    fn job_records_are_created_once_and_disagreement_names_the_field() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("shards/plan.json");
        let job = serde_json::json!({"components": 4, "input": "ab"});
        assert!(agree_or_create(&p, &job).unwrap());
        assert!(!agree_or_create(&p, &job).unwrap());
        let before = fs::read(&p).unwrap();
        let other = serde_json::json!({"components": 8, "input": "ab"});
        let e = agree_or_create(&p, &other).unwrap_err().to_string();
        assert!(e.contains("components: was 4, now 8") && e.contains("plan.json"), "{e}");
        assert_eq!(fs::read(&p).unwrap(), before);
    }

    #[test]
    fn fingerprints_follow_content_not_place() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a");
        fs::create_dir_all(a.join("c/0")).unwrap();
        fs::write(a.join("zarr.json"), "{}").unwrap();
        fs::write(a.join("c/0/0"), [1, 2, 3, 4, 5, 6]).unwrap();
        let fa = fingerprint(&a).unwrap();
        let b = d.path().join("b");
        fs::create_dir_all(b.join("c/0")).unwrap();
        fs::write(b.join("zarr.json"), "{}").unwrap();
        fs::write(b.join("c/0/0"), [1, 2, 3, 4, 5, 6]).unwrap();
        assert_eq!(fingerprint(&b).unwrap(), fa);
        fs::write(b.join("c/0/0"), [0, 2, 3, 4, 5, 6]).unwrap();
        assert_ne!(fingerprint(&b).unwrap(), fa, "a small chunk is hashed whole");
        // A large chunk: its length and stored checksum (the last four bytes).
        let big = |last: u8| {
            let mut v = vec![7u8; (SMALL_FILE + 1) as usize];
            *v.last_mut().unwrap() = last;
            v
        };
        fs::write(a.join("c/0/1"), big(1)).unwrap();
        fs::write(b.join("c/0/0"), [1, 2, 3, 4, 5, 6]).unwrap();
        fs::write(b.join("c/0/1"), big(1)).unwrap();
        assert_eq!(fingerprint(&b).unwrap(), fingerprint(&a).unwrap());
        fs::write(b.join("c/0/1"), big(2)).unwrap();
        assert_ne!(fingerprint(&b).unwrap(), fingerprint(&a).unwrap());
    }
}
