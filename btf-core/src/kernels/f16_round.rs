//! The `f16` rounding of one block row of eigentextures in the fused pass of the per-slot
//! PCA ([S03 eq. 1]; `pca/fused.rs`): from the exact `B` (in `f64`) the
//! stored halves `S` (rounded through `f32` to nearest even, at unit scale), `S` back in
//! `f64`, the error `E = S − B` in `f32` and the running largest and smallest entry of `B`,
//! in one pass over the row instead of five.

use super::runnable;
use crate::simd::Isa;
use half::f16;
use half::slice::HalfFloatSliceExt;

/// Writes `halves[t] = f16(f32(b[t]))`, `stored[t] = halves[t]` as `f64`, `err[t] =
/// f32(stored[t] − b[t])` for every `t < b.len()`, and widens `hi`/`lo` to the largest and
/// smallest `b[t]`. `narrow` is scratch of at least `b.len()` values (portable path).
pub fn round_to_f16(
    b: &[f64],
    halves: &mut [f16],
    stored: &mut [f64],
    err: &mut [f32],
    (hi, lo): (&mut f64, &mut f64),
    narrow: &mut [f32],
) {
    round_to_f16_with(b, halves, stored, err, (hi, lo), narrow, Isa::active());
}

/// [`round_to_f16`] on the path `isa` (all paths give the same bits: every step is a
/// correctly rounded conversion, or exact).
pub(crate) fn round_to_f16_with(
    b: &[f64],
    halves: &mut [f16],
    stored: &mut [f64],
    err: &mut [f32],
    (hi, lo): (&mut f64, &mut f64),
    narrow: &mut [f32],
    isa: Isa,
) {
    let w = b.len();
    assert!(halves.len() >= w && stored.len() >= w && err.len() >= w && narrow.len() >= w);
    let (halves, stored, err) = (&mut halves[..w], &mut stored[..w], &mut err[..w]);
    match runnable(isa) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX-512F and F16C checked (`runnable`); the function is safe code.
        Isa::Avx512 => unsafe { super::avx512::round_to_f16(b, halves, stored, err, (hi, lo)) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: AVX2, FMA and F16C checked (`runnable`); the function is safe code.
        Isa::Avx2 => unsafe { super::avx2::round_to_f16(b, halves, stored, err, (hi, lo)) },
        _ => round_portable(b, halves, stored, err, (hi, lo), narrow),
    }
}

/// The portable rounding (scalar, AVX2 and NEON paths): the `half` crate's slice
/// conversions (F16C or the ARM half-precision instructions where the CPU has them).
#[inline(always)]
pub(super) fn round_portable(
    b: &[f64],
    halves: &mut [f16],
    stored: &mut [f64],
    err: &mut [f32],
    (hi, lo): (&mut f64, &mut f64),
    narrow: &mut [f32],
) {
    let w = b.len();
    let narrow = &mut narrow[..w];
    narrow.iter_mut().zip(b).for_each(|(o, &v)| *o = v as f32);
    halves.convert_from_f32_slice(narrow);
    halves.convert_to_f64_slice(stored);
    for ((e, &s), &v) in err.iter_mut().zip(&*stored).zip(b) {
        *e = (s - v) as f32;
    }
    for &v in b {
        *hi = if v > *hi { v } else { *hi };
        *lo = if v < *lo { v } else { *lo };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_path_rounds_alike_down_to_subnormals_and_ties() {
        // 45 values (five groups of 8 and a tail of 5): ordinary, f16-subnormal, exact
        // f16 ties (1 + 2⁻¹¹ rounds to even 1), and values that f32 rounding moves.
        let mut b: Vec<f64> = (0..45).map(|i| ((i * 37 % 91) as f64 / 91.0 - 0.4) * 0.9).collect();
        b[3] = 1.0 + 2f64.powi(-11);
        b[9] = 3.1e-7;
        b[17] = -6.0e-8;
        b[30] = 1.0 + 2f64.powi(-11) + 2f64.powi(-40);
        let run = |isa: Isa| {
            let mut h = vec![f16::ZERO; 45];
            let (mut s, mut e, mut n) = (vec![0.0; 45], vec![0f32; 45], vec![0f32; 45]);
            let (mut hi, mut lo) = (0.0, 0.0);
            round_to_f16_with(&b, &mut h, &mut s, &mut e, (&mut hi, &mut lo), &mut n, isa);
            (h, s, e, hi, lo)
        };
        let p = run(Isa::Scalar);
        for isa in Isa::supported_all() {
            let v = run(isa);
            assert_eq!(p.0, v.0, "{isa}");
            assert_eq!((p.1.clone(), p.2.clone(), p.3, p.4), (v.1, v.2, v.3, v.4), "{isa}");
        }
        assert_eq!(p.0[3], f16::ONE, "a tie rounds to even");
        for t in 0..45 {
            assert_eq!(p.1[t], p.0[t].to_f64());
            assert_eq!(p.2[t], (p.1[t] - b[t]) as f32);
        }
        assert_eq!(
            (p.3, p.4),
            (b.iter().copied().fold(0.0, f64::max), b.iter().copied().fold(0.0, f64::min))
        );
    }
}
