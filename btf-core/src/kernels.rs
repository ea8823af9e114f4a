//! Dense kernels of the per-slot PCA ([S03 eq. 1], by the snapshot method): the
//! row-by-row dot products `A·Bᵀ` behind the Gram matrix `YYᵀ` and the cross products
//! `E·Yᵀ`, and the lift `Lᵀ·Y` that forms eigentextures, each on one block of columns held
//! in `f64` ([`Block`]) or `f32` ([`Block32`]), and the loads that fill those blocks.
//!
//! In `f64`, every product is of `f32` data widened exactly, so each single product is
//! exact and only the sums round; in `f32` (the Gram matrix of `f16` data, the `f16`
//! correction: `single.rs`, `panel.rs`) one lane sums each chunk of 64 columns and `f64`
//! the chunks. Each kernel has a path per instruction set ([`Isa`], chosen at run time or
//! forced by `BTF_SIMD`): AVX-512 intrinsics (`avx512.rs`); the portable lane model
//! (`lanes.rs`) with fused multiply-adds, compiled for AVX2 + FMA + F16C (`avx2.rs`, whose
//! loads, widening, rounding and `f32` panel tiles are intrinsics in the same arithmetic)
//! or for NEON; and the same lane model
//! without fusing, the scalar reference. The SIMD paths agree bit for bit, the scalar one
//! within the rounding of its unfused products; the tests check both. `f16` rows are
//! widened in the AVX-512 and AVX2 loads (`vcvtph2ps`), elsewhere by the `half` crate's
//! slice conversions. This and `gemm.rs` are the only modules allowed `unsafe`: the
//! raw-pointer loads of `std::arch`, and calls of functions compiled for a CPU feature,
//! behind bounds and the feature checked once per call.
#![allow(unsafe_code)]

use crate::simd::Isa;
use half::slice::HalfFloatSliceExt;

/// `f64` lanes of one AVX-512 register; block widths are padded to a multiple of it.
pub const LANES: usize = 8;
/// Rows of `B` per dot-product tile (and of `A`, unless `A` has few rows that 4 divides).
const TB: usize = 5;
/// Columns per dot-product sub-block: five rows of them fit the L1 cache.
const SUB_BLOCK: usize = 256;
/// Components per lift tile.
pub const LIFT_COMPONENTS: usize = 8;

/// An element type of stored normtextures that the block loads widen to `f64` exactly:
/// `f32`, or IEEE half precision (`half::f16`, converted with `vcvtph2ps` under AVX-512).
pub trait Texel: bytemuck::Pod + Send + Sync + 'static {
    /// True for `f16`.
    const HALF: bool;
    /// The value as `f32` (exact for both types).
    fn widen(self) -> f32;
}

impl Texel for f32 {
    const HALF: bool = false;
    #[inline(always)]
    fn widen(self) -> f32 {
        self
    }
}

impl Texel for half::f16 {
    const HALF: bool = true;
    #[inline(always)]
    fn widen(self) -> f32 {
        self.to_f32()
    }
}

/// Rows of `f64` values over one block of columns: row `i` is `data[i·stride..][..stride]`,
/// the columns past the block's width and the rows past `rows` (at least [`Block::PAD_ROWS`]
/// of them) are zero so that whole tiles can be read.
#[derive(Debug, Default, Clone)]
pub struct Block {
    /// The values, row-major.
    pub data: Vec<f64>,
    /// Rows in use.
    pub rows: usize,
    /// Columns per row (a multiple of [`LANES`]).
    pub stride: usize,
}

impl Block {
    /// Zero rows kept after the last one.
    pub const PAD_ROWS: usize = TB;

    /// Reshapes to `rows × width` (width rounded up to [`LANES`]). Contents are zeroed only
    /// when the shape changes: a caller that rewrites the first `width` columns of every
    /// row keeps the padding zero.
    pub fn shape(&mut self, rows: usize, width: usize) {
        let stride = padded_stride(width.div_ceil(LANES) * LANES, LANES);
        if rows != self.rows || stride != self.stride || !width.is_multiple_of(LANES) {
            self.rows = rows;
            self.stride = stride;
            self.data.clear();
            self.data.resize((rows + Self::PAD_ROWS) * stride, 0.0);
        }
    }

    /// Row `i` (all `stride` columns).
    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.data[i * self.stride..(i + 1) * self.stride]
    }
}

/// A value type of the blocks the loads fill: `f64` (exact differences) or `f32` (the
/// differences rounded to nearest, for the single-precision Gram matrix of `f16` data).
pub trait Lane: Copy + Default + Send + Sync + 'static {
    /// True for `f64`.
    const WIDE: bool;
    /// `y` as a lane value (exact for `f64`, rounded to nearest for `f32`).
    fn of(y: f64) -> Self;
}

