//! The kernels of `kernels.rs` as portable Rust over fixed lanes — the "lane model": the
//! dot-product tiles of the Gram matrix (eight `f64` partial sums per output), the lift
//! (one `f64` sum per output, over the images in order) and the `f32` panel tiles of
//! `panel.rs` (one `f32` lane per output and chunk of columns).
//!
//! With `FUSED` every step is a fused multiply-add (`f64::mul_add`): the arithmetic of the
//! AVX-512 kernels lane for lane, so the results are theirs bit for bit. That is the AVX2
//! path (compiled with AVX2 + FMA enabled, the compiler turns each group of four lanes into
//! one 256-bit register) and the NEON path. Without `FUSED` each step multiplies, rounds
//! and adds: the scalar path. The `f64` lanes are processed four at a time in "half
//! passes" over the columns, and the outputs in sub-tiles of at most 2 × 5, so that a
//! sub-tile's partial sums fit sixteen 256-bit (or thirty-two 128-bit) registers; which
//! outputs are grouped does not change any output's arithmetic. The AVX2 path's panel
//! tiles are intrinsics (`avx2.rs`), in this arithmetic.

use super::dot::Tile;
use super::{LANES, TB};

/// `c + a·b`, fused (one rounding) or not (two).
#[inline(always)]
fn madd<const FUSED: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FUSED { a.mul_add(b, c) } else { c + a * b }
}

#[inline(always)]
fn madd32<const FUSED: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FUSED { a.mul_add(b, c) } else { c + a * b }
}

/// The sum of eight lanes in the order of AVX-512's horizontal reduction (upper half onto
/// lower, then again): `((s₀+s₄)+(s₂+s₆)) + ((s₁+s₅)+(s₃+s₇))`. Every path reduces so.
#[inline(always)]
pub(crate) fn reduce8(s: [f64; 8]) -> f64 {
    let t = [s[0] + s[4], s[1] + s[5], s[2] + s[6], s[3] + s[7]];
    let u = [t[0] + t[2], t[1] + t[3]];
    u[0] + u[1]
}

/// `acc[(r·5 + s)·8 + l] += Σ_k a_r[8k + l]·b_s[8k + l]` over columns `k0..k1` of the `ta`
/// rows of `a` and the 5 of `b` (rows `w` apart), for the outputs `kind` names (a diagonal
/// tile also computes a few of its lower outputs, which `DotAcc::finish` ignores).
#[inline(always)]
pub(super) fn tile<const FUSED: bool>(
    ta: usize,
    kind: Tile,
    a: &[f64],
    b: &[f64],
    w: usize,
    cols: (usize, usize),
    acc: &mut [f64],
) {
    // Row pairs (and the fifth row alone) against the columns each needs.
    for r0 in (0..ta).step_by(2) {
        let two = r0 + 1 < ta;
        let (s0, s1) = match kind {
            Tile::Full => (0, TB),
            Tile::Upper => (r0, TB),
            Tile::Narrow(s) => (0, s),
        };
        let acc = &mut *acc;
        macro_rules! go {
            ($r:literal, $s:literal) => {
                sub_tile::<$r, $s, FUSED>(a, b, w, (r0, s0), cols, acc)
            };
        }
        match (two, s1 - s0) {
            (true, 5) => go!(2, 5),
            (true, 4) => go!(2, 4),
            (true, 3) => go!(2, 3),
            (true, 2) => go!(2, 2),
            (true, _) => go!(2, 1),
            (false, 5) => go!(1, 5),
            (false, 4) => go!(1, 4),
            (false, 3) => go!(1, 3),
            (false, 2) => go!(1, 2),
            (false, _) => go!(1, 1),
        }
    }
}

