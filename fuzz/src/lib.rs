//! Helpers shared by the fuzz targets: a per-process scratch folder on a tmpfs
//! (`/dev/shm` where it exists) where the input bytes are written as the file a parser
//! opens, and the splitting of one input into several files.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A scratch folder private to this process, created once (on `/dev/shm` when present,
/// so that writing the input costs no disk I/O).
pub fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let base = Path::new("/dev/shm");
        let base = if base.is_dir() { base.to_owned() } else { std::env::temp_dir() };
        let dir = base.join(format!("btf-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        dir
    })
}

/// Writes `bytes` to `name` inside the scratch folder (creating parent folders) and
/// returns its path.
pub fn put(name: &str, bytes: &[u8]) -> PathBuf {
    let p = scratch().join(name);
    if let Some(d) = p.parent() {
        std::fs::create_dir_all(d).expect("scratch subfolder");
    }
    std::fs::write(&p, bytes).expect("scratch file");
    p
}

/// A fresh, empty folder `name` inside the scratch folder.
pub fn fresh_dir(name: &str) -> PathBuf {
    let p = scratch().join(name);
    let _ = std::fs::remove_dir_all(&p);
    std::fs::create_dir_all(&p).expect("scratch subfolder");
    p
}

/// The separator between the files of a multi-file input: `0xFF` never occurs in UTF-8
/// text, so JSON parts stay intact.
pub const SEP: u8 = 0xFF;

/// Splits `data` at every [`SEP`] into at most `n` parts (the last keeps any further
/// separators); missing parts are `None`.
pub fn parts(data: &[u8], n: usize) -> Vec<Option<&[u8]>> {
    let mut out: Vec<Option<&[u8]>> = data.splitn(n, |&b| b == SEP).map(Some).collect();
    out.resize(n, None);
    out
}
