//! Dense `f64` kernels of the per-slot PCA (Sattler et al. 2003, eq. 1, by the snapshot
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
/// Rows of `A` per dot-product tile.
const TA: usize = 4;
/// Rows of `B` per dot-product tile.
const TB: usize = 5;
/// Components per lift tile.
pub const LIFT_COMPONENTS: usize = 8;

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
        let stride = width.div_ceil(LANES) * LANES;
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

/// `out[i·ldo + j] += Σ_t a_i[t]·b_j[t]` for every row `i` of `a` and `j` of `b`; with
/// `upper`, only for `j ≥ i` (a symmetric product's upper triangle; `a` and `b` the same).
pub fn dot_rows(a: &Block, b: &Block, upper: bool, out: &mut [f64], ldo: usize) {
    dot_rows_with(a, b, upper, out, ldo, has_avx512());
}

/// [`dot_rows`] with the kernel chosen by the caller (`simd` only where AVX-512 exists).
pub(crate) fn dot_rows_with(
    a: &Block,
    b: &Block,
    upper: bool,
    out: &mut [f64],
    ldo: usize,
    simd: bool,
) {
    assert_eq!(a.stride, b.stride, "blocks of different widths");
    let w = a.stride;
    assert!(a.data.len() >= (a.rows.div_ceil(TA) * TA) * w, "block a lacks padding rows");
    assert!(b.data.len() >= (b.rows.div_ceil(TB) * TB) * w, "block b lacks padding rows");
    assert!(a.rows == 0 || out.len() >= (a.rows - 1) * ldo + b.rows, "output too small");
    assert!(ldo >= b.rows, "output row stride smaller than b's rows");
    let simd = simd && has_avx512();
    for i0 in (0..a.rows).step_by(TA) {
        let j_start = if upper { i0 } else { 0 };
        for j0 in (j_start..b.rows).step_by(TB) {
            let ta = &a.data[i0 * w..(i0 + TA) * w];
            let tb = &b.data[j0 * w..(j0 + TB) * w];
            let t = if simd { tile_simd(ta, tb, w) } else { tile_portable(ta, tb, w) };
            for r in 0..TA {
                for s in 0..TB {
                    let (i, j) = (i0 + r, j0 + s);
                    if i < a.rows && j < b.rows && (!upper || j >= i) {
                        out[i * ldo + j] += t[r][s];
                    }
                }
            }
        }
    }
}

/// Dot products of the `TA` rows of `a` with the `TB` rows of `b` (rows `w` apart).
fn tile_portable(a: &[f64], b: &[f64], w: usize) -> [[f64; TB]; TA] {
    let mut acc = [[[0f64; LANES]; TB]; TA];
    for k in (0..w).step_by(LANES) {
        for r in 0..TA {
            let ar = &a[r * w + k..r * w + k + LANES];
            for s in 0..TB {
                let bs = &b[s * w + k..s * w + k + LANES];
                for l in 0..LANES {
                    acc[r][s][l] += ar[l] * bs[l];
                }
            }
        }
    }
    acc.map(|row| row.map(|v| v.iter().sum()))
}

fn tile_simd(a: &[f64], b: &[f64], w: usize) -> [[f64; TB]; TA] {
    assert!(a.len() >= TA * w && b.len() >= TB * w && w.is_multiple_of(LANES));
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: the caller checked AVX-512F at run time; the slices hold TA and TB rows of
        // w values and w is a multiple of 8, so every 8-wide load lies inside them.
        unsafe { avx512::tile(a.as_ptr(), b.as_ptr(), w) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        tile_portable(a, b, w)
    }
}

/// `out[k·ldo + c0 + t] = Σ_i coef[i·cp + k]·y_i[t]` for `k < cp` (`cp` a multiple of
/// [`LIFT_COMPONENTS`]) and every column `t` of the block `y`: the columns `c0..` of
/// `Lᵀ·Y` for an `n × cp` coefficient matrix `L`.
pub fn lift_rows(y: &Block, coef: &[f64], cp: usize, out: &mut [f64], ldo: usize, c0: usize) {
    lift_rows_with(y, coef, cp, out, ldo, c0, has_avx512());
}

