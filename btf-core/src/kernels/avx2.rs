//! The AVX2 path: the portable kernels (`lanes.rs` with fused multiply-adds, the `f16`
//! rounding of `kernels.rs`) compiled with AVX2, FMA and F16C enabled, so that the
//! compiler turns four `f64` (eight `f32`) lanes into one 256-bit register and each
//! `mul_add` into one `vfmadd`: the arithmetic is the lane model's, which is the AVX-512
//! kernels', bit for bit. The block loads and widenings are written with intrinsics (the
//! vectoriser leaves the portable load's `f16` conversion, NaN-aware maximum and energy
//! lanes scalar, five times slower), in the lanes of the portable load, so they give its
//! bits; so are the lift (8 components × 4 columns a step, where the vectoriser widened
//! every value four times) and the `f32` panel tiles of `panel.rs` with their 8 × 8
//! transpositions, in the lane model's order of operations per output. Callers check the
//! features at run time ([`crate::simd::Isa::supported`]).

use super::{Lane, LoadStats, LoadTarget, Texel, lanes};
use std::arch::x86_64::*;

/// `lanes::lift` in intrinsics: 8 components × 4 columns per step (eight registers of sums;
/// each row's four values widened once for eight multiply-adds, where the lane model's
/// 4 × 8 widens each value for four), the same fused multiply-adds in the same order per
/// output.
#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn lift(
    y: &[f32],
    n: usize,
    w: usize,
    coef: &[f64],
    (cp, k0, step): (usize, usize, usize),
    out: &mut [f64],
    ldo: usize,
) {
    const K: usize = super::LIFT_COMPONENTS;
    assert!(y.len() >= n * w && w.is_multiple_of(4) && step.is_multiple_of(K));
    assert!(coef.len() >= n * cp && k0 + step <= cp);
    assert!(step == 0 || out.len() >= (step - 1) * ldo + w);
    for kg in (0..step).step_by(K) {
        for t in (0..w).step_by(4) {
            let mut acc = [_mm256_setzero_pd(); K];
            for i in 0..n {
                // SAFETY: i < n and t + 4 ≤ w (the rows of y); k0 + kg + K ≤ cp (coef's
                // row i).
                unsafe {
                    let yv = _mm256_cvtps_pd(_mm_loadu_ps(y.as_ptr().add(i * w + t)));
                    let c = coef.as_ptr().add(i * cp + k0 + kg);
                    for (k, a) in acc.iter_mut().enumerate() {
                        *a = _mm256_fmadd_pd(_mm256_broadcast_sd(&*c.add(k)), yv, *a);
                    }
                }
            }
            for (k, a) in acc.iter().enumerate() {
                // SAFETY: kg + k < step and t + 4 ≤ w: inside out (asserted).
                unsafe { _mm256_storeu_pd(out.as_mut_ptr().add((kg + k) * ldo + t), *a) };
            }
        }
    }
}

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn tile(
    ta: usize,
    kind: super::dot::Tile,
    a: &[f64],
    b: &[f64],
    w: usize,
    cols: (usize, usize),
    acc: &mut [f64],
) {
    lanes::tile::<true>(ta, kind, a, b, w, cols, acc)
}

