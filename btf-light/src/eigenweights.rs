//! Eigenweightsets ([S03 §5.4, eq. 13]): a PCA over the weight vectors
//! `U_a` of `A` rotations of the environment about world `+z` (default 30 in 12° steps), so
//! that the lighting for any rotation `δ` is `U(δ) ≈ Ū + Σ_{k≤e} o_k(δ) W_k` at the cost of
//! `e` vector additions instead of a new gather.
//!
//! `U = G · P` is linear in the gathered radiances `G` ([`Radiances`]), so the PCA is done
//! on the `G_a` with the inner product `⟨X, Y⟩ = Σ_rows x M yᵀ`, `M = P Pᵀ`: this is
//! exactly the PCA of the `U_a` (same Gram matrix, same coefficients) while every stored
//! vector is `3 · n_lights` per frame instead of `3 · slots · (c+2)`. Snapshot method: the
//! `A × A` Gram matrix of the centred sets is accumulated in f64 and eigen-solved;
//! `W_k = Σ_a v_ka (G_a − Ḡ) / √λ_k` and `o_ak = √λ_k v_ka` (so `o_ak = ⟨U_a − Ū, W_k⟩`
//! as in eq. 13). Signs are made deterministic (largest-magnitude `v_ka` positive).
//! Between the sampled rotations `o_k(δ)` is interpolated by a periodic Catmull–Rom
//! spline, so rotating by 360° is the identity and the samples are reproduced exactly.

use crate::coefficients::{CoefficientMatrix, gamma_star_of, metric_dot};
use crate::gather::Radiances;
use crate::{Error, Result};
use btf_core::gemm::{Mat, dgemm};
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

/// The decomposition of `A` weight sets.
#[derive(Debug, Clone)]
pub struct EigenWeightSets {
    /// Rotations sampled (`A`), at `δ_a = a · 360° / A`.
    pub rotations: usize,
    /// Mean `Ḡ`.
    pub mean: Radiances,
    /// Eigenweightsets `W_k` (in `G` form), descending eigenvalue.
    pub sets: Vec<Vec<f32>>,
    /// All eigenvalues of the Gram matrix, descending.
    pub eigenvalues: Vec<f64>,
    /// Coefficients `o_ak`, `A × sets.len()`, row-major.
    pub coefficients: Vec<f64>,
}

impl EigenWeightSets {
    /// PCA of `sets` (the weight sets of `A` equally spaced rotations) under `metric`,
    /// keeping `e` eigenweightsets (at most the rank `≤ A − 1`).
    pub fn build(sets: &[Radiances], metric: &[f64], e: usize) -> Result<EigenWeightSets> {
        let a_n = sets.len();
        if a_n < 2 || e == 0 {
            return Err(Error::Invalid(format!(
                "eigenweightsets need ≥ 2 rotations and e ≥ 1 (got {a_n}, {e})"
            )));
        }
        let (frames, n_l) = (sets[0].frames, sets[0].lights);
        if sets.iter().any(|s| s.frames != frames || s.lights != n_l) || metric.len() != n_l * n_l {
            return Err(Error::Invalid("weight sets of different shapes".into()));
        }
        let len = sets[0].g.len();
        let mut mean64 = vec![0f64; len];
        for s in sets {
            mean64.iter_mut().zip(&s.g).for_each(|(m, &x)| *m += x as f64);
        }
        let mean: Vec<f32> = mean64.iter().map(|m| (m / a_n as f64) as f32).collect();
        let centred: Vec<Vec<f32>> =
            sets.iter().map(|s| s.g.iter().zip(&mean).map(|(x, m)| x - m).collect()).collect();
        let gram = gram_matrix(&centred, n_l, metric);
        let eig = SymmetricEigen::new(DMatrix::from_row_slice(a_n, a_n, &gram));
        let mut order: Vec<usize> = (0..a_n).collect();
        order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
        let eigenvalues: Vec<f64> = order.iter().map(|&k| eig.eigenvalues[k].max(0.0)).collect();
        let tol = eigenvalues[0] * 1e-12 * a_n as f64;
        let keep = e.min(eigenvalues.iter().filter(|&&l| l > tol).count());
        let mut out_sets = Vec::with_capacity(keep);
        let mut coefficients = vec![0f64; a_n * keep];
        for (k, &col) in order.iter().take(keep).enumerate() {
            let mut v: Vec<f64> = (0..a_n).map(|a| eig.eigenvectors[(a, col)]).collect();
            let big = v.iter().copied().fold(0f64, |m, x| if x.abs() > m.abs() { x } else { m });
            if big < 0.0 {
                v.iter_mut().for_each(|x| *x = -*x);
            }
            let s = eigenvalues[k].sqrt();
            let mut w = vec![0f64; len];
            for (a, x) in centred.iter().enumerate() {
                let f = v[a] / s;
                w.iter_mut().zip(x).for_each(|(w, &x)| *w += f * x as f64);
                coefficients[a * keep + k] = s * v[a];
            }
            out_sets.push(w.iter().map(|&x| x as f32).collect());
        }
        Ok(EigenWeightSets {
            rotations: a_n,
            mean: Radiances { frames, lights: n_l, g: mean },
            sets: out_sets,
            eigenvalues,
            coefficients,
        })
    }

