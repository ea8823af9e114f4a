//! The dot-product accumulator of the per-slot PCA ([S03 eq. 1], by the
//! snapshot method): `A·Bᵀ` block by block of columns, for the Gram matrix `YYᵀ`, the
//! stored basis's `SSᵀ` and (for 8-bit storage) the correction `E·Yᵀ`, in `f64` tiles of
//! 5 × 5 (or 4 × 5) outputs, narrower at the edge and triangular on a symmetric diagonal.

use super::{Block, LANES, SUB_BLOCK, TB, lanes, runnable};
#[cfg(target_arch = "x86_64")]
use super::{avx2, avx512};
use crate::simd::Isa;

/// What one tile of [`DotAcc`] computes of its `ta × 5` outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Tile {
    /// All of them.
    Full,
    /// Those with `s ≥ r` (a diagonal tile of a symmetric product): 15 of 25.
    Upper,
    /// The first `s < 5` columns (the rows of `B` past the last multiple of 5).
    Narrow(usize),
}

/// Accumulates `A·Bᵀ` block by block of columns: each output keeps one register's worth
/// ([`LANES`]) of partial sums across blocks, reduced only by [`DotAcc::finish`], so a tile
/// of `R × 5` outputs is loaded, updated over the block's columns and stored back, and the
/// rows of `A` stay in the L1 cache while those of `B` stream past. The rows of `B` past
/// the last multiple of 5 get narrower tiles, and a symmetric product's diagonal tiles
/// compute only their upper triangle, so that 81 rows cost 3325 products per column rather
/// than the 3825 of whole 5 × 5 tiles (3321 are needed).
#[derive(Debug, Clone)]
pub struct DotAcc {
    a_rows: usize,
    b_rows: usize,
    upper: bool,
    /// Rows of `A` per tile (4 or 5).
    ta: usize,
    /// Top-left output and kind of every tile.
    tiles: Vec<(usize, usize, Tile)>,
    /// `LANES` partial sums per output, tile after tile.
    partial: Vec<f64>,
}

impl DotAcc {
    /// For `a_rows × b_rows` outputs; with `upper`, only `j ≥ i` (a symmetric product's
    /// upper triangle, `A` and `B` the same rows).
    pub fn new(a_rows: usize, b_rows: usize, upper: bool) -> Self {
        let ta = if a_rows <= 16 && a_rows.is_multiple_of(4) { 4 } else { TB };
        let mut tiles = Vec::new();
        let b_whole = b_rows / TB * TB;
        for i0 in (0..a_rows).step_by(ta) {
            if upper && ta != TB {
                // 4-row tiles do not line up with the 5-column ones: whole tiles from i0.
                tiles.extend((i0..b_rows).step_by(TB).map(|j0| (i0, j0, Tile::Full)));
                continue;
            }
            let j_start = if upper { i0 } else { 0 };
            for j0 in (j_start..b_whole).step_by(TB) {
                tiles.push((i0, j0, if upper && j0 == i0 { Tile::Upper } else { Tile::Full }));
            }
            if b_whole < b_rows {
                tiles.push((i0, b_whole, Tile::Narrow(b_rows - b_whole)));
            }
        }
        let partial = vec![0f64; tiles.len() * ta * TB * LANES];
        DotAcc { a_rows, b_rows, upper, ta, tiles, partial }
    }

    /// Adds the products of one block of columns.
    pub fn add(&mut self, a: &Block, b: &Block) {
        self.add_with(a, b, Isa::active());
    }

