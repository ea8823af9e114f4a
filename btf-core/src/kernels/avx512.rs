//! AVX-512 versions of the kernels in `kernels.rs` (the same sums, eight `f64` lanes per
//! register, fused multiply-adds: the lane model of `lanes.rs`, bit for bit); callers
//! check the CPU feature at run time.

use super::{LANES, Lane, LoadTarget, TB, Texel};
use std::arch::x86_64::*;

/// The eight lanes summed in the order every path uses ([`super::lanes::reduce8`]).
#[target_feature(enable = "avx512f")]
#[inline]
fn reduce8(v: __m512d) -> f64 {
    let mut s = [0f64; 8];
    // SAFETY: `s` holds eight values.
    unsafe { _mm512_storeu_pd(s.as_mut_ptr(), v) };
    super::lanes::reduce8(s)
}

/// 16 stored values from `p` as `f32` (`vcvtph2ps` for `f16`, exact). Safety: AVX-512F
/// present, `p` valid for 16 reads.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load16<T: Texel>(p: *const T) -> __m512 {
    // SAFETY: forwarded from the caller; 16 values of T are 32 or 64 bytes.
    unsafe {
        if T::HALF {
            _mm512_cvtph_ps(_mm256_loadu_si256(p.cast()))
        } else {
            _mm512_loadu_ps(p.cast())
        }
    }
}

/// The 16 `f32` lanes of `v` as two registers of `f64` (exact).
#[target_feature(enable = "avx512f")]
#[inline]
fn widen16(v: __m512) -> (__m512d, __m512d) {
    let lo = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
    let hi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(v), 1)));
    (lo, hi)
}

/// Stores the 16 values `lo` (first eight) and `hi` at `p`: as they are, or rounded to
/// nearest `f32` ([`Lane::of`]). Safety: AVX-512F present, `p` valid for 16 writes.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn store16<V: Lane>(p: *mut V, lo: __m512d, hi: __m512d) {
    // SAFETY: forwarded from the caller; V is f64 when WIDE, else f32.
    unsafe {
        if V::WIDE {
            _mm512_storeu_pd(p.cast(), lo);
            _mm512_storeu_pd(p.cast::<f64>().add(8), hi);
        } else {
            _mm256_storeu_ps(p.cast(), _mm512_cvtpd_ps(lo));
            _mm256_storeu_ps(p.cast::<f32>().add(8), _mm512_cvtpd_ps(hi));
        }
    }
}

/// `load_shifted_with` under AVX-512 (callers check the feature): whole 16-value groups
/// by hand (the vectoriser leaves the NaN-aware maximum, the energy sum and the `f16`
/// conversion scalar), the last `w mod 16` columns one by one.
#[target_feature(enable = "avx512f")]
pub(super) fn load_shifted<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut B,
    colsum: Option<&mut [f64]>,
) -> Option<super::LoadStats> {
    let sh = shift.map(|s| &s[c0..c0 + w]);
    match (colsum, sh) {
        (Some(cs), Some(sh)) => Some(load_with_stats(x, c0, w, sh, blk, &mut cs[..w])),
        (_, sh) => {
            load_plain(x, c0, w, sh, blk);
            None
        }
    }
}

/// `y_i = x_i − s` (or `x_i`) for the columns `c0..c0 + w` of every row.
#[target_feature(enable = "avx512f")]
fn load_plain<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    sh: Option<&[T]>,
    blk: &mut B,
) {
    let body = w - w % 16;
    for i in 0..blk.rows() {
        let src = &x[i][c0..c0 + w];
        let dst = &mut blk.row_mut(i)[..w];
        for t in (0..body).step_by(16) {
            // SAFETY: t + 16 ≤ body ≤ w, the length of src, sh and dst.
            unsafe {
                let (mut lo, mut hi) = widen16(load16(src.as_ptr().add(t)));
                if let Some(sh) = sh {
                    let (hlo, hhi) = widen16(load16(sh.as_ptr().add(t)));
                    (lo, hi) = (_mm512_sub_pd(lo, hlo), _mm512_sub_pd(hi, hhi));
                }
                store16(dst.as_mut_ptr().add(t), lo, hi);
            }
        }
        super::plain_tail(&src[body..], sh.map(|s| &s[body..]), &mut dst[body..]);
    }
}

