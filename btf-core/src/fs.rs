//! Files that are either complete or absent, and the rules every command keeps about the
//! paths it writes.
//!
//! - **Atomic writes.** [`write_atomic`] and [`write_atomic_with`] write to a temporary name
//!   in the output's folder ([`temp_path`]), check every write, flush, `fsync` and rename.
//!   A failed write (a full disk, a closed pipe, an error from the producer) removes the
//!   temporary file and leaves the previous file untouched; nothing half-written ever
//!   carries the final name. [`write_atomic_unsynced`] skips the `fsync` for the many small
//!   chunks of a store being built, whose checksums [`crate::zarr`] verifies on resume.
//! - **Leftovers.** Temporary names are recognisable ([`is_temp_name`]);
//!   [`sweep_temps`] removes the ones a killed run left inside a folder before it is
//!   committed.
//! - **Outputs are never inputs.** [`refuse_overlap`] refuses an output that is, contains or
//!   lies inside an input, comparing canonical paths and inode identity (so a hard link,
//!   a symlink or `a/../a` is seen through), and two outputs that are the same file.
//! - **Only what the toolkit made is replaced.** [`check_replaceable`] allows an existing
//!   output to be replaced only when it is of the kind being written: a store this toolkit
//!   wrote (a folder whose `zarr.json` carries `"btf"` attributes), a folder carrying the
//!   toolkit's marker file, or a regular file whose first bytes are of the format being
//!   written. Anything else (a user's notes, a folder of photographs) is refused by name.

use crate::{Error, Result};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Component, Path, PathBuf};

/// The temporary name beside `path` that a write goes through: `.NAME.tmp-PIDNONCE`, where
/// the nonce is drawn once per process so that writers on different machines sharing one
/// file system (shards of a job, issue #23) never share a temporary name even when their
/// process ids coincide (every pod of a Kubernetes job may be pid 1).
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}{:09}", std::process::id(), process_nonce()))
}

/// A number fixed for the life of the process and unlikely to repeat in another one: the
/// start time's nanoseconds mixed with the host name's bytes.
fn process_nonce() -> u32 {
    static NONCE: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    *NONCE.get_or_init(|| {
        let t = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let host = fs::read("/proc/sys/kernel/hostname").unwrap_or_default();
        let mut h = 0xcbf2_9ce4_8422_2325u64 ^ t;
        for b in host.iter().chain(&std::process::id().to_le_bytes()) {
            h = (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        (h % 1_000_000_000) as u32
    })
}

/// Writes `bytes` to `path` only if nothing is there yet, atomically and durably: the
/// document is written to a temporary name, synced, and moved to `path` by a rename that
/// refuses to replace (`renameat2(RENAME_NOREPLACE)`, or a hard link where the file system
/// lacks it, as NFS does). Returns `true` when this call created `path`, `false` when
/// another writer had (its content is left as it was, for the caller to compare). How
/// metadata shared by the shards of a job is written once, by whoever comes first.
pub fn write_new(path: &Path, bytes: &[u8]) -> Result<bool> {
    if path.exists() {
        return Ok(false);
    }
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes).map_err(|e| Error::io(path, e))?;
    let tmp = file.tmp.clone();
    let out = file.out.take().expect("an AtomicFile before its commit");
    let synced = out.into_inner().map_err(|e| e.into_error()).and_then(|f| f.sync_all());
    let linked = synced.and_then(|()| rename_no_replace(&tmp, path));
    let _ = fs::remove_file(&tmp);
    match linked {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(Error::io(path, e)),
    }
}

/// Moves `tmp` to `path` unless `path` exists (`AlreadyExists` then). Leaves `tmp` for the
/// caller to remove when it was linked rather than renamed.
fn rename_no_replace(tmp: &Path, path: &Path) -> std::io::Result<()> {
    #[cfg(any(target_os = "linux", target_os = "android"))]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        match renameat_with(CWD, tmp, CWD, path, RenameFlags::NOREPLACE) {
            Ok(()) => return Ok(()),
            Err(e) if e == rustix::io::Errno::EXIST => {
                return Err(std::io::ErrorKind::AlreadyExists.into());
            }
            // Not supported by this file system or kernel: fall back to a hard link.
            Err(_) => {}
        }
    }
    fs::hard_link(tmp, path)
}

