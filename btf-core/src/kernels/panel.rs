//! Outer-product tiles of the single-precision products of the per-slot PCA ([S03 eq. 1]):
//! the Gram matrix `YYᵀ` of `f16` data and the cross products `E·Yᵀ` ([`super::GramAcc32`],
//! [`super::CrossAcc32`]).
//!
//! A block's columns are taken in chunks of [`CHUNK`]. Each chunk of `A` is first copied
//! column by column ("packed": `pack[k·ld + i] = a_i[k0 + k]`), so that one vector load
//! gives one column of a panel of rows of `A` (8 `f32` lanes on AVX2 and NEON, 16 on
//! AVX-512), and each value of `B` is broadcast — from the same packed chunk for a Gram
//! matrix (`B = A`), from `B`'s rows for a product: per column, one load, then one
//! broadcast and one fused multiply-add per output of a tile of 8 (16) × [`NR`] outputs
//! held in registers. An output's sum over a chunk is therefore one `f32` lane adding the
//! chunk's products in column order from zero, and the chunk sums are added in `f64`, in
//! chunk order. That arithmetic does not depend on the panel or tile shape: every SIMD
//! path gives the same bits, and each output is within `(CHUNK + 2)·2⁻²⁴` of the sum of
//! its products' magnitudes (`CHUNK` roundings of the sum, two of the operands' rounding
//! to `f32`), the bound [`crate::pca::GRAM32_EPS`] states. The scalar path, which has no
//! fused multiply-add and pays two SSE2 instructions per broadcast, keeps the dot products
//! along the columns instead (`lanes::dot_tile32`: sixteen lanes over a block of at most
//! 1024 columns, so at most 64 roundings a lane, the same bound), and agrees within it.
//!
//! Why not lanes along the columns, as the `f64` tiles (`lanes.rs`) and, until session 27,
//! these did: a dot product of two rows costs two loads per multiply-add unless a tile of
//! outputs reuses them, and a tile of `4 × 5` outputs of sixteen lanes needs forty 256-bit
//! registers (AVX2 has sixteen), so the AVX2 tiles swept the columns twice, in halves of
//! 2 × 5 outputs, and ran at half the core's multiply-add peak. Here a tile needs
//! [`NR`] + 2 registers, the packed chunk (`96 × 64` values with its padding rows, 24 KB)
//! stays in the L1 cache for every tile, and the packing costs one transposition per
//! value: for the Gram matrix of 81 rows, 81 values moved against 3 321 multiply-adds a
//! column (15 % of its time in `examples/gram_rate.rs`'s profile).

use super::{Block32, lanes, runnable};
use crate::simd::Isa;

/// Columns per chunk: an output's `f32` lane sums this many products before the chunk's
/// sum is added to its `f64` total.
pub const CHUNK: usize = 64;
/// Outputs of a tile along `B` (broadcast operands).
pub(super) const NR: usize = 12;
/// Rows of `A` per panel on the AVX-512 path (and the padding of a packed chunk's rows).
const PANEL_WIDE: usize = 16;

/// Rows of `A` per panel and outputs per tile on the path `isa`: a register of `f32`
/// rows (16 on AVX-512, 8 on AVX2) times [`NR`]; 8 × 12 in NEON's 32 registers of 4
/// lanes. (The scalar path does not use panels: [`PanelSums::add_scalar`].)
fn panel_shape(isa: Isa) -> (usize, usize) {
    match isa {
        Isa::Avx512 => (PANEL_WIDE, NR),
        _ => (8, NR),
    }
}

/// `Σ a_i·b_j` over the columns of every block added, for the rows `i` of `A` and `j` of
/// `B` a product asks for, summed as the module says. The sums are kept as `sums[j·ld + i]`
/// (the lanes of a register are rows `i` of one output column `j`).
#[derive(Debug, Clone)]
pub(super) struct PanelSums {
    a_rows: usize,
    b_rows: usize,
    /// Rows of `A` rounded up to [`PANEL_WIDE`]: the pitch of `sums` and of `pack_a`.
    ld: usize,
    /// Only outputs with `j ≥ i` (and `A = B`): the upper triangle of a Gram matrix.
    upper: bool,
    sums: Vec<f64>,
    pack_a: Vec<f32>,
}