/// `y_i = x_i − s` with the column sums of `y`, and the energy, peak and finiteness of `x`.
#[target_feature(enable = "avx512f")]
fn load_with_stats<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    sh: &[T],
    blk: &mut B,
    cs: &mut [f64],
) -> super::LoadStats {
    let body = w - w % 16;
    let mut e = _mm512_setzero_pd();
    let mut p = _mm512_set1_ps(f32::MIN);
    let mut bad = _mm512_setzero_ps();
    let zero = _mm512_setzero_ps();
    for i in 0..blk.rows() {
        let src = &x[i][c0..c0 + w];
        let dst = &mut blk.row_mut(i)[..w];
        for t in (0..body).step_by(16) {
            // SAFETY: t + 16 ≤ body ≤ w, the length of src, sh, dst and cs.
            unsafe {
                let v = load16(src.as_ptr().add(t));
                p = _mm512_max_ps(p, v);
                bad = _mm512_fmadd_ps(v, zero, bad); // NaN for NaN or ±∞
                let (vlo, vhi) = widen16(v);
                let (hlo, hhi) = widen16(load16(sh.as_ptr().add(t)));
                e = _mm512_fmadd_pd(vlo, vlo, e);
                e = _mm512_fmadd_pd(vhi, vhi, e);
                let (ylo, yhi) = (_mm512_sub_pd(vlo, hlo), _mm512_sub_pd(vhi, hhi));
                store16(dst.as_mut_ptr().add(t), ylo, yhi);
                let c = cs.as_mut_ptr().add(t);
                _mm512_storeu_pd(c, _mm512_add_pd(_mm512_loadu_pd(c), ylo));
                _mm512_storeu_pd(c.add(8), _mm512_add_pd(_mm512_loadu_pd(c.add(8)), yhi));
            }
        }
    }
    let st = super::LoadStats {
        energy: reduce8(e),
        peak: _mm512_reduce_max_ps(p),
        finite: _mm512_reduce_add_ps(bad) == 0.0,
    };
    super::load_tail(x, c0, (body, w), sh, blk, cs, st)
}

/// See `tile_portable` (`R` rows of `a`, the first `S` of `b`). Safety: AVX-512F present,
/// `a` and `b` valid for `R·w` and `S·w` reads, `acc` for `R·5·8` reads and writes, `w`
/// and `k0` multiples of 8, `k1 ≤ w`.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn tile<const R: usize, const S: usize>(
    a: *const f64,
    b: *const f64,
    w: usize,
    (k0, k1): (usize, usize),
    acc: *mut f64,
) {
    let mut v = [[_mm512_setzero_pd(); S]; R];
    for r in 0..R {
        for s in 0..S {
            // SAFETY: (r·5 + s)·8 + 8 ≤ R·5·8.
            v[r][s] = unsafe { _mm512_loadu_pd(acc.add((r * TB + s) * LANES)) };
        }
    }
    let mut k = k0;
    while k < k1 {
        let mut av = [_mm512_setzero_pd(); R];
        // SAFETY: k + 8 ≤ w, rows r < R and s < S lie inside the caller's extents.
        unsafe {
            for (r, x) in av.iter_mut().enumerate() {
                *x = _mm512_loadu_pd(a.add(r * w + k));
            }
            for s in 0..S {
                let bs = _mm512_loadu_pd(b.add(s * w + k));
                for r in 0..R {
                    v[r][s] = _mm512_fmadd_pd(av[r], bs, v[r][s]);
                }
            }
        }
        k += LANES;
    }
    for r in 0..R {
        for s in 0..S {
            // SAFETY: as for the loads.
            unsafe { _mm512_storeu_pd(acc.add((r * TB + s) * LANES), v[r][s]) };
        }
    }
}

