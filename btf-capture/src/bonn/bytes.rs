//! A bounds-checked little-endian reader for the Bonn binary formats, and the matching
//! writer helpers.
//!
//! Every read names the header field it reads. Before any allocation the claimed size is
//! checked against the bytes that remain in the file and against [`Limits`], so a header
//! that claims 4 GB in a 54-byte file is refused with an error naming the field instead of
//! allocating; overflowing size products are refused the same way. Scalars are checked to be
//! finite as they are read.

use crate::{Error, Result};
use half::f16;
use std::io::{Read, Seek, SeekFrom, Write};

/// Allocation limits applied while parsing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest single allocation, bytes.
    pub max_alloc_bytes: u64,
    /// Largest number of view or light directions.
    pub max_directions: usize,
    /// Largest texture side, texels.
    pub max_side: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_alloc_bytes: 2 << 30, max_directions: 100_000, max_side: 1 << 16 }
    }
}

/// Little-endian reader over a seekable source of known length.
#[derive(Debug)]
pub struct ByteReader<R> {
    inner: R,
    file: String,
    pos: u64,
    len: u64,
    /// Limits in force.
    pub limits: Limits,
}

impl<R: Read + Seek> ByteReader<R> {
    /// Wraps `inner`, whose total length is `len` bytes; `file` names it in errors.
    pub fn new(inner: R, len: u64, file: impl Into<String>, limits: Limits) -> Self {
        ByteReader { inner, file: file.into(), pos: 0, len, limits }
    }

    /// The name used in errors.
    pub fn file(&self) -> &str {
        &self.file
    }
    /// Current offset.
    pub fn pos(&self) -> u64 {
        self.pos
    }
    /// Bytes left.
    pub fn remaining(&self) -> u64 {
        self.len.saturating_sub(self.pos)
    }

    /// An [`Error::Invalid`] for this file.
    pub fn invalid(&self, field: &str, what: impl Into<String>) -> Error {
        Error::invalid(&self.file, field, what)
    }

    /// Fails unless `n` more bytes are present.
    pub fn need(&self, n: u64, field: &str) -> Result<()> {
        if n > self.remaining() {
            return Err(self.invalid(
                field,
                format!(
                    "truncated: needs {n} bytes at offset {} but only {} remain",
                    self.pos,
                    self.remaining()
                ),
            ));
        }
        Ok(())
    }

    /// Checks that `count` elements of `elem_bytes` each stay within the allocation limit
    /// (for buffers that are computed, not read).
    pub fn check_limit(&self, count: u64, elem_bytes: u64, field: &str) -> Result<usize> {
        let bytes = count.checked_mul(elem_bytes).ok_or_else(|| {
            Error::limit(&self.file, field, format!("{count} x {elem_bytes} bytes overflows"))
        })?;
        if bytes > self.limits.max_alloc_bytes {
            return Err(Error::limit(
                &self.file,
                field,
                format!("{bytes} bytes needed, limit {}", self.limits.max_alloc_bytes),
            ));
        }
        usize::try_from(bytes).map_err(|_| Error::limit(&self.file, field, "too large"))
    }

    /// Checks that `count` elements of `elem_bytes` each may be allocated and are present.
    pub fn check_alloc(&self, count: u64, elem_bytes: u64, field: &str) -> Result<usize> {
        let bytes = self.check_limit(count, elem_bytes, field)?;
        self.need(bytes as u64, field)?;
        Ok(bytes)
    }

    /// Reads exactly `n` bytes (checked first).
    pub fn bytes(&mut self, n: u64, field: &str) -> Result<Vec<u8>> {
        let n = self.check_alloc(n, 1, field)?;
        let mut buf = vec![0u8; n];
        self.fill(&mut buf, field)?;
        Ok(buf)
    }