impl PanelSums {
    /// For `A·Bᵀ` with `a_rows` and `b_rows` rows, or with `upper` the upper triangle of
    /// `A·Aᵀ` (`a_rows == b_rows`, and `B` is not passed to [`PanelSums::add`]).
    pub(super) fn new(a_rows: usize, b_rows: usize, upper: bool) -> Self {
        assert!(!upper || a_rows == b_rows, "a Gram matrix is square");
        let ld = a_rows.div_ceil(PANEL_WIDE) * PANEL_WIDE;
        PanelSums {
            a_rows,
            b_rows,
            ld,
            upper,
            sums: vec![0.0; b_rows * ld],
            pack_a: vec![0.0; CHUNK * ld],
        }
    }

    /// Adds the products over the columns of one block: `a` (and `b`, unless `upper`) with
    /// the rows and width the product was made for.
    pub(super) fn add(&mut self, a: &Block32, b: Option<&Block32>, isa: Isa) {
        assert_eq!(a.rows, self.a_rows, "a block of other rows");
        assert_eq!(b.is_none(), self.upper, "a Gram matrix takes one block, a product two");
        if let Some(b) = b {
            assert_eq!(b.rows, self.b_rows, "a block of other rows");
            assert_eq!(a.width, b.width, "blocks of different widths");
        }
        let isa = runnable(isa);
        if isa == Isa::Scalar {
            return self.add_scalar(a, b);
        }
        let (mr, nr_most) = panel_shape(isa);
        let ld = self.ld;
        for k0 in (0..a.width).step_by(CHUNK) {
            let kc = CHUNK.min(a.width - k0);
            pack(a, k0, kc, &mut self.pack_a, ld, isa);
            for i0 in (0..self.a_rows).step_by(mr) {
                let j_first = if self.upper { i0 } else { 0 };
                // The rows from j_first on in tiles of near-equal size (73 rows: 11, 11, 11,
                // 10, 10, 10, 10, not six of 12 and one of 1, whose one chain of sums would
                // wait on every multiply-add's latency).
                let rest = self.b_rows - j_first;
                let tiles = rest.div_ceil(nr_most);
                let mut j0 = j_first;
                for t in 0..tiles {
                    let nr = rest / tiles + usize::from(t < rest % tiles);
                    let (a, s) = (&self.pack_a[i0..], &mut self.sums[j0 * ld + i0..]);
                    // A Gram matrix's B is the packed chunk; a product's, the rows of `b`.
                    let b = match b {
                        None => Operand::Packed(&self.pack_a[j0..], ld),
                        Some(b) => Operand::Rows(&b.data[j0 * b.stride + k0..], b.stride),
                    };
                    tile(isa, nr, (a, ld), b, kc, (s, ld));
                    j0 += nr;
                }
            }
        }
    }

    /// [`PanelSums::add`] on the scalar path: dot products along the columns in tiles of
    /// 4 × 5 outputs (`lanes::dot_tile32`), each block's sixteen lanes added into `f64`.
    fn add_scalar(&mut self, a: &Block32, b: Option<&Block32>) {
        let (w, ld) = (a.stride, self.ld);
        let bd = b.map_or(&a.data, |b| &b.data);
        assert!(b.is_none_or(|b| b.stride == w), "blocks of different pitches");
        // Rows past `a_rows` (up to 3 of them, read as whole tiles) are the block's zero
        // padding rows; their sums land in `sums`'s padding lanes.
        assert!(a.data.len() >= a.rows.div_ceil(4) * 4 * w && bd.len() >= self.b_rows * w);
        for i0 in (0..self.a_rows).step_by(4) {
            let e = &a.data[i0 * w..(i0 + 4) * w];
            let mut j = if self.upper { i0 } else { 0 };
            while j < self.b_rows {
                let s = 5.min(self.b_rows - j);
                let out = &mut self.sums[j * ld + i0..];
                lanes::dot_tile32(s, e, &bd[j * w..(j + s) * w], w, out, (1, ld));
                j += s;
            }
        }
    }

    /// Rows of `A`.
    pub(super) fn a_rows(&self) -> usize {
        self.a_rows
    }

    /// Rows of `B`.
    pub(super) fn b_rows(&self) -> usize {
        self.b_rows
    }

    /// The sum for row `i` of `A` and row `j` of `B` (for `upper`, `j ≥ i`).
    #[inline]
    pub(super) fn get(&self, i: usize, j: usize) -> f64 {
        debug_assert!(i < self.a_rows && j < self.b_rows && (!self.upper || j >= i));
        self.sums[j * self.ld + i]
    }
}