    /// [`DotAcc::add`] on the path `isa`.
    pub(crate) fn add_with(&mut self, a: &Block, b: &Block, isa: Isa) {
        assert_eq!((a.rows, b.rows), (self.a_rows, self.b_rows), "blocks of other shapes");
        assert_eq!(a.stride, b.stride, "blocks of different widths");
        let (w, ta) = (a.stride, self.ta);
        assert!(a.data.len() >= a.rows.div_ceil(ta) * ta * w, "block a lacks padding rows");
        assert!(b.data.len() >= b.rows.div_ceil(TB) * TB * w, "block b lacks padding rows");
        let isa = runnable(isa);
        let per_tile = ta * TB * LANES;
        // Sub-blocks of columns small enough for a tile's `A` rows to stay in L1.
        for k0 in (0..w).step_by(SUB_BLOCK) {
            let cols = (k0, (k0 + SUB_BLOCK).min(w));
            let tiles = self.tiles.iter().zip(self.partial.chunks_exact_mut(per_tile));
            for (&(i0, j0, kind), acc) in tiles {
                let ra = &a.data[i0 * w..(i0 + ta) * w];
                let rb = &b.data[j0 * w..(j0 + TB) * w];
                match isa {
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx512 => tile_avx512(ta, kind, ra, rb, w, cols, acc),
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: AVX2, FMA and F16C checked (`runnable`); the kernel is safe code.
                    Isa::Avx2 => unsafe { avx2::tile(ta, kind, ra, rb, w, cols, acc) },
                    Isa::Scalar => lanes::tile::<false>(ta, kind, ra, rb, w, cols, acc),
                    _ => lanes::tile::<true>(ta, kind, ra, rb, w, cols, acc),
                }
            }
        }
    }

    /// `out[i·ldo + j] += Σ_t a_i[t]·b_j[t]` over every block added (only `j ≥ i` with
    /// `upper`; other entries are left alone).
    pub fn finish(&self, out: &mut [f64], ldo: usize) {
        assert!(ldo >= self.b_rows, "output row stride smaller than b's rows");
        assert!(self.a_rows == 0 || out.len() >= (self.a_rows - 1) * ldo + self.b_rows);
        let per_tile = self.ta * TB * LANES;
        for (&(i0, j0, _), acc) in self.tiles.iter().zip(self.partial.chunks_exact(per_tile)) {
            for r in 0..self.ta {
                for s in 0..TB {
                    let (i, j) = (i0 + r, j0 + s);
                    if i < self.a_rows && j < self.b_rows && (!self.upper || j >= i) {
                        let lanes = &acc[(r * TB + s) * LANES..(r * TB + s + 1) * LANES];
                        out[i * ldo + j] += lanes.iter().sum::<f64>();
                    }
                }
            }
        }
    }
}

/// `lanes::tile` with AVX-512 intrinsics (checked by the caller's caller), one instance per
/// shape.
#[cfg(target_arch = "x86_64")]
fn tile_avx512(
    ta: usize,
    kind: Tile,
    a: &[f64],
    b: &[f64],
    w: usize,
    cols: (usize, usize),
    acc: &mut [f64],
) {
    assert!(a.len() >= ta * w && b.len() >= TB * w && w.is_multiple_of(LANES));
    assert!(cols.0 <= cols.1 && cols.1 <= w && cols.0.is_multiple_of(LANES));
    assert!(acc.len() >= ta * TB * LANES && (ta == 4 || ta == TB));
    {
        let (a, b, acc) = (a.as_ptr(), b.as_ptr(), acc.as_mut_ptr());
        // SAFETY: the caller checked AVX-512F at run time; the slices hold ta (4 or 5) and 5
        // rows of w values (w and the first column multiples of 8, the last ≤ w) and
        // ta·5·8 partial sums, so every access lies inside.
        unsafe {
            match (ta, kind) {
                (4, Tile::Full) => avx512::tile::<4, TB>(a, b, w, cols, acc),
                (4, Tile::Upper) => avx512::tile::<4, TB>(a, b, w, cols, acc),
                (4, Tile::Narrow(1)) => avx512::tile::<4, 1>(a, b, w, cols, acc),
                (4, Tile::Narrow(2)) => avx512::tile::<4, 2>(a, b, w, cols, acc),
                (4, Tile::Narrow(3)) => avx512::tile::<4, 3>(a, b, w, cols, acc),
                (4, Tile::Narrow(_)) => avx512::tile::<4, 4>(a, b, w, cols, acc),
                (_, Tile::Full) => avx512::tile::<TB, TB>(a, b, w, cols, acc),
                (_, Tile::Upper) => avx512::tile_upper(a, w, cols, acc),
                (_, Tile::Narrow(1)) => avx512::tile::<TB, 1>(a, b, w, cols, acc),
                (_, Tile::Narrow(2)) => avx512::tile::<TB, 2>(a, b, w, cols, acc),
                (_, Tile::Narrow(3)) => avx512::tile::<TB, 3>(a, b, w, cols, acc),
                (_, Tile::Narrow(_)) => avx512::tile::<TB, 4>(a, b, w, cols, acc),
            }
        }
    }
}
