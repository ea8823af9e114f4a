//! Weight vectors for environment lighting (Sattler et al. 2003, §5.3, eq. 10–12).
//!
//! Per hemicube frame (a vertex side), the radiance arriving "through" every measured light
//! direction `i` is `g_i = Σ_p h_i(p) · V(p) · L_env(R_δ · world(p)) · dω_p` (eq. 10's
//! `g_i`; [`LightTable`] holds `h_i(p)`, [`VisibilityMaps`] `V`, `R_δ` rotates the
//! environment by `δ` about world `+z`). The sum over pixels is done the other way round:
//! every source of the binned environment ([`EnvCube`], power `L dω` at direction `d`)
//! above the horizon is dropped into the hemicube pixel containing `d`, and if that pixel
//! is visible adds `h_i(p) · power` to `g_i` — the same quadrature, exact in energy. Since a
//! slot's reconstructed light image is `μ_j + b_ij + Σ_k p_ikj B_kj`, the texture under
//! the environment is `T_j = f · (γ*_μ μ_j + γ*_b + Σ_k γ*_kj B_kj)` (eq. 11) with RGB
//! coefficients `γ* = Σ_i g_i P_i·` over the columns of the [`CoefficientMatrix`]
//! `P = [1, b_ij, p_i0j … p_i(c−1)j]` of every slot. Stacking all frames, slots and
//! components gives `U` (eq. 12), one matrix product `G · P` ([`WeightSet::full_u`]); the
//! renderer needs only the four slots each vertex looks through ([`WeightSet::gamma_star`]).
//! The exposure `f` is applied by the caller, so `U` does not change with it.

