//! The gathers of `[S03 eq. 10]`: the radiances `g_i` arriving at every vertex side
//! through every measured light direction, and from them `γ*` and `U` ([S03 eq. 10–12]).
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
//! components gives `U` (eq. 12), one matrix product `G · P` ([`Radiances::full_u`]); the
//! renderer needs only the four slots each vertex looks through ([`Radiances::gamma_star`]).
//! The exposure `f` is applied by the caller, so `U` does not change with it.

mod fast;

use crate::coefficients::{CoefficientMatrix, gamma_star_of, metric_dot};
use crate::env_cube::EnvCube;
use crate::hemicube::{HemicubeFrame, LightTable, pixel_of};
use crate::visibility::VisibilityMaps;
use btf_core::gemm::{Mat, sgemm};
use rayon::prelude::*;

/// The radiances `g_i` of every frame: `frames · 3 · lights` floats, row `(frame, channel)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Radiances {
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

/// Rotation by `−δ` about `+z` applied to a world direction (the environment turned by `δ`).
pub(crate) fn rotate_z(d: [f32; 3], cos: f32, sin: f32) -> [f32; 3] {
    [cos * d[0] + sin * d[1], -sin * d[0] + cos * d[1], d[2]]
}

impl Radiances {
    /// Gathers `g` for the environment turned by `rotation_deg` about world `+z` (eq. 10),
    /// organised for speed (`fast.rs`): the sums of [`Radiances::gather_reference`], bit
    /// for bit.
    pub fn gather(input: &GatherInput, env: &EnvCube, rotation_deg: f64) -> Radiances {
        fast::gather(input, env, rotation_deg)
    }

    /// Eq. 10 frame by frame, the definition [`Radiances::gather`] must reproduce: every
    /// source above the frame's horizon is dropped into the hemicube pixel containing it and,
    /// if that pixel is visible, adds `h_i(p) · power` to `g_i`.
    pub fn gather_reference(input: &GatherInput, env: &EnvCube, rotation_deg: f64) -> Radiances {
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
                let p = pixel_of(res, x, y, z);
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
        Radiances { frames: input.frames.len(), lights: n_l, g }
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

    /// The whole of `U` ([S03 eq. 12]) as one product `G · P`: row `(frame, channel)`, column
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hemicube::Hemicube;
    use btf_core::{InterpMode, Sampling};

    #[test]
    fn fast_gather_is_the_reference_bit_for_bit_and_u_is_g_times_p() {
        // Two frames facing up and down at the origin, nothing occluding: a visible half
        // of a constant sky with a sun through each side.
        let cube = Hemicube::new(8).unwrap();
        let table = LightTable::new(&cube, &Sampling::ubo81(), InterpMode::Four).unwrap();
        let frames =
            HemicubeFrame::of_mesh(&[[0.0; 3]], &[[0.0, 0.0, 1.0]], &[[1.0, 0.0, 0.0, 1.0]], true);
        let vis = VisibilityMaps { res: 8, frames: 2, words: 3, bits: vec![u64::MAX; 6] };
        let env =
            btf_image::EnvMap::from_fn(64, |d| [1.0 + 1e4 * d[0].max(0.0).powi(200), 2.0, 0.5])
                .unwrap();
        let cube_env = EnvCube::new(&env, 8);
        let input = GatherInput {
            table: &table,
            visibility: &vis,
            frames: &frames,
            dirs: &cube.dirs,
            lights: 81,
        };
        for rot in [0.0, 37.5] {
            let fast = Radiances::gather(&input, &cube_env, rot);
            assert_eq!(fast, Radiances::gather_reference(&input, &cube_env, rot), "rotation {rot}");
        }
        let g = Radiances::gather(&input, &cube_env, 0.0);
        let p = CoefficientMatrix::from_rows(81, 2, 1, |j, i, w| {
            w[0] = (i + j) as f32 * 0.01;
            0.5
        });
        let u = g.full_u(&p);
        let mut gs = vec![0f32; 3 * p.per_slot()];
        g.gamma_star(&p, 1, 1, &mut gs);
        let row = |ch: usize| &u[(3 + ch) * p.cols() + p.per_slot()..][..p.per_slot()];
        for ch in 0..3 {
            for (a, b) in row(ch).iter().zip(&gs[ch * p.per_slot()..]) {
                assert!((a - b).abs() <= 1e-5 * a.abs().max(1.0), "{a} vs {b}");
            }
        }
    }
}
