//! Single-precision products of the per-slot PCA ([S03 eq. 1]): the Gram matrix `YYᵀ` of
//! `f16` data ([`GramAcc32`]), and `E·Yᵀ`, the projections of the images on the rounding
//! error `E = S − B` of the stored (`f16`) eigentextures. `E` is at most `2⁻¹¹` of an entry
//! of `B`, so its products need a relative precision of about `2⁻¹¹` less than the rest: in
//! `f32` they cost half the instructions of `f64`. Every output sums chunks of
//! [`CHUNK32`] columns in one `f32` lane each and the chunks in `f64` (`panel.rs`). The
//! images enter widened to `f32` (exact for `f32` and `f16` data) or as a `f64` block
//! rounded to `f32` (a relative change of `2⁻²⁴`).

use super::panel::PanelSums;
use super::{Block, Texel, runnable};
use crate::simd::Isa;

/// `f32` lanes of one AVX-512 register: the row pitch of a [`Block32`] is a multiple.
pub const LANES32: usize = 16;
pub use super::panel::CHUNK as CHUNK32;

/// Rows of `f32` values over one block of columns; like [`Block`], the columns past the
/// width and [`Block32::PAD_ROWS`] rows past the last are zero.
#[derive(Debug, Default, Clone)]
pub struct Block32 {
    /// The values, row-major.
    pub data: Vec<f32>,
    /// Rows in use.
    pub rows: usize,
    /// Columns in use.
    pub width: usize,
    /// Columns per row (a multiple of [`LANES32`]).
    pub stride: usize,
}

impl Block32 {
    /// Zero rows kept after the last one.
    pub const PAD_ROWS: usize = 5;

    /// Reshapes to `rows × width` (zeroed when the shape changes or the width is ragged).
    pub fn shape(&mut self, rows: usize, width: usize) {
        let stride = super::padded_stride(width.div_ceil(LANES32) * LANES32, LANES32);
        self.width = width;
        if rows != self.rows || stride != self.stride || !width.is_multiple_of(LANES32) {
            self.rows = rows;
            self.stride = stride;
            self.data.clear();
            self.data.resize((rows + Self::PAD_ROWS) * stride, 0.0);
        }
    }

    /// Row `i` (all `stride` columns).
    pub fn row_mut(&mut self, i: usize) -> &mut [f32] {
        &mut self.data[i * self.stride..(i + 1) * self.stride]
    }

    /// Columns `c0..c0 + width` of every row of `x`, widened to `f32` (exact for `f32` and
    /// `f16` data).
    pub fn widen_from<T: Texel>(&mut self, x: &[&[T]], c0: usize, width: usize) {
        self.widen_from_with(x, c0, width, Isa::active());
    }

    /// [`Block32::widen_from`] on the path `isa`.
    pub(crate) fn widen_from_with<T: Texel>(
        &mut self,
        x: &[&[T]],
        c0: usize,
        width: usize,
        isa: Isa,
    ) {
        self.shape(x.len(), width);
        let isa = runnable(isa);
        for (i, row) in x.iter().enumerate() {
            let from = &row[c0..c0 + width];
            let to = &mut self.data[i * self.stride..i * self.stride + width];
            match isa {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: AVX-512F checked (`runnable`); the function is safe code.
                Isa::Avx512 => unsafe { super::avx512::widen_to_f32(from, to) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: AVX2, FMA and F16C checked (`runnable`); the function is safe code.
                Isa::Avx2 => unsafe { super::avx2::widen_to_f32(from, to) },
                _ => super::widen_portable(from, to),
            }
        }
    }

    /// The first `width` columns of every row of `src`, rounded to `f32`.
    pub fn round_from(&mut self, src: &Block, width: usize) {
        self.shape(src.rows, width);
        let avx512 = Isa::active() == Isa::Avx512;
        for i in 0..src.rows {
            let from = &src.data[i * src.stride..i * src.stride + width];
            let to = &mut self.data[i * self.stride..i * self.stride + width];
            if avx512 {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the active path is supported, so AVX-512F is there.
                unsafe {
                    super::avx512::round_to_f32(from, to)
                };
            } else {
                to.iter_mut().zip(from).for_each(|(t, &f)| *t = f as f32);
            }
        }
    }
}

/// Accumulates `E·Yᵀ` (`e_rows × y_rows`) block by block: `f32` sums within a chunk of
/// columns, `f64` across chunks and blocks (`panel.rs`).
#[derive(Debug, Clone)]
pub struct CrossAcc32 {
    sums: PanelSums,
}

impl CrossAcc32 {
    /// For `e_rows × y_rows` outputs.
    pub fn new(e_rows: usize, y_rows: usize) -> Self {
        CrossAcc32 { sums: PanelSums::new(e_rows, y_rows, false) }
    }

