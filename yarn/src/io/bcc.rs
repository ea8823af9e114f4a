//! BCC files (Cem Yuksel's binary curve collection; the yarn models of [W19] ship in it).
//!
//! Layout (DESIGN §2.6, little-endian): a 64-byte header — `"BCC"`, a byte-count byte
//! `0x44` (4-byte integers and floats), the curve type `"C0"` (uniform Catmull–Rom), the
//! dimension byte `3`, the up-dimension byte, `u64` curve count, `u64` total control-point
//! count, 40 bytes of free text — then per curve an `i32` point count (negative: a closed
//! loop) and `|count|·3` `f32` coordinates. SOURCES.md's layout misses the up-dimension
//! byte; cyCodeBase's struct has it without explaining it. We read it as the index of the
//! up axis [guess] and rotate y-up (`(x, y, z) → (x, −z, y)`) and x-up
//! (`(x, y, z) → (y, z, x)`) files into our z-up world; we write 2 (z).
//!
//! **Refusals.** Other curve types, byte counts or dimensions are [`Error::Unsupported`].
//! The header's counts are checked against the file size *before* anything is allocated
//! (the exrs habit: a header may claim 2⁶⁴ points in 64 bytes), and against
//! [`MAX_POINTS`]; a curve whose count is zero, larger than what remains, or too small for
//! its kind, a non-finite coordinate, and counts that do not add up to the header are
//! refused naming the curve (and point) index.
//!
//! **What BCC cannot hold.** Length coordinates (recomputed at rest on reading), colours,
//! params ids and normals (defaults). A periodic course (closed with a shift) is written as
//! an open curve with one wrapped control point before and two after its period, so that
//! its segments `P_0 … P_n` are exactly the periodic curve's one period.

use crate::curve::{YarnCurve, YarnSet};
use crate::vec3::{self, V3};
use crate::{Error, Result};
use std::io::Read;
use std::path::Path;

/// Most control points a BCC file may hold (2²⁸ ≈ 268 M, 3.2 GB of coordinates).
pub const MAX_POINTS: u64 = 1 << 28;
/// Header size in bytes.
pub const HEADER_BYTES: usize = 64;

/// A parsed BCC file.
#[derive(Debug, Clone, PartialEq)]
pub struct BccFile {
    /// The curves (z-up).
    pub set: YarnSet,
    /// The file's up-dimension byte.
    pub up_dimension: u8,
    /// The header's 40 bytes of text (up to the first NUL, lossy UTF-8).
    pub info: String,
}

struct Header {
    up: u8,
    curves: u64,
    points: u64,
    info: String,
}

fn parse_header(h: &[u8], len: u64, source: &str) -> Result<Header> {
    if h.len() < HEADER_BYTES {
        return Err(Error::Invalid(format!(
            "{source}: {} bytes, shorter than the 64-byte BCC header",
            h.len()
        )));
    }
    if &h[0..3] != b"BCC" {
        return Err(Error::Invalid(format!("{source}: not a BCC file (signature {:?})", &h[0..3])));
    }
    if h[3] != 0x44 {
        return Err(Error::Unsupported(format!(
            "{source}: BCC byte counts 0x{:02x} (only 0x44: 4-byte integers and floats)",
            h[3]
        )));
    }
    if &h[4..6] != b"C0" {
        return Err(Error::Unsupported(format!(
            "{source}: BCC curve type {:?} (only \"C0\", uniform Catmull-Rom)",
            String::from_utf8_lossy(&h[4..6])
        )));
    }
    if h[6] != 3 {
        return Err(Error::Unsupported(format!("{source}: BCC dimension {} (only 3)", h[6])));
    }
    if h[7] > 2 {
        return Err(Error::Unsupported(format!("{source}: BCC up dimension {} (0, 1 or 2)", h[7])));
    }
    let u64_at = |o: usize| u64::from_le_bytes(h[o..o + 8].try_into().expect("8 bytes"));
    let (curves, points) = (u64_at(8), u64_at(16));
    let end = h[24..64].iter().position(|&b| b == 0).unwrap_or(40);
    let info = String::from_utf8_lossy(&h[24..24 + end]).into_owned();
    if points > MAX_POINTS {
        return Err(Error::Limit(format!(
            "{source}: header claims {points} control points (at most {MAX_POINTS})"
        )));
    }
    let need = HEADER_BYTES as u128 + 4 * curves as u128 + 12 * points as u128;
    if need != len as u128 {
        let what = if need > len as u128 {
            "the file is truncated or the header's counts are too large"
        } else {
            "trailing bytes after the last curve"
        };
        return Err(Error::Invalid(format!(
            "{source}: header claims {curves} curves and {points} control points ({need} bytes), \
             but the file has {len} bytes: {what}"
        )));
    }
    if curves > points {
        return Err(Error::Invalid(format!(
            "{source}: {curves} curves for {points} control points (every curve needs points)"
        )));
    }
    Ok(Header { up: h[7], curves, points, info })
}

fn to_z_up(p: V3, up: u8) -> V3 {
    match up {
        0 => [p[1], p[2], p[0]],
        1 => [p[0], -p[2], p[1]],
        _ => p,
    }
}

