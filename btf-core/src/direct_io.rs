//! Atomic writes of large chunk files past the page cache (`O_DIRECT` on Linux), for an
//! output that nothing reads back soon: the eigentextures and means of a compressed store
//! ([S03 eq. 1], per view slot). A buffered write of a fresh file copies
//! every byte into newly allocated page-cache pages, which on a virtual machine costs more
//! CPU than the PCA's own Gram products (0.25–1 GB/s of a core, against 1.1 GB/s of a
//! direct write the disk performs on its own); a direct write hands the disk the bytes
//! from a page-aligned buffer instead and leaves the cores to the computation.
//!
//! Direct I/O needs an aligned buffer, length and file offset, so the page-aligned prefix
//! of the chunk goes that way and its remainder (the tail of the payload and the 4-byte
//! checksum) is appended through the page cache. A file system that refuses direct I/O
//! (tmpfs, some network file systems) makes [`write_atomic_direct`] report that nothing
//! was written, and the caller writes the ordinary way. Like [`crate::zarr::write_atomic`],
//! the file is written under a temporary name and renamed into place.

use crate::{Error, Result};
use std::path::Path;

/// Alignment of buffer, length and offset that direct I/O requires (a page covers every
/// block size in use).
const ALIGN: usize = 4096;

/// Writes `payload` followed by `trailer` to `path` (temp file + rename), the page-aligned
/// prefix of `payload` by direct I/O. `Ok(false)`: the file system refused direct I/O and
/// nothing was left behind; write the file the ordinary way.
pub fn write_atomic_direct(path: &Path, payload: &[u8], trailer: &[u8]) -> Result<bool> {
    #[cfg(any(target_os = "linux", target_os = "android"))]
    {
        linux::write(path, payload, trailer)
    }
    #[cfg(not(any(target_os = "linux", target_os = "android")))]
    {
        let _ = (path, payload, trailer);
        Ok(false)
    }
}

#[cfg(any(target_os = "linux", target_os = "android"))]
mod linux {
    use super::{ALIGN, Error, Path, Result};
    use std::cell::RefCell;
    use std::fs;
    use std::io::{ErrorKind, Write};
    use std::os::unix::fs::OpenOptionsExt;

    thread_local! {
        /// Per-thread staging buffer (reused, so its pages are faulted in once).
        static STAGING: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    }

    /// EINVAL is how Linux says "no direct I/O here" (or "misaligned", which we are not).
    fn refused(e: &std::io::Error) -> bool {
        e.kind() == ErrorKind::InvalidInput
    }

    pub(super) fn write(path: &Path, payload: &[u8], trailer: &[u8]) -> Result<bool> {
        let dir = path.parent().unwrap_or(Path::new("."));
        fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
        let tmp = crate::fs::temp_path(&dir.join(name));
        let aligned = payload.len() / ALIGN * ALIGN;
        let direct = rustix::fs::OFlags::DIRECT.bits() as i32;
        let opened = fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .custom_flags(direct)
            .open(&tmp);
        let mut file = match opened {
            Ok(f) => f,
            Err(e) if refused(&e) => {
                // Some kernels create the file before they refuse `O_DIRECT` (tmpfs before
                // 6.6): leave nothing behind.
                let _ = fs::remove_file(&tmp);
                return Ok(false);
            }
            Err(e) => return Err(Error::io(&tmp, e)),
        };
        let written = STAGING.with(|buf| {
            let mut buf = buf.borrow_mut();
            if buf.len() < aligned + ALIGN {
                buf.resize(aligned + ALIGN, 0);
            }
            let off = buf.as_ptr().align_offset(ALIGN);
            let stage = &mut buf[off..off + aligned];
            stage.copy_from_slice(&payload[..aligned]);
            file.write_all(stage)
        });
        drop(file);
        match written {
            Ok(()) => {}
            Err(e) => {
                let _ = fs::remove_file(&tmp);
                return if refused(&e) { Ok(false) } else { Err(Error::io(&tmp, e)) };
            }
        }
        let mut rest =
            fs::OpenOptions::new().append(true).open(&tmp).map_err(|e| Error::io(&tmp, e))?;
        rest.write_all(&payload[aligned..]).map_err(|e| Error::io(&tmp, e))?;
        rest.write_all(trailer).map_err(|e| Error::io(&tmp, e))?;
        drop(rest);
        fs::rename(&tmp, path).map_err(|e| Error::io(path, e))?;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direct_write_holds_the_bytes_or_declines_leaving_nothing() {
        // Payloads of an aligned length, an unaligned one and one shorter than a page, on
        // the temporary folder's file system and on tmpfs (which refuses O_DIRECT before
        // Linux 6.6) where there is one.
        let shm = Path::new("/dev/shm");
        let mut dirs = vec![tempfile::tempdir().unwrap()];
        if shm.is_dir() {
            dirs.extend(tempfile::tempdir_in(shm).ok());
        }
        for (dir, len) in
            dirs.iter().flat_map(|d| [3 * ALIGN, 2 * ALIGN + 777, 100].map(|l| (d, l)))
        {
            let payload: Vec<u8> = (0..len).map(|i| (i * 31 % 251) as u8).collect();
            let path = dir.path().join(format!("sub/c/{len}"));
            match write_atomic_direct(&path, &payload, &[1, 2, 3, 4]).unwrap() {
                true => {
                    let back = std::fs::read(&path).unwrap();
                    assert_eq!(back.len(), len + 4);
                    assert_eq!(&back[..len], &payload[..]);
                    assert_eq!(&back[len..], &[1, 2, 3, 4]);
                }
                false => assert!(!path.exists()),
            }
            // No temporary file is left beside the chunk either way.
            let names: Vec<_> = std::fs::read_dir(path.parent().unwrap())
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .filter(|n| n.starts_with('.'))
                .collect();
            assert!(names.is_empty(), "{names:?}");
        }
    }

    #[test]
    fn a_zarr_chunk_written_directly_reads_back_with_its_checksum() {
        use crate::zarr::{ArrayMeta, DType, Limits, ZarrArray, encode_f32};
        // 70 001 values: 280 004 bytes, above the 256 KiB threshold, with an unaligned tail.
        let dir = tempfile::tempdir().unwrap();
        let meta = ArrayMeta {
            compression: crate::zarr::Compression::None,
            ..ArrayMeta::new(vec![2, 70_001], vec![1, 70_001], DType::F32, &["a", "b"])
        };
        let a = ZarrArray::create(dir.path(), meta).unwrap().with_direct_writes();
        let values: Vec<f32> = (0..70_001).map(|i| (i as f32 * 0.37).sin()).collect();
        let raw = encode_f32(&values, DType::F32);
        a.write_chunk(&[1, 0], &raw).unwrap();
        let b = ZarrArray::open(dir.path(), &Limits::default()).unwrap();
        assert_eq!(b.read_chunk(&[1, 0]).unwrap(), raw);
    }
}