    /// Adds the products of one block of columns (`e` and `y` of the rows given to
    /// [`CrossAcc32::new`] and the same width).
    pub fn add(&mut self, e: &Block32, y: &Block32) {
        self.add_with(e, y, Isa::active());
    }

    /// [`CrossAcc32::add`] on the path `isa`.
    pub(crate) fn add_with(&mut self, e: &Block32, y: &Block32, isa: Isa) {
        self.sums.add(e, Some(y), runnable(isa));
    }

    /// `out[i·ldo + j] = Σ e_i·y_j` over every block added.
    pub fn finish(&self, out: &mut [f64], ldo: usize) {
        let (m, n) = (self.sums.a_rows(), self.sums.b_rows());
        assert!(ldo >= n && (m == 0 || out.len() >= (m - 1) * ldo + n));
        for i in 0..m {
            for j in 0..n {
                out[i * ldo + j] = self.sums.get(i, j);
            }
        }
    }
}

/// Accumulates the upper triangle of the Gram matrix `Y·Yᵀ` of the rows of one block after
/// another, as [`CrossAcc32`] does `E·Yᵀ` (the same tiles: `f32` sums of at most
/// [`CHUNK32`] products, `f64` across chunks): each entry is within `(CHUNK32 + 2)·2⁻²⁴`
/// of the sum of its products' magnitudes — for `f16` data, whose values carry 11
/// significant bits, far below the data's own precision — at twice the lanes of `f64`
/// ([`crate::pca::GramPrecision`]). Panels of 8 rows (16 on AVX-512) are multiplied with
/// the rows from their first on (3 608 products a column for 81 rows, 3 936 on AVX-512;
/// 3 321 are needed).
#[derive(Debug, Clone)]
pub struct GramAcc32 {
    sums: PanelSums,
}

impl GramAcc32 {
    /// For the Gram matrix of `rows` rows.
    pub fn new(rows: usize) -> Self {
        GramAcc32 { sums: PanelSums::new(rows, rows, true) }
    }

    /// Adds the products of one block of columns (of the rows given to [`GramAcc32::new`]).
    pub fn add(&mut self, y: &Block32) {
        self.add_with(y, Isa::active());
    }

    /// [`GramAcc32::add`] on the path `isa`.
    pub(crate) fn add_with(&mut self, y: &Block32, isa: Isa) {
        self.sums.add(y, None, runnable(isa));
    }