impl Lane for f64 {
    const WIDE: bool = true;
    #[inline(always)]
    fn of(y: f64) -> Self {
        y
    }
}

impl Lane for f32 {
    const WIDE: bool = false;
    #[inline(always)]
    fn of(y: f64) -> Self {
        y as f32
    }
}

/// A block the loads fill ([`Block`] in `f64`, [`Block32`] in `f32`).
pub trait LoadTarget {
    /// Its value type.
    type V: Lane;
    /// Rows in use.
    fn rows(&self) -> usize;
    /// Reshapes to `rows × width` (see [`Block::shape`]).
    fn shape(&mut self, rows: usize, width: usize);
    /// Row `i` (all its columns).
    fn row_mut(&mut self, i: usize) -> &mut [Self::V];
}

impl LoadTarget for Block {
    type V = f64;
    fn rows(&self) -> usize {
        self.rows
    }
    fn shape(&mut self, rows: usize, width: usize) {
        Block::shape(self, rows, width)
    }
    fn row_mut(&mut self, i: usize) -> &mut [f64] {
        Block::row_mut(self, i)
    }
}

impl LoadTarget for Block32 {
    type V = f32;
    fn rows(&self) -> usize {
        self.rows
    }
    fn shape(&mut self, rows: usize, width: usize) {
        Block32::shape(self, rows, width)
    }
    fn row_mut(&mut self, i: usize) -> &mut [f32] {
        Block32::row_mut(self, i)
    }
}

/// A row pitch of `stride` values, one vector (`lanes` values, 64 bytes) longer when
/// `stride` spans a whole number of 4 KB: rows exactly 4 KB apart all fall into the same
/// L1 cache sets, so the tiles' ten (the lift's 81) row streams would evict each other.
pub(crate) fn padded_stride(stride: usize, lanes: usize) -> usize {
    if stride > 0 && (stride * 64 / lanes).is_multiple_of(4096) { stride + lanes } else { stride }
}

/// `isa`, checked to be one this CPU runs (the x86 paths would otherwise be undefined
/// behaviour). The NEON path is the portable lane model with fused multiply-adds, which
/// computes the same bits on any CPU, so it is accepted everywhere: the tests run it on
/// x86-64 too (`BTF_SIMD=neon` is still refused there, by [`Isa::choose`]).
#[inline]
fn runnable(isa: Isa) -> Isa {
    assert!(isa.supported() || isa == Isa::Neon, "the {isa} kernels cannot run on this CPU");
    isa
}

/// `out[k·ldo + c0 + t] = Σ_i coef[i·cp + k]·y_i[t]` for `k < cp` (`cp` a multiple of
/// [`LIFT_COMPONENTS`]) and every column `t` of the block `y` of `f32` rows, each value
/// widened to `f64` exactly as it is loaded: the columns `c0..` of `Lᵀ·Y` for an `n × cp`
/// coefficient matrix `L`, summed in `f64`.
pub fn lift_rows32(y: &Block32, coef: &[f64], cp: usize, out: &mut [f64], ldo: usize, c0: usize) {
    lift_rows32_with(y, coef, cp, out, ldo, c0, Isa::active());
}

/// [`lift_rows32`] on the path `isa`.
pub(crate) fn lift_rows32_with(
    y: &Block32,
    coef: &[f64],
    cp: usize,
    out: &mut [f64],
    ldo: usize,
    c0: usize,
    isa: Isa,
) {
    let (n, w) = (y.rows, y.stride);
    assert!(cp.is_multiple_of(LIFT_COMPONENTS) && coef.len() >= n * cp);
    assert!(cp == 0 || out.len() >= (cp - 1) * ldo + c0 + w, "lift output too small");
    assert!(y.data.len() >= n * w && w.is_multiple_of(LANES));
    let all = (cp, 0, cp);
    match runnable(isa) {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => {
            let mut k0 = 0;
            while k0 < cp {
                let o = &mut out[k0 * ldo + c0..];
                // Sixteen components at once where there are: each widened vector feeds 16
                // FMAs.
                let step = if cp - k0 >= 2 * LIFT_COMPONENTS {
                    2 * LIFT_COMPONENTS
                } else {
                    LIFT_COMPONENTS
                };
                // SAFETY: AVX-512F checked (`runnable`); y holds n rows of w values, coef
                // n·cp (`step` components from k0), and out `step` rows of ldo values from
                // c0 with w ≤ ldo − c0 (asserted).
                unsafe {
                    let (yp, cf, op) = (y.data.as_ptr(), coef.as_ptr().add(k0), o.as_mut_ptr());
                    if step == 2 * LIFT_COMPONENTS {
                        avx512::lift32::<{ 2 * LIFT_COMPONENTS }>(yp, n, w, cf, cp, op, ldo)
                    } else {
                        avx512::lift32::<LIFT_COMPONENTS>(yp, n, w, cf, cp, op, ldo)
                    }
                };
                k0 += step;
            }
        }
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX2, FMA and F16C checked (`runnable`); the kernel is safe code.
        Isa::Avx2 => unsafe { avx2::lift(&y.data, n, w, coef, all, &mut out[c0..], ldo) },
        Isa::Scalar => lanes::lift::<false>(&y.data, n, w, coef, all, &mut out[c0..], ldo),
        _ => lanes::lift::<true>(&y.data, n, w, coef, all, &mut out[c0..], ldo),
    }
}