/// Rows `r0..r0 + R` of `a` against rows `s0..s0 + S` of `b`, four lanes at a time.
#[inline(always)]
fn sub_tile<const R: usize, const S: usize, const FUSED: bool>(
    a: &[f64],
    b: &[f64],
    w: usize,
    (r0, s0): (usize, usize),
    (k0, k1): (usize, usize),
    acc: &mut [f64],
) {
    let groups = (k1 - k0) / LANES;
    fn row(m: &[f64], from: usize, groups: usize) -> &[[f64; LANES]] {
        m[from..].as_chunks::<LANES>().0.get(..groups).expect("rows inside the block")
    }
    let ar: [&[[f64; LANES]]; R] = std::array::from_fn(|r| row(a, (r0 + r) * w + k0, groups));
    let br: [&[[f64; LANES]]; S] = std::array::from_fn(|s| row(b, (s0 + s) * w + k0, groups));
    let at = |r: usize, s: usize| ((r0 + r) * TB + s0 + s) * LANES;
    for h in [0, 4] {
        let mut v = [[[0f64; 4]; S]; R];
        for r in 0..R {
            for s in 0..S {
                v[r][s].copy_from_slice(&acc[at(r, s) + h..at(r, s) + h + 4]);
            }
        }
        for g in 0..groups {
            let av: [[f64; 4]; R] = std::array::from_fn(|r| {
                let x = &ar[r][g];
                [x[h], x[h + 1], x[h + 2], x[h + 3]]
            });
            for s in 0..S {
                let x = &br[s][g];
                let bs = [x[h], x[h + 1], x[h + 2], x[h + 3]];
                for r in 0..R {
                    for l in 0..4 {
                        v[r][s][l] = madd::<FUSED>(av[r][l], bs[l], v[r][s][l]);
                    }
                }
            }
        }
        for r in 0..R {
            for s in 0..S {
                acc[at(r, s) + h..at(r, s) + h + 4].copy_from_slice(&v[r][s]);
            }
        }
    }
}

/// Components per lift group: four, over eight columns (eight 256-bit partial sums).
const LIFT_GROUP: usize = 4;

/// `out[k·ldo + t] = Σ_i coef[i·cp + k0 + k]·y_i[t]` for `k < step` (a multiple of 4) and
/// every column `t < w` of the `n` rows of `y` (`w` apart), summed over `i` in order: the
/// lift of `lift_rows32_with`.
#[inline(always)]
pub(super) fn lift<const FUSED: bool>(
    y: &[f32],
    n: usize,
    w: usize,
    coef: &[f64],
    (cp, k0, step): (usize, usize, usize),
    out: &mut [f64],
    ldo: usize,
) {
    assert!(y.len() >= n * w && w.is_multiple_of(LANES) && step.is_multiple_of(LIFT_GROUP));
    assert!(coef.len() >= n * cp && k0 + step <= cp);
    assert!(step == 0 || out.len() >= (step - 1) * ldo + w);
    for kg in (0..step).step_by(LIFT_GROUP) {
        for t in (0..w).step_by(LANES) {
            let mut v = [[0f64; LANES]; LIFT_GROUP];
            for i in 0..n {
                let yi: &[f32; LANES] = y[i * w + t..i * w + t + LANES].try_into().unwrap();
                let c: &[f64; LIFT_GROUP] =
                    coef[i * cp + k0 + kg..i * cp + k0 + kg + LIFT_GROUP].try_into().unwrap();
                for k in 0..LIFT_GROUP {
                    for l in 0..LANES {
                        v[k][l] = madd::<FUSED>(c[k], yi[l] as f64, v[k][l]);
                    }
                }
            }
            for k in 0..LIFT_GROUP {
                out[(kg + k) * ldo + t..(kg + k) * ldo + t + LANES].copy_from_slice(&v[k]);
            }
        }
    }
}