/// True for a name that [`temp_path`] makes (of any process).
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.')
        && name
            .rsplit_once(".tmp-")
            .is_some_and(|(_, pid)| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
}

/// Writes `bytes` to `path` atomically and durably (temporary file, checked writes,
/// `fsync`, rename). On failure the temporary file is removed and `path` is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`] without the `fsync`: for the chunks of a store that is still being
/// written (its commit is what makes it visible; a crash before it is repaired by resume,
/// which checks every chunk's checksum).
pub fn write_atomic_unsynced(path: &Path, bytes: &[u8]) -> Result<()> {
    write_impl(path, false, |w| w.write_all(bytes))
}

/// Streams a file through `produce` into `path` atomically and durably. Any error from
/// `produce` or from the file system (reported at a write, the flush, the `fsync` or the
/// rename) removes the temporary file, leaves `path` as it was, and is returned with the
/// path named.
pub fn write_atomic_with(
    path: &Path,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    write_impl(path, true, produce)
}

fn write_impl(
    path: &Path,
    sync: bool,
    produce: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let mut file = AtomicFile::create(path)?;
    produce(&mut file).map_err(|e| Error::io(path, e))?;
    file.commit(sync)
}

/// A file written under a temporary name ([`temp_path`]) and moved into place by
/// [`AtomicFile::commit`]: the one atomic writer of the workspace ([`write_atomic`] and
/// [`write_atomic_with`] stream through it; writers that append piece by piece, such as the
/// PVF exporter, hold one). Dropped without a commit — an error, a refusal, a panic — it
/// removes its temporary and `path` stays as it was.
pub struct AtomicFile {
    out: Option<BufWriter<fs::File>>,
    tmp: PathBuf,
    path: PathBuf,
}

