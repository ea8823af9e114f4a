//! Principal component analysis of one view slot (Sattler et al. 2003, eq. 1).
//!
//! The `n` light images of slot `j` are the rows of `X` (`n × 3hw`). With so few rows the
//! snapshot method is the efficient one: centre the rows on their mean `μ`, accumulate the
//! small Gram matrix `G = X̃X̃ᵀ` in `f64` (column block by column block, so memory stays
//! bounded), eigen-solve it in `f64`, and lift each eigenvector `v_k` to an eigentexture
//! `B_k = X̃ᵀv_k / √λ_k` of unit norm. Signs are fixed so that the largest-magnitude entry of
//! every `B_k` is positive. The eigentextures are then quantised for storage and the weights
//! `p_ik` are the least-squares coefficients of each centred image on the *stored* basis, so
//! quantisation costs as little as it can. By Eckart–Young, with the exact basis the squared
//! error of the slot equals the sum of the discarded eigenvalues; both are reported.

use crate::eigen::{Quantization, QuantizedSlot, dequantize, quantize};
use crate::gemm::{Mat, dgemm, sgemm};
use crate::store::SlotData;
use crate::{Error, Result};
use nalgebra::{DMatrix, SymmetricEigen};

/// Columns per block in the streaming passes (fits the L2 cache in `f64` for 81 rows).
const BLOCK: usize = 1024;

/// Result of the PCA of one slot.
#[derive(Debug, Clone)]
pub struct SlotPca {
    /// What goes into the eigen store.
    pub stored: QuantizedSlot,
    /// Components with a non-zero eigenvalue among those kept.
    pub effective_components: usize,
    /// Squared error of the exact (`f64`) `c`-component reconstruction, measured from the data.
    pub sse: f64,
    /// Squared error of the reconstruction from the stored (quantised) basis and weights.
    pub sse_stored: f64,
    /// Sum of the discarded eigenvalues (Eckart–Young: equals `sse`).
    pub discarded_eigen_sum: f64,
    /// `Σ_i ‖x_i‖²` of the uncentred images.
    pub energy: f64,
    /// Largest input value.
    pub peak: f32,
}

/// Largest number of components a slot of `n_lights` images supports (the centred data has
/// rank at most `n_lights − 1`), never less than one.
pub fn max_components(n_lights: usize) -> usize {
    n_lights.saturating_sub(1).max(1)
}

/// Converts columns `c0..c1` of the row-major `rows × cols` `f32` matrix into a dense `f64`
/// block `rows × (c1 − c0)`.
fn block_f64(data: &[f32], rows: usize, cols: usize, c0: usize, c1: usize, out: &mut Vec<f64>) {
    let w = c1 - c0;
    out.clear();
    out.reserve(rows * w);
    for r in 0..rows {
        out.extend(data[r * cols + c0..r * cols + c1].iter().map(|&v| v as f64));
    }
}

