//! Dense `f64` kernels of the per-slot PCA ([S03 eq. 1], by the snapshot
//! method): the row-by-row dot products `A·Bᵀ` behind the Gram matrix `YYᵀ` and the cross
//! products `E·Yᵀ`, and the lift `Lᵀ·Y` that forms eigentextures, each on one block of
//! columns held in `f64` ([`Block`]).
//!
//! Every product is of `f32` data widened to `f64`, so each single product is exact and only
//! the sums round. The AVX-512 versions are chosen at run time; the portable versions (the
//! same loops, left to the compiler's vectoriser) run elsewhere, and the tests check that
//! both agree. This and `gemm.rs` are the only modules allowed `unsafe`: the raw-pointer
//! loads of `std::arch`, behind bounds checked once per call.
#![allow(unsafe_code)]

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

/// A row pitch of `stride` values, one vector (`lanes` values, 64 bytes) longer when
/// `stride` spans a whole number of 4 KB: rows exactly 4 KB apart all fall into the same
/// L1 cache sets, so the tiles' ten (the lift's 81) row streams would evict each other.
pub(crate) fn padded_stride(stride: usize, lanes: usize) -> usize {
    if stride > 0 && (stride * 64 / lanes).is_multiple_of(4096) { stride + lanes } else { stride }
}

fn has_avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// `out[k·ldo + c0 + t] = Σ_i coef[i·cp + k]·y_i[t]` for `k < cp` (`cp` a multiple of
/// [`LIFT_COMPONENTS`]) and every column `t` of the block `y` of `f32` rows, each value
/// widened to `f64` exactly as it is loaded: the columns `c0..` of `Lᵀ·Y` for an `n × cp`
/// coefficient matrix `L`, summed in `f64`.
pub fn lift_rows32(y: &Block32, coef: &[f64], cp: usize, out: &mut [f64], ldo: usize, c0: usize) {
    lift_rows32_with(y, coef, cp, out, ldo, c0, has_avx512());
}

/// [`lift_rows32`] with the kernel chosen by the caller.
pub(crate) fn lift_rows32_with(
    y: &Block32,
    coef: &[f64],
    cp: usize,
    out: &mut [f64],
    ldo: usize,
    c0: usize,
    simd: bool,
) {
    let (n, w) = (y.rows, y.stride);
    assert!(cp.is_multiple_of(LIFT_COMPONENTS) && coef.len() >= n * cp);
    assert!(cp == 0 || out.len() >= (cp - 1) * ldo + c0 + w, "lift output too small");
    assert!(y.data.len() >= n * w && w.is_multiple_of(LANES));
    let simd = simd && has_avx512();
    let mut k0 = 0;
    while k0 < cp {
        let o = &mut out[k0 * ldo + c0..];
        // Sixteen components at once where there are: each widened vector feeds 16 FMAs.
        let step =
            if cp - k0 >= 2 * LIFT_COMPONENTS { 2 * LIFT_COMPONENTS } else { LIFT_COMPONENTS };
        if simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX-512F checked at run time; y holds n rows of w values, coef n·cp
            // (`step` components from k0), and out `step` rows of ldo values from c0 with
            // w ≤ ldo − c0 (asserted).
            unsafe {
                let (yp, cf, op) = (y.data.as_ptr(), coef.as_ptr().add(k0), o.as_mut_ptr());
                if step == 2 * LIFT_COMPONENTS {
                    avx512::lift32::<{ 2 * LIFT_COMPONENTS }>(yp, n, w, cf, cp, op, ldo)
                } else {
                    avx512::lift32::<LIFT_COMPONENTS>(yp, n, w, cf, cp, op, ldo)
                }
            };
        } else {
            for t in 0..w {
                for k in 0..step {
                    o[k * ldo + t] =
                        (0..n).map(|i| coef[i * cp + k0 + k] * y.data[i * w + t] as f64).sum();
                }
            }
        }
        k0 += step;
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

/// Loads columns `c0..c0 + w` of the rows `x[i]` into `blk` as `y_i = x_i − s` in `f64`
/// (`s = shift[c0..c0 + w]`, or zero), exactly: the difference of two `f32` values is an
/// `f64`. With `colsum` (`w` values), adds `Σ_i y_i` per column into it and returns the
/// input's statistics.
pub fn load_shifted<T: Texel>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut Block,
    colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    load_shifted_with(x, c0, w, shift, blk, colsum, has_avx512())
}

/// [`load_shifted`] with the kernel chosen by the caller.
pub(crate) fn load_shifted_with<T: Texel>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut Block,
    colsum: Option<&mut [f64]>,
    simd: bool,
) -> Option<LoadStats> {
    assert!(x.iter().all(|r| c0 + w <= r.len()), "block outside the rows");
    assert!(shift.is_none_or(|s| s.len() >= c0 + w), "shift row too short");
    assert!(colsum.as_ref().is_none_or(|c| c.len() >= w), "column sums too short");
    blk.shape(x.len(), w);
    if simd && has_avx512() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX-512F was detected at run time; the function itself is safe code.
        return unsafe { avx512::load_shifted(x, c0, w, shift, blk, colsum) };
    }
    load_shifted_body(x, c0, w, shift, blk, colsum)
}

#[inline(always)]
fn load_shifted_body<T: Texel>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut Block,
    mut colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    let zeros: [T; 0] = [];
    let mut e = [0f64; LANES];
    let mut p = [f32::MIN; LANES];
    let mut bad = [0f32; LANES];
    for i in 0..blk.rows {
        let src = &x[i][c0..c0 + w];
        let sh = shift.map_or(&zeros[..], |s| &s[c0..c0 + w]);
        let dst = &mut blk.row_mut(i)[..w];
        match (&mut colsum, shift) {
            (Some(cs), Some(_)) => {
                let cs = &mut cs[..w];
                for (((s8, h8), d8), c8) in src
                    .chunks_exact(LANES)
                    .zip(sh.chunks_exact(LANES))
                    .zip(dst.chunks_exact_mut(LANES))
                    .zip(cs.chunks_exact_mut(LANES))
                {
                    for l in 0..LANES {
                        let v = s8[l].widen();
                        let y = v as f64 - h8[l].widen() as f64;
                        d8[l] = y;
                        c8[l] += y;
                        e[l] += (v as f64) * (v as f64);
                        p[l] = p[l].max(v);
                        bad[l] += v * 0.0; // NaN for NaN or ±∞, 0 otherwise
                    }
                }
                let tail = w - w % LANES;
                for t in tail..w {
                    let v = src[t].widen();
                    let y = v as f64 - sh[t].widen() as f64;
                    dst[t] = y;
                    cs[t] += y;
                    e[0] += (v as f64) * (v as f64);
                    p[0] = p[0].max(v);
                    bad[0] += v * 0.0;
                }
            }
            (_, Some(_)) => {
                for ((d, &v), &h) in dst.iter_mut().zip(src).zip(sh) {
                    *d = v.widen() as f64 - h.widen() as f64;
                }
            }
            (_, None) => {
                for (d, &v) in dst.iter_mut().zip(src) {
                    *d = v.widen() as f64;
                }
            }
        }
    }
    colsum.map(|_| LoadStats {
        energy: e.iter().sum(),
        peak: p.iter().copied().fold(f32::MIN, f32::max),
        finite: bad.iter().all(|b| *b == 0.0),
    })
}

#[cfg(target_arch = "x86_64")]
mod avx512;
mod dot;
mod f16_round;
mod single;
pub use dot::DotAcc;
pub use f16_round::round_to_f16;
pub use single::{Block32, CrossAcc32, LANES32};

#[cfg(test)]
mod tests;