impl AtomicFile {
    /// Creates the temporary beside `path` (making the folder if needed). Refuses a path
    /// without a file name and a path that is a folder.
    pub fn create(path: &Path) -> Result<Self> {
        if path.file_name().is_none() {
            return Err(Error::Invalid(format!("{}: not a file name", path.display())));
        }
        if path.is_dir() {
            return Err(Error::Invalid(format!(
                "{}: is a folder; give the path of a file to write",
                path.display()
            )));
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let tmp = temp_path(path);
        let file = fs::File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        Ok(AtomicFile {
            out: Some(BufWriter::with_capacity(1 << 16, file)),
            tmp,
            path: path.to_owned(),
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, checks the flush, `fsync`s when `sync` and renames into place; any failure
    /// removes the temporary and leaves `path` untouched, with `path` named in the error.
    pub fn commit(mut self, sync: bool) -> Result<()> {
        let out = self.out.take().expect("an AtomicFile is committed once");
        let done = out
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|f| if sync { f.sync_all() } else { Ok(()) })
            .and_then(|()| fs::rename(&self.tmp, &self.path));
        if let Err(e) = done {
            let _ = fs::remove_file(&self.tmp);
            return Err(Error::io(&self.path, e));
        }
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.as_mut().expect("an AtomicFile before its commit").write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.out.as_mut().expect("an AtomicFile before its commit").write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.as_mut().expect("an AtomicFile before its commit").flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.out.take().is_some() {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

/// Removes every temporary file ([`is_temp_name`]) below `dir`; returns how many.
pub fn sweep_temps(dir: &Path) -> Result<usize> {
    let mut removed = 0;
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        let entries = match fs::read_dir(&d) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(Error::io(&d, e)),
        };
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(&d, e))?;
            let ty = entry.file_type().map_err(|e| Error::io(entry.path(), e))?;
            if ty.is_dir() {
                stack.push(entry.path());
            } else if entry.file_name().to_str().is_some_and(is_temp_name) {
                fs::remove_file(entry.path()).map_err(|e| Error::io(entry.path(), e))?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// `path` made absolute with symlinks resolved as far as it exists, walking it component by
/// component as the kernel (and `create_dir_all`) would: an existing prefix is
/// canonicalised, `..` steps back from what has been resolved so far, `.` is dropped.
pub fn resolve(path: &Path) -> Result<PathBuf> {
    let abs = if path.is_absolute() {
        path.to_owned()
    } else {
        std::env::current_dir().map_err(|e| Error::io(".", e))?.join(path)
    };
    let mut cur = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => cur.push(c.as_os_str()),
            Component::CurDir => {}
            Component::ParentDir => {
                cur.pop();
            }
            Component::Normal(name) => {
                cur.push(name);
                if let Ok(real) = cur.canonicalize() {
                    cur = real;
                }
            }
        }
    }
    Ok(cur)
}

/// What identifies an input for a job record: its canonical path and, where the platform
/// has them, device, inode and modification time (a store rewritten at the same path is a
/// new folder, so a partial begun from the old one is not resumed from the new one).
pub fn input_identity(path: &Path) -> serde_json::Value {
    let canonical = resolve(path).unwrap_or_else(|_| path.to_owned());
    let mut v = serde_json::json!({ "path": canonical.to_string_lossy() });
    #[cfg(unix)]
    if let Ok(m) = fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        v["dev"] = m.dev().into();
        v["ino"] = m.ino().into();
        v["mtime_ns"] =
            (m.mtime() as i128 * 1_000_000_000 + m.mtime_nsec() as i128).to_string().into();
    }
    v
}

#[cfg(unix)]
fn identity(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn identity(_: &Path) -> Option<(u64, u64)> {
    None
}

/// Refuses outputs that would destroy an input: an output that is an input (same canonical
/// path or same inode), that contains an input (an output folder holding it) or that lies
/// inside one (a file written into an input store); and two outputs that are one file.
/// Each path is given with the name a user knows it by (`"-o"`, `"--exr"`, `"input"`).
pub fn refuse_overlap(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    let outs: Vec<(&str, &Path, PathBuf)> =
        outputs.iter().map(|&(n, p)| Ok((n, p, resolve(p)?))).collect::<Result<_>>()?;
    let ins: Vec<(&str, &Path, PathBuf)> =
        inputs.iter().map(|&(n, p)| Ok((n, p, resolve(p)?))).collect::<Result<_>>()?;
    for (on, op, oc) in &outs {
        let oid = identity(oc);
        for (inn, ip, ic) in &ins {
            let same = oc == ic || (oid.is_some() && oid == identity(ic));
            let why = if same {
                Some("is")
            } else if oc.starts_with(ic) {
                Some("lies inside")
            } else if ic.starts_with(oc) {
                Some("contains")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(Error::Invalid(format!(
                    "refusing to write {on} {}: it {why} the {inn} {} (choose an output path \
                     outside every input)",
                    op.display(),
                    ip.display()
                )));
            }
        }
    }
    for (i, (an, ap, ac)) in outs.iter().enumerate() {
        for (bn, bp, bc) in &outs[i + 1..] {
            if ac == bc || ac.starts_with(bc) || bc.starts_with(ac) {
                return Err(Error::Invalid(format!(
                    "{an} {} and {bn} {} are the same path or one holds the other",
                    ap.display(),
                    bp.display()
                )));
            }
        }
    }
    Ok(())
}

/// What an output path will hold, for [`check_replaceable`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    /// A BTF or eigen store (a Zarr v3 folder with `"btf"` attributes).
    Store,
    /// A folder the toolkit fills; an existing one is reused when it is empty or carries
    /// this marker file, which the command writes.
    Folder {
        /// Name of the marker file inside the folder.
        marker: &'static str,
    },
    /// A single file whose format starts with these bytes (empty: any text file).
    File {
        /// The format's leading bytes.
        magic: &'static [u8],
        /// The format's name for messages.
        format: &'static str,
    },
}

/// PNG files.
pub const PNG: OutputKind = OutputKind::File { magic: b"\x89PNG\r\n\x1a\n", format: "PNG" };
/// OpenEXR files.
pub const EXR: OutputKind = OutputKind::File { magic: &[0x76, 0x2f, 0x31, 0x01], format: "EXR" };
/// NumPy `.npy` files.
pub const NPY: OutputKind = OutputKind::File { magic: b"\x93NUMPY", format: "NumPy" };
/// Radiance RGBE `.hdr` files.
pub const HDR: OutputKind = OutputKind::File { magic: b"#?", format: "Radiance HDR" };
/// Text files (OBJ, JSON, Markdown, CSV): replaced when they hold UTF-8 text.
pub const TEXT: OutputKind = OutputKind::File { magic: b"", format: "text" };

/// True when `dir` is a store this toolkit wrote (or began writing).
pub fn is_toolkit_store(dir: &Path) -> bool {
    let Ok(text) = fs::read(dir.join("zarr.json")) else { return false };
    if text.len() > 64 << 20 {
        return false;
    }
    serde_json::from_slice::<serde_json::Value>(&text).is_ok_and(|v| {
        v["zarr_format"] == 3 && v["attributes"].get("btf").is_some_and(|b| b.is_object())
            || v["attributes"].get("partial_job").is_some()
    })
}

/// Refuses to replace an existing `path` that is not of `kind` (see the module docs).
/// A missing path is always fine.
pub fn check_replaceable(path: &Path, kind: OutputKind) -> Result<()> {
    let Ok(meta) = fs::symlink_metadata(path) else { return Ok(()) };
    let refuse = |what: &str| {
        Err(Error::Invalid(format!(
            "{} exists and {what}; refusing to replace it (remove it yourself or choose \
             another output path)",
            path.display()
        )))
    };
    let meta = if meta.file_type().is_symlink() {
        match fs::metadata(path) {
            Ok(m) => m,
            Err(_) => return refuse("is a dangling symbolic link"),
        }
    } else {
        meta
    };
    match kind {
        OutputKind::Store => {
            if !meta.is_dir() {
                return refuse("is a file, not a store this toolkit wrote");
            }
            if !is_toolkit_store(path) {
                return refuse("is a folder that is not a store this toolkit wrote");
            }
        }
        OutputKind::Folder { marker } => {
            if !meta.is_dir() {
                return refuse("is a file, not a folder");
            }
            // A temporary of another writer creating the marker at this instant (a shard
            // of the same job) does not make the folder somebody else's.
            let empty = fs::read_dir(path).is_ok_and(|mut d| {
                d.all(|e| e.is_ok_and(|e| e.file_name().to_str().is_some_and(is_temp_name)))
            });
            if !empty && !path.join(marker).is_file() {
                return refuse(&format!(
                    "holds files this toolkit did not write (no {marker} in it)"
                ));
            }
        }
        OutputKind::File { magic, format } => {
            if meta.is_dir() {
                return refuse("is a folder");
            }
            if meta.len() == 0 {
                return Ok(());
            }
            let mut head = vec![0u8; magic.len().max(512)];
            let n = read_prefix(path, &mut head)?;
            let head = &head[..n];
            let ok = if magic.is_empty() {
                std::str::from_utf8(head).is_ok()
                    || std::str::from_utf8(&head[..n.saturating_sub(3)]).is_ok()
            } else {
                head.starts_with(magic)
            };
            if !ok {
                return refuse(&format!("is not a {format} file"));
            }
        }
    }
    Ok(())
}

fn read_prefix(path: &Path, buf: &mut [u8]) -> Result<usize> {
    use std::io::Read;
    let mut f = fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) => return Err(Error::io(path, e)),
        }
    }
    Ok(n)
}