/// Asks the cache to fetch columns `c0..c0 + w` of every row ahead of their use. Each row's
/// piece of a block is its own page (1024 `f32`), where the hardware prefetcher stops, so
/// without this every block of a pass starts with one cache miss per row and line.
pub fn prefetch_rows<T: Texel>(x: &[&[T]], c0: usize, w: usize) {
    #[cfg(target_arch = "x86_64")]
    for row in x {
        let Some(piece) = row.get(c0..(c0 + w).min(row.len())) else { continue };
        for line in piece.chunks(64 / size_of::<T>()) {
            // SAFETY: a prefetch never faults and reads nothing into registers; the pointer
            // lies inside the row in any case.
            unsafe {
                std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T1 }>(
                    line.as_ptr().cast(),
                )
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, c0, w);
}

/// `to[t] = from[t]` widened to `f32` (exact): a copy, or the `half` crate's conversion.
#[inline(always)]
fn widen_portable<T: Texel>(from: &[T], to: &mut [f32]) {
    let n = from.len().min(to.len());
    if T::HALF {
        let halves: &[half::f16] = bytemuck::cast_slice(&from[..n]);
        halves.convert_to_f32_slice(&mut to[..n]);
    } else {
        to[..n].copy_from_slice(bytemuck::cast_slice(&from[..n]));
    }
}

/// What [`load_shifted`] saw of the input, when asked for statistics.
#[derive(Debug, Clone, Copy)]
pub struct LoadStats {
    /// `Σ x²` of the (unshifted) input values, in `f64`.
    pub energy: f64,
    /// Largest input value.
    pub peak: f32,
    /// All values finite.
    pub finite: bool,
}

/// Loads columns `c0..c0 + w` of the rows `x[i]` into `blk` as `y_i = x_i − s`
/// (`s = shift[c0..c0 + w]`, or zero): exactly into a [`Block`] (the difference of two `f32`
/// values is an `f64`), rounded to nearest into a [`Block32`]. With `colsum` (`w` values),
/// adds the exact `Σ_i y_i` per column into it (in `f64`, whatever the block holds) and
/// returns the input's statistics; both are the same bits for either block.
pub fn load_shifted<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut B,
    colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    load_shifted_with(x, c0, w, shift, blk, colsum, Isa::active())
}

/// [`load_shifted`] on the path `isa`.
pub(crate) fn load_shifted_with<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut B,
    colsum: Option<&mut [f64]>,
    isa: Isa,
) -> Option<LoadStats> {
    assert!(x.iter().all(|r| c0 + w <= r.len()), "block outside the rows");
    assert!(shift.is_none_or(|s| s.len() >= c0 + w), "shift row too short");
    assert!(colsum.as_ref().is_none_or(|c| c.len() >= w), "column sums too short");
    blk.shape(x.len(), w);
    match runnable(isa) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX-512F checked (`runnable`); the function itself is safe code.
        Isa::Avx512 => unsafe { avx512::load_shifted(x, c0, w, shift, blk, colsum) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX2, FMA and F16C checked (`runnable`); the function is safe code.
        Isa::Avx2 => unsafe { avx2::load_shifted(x, c0, w, shift, blk, colsum) },
        _ => load_shifted_body(x, c0, w, shift, blk, colsum),
    }
}

/// Columns widened to `f32` at a time for the portable loads.
const PIECE: usize = 256;

/// `src` as `f32` values: itself, or (for `f16`) widened into `buf` by the `half` crate's
/// slice conversion (F16C or the ARM half-precision instructions where the CPU has them).
#[inline(always)]
fn as_f32<'a, T: Texel>(src: &'a [T], buf: &'a mut [f32]) -> &'a [f32] {
    if T::HALF {
        let halves: &[half::f16] = bytemuck::cast_slice(src);
        let buf = &mut buf[..src.len()];
        halves.convert_to_f32_slice(buf);
        buf
    } else {
        bytemuck::cast_slice(src)
    }
}