/// `pack[k·ld + i] = x_i[k0 + k]` for `k < kc` and every row `i` of `x` (8 × 8
/// transpositions on x86-64 with AVX2, value by value elsewhere: the same values).
fn pack(x: &Block32, k0: usize, kc: usize, pack: &mut [f32], ld: usize, isa: Isa) {
    assert!(pack.len() >= kc * ld && x.rows <= ld && k0 + kc <= x.width);
    let (rows, w) = (x.rows, x.stride);
    // The rows and columns done in 8 × 8 blocks; the rest value by value.
    let x86 = cfg!(target_arch = "x86_64") && matches!(isa, Isa::Avx2 | Isa::Avx512);
    let (i_done, k_done) = if x86 { (rows - rows % 8, kc - kc % 8) } else { (0, 0) };
    #[cfg(target_arch = "x86_64")]
    if x86 {
        // SAFETY: AVX2 checked (`runnable`: both paths' CPUs have it); rows < i_done ≤ rows
        // of x at columns k0.. + k_done ≤ width ≤ stride, and pack columns < k_done ≤ kc of
        // rows < i_done ≤ ld (asserted above).
        unsafe {
            super::avx2::transpose(
                x.data.as_ptr().add(k0),
                w,
                (i_done, k_done),
                pack.as_mut_ptr(),
                ld,
            )
        }
    }
    for i in 0..rows {
        let row = &x.data[i * w + k0..i * w + k0 + kc];
        let from = if i < i_done { k_done } else { 0 };
        for (k, &v) in row.iter().enumerate().skip(from) {
            pack[k * ld + i] = v;
        }
    }
}

/// The broadcast operand of a tile: `B` packed (`b[k·ld + j]`) or its rows (`b[j·ld + k]`).
#[derive(Clone, Copy)]
enum Operand<'a> {
    Packed(&'a [f32], usize),
    Rows(&'a [f32], usize),
}

/// One tile on the path `isa`: rows `0..mr` of the packed `a` against rows `0..nr` of `b`
/// over `kc` columns, the sums added to `s[j·lds + i]`.
fn tile(
    isa: Isa,
    nr: usize,
    (a, lda): (&[f32], usize),
    b: Operand,
    kc: usize,
    (s, lds): (&mut [f64], usize),
) {
    let mr = panel_shape(isa).0;
    assert!((1..=NR).contains(&nr) && kc >= 1);
    let (rows, b, ldb) = match b {
        Operand::Packed(b, ld) => (false, b, ld),
        Operand::Rows(b, ld) => (true, b, ld),
    };
    let b_last = if rows { (nr - 1) * ldb + kc - 1 } else { (kc - 1) * ldb + nr - 1 };
    assert!(a.len() > (kc - 1) * lda + mr - 1 && b.len() > b_last);
    assert!(s.len() > (nr - 1) * lds + mr - 1);
    macro_rules! each_nr {
        ($f:ident, $m:ident) => {
            match nr {
                1 => $f!($m, 1),
                2 => $f!($m, 2),
                3 => $f!($m, 3),
                4 => $f!($m, 4),
                5 => $f!($m, 5),
                6 => $f!($m, 6),
                7 => $f!($m, 7),
                8 => $f!($m, 8),
                9 => $f!($m, 9),
                10 => $f!($m, 10),
                11 => $f!($m, 11),
                _ => $f!($m, 12),
            }
        };
    }
    // The intrinsics of the module `$m` (`avx2`, `avx512`).
    #[cfg(target_arch = "x86_64")]
    let (ap, bp, sp) = (a.as_ptr(), b.as_ptr(), s.as_mut_ptr());
    #[cfg(target_arch = "x86_64")]
    macro_rules! simd {
        ($m:ident, $n:literal) => {
            // SAFETY: the path's features checked (`runnable`: AVX-512F, or AVX2 and FMA);
            // the extents are asserted above.
            unsafe {
                if rows {
                    super::$m::panel_tile::<$n, true>(ap, lda, bp, ldb, kc, sp, lds)
                } else {
                    super::$m::panel_tile::<$n, false>(ap, lda, bp, ldb, kc, sp, lds)
                }
            }
        };
    }
    // The lane model, fused (NEON; on x86 the tests' NEON path).
    macro_rules! portable {
        ($m:ident, $n:literal) => {
            if rows {
                $m::panel_tile::<8, $n, true, true>((a, lda), (b, ldb), kc, (s, lds))
            } else {
                $m::panel_tile::<8, $n, false, true>((a, lda), (b, ldb), kc, (s, lds))
            }
        };
    }
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => each_nr!(simd, avx512),
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => each_nr!(simd, avx2),
        _ => each_nr!(portable, lanes),
    }
}