/// [`lift_rows`] with the kernel chosen by the caller.
pub(crate) fn lift_rows_with(
    y: &Block,
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
    assert!(y.data.len() >= n * w);
    let simd = simd && has_avx512();
    for k0 in (0..cp).step_by(LIFT_COMPONENTS) {
        let o = &mut out[k0 * ldo + c0..];
        if simd {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX-512F checked at run time; y holds n rows of w values, coef n·cp,
            // and out LIFT_COMPONENTS rows of ldo values from c0 with w ≤ ldo − c0 (asserted).
            unsafe {
                avx512::lift(y.data.as_ptr(), n, w, coef.as_ptr().add(k0), cp, o.as_mut_ptr(), ldo)
            };
        } else {
            for t in (0..w).step_by(LANES) {
                let mut acc = [[0f64; LANES]; LIFT_COMPONENTS];
                for i in 0..n {
                    let yi = &y.data[i * w + t..i * w + t + LANES];
                    for (k, a) in acc.iter_mut().enumerate() {
                        let c = coef[i * cp + k0 + k];
                        for l in 0..LANES {
                            a[l] += c * yi[l];
                        }
                    }
                }
                for (k, a) in acc.iter().enumerate() {
                    o[k * ldo + t..k * ldo + t + LANES].copy_from_slice(a);
                }
            }
        }
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

/// Loads columns `c0..c0 + w` of the `rows` rows of the row-major `f32` matrix `x` (rows of
/// `m` values) into `blk` as `y_i = x_i − s` in `f64` (`s = shift[c0..c0 + w]`, or zero),
/// exactly: the difference of two `f32` values is an `f64`. With `colsum` (`w` values),
/// adds `Σ_i y_i` per column into it and returns the input's statistics.
pub fn load_shifted(
    x: &[f32],
    rows: usize,
    m: usize,
    c0: usize,
    w: usize,
    shift: Option<&[f32]>,
    blk: &mut Block,
    colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    load_shifted_with(x, rows, m, c0, w, shift, blk, colsum, has_avx512())
}

/// [`load_shifted`] with the kernel chosen by the caller.
pub(crate) fn load_shifted_with(
    x: &[f32],
    rows: usize,
    m: usize,
    c0: usize,
    w: usize,
    shift: Option<&[f32]>,
    blk: &mut Block,
    colsum: Option<&mut [f64]>,
    simd: bool,
) -> Option<LoadStats> {
    assert!(c0 + w <= m && x.len() >= rows * m, "block outside the matrix");
    assert!(shift.is_none_or(|s| s.len() >= c0 + w), "shift row too short");
    assert!(colsum.as_ref().is_none_or(|c| c.len() >= w), "column sums too short");
    blk.shape(rows, w);
    if simd && has_avx512() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX-512F was detected at run time; the function itself is safe code.
        return unsafe { avx512::load_shifted(x, m, c0, w, shift, blk, colsum) };
    }
    load_shifted_body(x, m, c0, w, shift, blk, colsum)
}

#[inline(always)]
fn load_shifted_body(
    x: &[f32],
    m: usize,
    c0: usize,
    w: usize,
    shift: Option<&[f32]>,
    blk: &mut Block,
    mut colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    let zeros = [0f32; 0];
    let mut e = [0f64; LANES];
    let mut p = [f32::MIN; LANES];
    let mut bad = [0f32; LANES];
    for i in 0..blk.rows {
        let src = &x[i * m + c0..i * m + c0 + w];
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
                        let v = s8[l];
                        let y = v as f64 - h8[l] as f64;
                        d8[l] = y;
                        c8[l] += y;
                        e[l] += (v as f64) * (v as f64);
                        p[l] = p[l].max(v);
                        bad[l] += v * 0.0; // NaN for NaN or ±∞, 0 otherwise
                    }
                }
                let tail = w - w % LANES;
                for t in tail..w {
                    let v = src[t];
                    let y = v as f64 - sh[t] as f64;
                    dst[t] = y;
                    cs[t] += y;
                    e[0] += (v as f64) * (v as f64);
                    p[0] = p[0].max(v);
                    bad[0] += v * 0.0;
                }
            }
            (_, Some(_)) => {
                for ((d, &v), &h) in dst.iter_mut().zip(src).zip(sh) {
                    *d = v as f64 - h as f64;
                }
            }
            (_, None) => {
                for (d, &v) in dst.iter_mut().zip(src) {
                    *d = v as f64;
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
mod avx512 {
    use super::{LANES, LIFT_COMPONENTS, TA, TB};
    use std::arch::x86_64::*;

    /// `load_shifted_body` compiled with AVX-512 (safe code; callers check the feature),
    /// the statistics of whole 16-value groups by hand (the vectoriser leaves the
    /// NaN-aware maximum and the energy sum scalar).
    #[target_feature(enable = "avx512f")]
    pub(super) fn load_shifted(
        x: &[f32],
        m: usize,
        c0: usize,
        w: usize,
        shift: Option<&[f32]>,
        blk: &mut super::Block,
        colsum: Option<&mut [f64]>,
    ) -> Option<super::LoadStats> {
        let (Some(cs), Some(sh)) = (colsum, shift) else {
            return super::load_shifted_body(x, m, c0, w, shift, blk, None);
        };
        let body = w - w % 16;
        let mut e = _mm512_setzero_pd();
        let mut p = _mm512_set1_ps(f32::MIN);
        let mut bad = _mm512_setzero_ps();
        let zero = _mm512_setzero_ps();
        let sh = &sh[c0..c0 + w];
        let cs = &mut cs[..w];
        for i in 0..blk.rows {
            let src = &x[i * m + c0..i * m + c0 + w];
            let dst = &mut blk.row_mut(i)[..w];
            for t in (0..body).step_by(16) {
                // SAFETY: t + 16 ≤ body ≤ w, the length of src, sh, dst and cs.
                unsafe {
                    let v = _mm512_loadu_ps(src.as_ptr().add(t));
                    let h = _mm512_loadu_ps(sh.as_ptr().add(t));
                    p = _mm512_max_ps(p, v);
                    bad = _mm512_fmadd_ps(v, zero, bad); // NaN for NaN or ±∞
                    let vlo = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
                    let vhi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(
                        _mm512_castps_pd(v),
                        1,
                    )));
                    let hlo = _mm512_cvtps_pd(_mm512_castps512_ps256(h));
                    let hhi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(
                        _mm512_castps_pd(h),
                        1,
                    )));
                    e = _mm512_fmadd_pd(vlo, vlo, e);
                    e = _mm512_fmadd_pd(vhi, vhi, e);
                    let (ylo, yhi) = (_mm512_sub_pd(vlo, hlo), _mm512_sub_pd(vhi, hhi));
                    _mm512_storeu_pd(dst.as_mut_ptr().add(t), ylo);
                    _mm512_storeu_pd(dst.as_mut_ptr().add(t + 8), yhi);
                    let c = cs.as_mut_ptr().add(t);
                    _mm512_storeu_pd(c, _mm512_add_pd(_mm512_loadu_pd(c), ylo));
                    _mm512_storeu_pd(c.add(8), _mm512_add_pd(_mm512_loadu_pd(c.add(8)), yhi));
                }
            }
        }
        let mut rest = super::LoadStats {
            energy: _mm512_reduce_add_pd(e),
            peak: _mm512_reduce_max_ps(p),
            finite: _mm512_reduce_add_ps(bad) == 0.0,
        };
        // The last w mod 16 columns, one by one.
        for i in 0..blk.rows {
            let src = &x[i * m + c0..i * m + c0 + w];
            let dst = blk.row_mut(i);
            for t in body..w {
                let v = src[t];
                let y = v as f64 - sh[t] as f64;
                dst[t] = y;
                cs[t] += y;
                rest.energy += (v as f64) * (v as f64);
                rest.peak = rest.peak.max(v);
                rest.finite &= v.is_finite();
            }
        }
        Some(rest)
    }

    /// See `tile_portable`. Safety: AVX-512F present, `a` and `b` valid for `TA·w` and
    /// `TB·w` reads, `w` a multiple of 8.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn tile(a: *const f64, b: *const f64, w: usize) -> [[f64; TB]; TA] {
        let mut acc = [[_mm512_setzero_pd(); TB]; TA];
        let mut k = 0;
        while k < w {
            // SAFETY: k + 8 ≤ w, rows r < TA / s < TB lie inside the caller's extents.
            unsafe {
                let a0 = _mm512_loadu_pd(a.add(k));
                let a1 = _mm512_loadu_pd(a.add(w + k));
                let a2 = _mm512_loadu_pd(a.add(2 * w + k));
                let a3 = _mm512_loadu_pd(a.add(3 * w + k));
                for s in 0..TB {
                    let bs = _mm512_loadu_pd(b.add(s * w + k));
                    acc[0][s] = _mm512_fmadd_pd(a0, bs, acc[0][s]);
                    acc[1][s] = _mm512_fmadd_pd(a1, bs, acc[1][s]);
                    acc[2][s] = _mm512_fmadd_pd(a2, bs, acc[2][s]);
                    acc[3][s] = _mm512_fmadd_pd(a3, bs, acc[3][s]);
                }
            }
            k += LANES;
        }
        let mut out = [[0f64; TB]; TA];
        for r in 0..TA {
            for s in 0..TB {
                out[r][s] = _mm512_reduce_add_pd(acc[r][s]);
            }
        }
        out
    }

    /// See `lift_rows_with`. Safety: AVX-512F present; `y` valid for `n·w` reads, `coef`
    /// for reads at `i·cp + k` (`i < n`, `k < 8`), `out` for writes at `k·ldo + t`
    /// (`k < 8`, `t < w`); `w` a multiple of 8.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn lift(
        y: *const f64,
        n: usize,
        w: usize,
        coef: *const f64,
        cp: usize,
        out: *mut f64,
        ldo: usize,
    ) {
        let vectors = w / LANES;
        let mut v = 0;
        // SAFETY (both loops): forwarded from the caller's contract.
        while v + 3 <= vectors {
            unsafe { lift_tile::<3>(y, n, w, v * LANES, coef, cp, out, ldo) };
            v += 3;
        }
        while v < vectors {
            unsafe { lift_tile::<1>(y, n, w, v * LANES, coef, cp, out, ldo) };
            v += 1;
        }
    }

    /// Eight components × `NV` vectors of columns from column `t`.
    #[target_feature(enable = "avx512f")]
    unsafe fn lift_tile<const NV: usize>(
        y: *const f64,
        n: usize,
        w: usize,
        t: usize,
        coef: *const f64,
        cp: usize,
        out: *mut f64,
        ldo: usize,
    ) {
        let mut acc = [[_mm512_setzero_pd(); NV]; LIFT_COMPONENTS];
        for i in 0..n {
            // SAFETY: i < n and t + 8·NV ≤ w, coefficient k < 8 of row i.
            unsafe {
                let mut yv = [_mm512_setzero_pd(); NV];
                for (q, v) in yv.iter_mut().enumerate() {
                    *v = _mm512_loadu_pd(y.add(i * w + t + q * LANES));
                }
                for (k, a) in acc.iter_mut().enumerate() {
                    let c = _mm512_set1_pd(*coef.add(i * cp + k));
                    for q in 0..NV {
                        a[q] = _mm512_fmadd_pd(c, yv[q], a[q]);
                    }
                }
            }
        }
        for (k, a) in acc.iter().enumerate() {
            for (q, v) in a.iter().enumerate() {
                // SAFETY: k < 8, t + 8·(q + 1) ≤ w.
                unsafe { _mm512_storeu_pd(out.add(k * ldo + t + q * LANES), *v) };
            }
        }
    }
}

#[cfg(test)]
mod tests;