    /// Eigenweightsets kept.
    pub fn kept(&self) -> usize {
        self.sets.len()
    }

    /// `o_k(δ)` for `k < e`: periodic Catmull–Rom through the sampled `o_ak`.
    pub fn coefficients_at(&self, delta_deg: f64, e: usize) -> Vec<f64> {
        let (a_n, keep) = (self.rotations, self.kept());
        let x = (delta_deg / 360.0).rem_euclid(1.0) * a_n as f64;
        let i = (x.floor() as usize).min(a_n - 1);
        let t = (x - i as f64).clamp(0.0, 1.0);
        let at = |d: isize, k: usize| {
            self.coefficients[((i as isize + d).rem_euclid(a_n as isize) as usize) * keep + k]
        };
        (0..e.min(keep))
            .map(|k| {
                let (p0, p1, p2, p3) = (at(-1, k), at(0, k), at(1, k), at(2, k));
                let t2 = t * t;
                0.5 * (2.0 * p1
                    + (p2 - p0) * t
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t2 * t)
            })
            .collect()
    }

    /// `G(δ) = Ḡ + Σ_{k<e} o_k(δ) W_k` (then `U(δ) = G(δ) · P`).
    pub fn reconstruct(&self, delta_deg: f64, e: usize) -> Radiances {
        self.reconstruct_from(&self.coefficients_at(delta_deg, e))
    }

    /// `G = Ḡ + Σ_k o_k W_k` for coefficients `o` (from [`EigenWeightSets::coefficients_at`]).
    pub fn reconstruct_from(&self, o: &[f64]) -> Radiances {
        let mut g = self.mean.g.clone();
        for (ok, w) in o.iter().zip(&self.sets) {
            let ok = *ok as f32;
            g.iter_mut().zip(w).for_each(|(g, &w)| *g += ok * w);
        }
        Radiances { g, ..self.mean.clone() }
    }
}

/// `γ*` of chosen `(frame, slot)` pairs as a function of the rotation: the renderer reads
/// `γ*` only for the four view slots of the side each vertex shows, so for a fixed camera
/// a rotation is `γ*(δ) = γ*(Ḡ) + Σ_{k<e} o_k(δ) γ*(W_k)` over those pairs alone — `e + 1`
/// streams of `3 (c + 2)` floats per pair instead of `e` additions over all of `G` plus a
/// `γ*` product (`3 · lights · (c + 2)` per pair) afterwards.
#[derive(Debug, Clone)]
pub struct GammaBasis {
    /// Pairs.
    pub picks: usize,
    /// Floats per pair, `3 (c + 2)` (layout of [`super::Radiances::gamma_star`]).
    pub per_pick: usize,
    /// Terms per pair: the mean and `e` eigenweightsets.
    pub terms: usize,
    /// `[pair][term][per_pick]`.
    data: Vec<f32>,
}

impl EigenWeightSets {
    /// `γ*` of the mean and of the first `e` eigenweightsets for every `(frame, slot)` in
    /// `picks`, for the coefficients `p`.
    pub fn gamma_basis(
        &self,
        p: &CoefficientMatrix,
        picks: &[(usize, usize)],
        e: usize,
    ) -> Result<GammaBasis> {
        let (frames, n_l) = (self.mean.frames, self.mean.lights);
        if p.lights != n_l {
            return Err(Error::Invalid(format!("{} lights in P, {n_l} in G", p.lights)));
        }
        if let Some(&(f, j)) = picks.iter().find(|&&(f, j)| f >= frames || j >= p.slots) {
            return Err(Error::Invalid(format!("pick (frame {f}, slot {j}) out of range")));
        }
        let terms = 1 + e.min(self.kept());
        let per_pick = 3 * p.per_slot();
        let row = 3 * n_l;
        let mut data = vec![0f32; picks.len() * terms * per_pick];
        data.par_chunks_mut(terms * per_pick).zip(picks.par_iter()).for_each(|(out, &(f, j))| {
            for (t, dst) in out.chunks_exact_mut(per_pick).enumerate() {
                let g = if t == 0 { &self.mean.g } else { &self.sets[t - 1] };
                gamma_star_of(&g[f * row..(f + 1) * row], p, j, dst);
            }
        });
        Ok(GammaBasis { picks: picks.len(), per_pick, terms, data })
    }
}

