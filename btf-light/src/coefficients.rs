//! The coefficient matrix `P` of `[S03 eq. 10–12]`: per view slot `j` and measured light
//! `i`, the factors `[1, b_ij, p_i0j … p_i(c−1)j]` that turn the radiance `g_i` arriving
//! through light direction `i` into the reconstruction's coefficients, so that
//! `γ*_j = Σ_i g_i P_ij·` (eq. 10) and, stacking every frame, slot and component,
//! `U = G · P` (eq. 12). The metric `M = P Pᵀ` expresses inner products of `U` on `G`,
//! which is what the eigenweightsets of eq. 13 use.

use btf_core::eigen::EigenSlot;
use btf_core::gemm::{Mat, dgemm};

/// Per slot and light, the factors that turn light radiance into coefficients:
/// `n_lights × (slots · (c + 2))`, row-major; per slot the columns are
/// `[mean, bias, component 0 … c−1]`.
#[derive(Debug, Clone)]
pub struct CoefficientMatrix {
    /// Measured light directions (rows).
    pub lights: usize,
    /// View slots.
    pub slots: usize,
    /// Components `c`.
    pub components: usize,
    /// The matrix.
    pub p: Vec<f32>,
}

impl CoefficientMatrix {
    /// Columns per slot (`c + 2`).
    pub fn per_slot(&self) -> usize {
        self.components + 2
    }

    /// Columns.
    pub fn cols(&self) -> usize {
        self.slots * self.per_slot()
    }

    /// From per-(slot, light) rows: `row(j, i)` gives the bias `b_ij` and the `c` weights
    /// `p_ikj` as the reconstruction reads them (the renderer passes its scaled weights and
    /// folded dequantisation biases; a CPU caller its plain weights and 0).
    pub fn from_rows(
        lights: usize,
        slots: usize,
        components: usize,
        row: impl Fn(usize, usize, &mut [f32]) -> f32,
    ) -> CoefficientMatrix {
        let c = components;
        let mut out = CoefficientMatrix { lights, slots, components: c, p: vec![] };
        out.p = vec![0.0; lights * out.cols()];
        for i in 0..lights {
            for j in 0..slots {
                let dst = &mut out.p[i * slots * (c + 2) + j * (c + 2)..][..c + 2];
                dst[0] = 1.0;
                dst[1] = row(j, i, &mut dst[2..]);
            }
        }
        out
    }

    /// From dequantised eigen-store slots (no bias), using `c` components.
    pub fn from_slots(slots: &[EigenSlot], lights: usize, c: usize) -> CoefficientMatrix {
        let n_v = slots.len();
        let mut out = CoefficientMatrix { lights, slots: n_v, components: c, p: vec![] };
        out.p = vec![0.0; lights * out.cols()];
        for (j, s) in slots.iter().enumerate() {
            for i in 0..lights {
                let row = &mut out.p[i * n_v * (c + 2) + j * (c + 2)..][..c + 2];
                row[0] = 1.0;
                row[2..].copy_from_slice(&s.weights_of(i)[..c]);
            }
        }
        out
    }

    /// `M = P Pᵀ` (`n_lights²`, f64): the inner product of `U` expressed on `G`,
    /// `U_a · U_b = Σ_rows g_a M g_bᵀ`.
    pub fn metric(&self) -> Vec<f64> {
        let p: Vec<f64> = self.p.iter().map(|&x| x as f64).collect();
        let mut m = vec![0.0; self.lights * self.lights];
        let a = Mat::new(&p, self.lights, self.cols());
        dgemm(1.0, a, a.t(), 0.0, &mut m, self.lights);
        m
    }
}

/// `Σ_rows a M bᵀ` for row-major `a`, `b` with `n` columns.
pub fn metric_dot(a: &[f32], b: &[f32], n: usize, metric: &[f64]) -> f64 {
    let mut s = 0.0;
    let mut mb = vec![0.0f64; n];
    for (ra, rb) in a.chunks_exact(n).zip(b.chunks_exact(n)) {
        mb.fill(0.0);
        for (j, &bj) in rb.iter().enumerate() {
            if bj != 0.0 {
                for (m, x) in mb.iter_mut().zip(&metric[j * n..(j + 1) * n]) {
                    *m += x * bj as f64;
                }
            }
        }
        s += ra.iter().zip(&mb).map(|(&x, y)| x as f64 * y).sum::<f64>();
    }
    s
}

/// `γ*` of slot `j` (eq. 10) for one frame's gathered radiances `g` (`3 · lights`, rows per
/// channel): `out[ch · (c+2) + col]` for the columns `[mean, bias, components]`.
pub fn gamma_star_of(g: &[f32], p: &CoefficientMatrix, j: usize, out: &mut [f32]) {
    let k = p.per_slot();
    let cols = p.cols();
    out[..3 * k].fill(0.0);
    for ch in 0..3 {
        let g = &g[ch * p.lights..(ch + 1) * p.lights];
        let dst = &mut out[ch * k..(ch + 1) * k];
        for (i, &gi) in g.iter().enumerate() {
            if gi != 0.0 {
                let src = &p.p[i * cols + j * k..][..k];
                for (d, s) in dst.iter_mut().zip(src) {
                    *d += gi * s;
                }
            }
        }
    }
}
