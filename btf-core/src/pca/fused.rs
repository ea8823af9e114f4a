//! Passes 2 and 3 of the per-slot PCA ([S03 eq. 1]) in one sweep over the
//! data, for `f16` eigentextures. Each block of columns of the images `X` is widened to
//! `f32` once (exact for `f32` and `f16` data) and lifted to the eigentextures
//! `B = (C·lift)ᵀY = (C·lift)ᵀX` in `f64` (the centred coefficients sum to zero over the
//! images, so the shift `Y = X − 1x₀ᵀ` drops out), rounded to `f16` and turned into the
//! stored basis `S` and its error `E = S − B` while the block is still in the cache, so the
//! correction and the Gram matrix `SSᵀ` that the least-squares weights need come from the
//! same read. The correction is of relative size `2⁻¹¹`, so it is summed in `f32`
//! ([`crate::kernels::CrossAcc32`]) as `E·Xᵀ`, `E` rounded to `f32`; the row-centring the
//! weights apply to it removes the shift's constant `E·x₀` from every row, leaving `X̃Eᵀ`.
//!
//! That needs the rounding to be fixed before the whole of `B` is known. It is: the
//! eigentextures have unit norm, so every entry is at most 1 in magnitude and rounds to
//! `f16` at unit scale without overflow. Afterwards each row is renormalised by a power of
//! two `2^e ≥ max |B_k|` (its largest magnitude then lies in `(½, 1]`, and the stored scale
//! is `2^e`) and given the deterministic sign; multiplying an `f16` by `±2^{−e} ≥ 1` is
//! exact, so `S` is the same before and after, and so are `E·Yᵀ` and `SSᵀ` up to the signs,
//! which are applied to them exactly. The rounding error is at most `2^{−11}` of an entry
//! for normal values and `2^{−25}` for entries below `2^{−14}` (the `f16` subnormals),
//! which stays below `2^{−11}` of the row's largest magnitude for rows of fewer than
//! `2^{28}` values (that largest magnitude is at least `1/√m`).

use super::{BLOCK, centred_coef, finish_symmetric};
use crate::kernels::{
    Block, Block32, CrossAcc32, DotAcc, LIFT_COMPONENTS, Texel, lift_rows32_with, prefetch_rows,
    round_to_f16_with,
};
use crate::simd::Isa;
use half::f16;
use half::slice::HalfFloatSliceExt;

/// The fused pass's working blocks, kept by the caller from slot to slot.
#[derive(Debug, Default)]
pub(super) struct Blocks {
    /// `Y` in `f64` (also the first pass's block).
    pub y: Block,
    /// `S` in `f64`.
    s: Block,
    /// `X` widened and `E` rounded to `f32` (`y32` is also the first pass's block for a
    /// Gram matrix in `f32`).
    pub y32: Block32,
    e32: Block32,
    /// The block of `B` (`cp × BLOCK`).
    lifted: Vec<f64>,
}

/// What the fused pass yields.
pub(super) struct Fused {
    /// `c` rows of `m` little-endian `f16` values, signs fixed.
    pub raw: Vec<u8>,
    /// `[2^e, 0]` per component.
    pub scale_offset: Vec<[f32; 2]>,
    /// `E·Xᵀ` (`c × n`, row-major; equal to `E·Yᵀ` once each row is centred), signs applied.
    pub cross: Vec<f64>,
    /// `SSᵀ` (`c × c`, full), signs applied.
    pub bgram: Vec<f64>,
}

