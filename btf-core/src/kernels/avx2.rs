//! The AVX2 path: the portable kernels (`lanes.rs` with fused multiply-adds, the loads and
//! the `f16` rounding of `kernels.rs`) compiled with AVX2, FMA and F16C enabled, so that the
//! compiler turns four `f64` (eight `f32`) lanes into one 256-bit register and each
//! `mul_add` into one `vfmadd`. No intrinsics: the arithmetic is the lane model's, which is
//! the AVX-512 kernels', bit for bit. Callers check the features at run time
//! ([`crate::simd::Isa::supported`]).

use super::{Block, LoadStats, Texel, lanes};

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn lift(
    y: &[f32],
    n: usize,
    w: usize,
    coef: &[f64],
    ks: (usize, usize, usize),
    out: &mut [f64],
    ldo: usize,
) {
    lanes::lift::<true>(y, n, w, coef, ks, out, ldo)
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

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn tile32(s_count: usize, e: &[f32], y: &[f32], w: usize, out: &mut [f64], ldo: usize) {
    lanes::tile32::<true>(s_count, e, y, w, out, ldo)
}

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn load_shifted<T: Texel>(
    x: &[&[T]],
    c0: usize,
    w: usize,
    shift: Option<&[T]>,
    blk: &mut Block,
    colsum: Option<&mut [f64]>,
) -> Option<LoadStats> {
    super::load_shifted_body(x, c0, w, shift, blk, colsum)
}

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn round_to_f16(
    b: &[f64],
    halves: &mut [half::f16],
    stored: &mut [f64],
    err: &mut [f32],
    hi_lo: (&mut f64, &mut f64),
    narrow: &mut [f32],
) {
    super::f16_round::round_portable(b, halves, stored, err, hi_lo, narrow)
}

#[target_feature(enable = "avx2,fma,f16c")]
pub(super) fn widen_to_f32<T: Texel>(from: &[T], to: &mut [f32]) {
    super::widen_portable(from, to)
}