/// Parses BCC bytes (`source` names the file in messages).
pub fn parse_bcc(bytes: &[u8], source: &str) -> Result<BccFile> {
    let h = parse_header(bytes, bytes.len() as u64, source)?;
    let mut off = HEADER_BYTES;
    let mut left = h.points;
    let mut curves = Vec::with_capacity(h.curves as usize);
    let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    for ci in 0..h.curves as usize {
        if off + 4 > bytes.len() {
            return Err(Error::Invalid(format!(
                "{source}: curve {ci}: file ends before its count"
            )));
        }
        let count = i32::from_le_bytes(bytes[off..off + 4].try_into().expect("4 bytes")) as i64;
        off += 4;
        let (n, closed) = (count.unsigned_abs(), count < 0);
        if n == 0 {
            return Err(Error::Invalid(format!("{source}: curve {ci}: 0 control points")));
        }
        if n > left {
            return Err(Error::Invalid(format!(
                "{source}: curve {ci}: {n} control points, but only {left} remain of the \
                 header's {}",
                h.points
            )));
        }
        left -= n;
        let mut pts = Vec::with_capacity(n as usize);
        for k in 0..n as usize {
            let o = off + 12 * k;
            let p = [f32_at(o), f32_at(o + 4), f32_at(o + 8)];
            if !p.iter().all(|v| v.is_finite()) {
                return Err(Error::Invalid(format!(
                    "{source}: curve {ci}, control point {k}: non-finite coordinate {p:?}"
                )));
            }
            pts.push(to_z_up(p.map(f64::from), h.up));
        }
        off += 12 * n as usize;
        let curve = if closed { YarnCurve::closed(pts) } else { YarnCurve::open(pts) };
        curves.push(curve.map_err(|e| match e {
            Error::Invalid(m) => Error::Invalid(format!("{source}: curve {ci}: {m}")),
            other => other,
        })?);
    }
    if left != 0 {
        return Err(Error::Invalid(format!(
            "{source}: the curves hold {} control points, the header claims {}",
            h.points - left,
            h.points
        )));
    }
    Ok(BccFile { set: YarnSet { curves, period: None }, up_dimension: h.up, info: h.info })
}

/// Reads a BCC file: the header is checked against the file's size before the body is
/// read or anything allocated.
pub fn read_bcc(path: &Path) -> Result<BccFile> {
    let source = path.display().to_string();
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = f.metadata().map_err(|e| Error::io(path, e))?.len();
    let mut head = vec![0u8; HEADER_BYTES.min(len as usize)];
    f.read_exact(&mut head).map_err(|e| Error::io(path, e))?;
    parse_header(&head, len, &source)?;
    let mut bytes = head;
    bytes.reserve_exact((len as usize).saturating_sub(HEADER_BYTES));
    f.read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    parse_bcc(&bytes, &source)
}

/// The control points a curve is written with (see the module documentation).
fn written_points(c: &YarnCurve) -> (Vec<V3>, bool) {
    if c.closed && c.shift != [0.0; 3] {
        let n = c.points.len() as isize;
        ((-1..=n + 1).map(|k| c.control_point(k)).collect(), false)
    } else {
        (c.points.clone(), c.closed)
    }
}

/// The BCC bytes of `set` (z-up, `info` truncated to 40 bytes).
pub fn bcc_bytes(set: &YarnSet, info: &str) -> Result<Vec<u8>> {
    set.validate()?;
    let curves: Vec<(Vec<V3>, bool)> = set.curves.iter().map(written_points).collect();
    let total: usize = curves.iter().map(|c| c.0.len()).sum();
    if total as u64 > MAX_POINTS || curves.iter().any(|c| c.0.len() > i32::MAX as usize) {
        return Err(Error::Limit(format!(
            "{total} control points exceed the BCC limit {MAX_POINTS}"
        )));
    }
    let mut out = Vec::with_capacity(HEADER_BYTES + 4 * curves.len() + 12 * total);
    out.extend_from_slice(b"BCC");
    out.extend_from_slice(&[0x44, b'C', b'0', 3, 2]);
    out.extend_from_slice(&(curves.len() as u64).to_le_bytes());
    out.extend_from_slice(&(total as u64).to_le_bytes());
    let mut text = [0u8; 40];
    let b = info.as_bytes();
    text[..b.len().min(40)].copy_from_slice(&b[..b.len().min(40)]);
    out.extend_from_slice(&text);
    for (ci, (pts, closed)) in curves.iter().enumerate() {
        let n = pts.len() as i32;
        out.extend_from_slice(&(if *closed { -n } else { n }).to_le_bytes());
        for (k, p) in pts.iter().enumerate() {
            let q = p.map(|v| v as f32);
            if !vec3::is_finite(q.map(f64::from)) {
                return Err(Error::Invalid(format!(
                    "curve {ci}, control point {k}: {p:?} does not fit in f32"
                )));
            }
            for v in q {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    Ok(out)
}

/// Writes `set` as a BCC file through the atomic writer.
pub fn write_bcc(path: &Path, set: &YarnSet, info: &str) -> Result<()> {
    let bytes = bcc_bytes(set, info)?;
    btf_core::fs::write_atomic(path, &bytes)?;
    Ok(())
}

#[cfg(test)]
mod tests;