/// A tile of `panel.rs`: the 8 rows of the packed `a` against the `N` of `b` (packed,
/// `b[k·ldb + j]`, or with `ROWS` row by row, `b[j·ldb + k]`) over `kc` columns (`lda`
/// values per column of `a`), one `f32` lane per output from zero (a fused multiply-add
/// per column, as `lanes::panel_tile`), added in `f64` to `s[j·lds + i]`. Safety: AVX2
/// and FMA present; `a` valid for reads at `k·lda + i` (`k < kc`, `i < 8`), `b` at those
/// of its `j < N` and `k < kc`, `s` for reads and writes at `j·lds + i`.
#[target_feature(enable = "avx2,fma,f16c")]
pub(super) unsafe fn panel_tile<const N: usize, const ROWS: bool>(
    a: *const f32,
    lda: usize,
    b: *const f32,
    ldb: usize,
    kc: usize,
    s: *mut f64,
    lds: usize,
) {
    let mut acc = [_mm256_setzero_ps(); N];
    // SAFETY: every access lies in the extents the caller guarantees.
    unsafe {
        let (mut a, mut b) = (a, b);
        for _ in 0..kc {
            let av = _mm256_loadu_ps(a);
            for (j, x) in acc.iter_mut().enumerate() {
                *x = _mm256_fmadd_ps(
                    av,
                    _mm256_broadcast_ss(&*b.add(if ROWS { j * ldb } else { j })),
                    *x,
                );
            }
            (a, b) = (a.add(lda), b.add(if ROWS { 1 } else { ldb }));
        }
        for (j, x) in acc.iter().enumerate() {
            let (lo, hi) = widen8(*x);
            let p = s.add(j * lds);
            _mm256_storeu_pd(p, _mm256_add_pd(_mm256_loadu_pd(p), lo));
            _mm256_storeu_pd(p.add(4), _mm256_add_pd(_mm256_loadu_pd(p.add(4)), hi));
        }
    }
}

/// `to[k·ldt + i] = from[i·ldf + k]` for `i < rows` and `k < cols` (both multiples of 8), in
/// 8 × 8 blocks. Safety: AVX present; `from` valid for those reads, `to` for those writes.
#[target_feature(enable = "avx2,fma,f16c")]
pub(super) unsafe fn transpose(
    from: *const f32,
    ldf: usize,
    (rows, cols): (usize, usize),
    to: *mut f32,
    ldt: usize,
) {
    for i in (0..rows).step_by(8) {
        for k in (0..cols).step_by(8) {
            // SAFETY: rows i..i + 8 and columns k..k + 8 lie inside the caller's extents.
            unsafe { transpose8(from.add(i * ldf + k), ldf, to.add(k * ldt + i), ldt) };
        }
    }
}