/// The upper triangle (`s ≥ r`) of a diagonal 5 × 5 tile of `a·aᵀ`: 15 products per
/// column instead of 25. Safety: as for [`tile`] with `R = S = 5` and `b = a`.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn tile_upper(a: *const f64, w: usize, (k0, k1): (usize, usize), acc: *mut f64) {
    let mut v = [[_mm512_setzero_pd(); TB]; TB];
    for r in 0..TB {
        for s in r..TB {
            // SAFETY: (r·5 + s)·8 + 8 ≤ 5·5·8.
            v[r][s] = unsafe { _mm512_loadu_pd(acc.add((r * TB + s) * LANES)) };
        }
    }
    let mut k = k0;
    while k < k1 {
        let mut av = [_mm512_setzero_pd(); TB];
        // SAFETY: k + 8 ≤ w, rows r < 5 lie inside the caller's extents.
        unsafe {
            for (r, x) in av.iter_mut().enumerate() {
                *x = _mm512_loadu_pd(a.add(r * w + k));
            }
        }
        for r in 0..TB {
            for s in r..TB {
                v[r][s] = _mm512_fmadd_pd(av[r], av[s], v[r][s]);
            }
        }
        k += LANES;
    }
    for r in 0..TB {
        for s in r..TB {
            // SAFETY: as for the loads.
            unsafe { _mm512_storeu_pd(acc.add((r * TB + s) * LANES), v[r][s]) };
        }
    }
}

/// See `lift_rows32_with`: `K` components (8 or 16) over all `w` columns, eight columns at
/// a time, each widened vector of `y` feeding `K` FMAs. Safety: AVX-512F present; `y`
/// valid for `n·w` reads, `coef` for reads at `i·cp + k` (`i < n`, `k < K`), `out` for
/// writes at `k·ldo + t` (`k < K`, `t < w`); `w` a multiple of 8.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn lift32<const K: usize>(
    y: *const f32,
    n: usize,
    w: usize,
    coef: *const f64,
    cp: usize,
    out: *mut f64,
    ldo: usize,
) {
    let mut t = 0;
    while t < w {
        let mut acc = [_mm512_setzero_pd(); K];
        for i in 0..n {
            // SAFETY: i < n, t + 8 ≤ w, coefficients k < K of row i.
            unsafe {
                let yv = _mm512_cvtps_pd(_mm256_loadu_ps(y.add(i * w + t)));
                for (k, a) in acc.iter_mut().enumerate() {
                    *a = _mm512_fmadd_pd(_mm512_set1_pd(*coef.add(i * cp + k)), yv, *a);
                }
            }
        }
        for (k, a) in acc.iter().enumerate() {
            // SAFETY: k < K, t + 8 ≤ w.
            unsafe { _mm512_storeu_pd(out.add(k * ldo + t), *a) };
        }
        t += LANES;
    }
}

/// `avx2::panel_tile` with 16 rows of `a`. Safety: AVX-512F present; `a` valid for reads
/// at `k·lda + i` (`k < kc`, `i < 16`), `b` at those of its `j < N` and `k < kc`, `s` for
/// reads and writes at `j·lds + i`.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn panel_tile<const N: usize, const ROWS: bool>(
    a: *const f32,
    lda: usize,
    b: *const f32,
    ldb: usize,
    kc: usize,
    s: *mut f64,
    lds: usize,
) {
    let mut acc = [_mm512_setzero_ps(); N];
    // SAFETY: every access lies in the extents the caller guarantees.
    unsafe {
        let (mut a, mut b) = (a, b);
        for _ in 0..kc {
            let av = _mm512_loadu_ps(a);
            for (j, x) in acc.iter_mut().enumerate() {
                *x =
                    _mm512_fmadd_ps(av, _mm512_set1_ps(*b.add(if ROWS { j * ldb } else { j })), *x);
            }
            (a, b) = (a.add(lda), b.add(if ROWS { 1 } else { ldb }));
        }
        for (j, x) in acc.iter().enumerate() {
            let (lo, hi) = widen16(*x);
            let p = s.add(j * lds);
            _mm512_storeu_pd(p, _mm512_add_pd(_mm512_loadu_pd(p), lo));
            _mm512_storeu_pd(p.add(8), _mm512_add_pd(_mm512_loadu_pd(p.add(8)), hi));
        }
    }
}