/// A tile of `panel.rs` in the lane model: rows `0..MR` of the packed `a` (`lda` values
/// per column) against rows `0..N` of `b` (packed, `b[k·ldb + j]`, or with `ROWS` row by
/// row, `b[j·ldb + k]`) over `kc` columns, one `f32` lane per output from zero, added in
/// `f64` to `s[j·lds + i]`.
#[inline(always)]
pub(super) fn panel_tile<const MR: usize, const N: usize, const ROWS: bool, const FUSED: bool>(
    (a, lda): (&[f32], usize),
    (b, ldb): (&[f32], usize),
    kc: usize,
    (s, lds): (&mut [f64], usize),
) {
    let mut acc = [[0f32; MR]; N];
    for k in 0..kc {
        let av: &[f32; MR] = a[k * lda..k * lda + MR].try_into().unwrap();
        let bv: [f32; N] =
            std::array::from_fn(|j| if ROWS { b[j * ldb + k] } else { b[k * ldb + j] });
        for j in 0..N {
            for l in 0..MR {
                acc[j][l] = madd32::<FUSED>(av[l], bv[j], acc[j][l]);
            }
        }
    }
    for (j, lanes) in acc.iter().enumerate() {
        for (o, &v) in s[j * lds..j * lds + MR].iter_mut().zip(lanes) {
            *o += v as f64;
        }
    }
}

/// `f32` lanes per output of the scalar path's dot-product tiles.
const LANES32: usize = 16;

/// The scalar path's `f32` products (`panel.rs`), as dot products along the columns:
/// `out[r·rs + s·ss] += Σ_l Σ_t e_r[16t + l]·y_s[16t + l]` for the 4 rows of `e` and
/// `s_count ≤ 5` of `y` (`w` values apart, `w` a multiple of 16), unfused, in sixteen `f32`
/// lanes per output over the whole block, the lanes added in `f64` (lane `l` to `l + 8`,
/// then [`reduce8`]). Without fused multiply-adds, a broadcast costs two SSE2
/// instructions per four products, these tiles none: 16 % faster end to end than the
/// panels (and within the same bound: `w/16 ≤ 64` roundings a lane).
pub(super) fn dot_tile32(
    s_count: usize,
    e: &[f32],
    y: &[f32],
    w: usize,
    out: &mut [f64],
    (rs, ss): (usize, usize),
) {
    for r0 in [0, 2] {
        match s_count {
            1 => dot_sub_tile32::<1>(r0, e, y, w, out, (rs, ss)),
            2 => dot_sub_tile32::<2>(r0, e, y, w, out, (rs, ss)),
            3 => dot_sub_tile32::<3>(r0, e, y, w, out, (rs, ss)),
            4 => dot_sub_tile32::<4>(r0, e, y, w, out, (rs, ss)),
            _ => dot_sub_tile32::<5>(r0, e, y, w, out, (rs, ss)),
        }
    }
}

/// Rows `r0, r0 + 1` of `dot_tile32`, eight lanes at a time (two half sweeps).
#[inline(always)]
fn dot_sub_tile32<const S: usize>(
    r0: usize,
    e: &[f32],
    y: &[f32],
    w: usize,
    out: &mut [f64],
    (rs, ss): (usize, usize),
) {
    let groups = w / LANES32;
    fn row(m: &[f32], from: usize, groups: usize) -> &[[f32; LANES32]] {
        m[from..].as_chunks::<LANES32>().0.get(..groups).expect("rows inside the block")
    }
    let er: [&[[f32; LANES32]]; 2] = std::array::from_fn(|r| row(e, (r0 + r) * w, groups));
    let yr: [&[[f32; LANES32]]; S] = std::array::from_fn(|s| row(y, s * w, groups));
    let mut lanes = [[[0f32; LANES32]; S]; 2];
    for h in [0, 8] {
        let mut v = [[[0f32; 8]; S]; 2];
        for g in 0..groups {
            let ev: [[f32; 8]; 2] = std::array::from_fn(|r| er[r][g][h..h + 8].try_into().unwrap());
            for s in 0..S {
                let ys: &[f32; 8] = yr[s][g][h..h + 8].try_into().unwrap();
                for r in 0..2 {
                    for l in 0..8 {
                        v[r][s][l] = madd32::<false>(ev[r][l], ys[l], v[r][s][l]);
                    }
                }
            }
        }
        for r in 0..2 {
            for s in 0..S {
                lanes[r][s][h..h + 8].copy_from_slice(&v[r][s]);
            }
        }
    }
    for r in 0..2 {
        for s in 0..S {
            let l = &lanes[r][s];
            out[(r0 + r) * rs + s * ss] +=
                reduce8(std::array::from_fn(|i| l[i] as f64 + l[i + 8] as f64));
        }
    }
}