/// `to[k·ldt + i] = from[i·ldf + k]` for `i, k < 8`: an 8 × 8 block of `f32` transposed
/// (rows `i` and `i + 4` loaded into the halves of one register, then two 4 × 4
/// transpositions within the halves: 16 shuffles). Safety: AVX present; `from` valid for
/// those reads, `to` for those writes.
#[target_feature(enable = "avx2,fma,f16c")]
#[inline]
unsafe fn transpose8(from: *const f32, ldf: usize, to: *mut f32, ldt: usize) {
    // SAFETY: forwarded from the caller.
    unsafe {
        for half in [0, 4] {
            let r: [__m256; 4] = std::array::from_fn(|i| {
                _mm256_loadu2_m128(from.add((i + 4) * ldf + half), from.add(i * ldf + half))
            });
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpackhi_ps(r[0], r[1]);
            let t2 = _mm256_unpacklo_ps(r[2], r[3]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            let c = [
                _mm256_shuffle_ps::<0x44>(t0, t2),
                _mm256_shuffle_ps::<0xEE>(t0, t2),
                _mm256_shuffle_ps::<0x44>(t1, t3),
                _mm256_shuffle_ps::<0xEE>(t1, t3),
            ];
            for (k, v) in c.into_iter().enumerate() {
                _mm256_storeu_ps(to.add((half + k) * ldt), v);
            }
        }
    }
}

/// Eight stored values from `p` as `f32` (`vcvtph2ps` for `f16`, exact). Safety: AVX2 and
/// F16C present, `p` valid for 8 reads.
#[target_feature(enable = "avx2,fma,f16c")]
#[inline]
unsafe fn load8<T: Texel>(p: *const T) -> __m256 {
    // SAFETY: forwarded from the caller; 8 values of T are 16 or 32 bytes.
    unsafe {
        if T::HALF { _mm256_cvtph_ps(_mm_loadu_si128(p.cast())) } else { _mm256_loadu_ps(p.cast()) }
    }
}

/// The eight `f32` lanes of `v` as two registers of `f64` (exact).
#[target_feature(enable = "avx2,fma,f16c")]
#[inline]
fn widen8(v: __m256) -> (__m256d, __m256d) {
    (_mm256_cvtps_pd(_mm256_castps256_ps128(v)), _mm256_cvtps_pd(_mm256_extractf128_ps(v, 1)))
}

/// Stores the four values `y` at `p`, as they are or rounded to nearest `f32`
/// ([`Lane::of`]). Safety: AVX present, `p` valid for 4 writes.
#[target_feature(enable = "avx2,fma,f16c")]
#[inline]
unsafe fn store4<V: Lane>(p: *mut V, y: __m256d) {
    // SAFETY: forwarded from the caller; V is f64 when WIDE, else f32.
    unsafe {
        if V::WIDE {
            _mm256_storeu_pd(p.cast(), y)
        } else {
            _mm_storeu_ps(p.cast(), _mm256_cvtpd_ps(y))
        }
    }
}

/// `load_shifted_with` on AVX2: whole 16-value groups by hand, in the portable load's lanes
/// (the energy of column `t` of a group in lane `t mod 8`: registers `e0` and `e1` hold
/// lanes 0–3 and 4–7), the last `w mod 16` columns by the portable code's rule.
#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn load_shifted<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut B,
    colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    let (Some(cs), Some(sh)) = (colsum, shift) else {
        load_plain(x, c0, w, shift.map(|s| &s[c0..c0 + w]), blk);
        return None;
    };
    let (sh, cs) = (&sh[c0..c0 + w], &mut cs[..w]);
    let body = w - w % 16;
    let (mut e0, mut e1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    let mut p = _mm256_set1_ps(f32::MIN);
    let mut bad = _mm256_setzero_ps();
    let zero = _mm256_setzero_ps();
    for i in 0..blk.rows() {
        let src = &x[i][c0..c0 + w];
        let dst = &mut blk.row_mut(i)[..w];
        for t in (0..body).step_by(16) {
            // SAFETY: t + 16 ≤ body ≤ w, the length of src, sh, dst and cs.
            unsafe {
                for half in [0, 8] {
                    let v = load8(src.as_ptr().add(t + half));
                    p = _mm256_max_ps(p, v);
                    bad = _mm256_fmadd_ps(v, zero, bad); // NaN for NaN or ±∞
                    let (vlo, vhi) = widen8(v);
                    let (hlo, hhi) = widen8(load8(sh.as_ptr().add(t + half)));
                    e0 = _mm256_fmadd_pd(vlo, vlo, e0);
                    e1 = _mm256_fmadd_pd(vhi, vhi, e1);
                    for (q, y) in [(0, _mm256_sub_pd(vlo, hlo)), (4, _mm256_sub_pd(vhi, hhi))] {
                        let at = t + half + q;
                        store4(dst.as_mut_ptr().add(at), y);
                        let c = cs.as_mut_ptr().add(at);
                        _mm256_storeu_pd(c, _mm256_add_pd(_mm256_loadu_pd(c), y));
                    }
                }
            }
        }
    }
    let mut e = [0f64; 8];
    let (mut peaks, mut bads) = ([0f32; 8], [0f32; 8]);
    // SAFETY: the arrays hold 4 + 4 and 8 values.
    unsafe {
        _mm256_storeu_pd(e.as_mut_ptr(), e0);
        _mm256_storeu_pd(e.as_mut_ptr().add(4), e1);
        _mm256_storeu_ps(peaks.as_mut_ptr(), p);
        _mm256_storeu_ps(bads.as_mut_ptr(), bad);
    }
    let st = LoadStats {
        energy: lanes::reduce8(e),
        peak: peaks.iter().copied().fold(f32::MIN, f32::max),
        finite: bads.iter().all(|b| *b == 0.0),
    };
    Some(super::load_tail(x, c0, (body, w), sh, blk, cs, st))
}

/// `y_i = x_i − s` (or `x_i`) for the columns `c0..c0 + w` of every row (`sh` is `s` there).
#[target_feature(enable = "avx2,fma,f16c")]
fn load_plain<T: Texel, B: LoadTarget>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    sh: Option<&[T]>,
    blk: &mut B,
) {
    let body = w - w % 8;
    for i in 0..blk.rows() {
        let src = &x[i][c0..c0 + w];
        let dst = &mut blk.row_mut(i)[..w];
        for t in (0..body).step_by(8) {
            // SAFETY: t + 8 ≤ body ≤ w, the length of src, sh and dst.
            unsafe {
                let (mut lo, mut hi) = widen8(load8(src.as_ptr().add(t)));
                if let Some(sh) = sh {
                    let (hlo, hhi) = widen8(load8(sh.as_ptr().add(t)));
                    (lo, hi) = (_mm256_sub_pd(lo, hlo), _mm256_sub_pd(hi, hhi));
                }
                store4(dst.as_mut_ptr().add(t), lo);
                store4(dst.as_mut_ptr().add(t + 4), hi);
            }
        }
        super::plain_tail(&src[body..], sh.map(|s| &s[body..]), &mut dst[body..]);
    }
}

