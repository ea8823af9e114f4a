//! Per-vertex evaluation as in the paper (§4.2): for every vertex, the view direction in
//! its tangent frame selects up to four view slots `j_m` with weights `ω_m` (eq. 5), each
//! light's direction gives light weights `τ_n` (eq. 3), and these fold into per-slot
//! coefficients `ω_m · e_l · γ_kj` (eq. 3–4), computed on the CPU every frame. The fragment
//! shader blends the three vertices' reconstructions of a triangle with barycentric weights
//! (the paper's three-pass blending, done in one pass) and multiplies each light by its
//! per-pixel visibility.
//!
//! Layout per (vertex, light `l`, slot `m`): `[e·ωΣτ, e·ωΣτ b_ij, 3·G coefficient vec4]`
//! with the `G`-group packing of [`crate::material`]; `G` is the largest over the scene's
//! materials so that all vertices share one stride. Slots are `u32::MAX` when unused.

use crate::material::MaterialData;
use crate::math::Vec3;
use crate::tangent;
use btf_core::{Direction, InterpMode};

/// Unused slot marker.
pub const NO_SLOT: u32 = u32::MAX;

/// A light as the per-vertex evaluation sees it.
#[derive(Debug, Clone, Copy)]
pub struct VertexLight {
    /// Position (`point = true`) or direction towards the light.
    pub pos_or_dir: Vec3,
    /// Whether it is a point light (`I / d²`).
    pub point: bool,
    /// RGB irradiance or intensity.
    pub color: [f32; 3],
}

/// Inputs shared by all vertices.
pub struct VertexEvalInput<'a> {
    /// Eye position (perspective) …
    pub eye: Vec3,
    /// … or, when `Some`, the direction towards an orthographic camera.
    pub ortho_to_camera: Option<Vec3>,
    /// Lights of the scene, in frame order.
    pub lights: &'a [VertexLight],
    /// View blending.
    pub view_mode: InterpMode,
    /// Light interpolation.
    pub light_mode: InterpMode,
    /// Largest `G` over the materials (layout stride).
    pub groups_stride: usize,
}

/// Per-vertex slot indices and coefficient vec4s.
pub struct VertexCoefficients {
    /// Four slot indices per vertex.
    pub slots: Vec<[u32; 4]>,
    /// Coefficients, `vertices · lights · 4 · (2 + 3G)` vec4.
    pub coef: Vec<[f32; 4]>,
}

/// Vec4 per (vertex, light, slot).
pub fn stride(groups: usize) -> usize {
    2 + 3 * groups
}

fn dir_of(v: Vec3, frame: (Vec3, Vec3, Vec3)) -> Option<Direction> {
    Direction::from_vector(tangent::to_tangent(v, frame))
}

/// Computes the coefficients of every vertex; `material_of[v]` picks the vertex's material.
pub fn compute(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    tangents: &[[f32; 4]],
    material_of: &[usize],
    materials: &[&MaterialData],
    input: &VertexEvalInput,
) -> VertexCoefficients {
    let n_l = input.lights.len().max(1);
    let k = stride(input.groups_stride);
    let per_vertex = n_l * 4 * k;
    let mut out = VertexCoefficients {
        slots: vec![[NO_SLOT; 4]; positions.len()],
        coef: vec![[0.0; 4]; positions.len() * per_vertex],
    };
    for v in 0..positions.len() {
        let Some(&mi) = material_of.get(v) else { continue };
        if mi == usize::MAX {
            continue;
        }
        let mat = materials[mi];
        let p = Vec3::from(positions[v]);
        let (t, b, mut n) = tangent::frame(normals[v], tangents[v]);
        let to_cam = input.ortho_to_camera.unwrap_or(input.eye - p).try_normalize(0.0).unwrap_or(n);
        if to_cam.dot(&n) < 0.0 {
            n = -n; // two-sided: the side facing the camera
        }
        let frame = (t, b, n);
        let Some(view) = dir_of(to_cam, frame) else { continue };
        let vw = mat.view_sampling.view_weights(view, input.view_mode);
        for (m, &(j, _)) in vw.as_slice().iter().enumerate() {
            out.slots[v][m] = j as u32;
        }
        for (l, light) in input.lights.iter().enumerate() {
            if light.color == [0.0; 3] {
                continue; // no power (e.g. the slot an environment light fills itself)
            }
            let (dir, falloff) = if light.point {
                let d = light.pos_or_dir - p;
                (d, 1.0 / d.norm_squared().max(1e-12))
            } else {
                (light.pos_or_dir, 1.0)
            };
            let Some(ld) = dir_of(dir, frame) else { continue };
            let lw = mat.light_sampling.light_weights(ld, input.light_mode);
            let e = light.color.map(|c| c * falloff);
            for (m, &(j, omega)) in vw.as_slice().iter().enumerate() {
                let base = ((v * n_l + l) * 4 + m) * k;
                let dst = &mut out.coef[base..base + k];
                fold_slot(mat, j, omega as f32, &lw, e, dst);
            }
        }
    }
    out
}

/// Writes `[mean coef, bias, A_g, B_g, C_g …]` of slot `j` for one light.
fn fold_slot(
    mat: &MaterialData,
    j: usize,
    omega: f32,
    lw: &btf_core::Weights,
    e: [f32; 3],
    dst: &mut [[f32; 4]],
) {
    let mut tau_sum = 0f32;
    let mut bias = 0f32;
    for &(i, tau) in lw.as_slice() {
        tau_sum += tau as f32;
        bias += tau as f32 * mat.bias(j, i);
    }
    let s = omega * tau_sum;
    dst[0] = [s * e[0], s * e[1], s * e[2], 0.0];
    let sb = omega * bias;
    dst[1] = [sb * e[0], sb * e[1], sb * e[2], 0.0];
    for g in 0..mat.groups {
        let mut gam = [0f32; 4];
        for &(i, tau) in lw.as_slice() {
            let w = mat.weight_group(j, i, g);
            for c in 0..4 {
                gam[c] += omega * tau as f32 * w[c];
            }
        }
        dst[2 + 3 * g] = [gam[0] * e[0], gam[0] * e[1], gam[0] * e[2], gam[1] * e[0]];
        dst[3 + 3 * g] = [gam[1] * e[1], gam[1] * e[2], gam[2] * e[0], gam[2] * e[1]];
        dst[4 + 3 * g] = [gam[2] * e[2], gam[3] * e[0], gam[3] * e[1], gam[3] * e[2]];
    }
}