/// Computes the PCA of `slot` with `components` components (already clamped by the caller
/// to `1..=max_components`), quantising the basis with `quantization`. The slot's data is
/// centred in place.
pub fn pca_slot(
    slot: &mut SlotData,
    components: usize,
    quantization: Quantization,
) -> Result<SlotPca> {
    let (n, m) = (slot.n_lights, slot.texel_values);
    let c = components;
    if c == 0 || c > n {
        return Err(Error::Invalid(format!("components {c} not in 1..={n}")));
    }
    // Mean, energy and peak, refusing non-finite input with its location.
    let mut mean64 = vec![0f64; m];
    let mut energy = 0f64;
    let mut peak = f32::MIN;
    for i in 0..n {
        let row = slot.row(i);
        let (e, p, finite) = row_stats(row, &mut mean64);
        if !finite {
            crate::store::check_finite(row, slot.view, i, 0)?;
        }
        energy += e;
        peak = peak.max(p);
    }
    let mean: Vec<f32> = mean64.iter().map(|s| (s / n as f64) as f32).collect();
    for row in slot.data.chunks_exact_mut(m) {
        for (v, mu) in row.iter_mut().zip(&mean) {
            *v -= mu;
        }
    }
    let x = &slot.data;

    // Pass 1: Gram matrix in f64.
    let gram = gram_f64(x, n, m);
    let eig = SymmetricEigen::new(DMatrix::from_row_slice(n, n, &gram));
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let eigenvalues: Vec<f64> = order.iter().map(|&k| eig.eigenvalues[k].max(0.0)).collect();
    let trace: f64 = (0..n).map(|i| gram[i * n + i]).sum();
    let tol = eigenvalues[0].max(0.0) * 1e-12 * n as f64;
    let effective = eigenvalues[..c].iter().filter(|&&l| l > tol && l > 0.0).count();
    // Lifting matrix: column k = v_k / √λ_k (zero for rank-deficient components).
    let mut lift = vec![0f64; n * c];
    for k in 0..effective {
        let s = 1.0 / eigenvalues[k].sqrt();
        for i in 0..n {
            lift[i * c + k] = eig.eigenvectors[(i, order[k])] * s;
        }
    }

    // Pass 2: eigentextures B = liftᵀ X̃ (c × m). Each entry sums only n products, so
    // single precision loses nothing the f16/u8 storage would keep.
    let lift32: Vec<f32> = lift.iter().map(|&v| v as f32).collect();
    let mut basis = vec![0f32; c * m];
    sgemm(1.0, Mat::new(&lift32, n, c).t(), Mat::new(x, n, m), 0.0, &mut basis, m);
    // Deterministic signs: the largest-magnitude entry of each eigentexture is positive.
    for k in 0..effective {
        let row = &mut basis[k * m..(k + 1) * m];
        let big = row.iter().copied().fold(0f32, |a, v| if v.abs() > a.abs() { v } else { a });
        if big < 0.0 {
            row.iter_mut().for_each(|v| *v = -*v);
            for i in 0..n {
                lift[i * c + k] = -lift[i * c + k];
            }
        }
    }
    let (raw, scale_offset) = quantize(&basis, c, quantization);
    drop(basis);
    let stored_basis = dequantize(&raw, &scale_offset, quantization);

    // The exact basis is B = liftᵀX̃, so its projections X̃Bᵀ = G·lift and its Gram matrix
    // BBᵀ = liftᵀ·G·lift follow from the small Gram matrix alone, in f64.
    let mut proj_exact = vec![0f64; n * c];
    dgemm(1.0, Mat::new(&gram, n, n), Mat::new(&lift, n, c), 0.0, &mut proj_exact, c);
    let mut bgram_exact = vec![0f64; c * c];
    dgemm(1.0, Mat::new(&lift, n, c).t(), Mat::new(&proj_exact, n, c), 0.0, &mut bgram_exact, c);

    // Pass 3: projections of X̃ on the stored basis (n × c) and its Gram matrix (c × c), in
    // f64: the stored error is the small difference ‖x̃‖² − qᵀM⁻¹q and needs the precision.
    let mut proj = vec![0f64; n * c];
    let mut bgram = vec![0f64; c * c];
    let (mut xb, mut bb) = (Vec::new(), Vec::new());
    for c0 in (0..m).step_by(BLOCK) {
        let c1 = (c0 + BLOCK).min(m);
        let w = c1 - c0;
        block_f64(x, n, m, c0, c1, &mut xb);
        block_f64(&stored_basis, c, m, c0, c1, &mut bb);
        let b = Mat::new(&bb, c, w);
        dgemm(1.0, Mat::new(&xb, n, w), b.t(), 1.0, &mut proj, c);
        dgemm(1.0, b, b.t(), 1.0, &mut bgram, c);
    }
    let (sse, _) = least_squares(&proj_exact, &bgram_exact, &gram, n, c);
    let (sse_stored, weights) = least_squares(&proj, &bgram, &gram, n, c);
    let discarded_eigen_sum = (trace - eigenvalues[..effective].iter().sum::<f64>()).max(0.0);

    for (l, w) in weights.chunks(c).enumerate() {
        crate::store::check_finite(w, slot.view, l, 0)?;
    }
    Ok(SlotPca {
        stored: QuantizedSlot { mean, eigentextures: raw, scale_offset, weights, eigenvalues },
        effective_components: effective,
        sse,
        sse_stored,
        discarded_eigen_sum,
        energy,
        peak,
    })
}