    fn fill(&mut self, buf: &mut [u8], field: &str) -> Result<()> {
        self.need(buf.len() as u64, field)?;
        self.inner.read_exact(buf).map_err(|e| self.invalid(field, format!("read failed: {e}")))?;
        self.pos += buf.len() as u64;
        Ok(())
    }

    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N]> {
        let mut b = [0u8; N];
        self.fill(&mut b, field)?;
        Ok(b)
    }

    /// One byte.
    pub fn u8(&mut self, field: &str) -> Result<u8> {
        Ok(self.array::<1>(field)?[0])
    }
    /// A little-endian `u32`.
    pub fn u32(&mut self, field: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array(field)?))
    }
    /// A little-endian `i32`.
    pub fn i32(&mut self, field: &str) -> Result<i32> {
        Ok(i32::from_le_bytes(self.array(field)?))
    }
    /// A finite little-endian `f32`.
    pub fn f32(&mut self, field: &str) -> Result<f32> {
        let v = f32::from_le_bytes(self.array(field)?);
        if !v.is_finite() {
            return Err(self.invalid(field, format!("non-finite value {v}")));
        }
        Ok(v)
    }

    /// `n` scalars of `scalar_size` bytes (2 = half, 4 = f32, 8 = f64) as `f32`, finite.
    pub fn scalars(&mut self, n: u64, scalar_size: u8, field: &str) -> Result<Vec<f32>> {
        if !matches!(scalar_size, 2 | 4 | 8) {
            return Err(self.invalid(field, format!("scalar size {scalar_size} is not 2, 4 or 8")));
        }
        let s = scalar_size as usize;
        self.check_alloc(n, s as u64, field)?;
        // Out-of-range f64 values would become infinite in f32 and are refused below.
        let mut out = Vec::with_capacity(n as usize);
        let mut buf = vec![0u8; (64 << 10) / s * s];
        let mut left = n as usize * s;
        while left > 0 {
            let take = left.min(buf.len());
            self.fill(&mut buf[..take], field)?;
            for c in buf[..take].chunks_exact(s) {
                out.push(match s {
                    2 => f16::from_le_bytes([c[0], c[1]]).to_f32(),
                    4 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                    _ => f64::from_le_bytes(c.try_into().expect("8 bytes")) as f32,
                });
            }
            left -= take;
        }
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(self.invalid(field, format!("non-finite value at element {i}")));
        }
        Ok(out)
    }

    /// A fixed-length, NUL-padded text field.
    pub fn text(&mut self, n: u64, field: &str) -> Result<String> {
        let b = self.bytes(n, field)?;
        let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
        Ok(String::from_utf8_lossy(&b[..end]).into_owned())
    }

    /// Skips `n` bytes (checked).
    pub fn skip(&mut self, n: u64, field: &str) -> Result<()> {
        self.need(n, field)?;
        self.seek_to(self.pos + n, field)
    }

    /// Moves to absolute offset `pos` (within the file).
    pub fn seek_to(&mut self, pos: u64, field: &str) -> Result<()> {
        if pos > self.len {
            return Err(self.invalid(field, format!("offset {pos} is past the end ({})", self.len)));
        }
        self.inner
            .seek(SeekFrom::Start(pos))
            .map_err(|e| self.invalid(field, format!("seek failed: {e}")))?;
        self.pos = pos;
        Ok(())
    }
}

/// Writes a little-endian `u32`.
pub fn put_u32(w: &mut impl Write, v: u32) -> std::io::Result<()> {
    w.write_all(&v.to_le_bytes())
}
/// Writes a little-endian `i32`.
pub fn put_i32(w: &mut impl Write, v: i32) -> std::io::Result<()> {
    w.write_all(&v.to_le_bytes())
}
/// Writes little-endian `f32`s.
pub fn put_f32s(w: &mut impl Write, v: &[f32]) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(v.len() * 4);
    for x in v {
        buf.extend_from_slice(&x.to_le_bytes());
    }
    w.write_all(&buf)
}
/// Writes scalars with `scalar_size` bytes each (2 = half, 4 = f32, 8 = f64).
pub fn put_scalars(w: &mut impl Write, v: &[f32], scalar_size: u8) -> std::io::Result<()> {
    match scalar_size {
        2 => {
            w.write_all(&v.iter().flat_map(|x| f16::from_f32(*x).to_le_bytes()).collect::<Vec<_>>())
        }
        8 => w.write_all(&v.iter().flat_map(|x| (*x as f64).to_le_bytes()).collect::<Vec<_>>()),
        _ => put_f32s(w, v),
    }
}
/// Writes a fixed-length NUL-padded text field (truncated to `n` bytes).
pub fn put_text(w: &mut impl Write, s: &str, n: usize) -> std::io::Result<()> {
    let mut b = s.as_bytes().to_vec();
    b.resize(n, 0);
    w.write_all(&b)
}