impl GammaBasis {
    /// `γ*` of every pair for the coefficients `o` (from
    /// [`EigenWeightSets::coefficients_at`]; extra ones are ignored) into `out`
    /// (`picks · per_pick`).
    pub fn at(&self, o: &[f64], out: &mut [f32]) {
        let o: Vec<f32> = o.iter().take(self.terms - 1).map(|&x| x as f32).collect();
        let per = self.per_pick;
        out[..self.picks * per]
            .par_chunks_mut(per * 256)
            .zip(self.data.par_chunks(self.terms * per * 256))
            .for_each(|(dst, src)| {
                for (d, s) in dst.chunks_exact_mut(per).zip(src.chunks_exact(self.terms * per)) {
                    d.copy_from_slice(&s[..per]);
                    for (ok, w) in o.iter().zip(s[per..].chunks_exact(per)) {
                        d.iter_mut().zip(w).for_each(|(d, &w)| *d += ok * w);
                    }
                }
            });
    }
}

impl GammaBasis {
    /// `γ*` of pair `i` alone for the coefficients `o` (as `f32`, at most `terms − 1` used)
    /// into `out` (`per_pick`): the sums of [`GammaBasis::at`] in the same order.
    pub fn at_one(&self, i: usize, o: &[f32], out: &mut [f32]) {
        let per = self.per_pick;
        let s = &self.data[i * self.terms * per..(i + 1) * self.terms * per];
        out[..per].copy_from_slice(&s[..per]);
        for (ok, w) in o.iter().take(self.terms - 1).zip(s[per..].chunks_exact(per)) {
            out[..per].iter_mut().zip(w).for_each(|(d, &w)| *d += ok * w);
        }
    }
}

/// Relative error `‖U − U_ref‖ / ‖U_ref‖` under `metric`.
pub fn relative_error(u: &Radiances, reference: &Radiances, metric: &[f64]) -> f64 {
    let d: Vec<f32> = u.g.iter().zip(&reference.g).map(|(a, b)| a - b).collect();
    let r = reference.norm2(metric);
    if r <= 0.0 {
        metric_dot(&d, &d, u.lights, metric).sqrt()
    } else {
        (metric_dot(&d, &d, u.lights, metric) / r).sqrt()
    }
}

/// `K_ab = ⟨X_a, X_b⟩_M` accumulated in f64 (`X_a M` by one product per set).
fn gram_matrix(centred: &[Vec<f32>], n_l: usize, metric: &[f64]) -> Vec<f64> {
    let a_n = centred.len();
    let rows = centred[0].len() / n_l;
    let mut k = vec![0f64; a_n * a_n];
    let mut x64 = vec![0f64; rows * n_l];
    let mut y = vec![0f64; rows * n_l];
    for a in 0..a_n {
        x64.iter_mut().zip(&centred[a]).for_each(|(d, &s)| *d = s as f64);
        dgemm(1.0, Mat::new(&x64, rows, n_l), Mat::new(metric, n_l, n_l), 0.0, &mut y, n_l);
        for b in 0..=a {
            let s: f64 = centred[b].iter().zip(&y).map(|(&x, y)| x as f64 * y).sum();
            k[a * a_n + b] = s;
            k[b * a_n + a] = s;
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sets(a_n: usize) -> Vec<Radiances> {
        // Smooth periodic functions of the rotation plus a fixed part, 5 frames × 4 lights.
        (0..a_n)
            .map(|a| {
                let d = a as f64 / a_n as f64 * std::f64::consts::TAU;
                let g = (0..5 * 3 * 4)
                    .map(|i| {
                        (1.0 + 0.5 * (d + i as f64).sin()
                            + 0.2 * (2.0 * d + 0.3 * i as f64).cos()
                            + 0.05 * (7.0 * d).sin()) as f32
                    })
                    .collect();
                Radiances { frames: 5, lights: 4, g }
            })
            .collect()
    }

    fn metric() -> Vec<f64> {
        let mut m = vec![0.0; 16];
        (0..4).for_each(|i| m[i * 5] = 1.0 + i as f64);
        m[1] = 0.3;
        m[4] = 0.3;
        m
    }

    #[test]
    fn full_rank_reproduces_every_set_and_360_is_identity() {
        let s = sets(12);
        let m = metric();
        let ews = EigenWeightSets::build(&s, &m, 11).unwrap();
        for (a, set) in s.iter().enumerate() {
            let r = ews.reconstruct(a as f64 * 30.0, 11);
            assert!(relative_error(&r, set, &m) < 1e-6, "set {a}");
            let r2 = ews.reconstruct(a as f64 * 30.0 + 360.0, 11);
            assert_eq!(r.g, r2.g);
        }
        // Eigenvalues descend, and o_ak = <U_a − Ū, W_k>.
        assert!(ews.eigenvalues.windows(2).all(|w| w[0] >= w[1]));
    }

    #[test]
    fn error_falls_with_more_sets_and_bad_input_is_refused() {
        let s = sets(12);
        let m = metric();
        let ews = EigenWeightSets::build(&s, &m, 11).unwrap();
        let errs: Vec<f64> =
            (1..=6).map(|e| relative_error(&ews.reconstruct(60.0, e), &s[2], &m)).collect();
        assert!(errs.windows(2).all(|w| w[1] <= w[0] + 1e-9), "{errs:?}");
        assert!(EigenWeightSets::build(&s[..1], &m, 1).is_err());
        assert!(EigenWeightSets::build(&s, &m, 0).is_err());
    }
}
