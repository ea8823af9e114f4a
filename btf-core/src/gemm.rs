//! Safe, bounds-checked wrappers around `matrixmultiply`'s general matrix products, the
//! only dense kernels the PCA needs: `C ← α·A·B + β·C` for row-major slices, with either
//! operand optionally transposed through its strides.
#![allow(unsafe_code)]

/// A row-major `rows × cols` matrix view over a slice, optionally read transposed.
#[derive(Clone, Copy)]
pub struct Mat<'a, T> {
    /// The elements, row-major.
    pub data: &'a [T],
    /// Rows of the stored matrix.
    pub rows: usize,
    /// Columns of the stored matrix.
    pub cols: usize,
    /// Elements between the starts of consecutive rows (≥ `cols`).
    pub row_stride: usize,
    /// Read as its transpose.
    pub transposed: bool,
}

impl<'a, T> Mat<'a, T> {
    /// A view of `data` as `rows × cols`.
    pub fn new(data: &'a [T], rows: usize, cols: usize) -> Self {
        Self::strided(data, rows, cols, cols)
    }
    /// A view of `rows × cols` elements whose rows start `row_stride` elements apart (a
    /// block of columns of a wider row-major matrix).
    pub fn strided(data: &'a [T], rows: usize, cols: usize, row_stride: usize) -> Self {
        assert!(row_stride >= cols, "row stride smaller than the row");
        let need = if rows == 0 { 0 } else { (rows - 1) * row_stride + cols };
        assert!(data.len() >= need, "matrix view larger than its slice");
        Mat { data, rows, cols, row_stride, transposed: false }
    }
    /// The same view, transposed.
    pub fn t(self) -> Self {
        Mat { transposed: !self.transposed, ..self }
    }
    fn shape(&self) -> (usize, usize) {
        if self.transposed { (self.cols, self.rows) } else { (self.rows, self.cols) }
    }
    fn strides(&self) -> (isize, isize) {
        let rs = self.row_stride as isize;
        if self.transposed { (1, rs) } else { (rs, 1) }
    }
}

macro_rules! gemm_fn {
    ($name:ident, $t:ty, $kernel:path) => {
        /// `c ← alpha · a · b + beta · c`, with `c` row-major `m × n`.
        pub fn $name(alpha: $t, a: Mat<'_, $t>, b: Mat<'_, $t>, beta: $t, c: &mut [$t], n: usize) {
            let (m, k) = a.shape();
            let (k2, n2) = b.shape();
            assert_eq!(k, k2, "inner dimensions differ");
            assert_eq!(n, n2, "output columns differ");
            assert!(c.len() >= m * n, "output slice too small");
            if m == 0 || n == 0 {
                return;
            }
            let (rsa, csa) = a.strides();
            let (rsb, csb) = b.strides();
            // SAFETY: the views were checked to lie within their slices (Mat::new) and the
            // output slice holds m·n elements; strides describe exactly those extents.
            unsafe {
                $kernel(
                    m,
                    k,
                    n,
                    alpha,
                    a.data.as_ptr(),
                    rsa,
                    csa,
                    b.data.as_ptr(),
                    rsb,
                    csb,
                    beta,
                    c.as_mut_ptr(),
                    n as isize,
                    1,
                );
            }
        }
    };
}

gemm_fn!(dgemm, f64, matrixmultiply::dgemm);
gemm_fn!(sgemm, f32, matrixmultiply::sgemm);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_naive_product_with_transposes() {
        let a: Vec<f64> = (0..6).map(|x| x as f64).collect(); // 2×3
        let b: Vec<f64> = (0..12).map(|x| (x as f64) * 0.5 - 1.0).collect(); // 3×4
        let mut c = vec![1.0; 8];
        dgemm(2.0, Mat::new(&a, 2, 3), Mat::new(&b, 3, 4), 1.0, &mut c, 4);
        for i in 0..2 {
            for j in 0..4 {
                let s: f64 = (0..3).map(|k| a[i * 3 + k] * b[k * 4 + j]).sum();
                assert!((c[i * 4 + j] - (2.0 * s + 1.0)).abs() < 1e-12);
            }
        }
        // a·aᵀ (2×2).
        let mut g = vec![0.0; 4];
        dgemm(1.0, Mat::new(&a, 2, 3), Mat::new(&a, 2, 3).t(), 0.0, &mut g, 2);
        assert_eq!(g, vec![5.0, 14.0, 14.0, 50.0]);
    }
}