/// The fused lift and stored-basis pass over the rows `x` (`m` values each), with the
/// lifting matrix `lift` (`n × c`, column `k` = `v_k/√λ_k`; its columns' signs are fixed
/// here as the eigentextures' are). `raw` is reused for the stored bytes (its contents
/// are overwritten; a buffer whose pages are already mapped costs no page faults).
pub(super) fn lift_store_f16<T: Texel>(
    x: &[&[T]],
    m: usize,
    (lift, c): (&mut [f64], usize),
    effective: usize,
    mut raw: Vec<u8>,
    blocks: &mut Blocks,
    isa: Isa,
) -> Fused {
    let n = x.len();
    let cp = c.div_ceil(LIFT_COMPONENTS) * LIFT_COMPONENTS;
    let coef = centred_coef(lift, n, c, cp);
    // The halves are formed in `raw` itself where it is aligned for them on a
    // little-endian host (every entry is written below), else in a buffer of their own.
    raw.resize(c * m * 2, 0);
    let in_place = cfg!(target_endian = "little")
        && bytemuck::try_cast_slice_mut::<u8, f16>(&mut raw[..]).is_ok();
    let mut own = if in_place { Vec::new() } else { vec![f16::ZERO; c * m] };
    let halves: &mut [f16] =
        if in_place { bytemuck::cast_slice_mut(&mut raw[..]) } else { &mut own };
    let Blocks { s: sb, y32, e32, lifted, .. } = blocks;
    // Every value of the block of B is written by the lift before it is read (rows of the
    // block's pitch, which may exceed BLOCK).
    lifted.resize(cp * crate::kernels::padded_stride(BLOCK, crate::kernels::LANES32), 0.0);
    let mut narrow = vec![0f32; BLOCK];
    let (mut cross_acc, mut bgram_acc) = (CrossAcc32::new(c, n), DotAcc::new(c, c, true));
    let (mut hi, mut lo) = (vec![0f64; c], vec![0f64; c]);
    for c0 in (0..m).step_by(BLOCK) {
        let w = BLOCK.min(m - c0);
        // The images themselves, widened exactly to f32: the lift's coefficients are
        // centred (each column sums to zero over the images), so B = coefᵀX = coefᵀY, and
        // the row-centring of the cross terms below removes the shift by the first image.
        y32.widen_from_with(x, c0, w, isa);
        let ws = y32.stride;
        prefetch_rows(x, c0 + w, BLOCK);
        lift_rows32_with(y32, &coef, cp, lifted, ws, 0, isa);
        sb.shape(c, w);
        e32.shape(c, w);
        for k in 0..c {
            // f64 → f32 → f16 at unit scale, back to f64 exactly: the stored value, its
            // error and the row's extremes (used for k < effective only).
            round_to_f16_with(
                &lifted[k * ws..k * ws + w],
                &mut halves[k * m + c0..k * m + c0 + w],
                sb.row_mut(k),
                e32.row_mut(k),
                (&mut hi[k], &mut lo[k]),
                &mut narrow,
                isa,
            );
        }
        cross_acc.add_with(e32, y32, isa);
        bgram_acc.add_with(sb, sb, isa);
    }
    let mut cross = vec![0f64; c * n];
    cross_acc.finish(&mut cross, n);
    let mut bgram = finish_symmetric(&bgram_acc, c);
    let mut sign = vec![1f64; c];
    let mut scale_offset = vec![[1f32, 0.0]; c];
    for k in 0..effective {
        let row = &mut halves[k * m..(k + 1) * m];
        // The entry of largest magnitude; on a tie of ±, the first stored one of them.
        let big = if hi[k] != -lo[k] {
            if hi[k] > -lo[k] { hi[k] } else { lo[k] }
        } else {
            let top = row.iter().map(|h| h.to_f32().abs()).fold(0f32, f32::max);
            row.iter().map(|h| h.to_f64()).find(|v| v.abs() as f32 == top).unwrap_or(0.0)
        };
        sign[k] = if big < 0.0 { -1.0 } else { 1.0 };
        // The scale `quantize` would choose, from the largest magnitude of the f32 values
        // it would see; at most 1 (an f32 unit-norm row has no entry above 1 + 2⁻²⁴ ulp).
        let largest = (hi[k].max(-lo[k]) as f32).min(1.0);
        let scale = crate::eigen::f16_scale(largest);
        scale_offset[k] = [scale, 0.0];
        renormalise(row, sign[k] as f32 / scale, &mut narrow);
        if sign[k] < 0.0 {
            for i in 0..n {
                lift[i * c + k] = -lift[i * c + k];
            }
        }
    }
    for k in 0..c {
        cross[k * n..(k + 1) * n].iter_mut().for_each(|v| *v *= sign[k]);
        for j in 0..c {
            bgram[k * c + j] *= sign[k] * sign[j];
        }
    }
    if !in_place {
        raw.clear();
        raw.extend(own.iter().flat_map(|h| h.to_le_bytes()));
    }
    Fused { raw, scale_offset, cross, bgram }
}

/// Multiplies `f16` values by `factor` (`±2^j`, `j ≥ 0`, so exact while the results stay
/// at most 1 in magnitude), through `f32` in pieces of `buf`'s length.
fn renormalise(row: &mut [f16], factor: f32, buf: &mut [f32]) {
    if factor == 1.0 {
        return;
    }
    for piece in row.chunks_mut(buf.len()) {
        let b = &mut buf[..piece.len()];
        piece.convert_to_f32_slice(b);
        b.iter_mut().for_each(|v| *v *= factor);
        piece.convert_from_f32_slice(b);
    }
}