/// See `f16_round::round_to_f16_with`, eight values at a time (all slices of `b.len()`):
/// every step a correctly rounded conversion or exact, so the portable path's bits.
#[target_feature(enable = "avx2,fma,f16c")]
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
    let (mut vhi, mut vlo) = (_mm256_set1_pd(*hi), _mm256_set1_pd(*lo));
    for t in (0..body).step_by(8) {
        // SAFETY: t + 8 ≤ body ≤ w, the length of every slice.
        unsafe {
            let (v0, v1) =
                (_mm256_loadu_pd(b.as_ptr().add(t)), _mm256_loadu_pd(b.as_ptr().add(t + 4)));
            // The second operand wins ties of ±0 and NaN, as in `if v > hi { v } else { hi }`.
            vhi = _mm256_max_pd(v1, _mm256_max_pd(v0, vhi));
            vlo = _mm256_min_pd(v1, _mm256_min_pd(v0, vlo));
            let narrow = _mm256_set_m128(_mm256_cvtpd_ps(v1), _mm256_cvtpd_ps(v0));
            let h = _mm256_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(narrow);
            _mm_storeu_si128(halves.as_mut_ptr().add(t).cast(), h);
            let (s0, s1) = widen8(_mm256_cvtph_ps(h));
            _mm256_storeu_pd(stored.as_mut_ptr().add(t), s0);
            _mm256_storeu_pd(stored.as_mut_ptr().add(t + 4), s1);
            let e = _mm256_set_m128(
                _mm256_cvtpd_ps(_mm256_sub_pd(s1, v1)),
                _mm256_cvtpd_ps(_mm256_sub_pd(s0, v0)),
            );
            _mm256_storeu_ps(err.as_mut_ptr().add(t), e);
        }
    }
    let (mut h4, mut l4) = ([0f64; 4], [0f64; 4]);
    // SAFETY: the arrays hold four values each.
    unsafe {
        _mm256_storeu_pd(h4.as_mut_ptr(), vhi);
        _mm256_storeu_pd(l4.as_mut_ptr(), vlo);
    }
    *hi = h4.iter().copied().fold(*hi, f64::max);
    *lo = l4.iter().copied().fold(*lo, f64::min);
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

/// `to[t] = from[t]` widened to `f32` (exact), eight at a time.
#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn widen_to_f32<T: Texel>(from: &[T], to: &mut [f32]) {
    let n = from.len().min(to.len());
    let body = n - n % 8;
    for t in (0..body).step_by(8) {
        // SAFETY: t + 8 ≤ body ≤ the length of both slices.
        unsafe { _mm256_storeu_ps(to.as_mut_ptr().add(t), load8(from.as_ptr().add(t))) };
    }
    for t in body..n {
        to[t] = from[t].widen();
    }
}