/// Adds `row` into `sum` and returns its energy `Σ v²`, its largest value and whether all
/// its values are finite. Eight independent accumulators keep the loop vectorisable (a
/// single running sum would be a serial chain of dependent additions).
fn row_stats(row: &[f32], sum: &mut [f64]) -> (f64, f32, bool) {
    const L: usize = 8;
    let mut e = [0f64; L];
    let mut p = [f32::MIN; L];
    let mut bad = [0f32; L];
    let (rc, rr) = (row.chunks_exact(L), row.chunks_exact(L).remainder());
    for (r, s) in rc.zip(sum.chunks_exact_mut(L)) {
        for k in 0..L {
            let v = r[k];
            s[k] += v as f64;
            e[k] += (v as f64) * (v as f64);
            p[k] = p[k].max(v);
            bad[k] += v * 0.0; // NaN for NaN or ±∞, 0 otherwise
        }
    }
    let tail = row.len() - rr.len();
    for (k, &v) in rr.iter().enumerate() {
        sum[tail + k] += v as f64;
        e[k] += (v as f64) * (v as f64);
        p[k] = p[k].max(v);
        bad[k] += v * 0.0;
    }
    let finite = bad.iter().all(|b| *b == 0.0);
    (e.iter().sum(), p.iter().copied().fold(f32::MIN, f32::max), finite)
}

/// `X̃X̃ᵀ` in `f64` for the row-major `n × m` matrix `x`, streaming column blocks converted
/// to `f64`. Only the blocks on and above the diagonal are multiplied (rows split into
/// three bands), then mirrored: two thirds of the work of the full product.
fn gram_f64(x: &[f32], n: usize, m: usize) -> Vec<f64> {
    let band = n.div_ceil(3).max(1);
    let bands: Vec<(usize, usize)> = (0..n).step_by(band).map(|r| (r, (r + band).min(n))).collect();
    let mut gram = vec![0f64; n * n];
    let mut blk = Vec::new();
    let mut part = vec![0f64; band * band];
    for c0 in (0..m).step_by(BLOCK) {
        let c1 = (c0 + BLOCK).min(m);
        let w = c1 - c0;
        block_f64(x, n, m, c0, c1, &mut blk);
        for (bi, &(r0, r1)) in bands.iter().enumerate() {
            for &(s0, s1) in &bands[bi..] {
                let (rows, cols) = (r1 - r0, s1 - s0);
                let a = Mat::new(&blk[r0 * w..r1 * w], rows, w);
                let b = Mat::new(&blk[s0 * w..s1 * w], cols, w);
                dgemm(1.0, a, b.t(), 0.0, &mut part[..rows * cols], cols);
                for i in 0..rows {
                    for j in 0..cols {
                        gram[(r0 + i) * n + s0 + j] += part[i * cols + j];
                    }
                }
            }
        }
    }
    for i in 0..n {
        for j in 0..i {
            gram[i * n + j] = gram[j * n + i];
        }
    }
    gram
}

/// Least-squares weights of each centred image on a basis, given the projections `q_i`
/// (`n × c`) and the basis's Gram matrix `M` (`c × c`), and the resulting total squared
/// error `Σ_i ‖x̃_i‖² − q_iᵀ M⁻¹ q_i`.
fn least_squares(proj: &[f64], bgram: &[f64], gram: &[f64], n: usize, c: usize) -> (f64, Vec<f32>) {
    let m = DMatrix::from_fn(c, c, |a, b| bgram[a * c + b]);
    // Zero components (rank deficiency) make M singular: solve on the non-zero ones.
    let active: Vec<usize> = (0..c).filter(|&k| m[(k, k)] > 0.0).collect();
    let ma = DMatrix::from_fn(active.len(), active.len(), |a, b| m[(active[a], active[b])]);
    let chol = ma.cholesky();
    let mut sse = 0f64;
    let mut weights = vec![0f32; n * c];
    for i in 0..n {
        let q = nalgebra::DVector::from_fn(active.len(), |a, _| proj[i * c + active[a]]);
        let p = match &chol {
            Some(ch) => ch.solve(&q),
            None => q.clone(),
        };
        sse += (gram[i * n + i] - q.dot(&p)).max(0.0);
        for (a, &k) in active.iter().enumerate() {
            weights[i * c + k] = p[a] as f32;
        }
    }
    (sse, weights)
}

#[cfg(test)]
mod tests;
