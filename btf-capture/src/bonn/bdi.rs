//! BDI payloads: the uncompressed BTF tensor, stored ABRDF by ABRDF (one texel's values for
//! all channels, lights and views, channel fastest, then light, then view) in chunks of
//! `scan_lines_per_chunk` texture rows, as half floats.
//!
//! Layout: signature `!BDIF06R2!`, metadata, sampling, `u32 width`, `u32 height`,
//! `u32 scan_lines_per_chunk`, `u8 compression` (0 full, 1 bzip2, 2 sparse), the texel mask
//! (`width × height` bytes, byte `x·height + y`, as the public reader indexes it),
//! rotation matrices, then the chunks, each `u32 byte_count` and its halves. Full files
//! store every texel, sparse ones only those whose mask byte is non-zero (in scan-line
//! order); missing texels decode as 0. bzip2 chunks are not supported.
//!
//! Since a texture needs one value from every ABRDF, import reads the file once per group of
//! views that fits the memory budget.

use super::bytes::ByteReader;
use super::header::Payload;
use super::header::{Header, read_meta, read_rotations, read_sampling, read_side, read_signature};
use crate::{Error, Result};
use half::f16;
use std::io::{Read, Seek};

/// A BDI file with its chunk index.
#[derive(Debug)]
pub struct BdiReader<R> {
    /// The header.
    pub header: Header,
    /// Texture rows per chunk.
    pub scan_lines_per_chunk: usize,
    /// Compression byte (0 full, 2 sparse).
    pub compression: u8,
    /// Logical texel (`x + w·y`) of each stored ABRDF, in storage order.
    pub stored: Vec<usize>,
    /// File offset of each chunk's data and its byte count.
    pub chunks: Vec<(u64, u64)>,
    r: ByteReader<R>,
}

impl<R: Read + Seek> BdiReader<R> {
    /// Reads the header and indexes the chunks (each chunk's size is checked).
    pub fn new(mut r: ByteReader<R>) -> Result<Self> {
        let signature = read_signature(&mut r)?;
        if signature.payload != Payload::Bdi {
            return Err(
                r.invalid("signature", format!("{} is not a BDI signature", signature.text))
            );
        }
        let meta = read_meta(&mut r)?;
        let (views, lights) = read_sampling(&mut r)?;
        let width = read_side(&mut r, "width")?;
        let height = read_side(&mut r, "height")?;
        let lines = r.u32("scan_lines_per_chunk")? as usize;
        if lines == 0 || lines > height {
            return Err(
                r.invalid("scan_lines_per_chunk", format!("{lines} is not in 1..={height}"))
            );
        }
        let compression = if signature.extended { r.u8("compression")? } else { 1 };
        match compression {
            0 | 2 => {}
            1 => return Err(Error::unsupported(r.file(), "bzip2-compressed BDI chunks")),
            c => return Err(r.invalid("compression", format!("{c} is not 0, 1 or 2"))),
        }
        let n = r.check_alloc((width * height) as u64, 1, "mask")?;
        let mask = r.bytes(n as u64, "mask")?;
        let rotations = if signature.rotations { read_rotations(&mut r)? } else { Vec::new() };
        let header = Header { signature, meta, views, lights, width, height, rotations };
        // Storage order is scan-line order (x fastest); the mask byte of (x, y) is x·h + y.
        let stored: Vec<usize> = (0..width * height)
            .filter(|&t| compression == 0 || mask[(t % width) * height + t / width] != 0)
            .collect();
        let abrdf_bytes = (header.channels() * header.views.len() * header.lights.len()) as u64 * 2;
        let per_chunk = (width * lines) as u64;
        let n_chunks = (stored.len() as u64).div_ceil(per_chunk);
        let mut chunks = Vec::with_capacity(r.check_alloc(n_chunks, 4, "chunk count")? / 4);
        for c in 0..n_chunks {
            let abrdfs = per_chunk.min(stored.len() as u64 - c * per_chunk);
            let size = r.u32("chunk.byte_count")? as u64;
            if size != abrdfs * abrdf_bytes {
                return Err(r.invalid(
                    "chunk.byte_count",
                    format!(
                        "chunk {c}: {size} bytes, {abrdfs} ABRDFs need {}",
                        abrdfs * abrdf_bytes
                    ),
                ));
            }
            chunks.push((r.pos(), size));
            r.skip(size, "chunk data")?;
        }
        Ok(BdiReader { header, scan_lines_per_chunk: lines, compression, stored, chunks, r })
    }

    /// Decodes all lights of the given views (file indices): per view, `nL × h·w·nC` values.
    pub fn read_views(&mut self, views: &[usize]) -> Result<Vec<Vec<f32>>> {
        let h = &self.header;
        let (nc, nl, nv) = (h.channels(), h.lights.len(), h.views.len());
        let image = h.width * h.height * nc;
        if let Some(&v) = views.iter().find(|&&v| v >= nv) {
            return Err(self.r.invalid("views", format!("view {v} requested, file has {nv}")));
        }
        let per_view = self.r.check_limit((nl * image) as u64, 4, "view buffer")? / 4;
        let mut out: Vec<Vec<f32>> = views.iter().map(|_| vec![0f32; per_view]).collect();
        let abrdf = nc * nl * nv;
        let per_chunk = h.width * self.scan_lines_per_chunk;
        let mut buf = Vec::new();
        for (ci, &(off, size)) in self.chunks.iter().enumerate() {
            self.r.seek_to(off, "chunk data")?;
            buf.resize(size as usize, 0);
            let bytes = self.r.bytes(size, "chunk data")?;
            buf.copy_from_slice(&bytes);
            for (a, vals) in buf.chunks_exact(abrdf * 2).enumerate() {
                let texel = self.stored[ci * per_chunk + a];
                for (slot, &v) in views.iter().enumerate() {
                    for l in 0..nl {
                        for c in 0..nc {
                            let k = 2 * (c + nc * (l + nl * v));
                            let x = f16::from_le_bytes([vals[k], vals[k + 1]]).to_f32();
                            if !x.is_finite() {
                                return Err(self.r.invalid(
                                    "chunk data",
                                    format!("non-finite value in chunk {ci}, texel {texel}"),
                                ));
                            }
                            out[slot][l * image + texel * nc + c] = x;
                        }
                    }
                }
            }
        }
        Ok(out)
    }
}