/// Removes the files named `names` (and folders `dirs`, recursively, only when each holds
/// nothing but what `is_ours` accepts) from `dir`: how `--fresh` clears what a job wrote
/// without touching anything else in the folder.
pub fn remove_listed(dir: &Path, is_ours: &dyn Fn(&Path) -> bool) -> Result<usize> {
    let mut removed = 0;
    let entries = match fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(Error::io(dir, e)),
    };
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let p = entry.path();
        if !is_ours(&p) {
            continue;
        }
        let ty = entry.file_type().map_err(|e| Error::io(&p, e))?;
        if ty.is_dir() {
            removed += remove_listed(&p, is_ours)?;
            let _ = fs::remove_dir(&p);
        } else {
            fs::remove_file(&p).map_err(|e| Error::io(&p, e))?;
            removed += 1;
        }
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_new_creates_once_and_never_replaces() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("job.json");
        assert!(write_new(&p, b"first").unwrap());
        assert!(!write_new(&p, b"second").unwrap());
        assert_eq!(fs::read(&p).unwrap(), b"first");
        assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1, "no temporary left");
    }

    #[test]
    fn temp_names_are_recognised() {
        let t = temp_path(Path::new("/x/out.png"));
        assert!(is_temp_name(t.file_name().unwrap().to_str().unwrap()));
        assert!(!is_temp_name("out.png"));
        assert!(!is_temp_name(".hidden"));
        assert!(!is_temp_name(".a.tmp-"));
        assert!(!is_temp_name(".a.tmp-12x"));
    }

    #[test]
    fn a_failed_producer_leaves_the_previous_file_and_no_temp() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        write_atomic(&p, b"old").unwrap();
        let e = write_atomic_with(&p, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("producer failed"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("a.txt"), "{e}");
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert_eq!(fs::read_dir(d.path()).unwrap().count(), 1);
    }

    #[test]
    fn overlap_is_seen_through_links_dots_and_nesting() {
        let d = tempfile::tempdir().unwrap();
        let a = d.path().join("a.btf");
        fs::create_dir(&a).unwrap();
        let f = d.path().join("s.toml");
        fs::write(&f, "x").unwrap();
        let hard = d.path().join("hard.toml");
        fs::hard_link(&f, &hard).unwrap();
        let bad: Vec<PathBuf> = vec![
            a.clone(),
            d.path().join("x/../a.btf"),
            a.join("c/0"),
            d.path().to_owned(),
            hard.clone(),
        ];
        for out in &bad {
            let e = refuse_overlap(&[("-o", out)], &[("input", &a), ("scene", &f)]);
            assert!(e.is_err(), "{} accepted", out.display());
        }
        refuse_overlap(&[("-o", &d.path().join("b.eig"))], &[("input", &a)]).unwrap();
        assert!(
            refuse_overlap(
                &[("-o", &d.path().join("o.png")), ("--exr", &d.path().join("./o.png"))],
                &[]
            )
            .is_err()
        );
    }

    #[test]
    fn only_what_the_toolkit_made_is_replaced() {
        let d = tempfile::tempdir().unwrap();
        let notes = d.path().join("notes.eig");
        fs::write(&notes, "my notes").unwrap();
        assert!(check_replaceable(&notes, OutputKind::Store).is_err());
        let photos = d.path().join("photos");
        fs::create_dir(&photos).unwrap();
        fs::write(photos.join("a.jpg"), "x").unwrap();
        assert!(check_replaceable(&photos, OutputKind::Store).is_err());
        assert!(check_replaceable(&photos, OutputKind::Folder { marker: "job.json" }).is_err());
        fs::write(photos.join("job.json"), "{}").unwrap();
        check_replaceable(&photos, OutputKind::Folder { marker: "job.json" }).unwrap();
        let store = d.path().join("s.btf");
        fs::create_dir(&store).unwrap();
        fs::write(
            store.join("zarr.json"),
            r#"{"zarr_format":3,"node_type":"group","attributes":{"btf":{}}}"#,
        )
        .unwrap();
        check_replaceable(&store, OutputKind::Store).unwrap();
        assert!(check_replaceable(&notes, PNG).is_err());
        check_replaceable(&notes, TEXT).unwrap();
        let png = d.path().join("a.png");
        fs::write(&png, b"\x89PNG\r\n\x1a\n....").unwrap();
        check_replaceable(&png, PNG).unwrap();
        assert!(check_replaceable(&png, EXR).is_err());
        check_replaceable(&d.path().join("missing"), OutputKind::Store).unwrap();
    }

    #[test]
    fn sweeping_removes_only_temporaries() {
        let d = tempfile::tempdir().unwrap();
        fs::create_dir_all(d.path().join("c/0")).unwrap();
        fs::write(d.path().join("c/0/1"), "chunk").unwrap();
        fs::write(d.path().join("c/0/.1.tmp-4242"), "half").unwrap();
        fs::write(d.path().join(".zarr.json.tmp-7"), "half").unwrap();
        assert_eq!(sweep_temps(d.path()).unwrap(), 2);
        assert!(d.path().join("c/0/1").exists());
    }
}