    /// `out[i·ldo + j] += Σ_t y_i[t]·y_j[t]` over every block added, for `j ≥ i` (the
    /// other entries are left alone).
    pub fn finish(&self, out: &mut [f64], ldo: usize) {
        let n = self.sums.a_rows();
        assert!(ldo >= n && (n == 0 || out.len() >= (n - 1) * ldo + n));
        for i in 0..n {
            for j in i..n {
                out[i * ldo + j] += self.sums.get(i, j);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paths the tests run: those this CPU supports, and NEON (portable code).
    fn paths() -> Vec<Isa> {
        let mut p = Isa::supported_all();
        if !p.contains(&Isa::Neon) {
            p.push(Isa::Neon);
        }
        p
    }

    #[test]
    fn gram_matches_f64_sums_within_its_bound_on_every_path_and_the_simd_paths_agree_bitwise() {
        // 13 rows (panels of 8 and 16 rows, partial; tiles of 12 and fewer), three blocks
        // of 1024, 200 and 75 columns (chunks of 64, a last one of 8, and 11: 8 columns
        // transposed and 3 copied) of values of mixed sign and magnitude.
        let n = 13;
        let val = |i: usize, t: usize| {
            let v = ((i * 7919 + t * 104_729) % 1009) as f64 / 1009.0 - 0.45;
            (v * (1.0 + (t % 5) as f64)) as f32
        };
        let mut first: Option<Vec<f64>> = None;
        for isa in paths() {
            let mut acc = GramAcc32::new(n);
            let (mut want, mut abs) = (vec![0f64; n * n], vec![0f64; n * n]);
            let mut longest = 0;
            for (c0, w) in [(0, 1024), (1024, 200), (1224, 75)] {
                let mut y = Block32::default();
                y.shape(n, w);
                for i in 0..n {
                    for t in 0..w {
                        y.row_mut(i)[t] = val(i, c0 + t);
                    }
                }
                for i in 0..n {
                    for j in 0..n {
                        for t in 0..w {
                            let p = val(i, c0 + t) as f64 * val(j, c0 + t) as f64;
                            want[i * n + j] += p;
                            abs[i * n + j] += p.abs();
                        }
                    }
                }
                acc.add_with(&y, isa);
                longest = longest.max(w.min(CHUNK32));
            }
            let mut out = vec![f64::NAN; n * n];
            for i in 0..n {
                for j in i..n {
                    out[i * n + j] = 0.0;
                }
            }
            acc.finish(&mut out, n);
            for i in 0..n {
                for j in 0..n {
                    let o = out[i * n + j];
                    if j < i {
                        assert!(o.is_nan(), "{isa}: lower entry ({i}, {j}) written");
                        continue;
                    }
                    // At most `longest` rounded f32 steps a chunk (fused or not: a product
                    // and a sum rounded once each, or the sum of the rounded product),
                    // then f64 sums.
                    let tol = (longest + 2) as f64 * f32::EPSILON as f64 / 2.0 * abs[i * n + j];
                    let e = (o - want[i * n + j]).abs();
                    assert!(e <= tol, "{isa} ({i}, {j}): {o} vs {} (tol {tol})", want[i * n + j]);
                }
            }
            if isa != Isa::Scalar {
                match &first {
                    None => first = Some(out),
                    Some(f) => {
                        let same = f.iter().zip(&out).all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "{isa} differs from the other SIMD paths")
                    }
                }
            }
        }
    }

    #[test]
    fn cross_products_match_f64_sums_on_every_path_and_the_simd_paths_agree_bitwise() {
        // 10 E rows (one 8-row transposition group and 2 copied; a partial panel), 14 Y
        // rows (tiles of 7 and 7), blocks of 48 and 43 columns (one chunk each; the second
        // with 3 columns past the transposition's 8 × 8 blocks).
        let (ne, ny) = (10, 14);
        let val = |i: usize, t: usize, k: f64| ((i * 131 + t * 17) % 97) as f64 / 97.0 - k;
        let mut first: Option<Vec<f64>> = None;
        for isa in paths() {
            let mut acc = CrossAcc32::new(ne, ny);
            let (mut want, mut abs) = (vec![0f64; ne * ny], vec![0f64; ne * ny]);
            for (c0, w) in [(0, 48), (48, 43)] {
                let (mut e, mut y) = (Block32::default(), Block32::default());
                e.shape(ne, w);
                y.shape(ny, w);
                for t in 0..w {
                    for i in 0..ne {
                        e.row_mut(i)[t] = (val(i, c0 + t, 0.5) * 1e-3) as f32;
                    }
                    for j in 0..ny {
                        y.row_mut(j)[t] = val(j + 50, c0 + t, 0.3) as f32;
                    }
                }
                for i in 0..ne {
                    for j in 0..ny {
                        for t in 0..w {
                            let p =
                                e.data[i * e.stride + t] as f64 * y.data[j * y.stride + t] as f64;
                            want[i * ny + j] += p;
                            abs[i * ny + j] += p.abs();
                        }
                    }
                }
                acc.add_with(&e, &y, isa);
            }
            let mut out = vec![0f64; ne * ny];
            acc.finish(&mut out, ny);
            for (k, o) in out.iter().enumerate() {
                // f32 sums of at most 48 products a chunk: within (48 + 2)·2⁻²⁴ of Σ|e·y|
                // (the f64 sum of the chunks and the naive sum add less).
                let tol = 50.0 * f32::EPSILON as f64 / 2.0 * abs[k] * 1.01;
                assert!((o - want[k]).abs() <= tol, "{isa} output {k}: {o} vs {}", want[k]);
            }
            if isa != Isa::Scalar {
                match &first {
                    None => first = Some(out),
                    Some(f) => assert!(*f == out, "{isa} differs from the other SIMD paths"),
                }
            }
        }
    }
}