/// `to[t] = from[t]` widened to `f32` (exact), sixteen at a time.
#[target_feature(enable = "avx512f")]
pub(super) fn widen_to_f32<T: Texel>(from: &[T], to: &mut [f32]) {
    let n = from.len().min(to.len());
    let body = n - n % 16;
    for t in (0..body).step_by(16) {
        // SAFETY: t + 16 ≤ body ≤ the length of both slices.
        unsafe { _mm512_storeu_ps(to.as_mut_ptr().add(t), load16(from.as_ptr().add(t))) };
    }
    for t in body..n {
        to[t] = from[t].widen();
    }
}

/// `to[t] = from[t] as f32` (round to nearest), eight at a time.
#[target_feature(enable = "avx512f")]
pub(super) fn round_to_f32(from: &[f64], to: &mut [f32]) {
    let n = from.len().min(to.len());
    let body = n - n % 8;
    for t in (0..body).step_by(8) {
        // SAFETY: t + 8 ≤ body ≤ the length of both slices.
        unsafe {
            let v = _mm512_cvtpd_ps(_mm512_loadu_pd(from.as_ptr().add(t)));
            _mm256_storeu_ps(to.as_mut_ptr().add(t), v);
        }
    }
    for t in body..n {
        to[t] = from[t] as f32;
    }
}

/// See `f16_round::round_to_f16_with`, eight values at a time (all slices of `b.len()`).
#[target_feature(enable = "avx512f,f16c")]
pub(super) fn round_to_f16(
    b: &[f64],
    halves: &mut [half::f16],
    stored: &mut [f64],
    err: &mut [f32],
    (hi, lo): (&mut f64, &mut f64),
) {
    let w = b.len();
    assert!(halves.len() == w && stored.len() == w && err.len() == w);
    let body = w - w % 8;
    let (mut vhi, mut vlo) = (_mm512_set1_pd(*hi), _mm512_set1_pd(*lo));
    for t in (0..body).step_by(8) {
        // SAFETY: t + 8 ≤ body ≤ w, the length of every slice.
        unsafe {
            let v = _mm512_loadu_pd(b.as_ptr().add(t));
            // The second operand wins ties of ±0 and NaN, as in `if v > hi { v } else { hi }`.
            vhi = _mm512_max_pd(v, vhi);
            vlo = _mm512_min_pd(v, vlo);
            let h = _mm256_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(_mm512_cvtpd_ps(v));
            _mm_storeu_si128(halves.as_mut_ptr().add(t).cast(), h);
            let s = _mm512_cvtps_pd(_mm256_cvtph_ps(h));
            _mm512_storeu_pd(stored.as_mut_ptr().add(t), s);
            _mm256_storeu_ps(err.as_mut_ptr().add(t), _mm512_cvtpd_ps(_mm512_sub_pd(s, v)));
        }
    }
    *hi = _mm512_reduce_max_pd(vhi);
    *lo = _mm512_reduce_min_pd(vlo);
    // The last w mod 8 values as the portable path rounds them (the same conversions).
    super::f16_round::round_portable(
        &b[body..],
        &mut halves[body..],
        &mut stored[body..],
        &mut err[body..],
        (hi, lo),
        &mut [0f32; 8],
    );
}