/// The portable load (the scalar, AVX2 and NEON paths), in the AVX-512 load's lanes: the
/// energy of column `t` of a group of sixteen goes to lane `t mod 8`, the last `w mod 16`
/// columns are added after the lanes are reduced ([`lanes::reduce8`]), so every path
/// computes the same statistics bit for bit (the squares of `f32` values are exact in
/// `f64`, fused or not).
#[inline(always)]
fn load_shifted_body<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut B,
    mut colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    let body = w - w % 16;
    let (mut vb, mut hb) = ([0f32; PIECE], [0f32; PIECE]);
    let mut e = [0f64; LANES];
    let mut p = [f32::MIN; LANES];
    let mut bad = [0f32; LANES];
    let stats = colsum.is_some() && shift.is_some();
    for i in 0..blk.rows() {
        let dst = &mut blk.row_mut(i)[..w];
        let upto = if stats { body } else { w };
        for p0 in (0..upto).step_by(PIECE) {
            let p1 = (p0 + PIECE).min(upto);
            let src = as_f32(&x[i][c0 + p0..c0 + p1], &mut vb);
            let d = &mut dst[p0..p1];
            match (&mut colsum, shift) {
                (Some(cs), Some(s)) => {
                    let sh = as_f32(&s[c0 + p0..c0 + p1], &mut hb);
                    let cs = &mut cs[p0..p1];
                    for (((s16, h16), d16), c16) in src
                        .chunks_exact(16)
                        .zip(sh.chunks_exact(16))
                        .zip(d.chunks_exact_mut(16))
                        .zip(cs.chunks_exact_mut(16))
                    {
                        for l in 0..16 {
                            let v = s16[l];
                            let y = v as f64 - h16[l] as f64;
                            d16[l] = B::V::of(y);
                            c16[l] += y;
                            e[l % 8] += (v as f64) * (v as f64);
                            p[l % 8] = p[l % 8].max(v);
                            bad[l % 8] += v * 0.0; // NaN for NaN or ±∞, 0 otherwise
                        }
                    }
                }
                (_, Some(s)) => {
                    let sh = as_f32(&s[c0 + p0..c0 + p1], &mut hb);
                    for ((d, &v), &h) in d.iter_mut().zip(src).zip(sh) {
                        *d = B::V::of(v as f64 - h as f64);
                    }
                }
                (_, None) => {
                    for (d, &v) in d.iter_mut().zip(src) {
                        *d = B::V::of(v as f64);
                    }
                }
            }
        }
    }
    let (Some(cs), Some(sh)) = (colsum, shift) else { return None };
    let st = LoadStats {
        energy: lanes::reduce8(e),
        peak: p.iter().copied().fold(f32::MIN, f32::max),
        finite: bad.iter().all(|b| *b == 0.0),
    };
    Some(load_tail(x, c0, (body, w), &sh[c0..c0 + w], blk, cs, st))
}

/// `dst[t] = src[t] − sh[t]` (or `src[t]`), exactly in `f64` then as a lane value: the
/// columns after the vector body of the AVX2 and AVX-512 loads without statistics.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn plain_tail<T: Texel, V: Lane>(src: &[T], sh: Option<&[T]>, dst: &mut [V]) {
    for (t, d) in dst.iter_mut().enumerate() {
        *d = V::of(src[t].widen() as f64 - sh.map_or(0.0, |s| s[t].widen() as f64));
    }
}

/// The last columns `body..w` of a load with statistics, one by one after the lanes are
/// reduced into `st` (every path's rule): `sh` and `cs` start at column `c0`.
#[inline(always)]
fn load_tail<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    (body, w): (usize, usize),
    sh: &[T],
    blk: &mut B,
    cs: &mut [f64],
    mut st: LoadStats,
) -> LoadStats {
    for i in 0..blk.rows() {
        let dst = blk.row_mut(i);
        for t in body..w {
            let v = x[i][c0 + t].widen();
            let y = v as f64 - sh[t].widen() as f64;
            dst[t] = B::V::of(y);
            cs[t] += y;
            st.energy += (v as f64) * (v as f64);
            st.peak = st.peak.max(v);
            st.finite &= v.is_finite();
        }
    }
    st
}

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod dot;
mod f16_round;
mod lanes;
mod panel;
mod single;
pub use dot::DotAcc;
pub use f16_round::round_to_f16;
pub(crate) use f16_round::round_to_f16_with;
pub use single::{Block32, CHUNK32, CrossAcc32, GramAcc32, LANES32};

#[cfg(test)]
mod tests;
