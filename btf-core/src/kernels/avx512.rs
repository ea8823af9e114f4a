//! AVX-512 versions of the kernels in `kernels.rs` (the same sums, eight `f64` lanes per
//! register, fused multiply-adds); callers check the CPU feature at run time.

use super::{LANES, LIFT_COMPONENTS, TB};
use std::arch::x86_64::*;

/// `load_shifted_body` compiled with AVX-512 (safe code; callers check the feature),
/// the statistics of whole 16-value groups by hand (the vectoriser leaves the
/// NaN-aware maximum and the energy sum scalar).
#[target_feature(enable = "avx512f")]
pub(super) fn load_shifted(
    x: &[&[f32]],
    c0: usize,
    w: usize,
    shift: Option<&[f32]>,
    blk: &mut super::Block,
    colsum: Option<&mut [f64]>,
) -> Option<super::LoadStats> {
    let (Some(cs), Some(sh)) = (colsum, shift) else {
        return super::load_shifted_body(x, c0, w, shift, blk, None);
    };
    let body = w - w % 16;
    let mut e = _mm512_setzero_pd();
    let mut p = _mm512_set1_ps(f32::MIN);
    let mut bad = _mm512_setzero_ps();
    let zero = _mm512_setzero_ps();
    let sh = &sh[c0..c0 + w];
    let cs = &mut cs[..w];
    for i in 0..blk.rows {
        let src = &x[i][c0..c0 + w];
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
        let src = &x[i][c0..c0 + w];
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

/// See `tile_portable`. Safety: AVX-512F present, `a` and `b` valid for `R·w` and `5·w`
/// reads, `acc` for `R·5·8` reads and writes, `w` and `k0` multiples of 8, `k1 ≤ w`.
#[target_feature(enable = "avx512f")]
pub(super) unsafe fn tile<const R: usize>(
    a: *const f64,
    b: *const f64,
    w: usize,
    (k0, k1): (usize, usize),
    acc: *mut f64,
) {
    let mut v = [[_mm512_setzero_pd(); TB]; R];
    for r in 0..R {
        for s in 0..TB {
            // SAFETY: (r·5 + s)·8 + 8 ≤ R·5·8.
            v[r][s] = unsafe { _mm512_loadu_pd(acc.add((r * TB + s) * LANES)) };
        }
    }
    let mut k = k0;
    while k < k1 {
        let mut av = [_mm512_setzero_pd(); R];
        // SAFETY: k + 8 ≤ w, rows r < R and s < 5 lie inside the caller's extents.
        unsafe {
            for (r, x) in av.iter_mut().enumerate() {
                *x = _mm512_loadu_pd(a.add(r * w + k));
            }
            for s in 0..TB {
                let bs = _mm512_loadu_pd(b.add(s * w + k));
                for r in 0..R {
                    v[r][s] = _mm512_fmadd_pd(av[r], bs, v[r][s]);
                }
            }
        }
        k += LANES;
    }
    for r in 0..R {
        for s in 0..TB {
            // SAFETY: as for the loads.
            unsafe { _mm512_storeu_pd(acc.add((r * TB + s) * LANES), v[r][s]) };
        }
    }
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