use super::env_cube::EnvCube;
use super::hemicube::LightTable;
use super::visibility::{HemicubeFrame, VisibilityMaps};
use crate::material::MaterialData;
use btf_core::eigen::EigenSlot;
use btf_core::gemm::{Mat, dgemm, sgemm};
use rayon::prelude::*;

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

    /// From GPU-packed material data (scaled weights and dequantisation biases).
    pub fn from_material(m: &MaterialData) -> CoefficientMatrix {
        let (n_l, n_v, c) = (m.light_sampling.len(), m.view_sampling.len(), m.components);
        let mut out = CoefficientMatrix { lights: n_l, slots: n_v, components: c, p: vec![] };
        out.p = vec![0.0; n_l * out.cols()];
        for i in 0..n_l {
            for j in 0..n_v {
                let row = &mut out.p[i * n_v * (c + 2) + j * (c + 2)..][..c + 2];
                row[0] = 1.0;
                row[1] = m.bias(j, i);
                for k in 0..c {
                    row[2 + k] = m.weight_group(j, i, k / 4)[k % 4];
                }
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

/// The radiances `g_i` of every frame: `frames · 3 · lights` floats, row `(frame, channel)`.
#[derive(Debug, Clone, PartialEq)]
pub struct WeightSet {
    /// Frames (vertex sides).
    pub frames: usize,
    /// Measured light directions.
    pub lights: usize,
    /// `g`, row-major `(frame · 3 + channel) × light`.
    pub g: Vec<f32>,
}

/// The fixed inputs of eq. 10 for one mesh and material.
pub struct GatherInput<'a> {
    /// Pixel → light table of the hemicube.
    pub table: &'a LightTable,
    /// Visibility of every frame.
    pub visibility: &'a VisibilityMaps,
    /// The frames.
    pub frames: &'a [HemicubeFrame],
    /// Tangent-space pixel directions.
    pub dirs: &'a [[f32; 3]],
    /// Light directions of the material.
    pub lights: usize,
}

/// The hemicube pixel (layout of [`super::hemicube`]) containing tangent-space `(x, y, z)`,
/// `z > 0`.
pub fn hemicube_pixel(res: usize, x: f32, y: f32, z: f32) -> usize {
    let cell = |a: f32, n: usize| ((a * n as f32) as usize).min(n - 1);
    let (half, top) = (res / 2, res * res);
    let (ax, ay) = (x.abs(), y.abs());
    if z >= ax && z >= ay {
        let (u, v) = ((x / z + 1.0) * 0.5, (y / z + 1.0) * 0.5);
        return cell(v, res) * res + cell(u, res);
    }
    let (face, m, a) = if ax >= ay {
        (if x > 0.0 { 0 } else { 1 }, ax, y)
    } else {
        (if y > 0.0 { 2 } else { 3 }, ay, x)
    };
    let (u, v) = ((a / m + 1.0) * 0.5, z / m);
    top + face * res * half + cell(v, half) * res + cell(u, res)
}

/// Rotation by `−δ` about `+z` applied to a world direction (the environment turned by `δ`).
pub(super) fn rotate_z(d: [f32; 3], cos: f32, sin: f32) -> [f32; 3] {
    [cos * d[0] + sin * d[1], -sin * d[0] + cos * d[1], d[2]]
}

impl WeightSet {
    /// Eq. 10 frame by frame, the definition [`WeightSet::gather`] must reproduce: every
    /// source above the frame's horizon is dropped into the hemicube pixel containing it and,
    /// if that pixel is visible, adds `h_i(p) · power` to `g_i`.
    pub fn gather_reference(input: &GatherInput, env: &EnvCube, rotation_deg: f64) -> WeightSet {
        let n_l = input.lights;
        let (sin, cos) = rotation_deg.to_radians().sin_cos();
        let (sin, cos) = (sin as f32, cos as f32);
        let res = input.visibility.res as usize;
        let mut g = vec![0f32; input.frames.len() * 3 * n_l];
        g.par_chunks_mut(3 * n_l).enumerate().for_each(|(f, out)| {
            let [t, b, n] = input.frames[f].axes.map(|a| rotate_z(a, cos, sin));
            let bits = input.visibility.frame_bits(f);
            for (d, pw) in env.dirs.iter().zip(&env.power) {
                let z = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                if z <= 0.0 {
                    continue;
                }
                let x = d[0] * t[0] + d[1] * t[1] + d[2] * t[2];
                let y = d[0] * b[0] + d[1] * b[1] + d[2] * b[2];
                let p = hemicube_pixel(res, x, y, z);
                if bits[p / 64] >> (p % 64) & 1 == 0 {
                    continue;
                }
                let (idx, h) = (input.table.index[p], input.table.interp[p]);
                for k in 0..4 {
                    let i = idx[k] as usize;
                    out[i] += h[k] * pw[0];
                    out[n_l + i] += h[k] * pw[1];
                    out[2 * n_l + i] += h[k] * pw[2];
                }
            }
        });
        WeightSet { frames: input.frames.len(), lights: n_l, g }
    }

    /// `g` of frame `f`, channel `ch`.
    pub fn row(&self, f: usize, ch: usize) -> &[f32] {
        &self.g[(f * 3 + ch) * self.lights..][..self.lights]
    }

    /// `γ*` of frame `f` and slot `j` (eq. 10): `out[ch · (c+2) + col]` for the columns
    /// `[mean, bias, components]`.
    pub fn gamma_star(&self, p: &CoefficientMatrix, f: usize, j: usize, out: &mut [f32]) {
        gamma_star_of(&self.g[f * 3 * self.lights..][..3 * self.lights], p, j, out);
    }

    /// The whole of `U` (eq. 12) as one product `G · P`: row `(frame, channel)`, column
    /// `(slot, [mean, bias, components])`.
    pub fn full_u(&self, p: &CoefficientMatrix) -> Vec<f32> {
        let rows = self.frames * 3;
        let mut u = vec![0f32; rows * p.cols()];
        sgemm(
            1.0,
            Mat::new(&self.g, rows, self.lights),
            Mat::new(&p.p, p.lights, p.cols()),
            0.0,
            &mut u,
            p.cols(),
        );
        u
    }

    /// `‖U‖²` under `metric` (see [`CoefficientMatrix::metric`]), f64.
    pub fn norm2(&self, metric: &[f64]) -> f64 {
        metric_dot(&self.g, &self.g, self.lights, metric)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envlight::Hemicube;

    #[test]
    fn pixel_of_a_direction_is_the_pixel_whose_centre_it_is() {
        for res in [2usize, 8, 16] {
            let cube = Hemicube::new(res as u32).unwrap();
            for (p, d) in cube.dirs.iter().enumerate() {
                assert_eq!(hemicube_pixel(res, d[0], d[1], d[2]), p, "res {res}");
            }
        }
    }
}
