//! Read-only memory maps of store chunks. The per-slot PCA ([S03 eq. 1])
//! streams every normtexture of a slot several times; mapping the chunk files lets it read
//! them straight from the page cache, without first copying 64 MB per slot (at 256²) into
//! a buffer, and lets the first pass check each chunk's CRC32C on the same cache lines it
//! feeds into the Gram matrix.
//!
//! This is the one module besides the dense kernels that needs `unsafe`: creating a map.
//! The store's own writers never modify a chunk in place (they write a temporary file and
//! rename it over the old name, so a mapped inode keeps its bytes), hence a map sees a
//! fixed file. A *foreign* program truncating a chunk while it is mapped would end the
//! process with SIGBUS; that is the documented price of the zero-copy read.
#![allow(unsafe_code)]

use crate::{Error, Result};
use std::fs;
use std::path::{Path, PathBuf};

/// One chunk file mapped read-only: its payload and its trailing CRC32C.
#[derive(Debug)]
pub struct MappedChunk {
    map: memmap2::Mmap,
    path: PathBuf,
}

impl MappedChunk {
    /// Maps `path`, which must hold exactly `expect` bytes (payload + 4-byte checksum).
    pub fn open(path: &Path, expect: u64) -> Result<Self> {
        let file = fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        if len != expect || len < 4 {
            return Err(Error::Corrupt {
                path: path.to_owned(),
                what: format!("chunk has {len} bytes, {expect} expected (truncated or foreign)"),
            });
        }
        // SAFETY: read-only map of a file whose length was just checked; the store's
        // writers replace chunks by rename and never write into an existing one (module
        // docs), so the mapped bytes do not change while the map lives.
        let map = unsafe { memmap2::MmapOptions::new().populate().map(&file) }
            .map_err(|e| Error::io(path, e))?;
        if map.len() as u64 != expect {
            return Err(Error::Corrupt {
                path: path.to_owned(),
                what: format!("chunk changed size while being mapped ({} bytes)", map.len()),
            });
        }
        Ok(MappedChunk { map, path: path.to_owned() })
    }

    /// The element bytes (without the checksum).
    pub fn payload(&self) -> &[u8] {
        &self.map[..self.map.len() - 4]
    }

    /// The CRC32C stored after the payload.
    pub fn stored_crc(&self) -> u32 {
        let n = self.map.len();
        u32::from_le_bytes([self.map[n - 4], self.map[n - 3], self.map[n - 2], self.map[n - 1]])
    }

    /// The chunk's file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The light images of one view slot, mapped: one chunk per light.
#[derive(Debug)]
pub struct MappedSlot {
    view: usize,
    chunks: Vec<MappedChunk>,
}

impl MappedSlot {
    /// Wraps the chunks of view slot `view`, light by light.
    pub fn new(view: usize, chunks: Vec<MappedChunk>) -> Self {
        MappedSlot { view, chunks }
    }

    /// Each light's payload as values of `T` (`f32` or `f16`; little-endian hosts, and a
    /// map is page-aligned).
    pub fn rows<T: bytemuck::Pod>(&self) -> Result<Vec<&[T]>> {
        self.chunks
            .iter()
            .map(|c| {
                bytemuck::try_cast_slice(c.payload()).map_err(|e| Error::Corrupt {
                    path: c.path().to_owned(),
                    what: format!(
                        "chunk payload is not a run of {} values ({e})",
                        std::any::type_name::<T>()
                    ),
                })
            })
            .collect()
    }

    /// Compares the checksums a pass over the payloads computed (`crcs[l]` for light `l`)
    /// with the stored ones; the first mismatch is reported with its file and light.
    pub fn verify(&self, crcs: &[u32]) -> Result<()> {
        for (l, (c, &crc)) in self.chunks.iter().zip(crcs).enumerate() {
            if c.stored_crc() != crc {
                return Err(Error::Corrupt {
                    path: c.path().to_owned(),
                    what: format!("view slot {}, light {l}: crc32c checksum mismatch", self.view),
                });
            }
        }
        Ok(())
    }
}
