//! Per-vertex evaluation as in the paper (§4.2): for every vertex, the view direction in
//! its tangent frame selects up to four view slots `j_m` with weights `ω_m` ([S03 eq. 5]), each
//! light's direction gives light weights `τ_n` ([S03 eq. 3]), and these fold into per-slot
//! coefficients `ω_m · e_l · γ_kj` ([S03 eq. 3–4]), computed on the CPU every frame. The fragment
//! shader blends the three vertices' reconstructions of a triangle with barycentric weights
//! (the paper's three-pass blending, done in one pass) and multiplies each light by its
//! per-pixel visibility.
//!
//! Layout per (vertex, light `l`, slot `m`): `[e·ωΣτ, e·ωΣτ b_ij, 3·G coefficient vec4]`
//! with the `G`-group packing of [`crate::material`]; `G` is the largest over the scene's
//! materials so that all vertices share one stride. Slots are `u32::MAX` when unused.
//!
//! With only point and directional lights each entry is the outer product of the light's
//! RGB irradiance `e_l` at the vertex and scalars (eq. 4's γ is a scalar per component), so
//! the *separable* layout stores `[ωΣτ, ωΣτ b_ij, 0, 0]` and one vec4 `ωΣτ γ_kj` per group,
//! and `e_l` once per (vertex, light): `1 + G` vec4 per entry instead of `2 + 3G`, fewer
//! still packed as `f16` ([`pack_scalars_f16`]). An environment light's coefficients (eq.
//! 11) mix colours per direction and keep the full layout.

use crate::material::MaterialData;
use crate::math::{Vec3, v3};
use crate::scene::Light;
use btf_core::{Direction, InterpMode};
use btf_light::tangent;

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

impl VertexLight {
    /// The light as the per-vertex fold reads it; an environment light has zero power here
    /// (its own coefficients, `[S03 eq. 11]`, fill its entry).
    pub fn from_light(light: &Light) -> VertexLight {
        match light {
            Light::Directional { direction, irradiance, .. } => VertexLight {
                pos_or_dir: v3(*direction).normalize(),
                point: false,
                color: *irradiance,
            },
            Light::Point { position, intensity, .. } => {
                VertexLight { pos_or_dir: v3(*position), point: true, color: *intensity }
            }
            Light::Environment(_) => {
                VertexLight { pos_or_dir: Vec3::z(), point: false, color: [0.0; 3] }
            }
        }
    }
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
    /// Write the separable layout (no environment light among the entries).
    pub separable: bool,
}

/// Per-vertex slot indices and coefficient vec4s.
pub struct VertexCoefficients {
    /// Four slot indices per vertex.
    pub slots: Vec<[u32; 4]>,
    /// Coefficients, `vertices · lights · 4 · (2 + 3G)` vec4 (separable: `1 + G`).
    pub coef: Vec<[f32; 4]>,
    /// Separable layout only: `e_l` (RGB, falloff included) per (vertex, light).
    pub irradiance: Vec<[f32; 4]>,
}

/// Vec4 per (vertex, light, slot).
pub fn stride(groups: usize) -> usize {
    2 + 3 * groups
}

/// Vec4 per (vertex, light, slot) in the separable layout.
pub fn scalar_stride(groups: usize) -> usize {
    1 + groups
}

/// `vec4<u32>` per (vertex, light, slot) in the packed layout of [`pack_scalars_f16`].
pub fn packed_scalar_stride(groups: usize) -> usize {
    (1 + 2 * groups).div_ceil(4)
}

/// The separable layout as `f16` halves: `[ωΣτ, ωΣτ b]` in word 0, then each group's four
/// scalars in two words. No scale is needed: the scalars are convex combinations of the
/// material's weights and biases (ω and τ are each ≤ 1 and sum to ≤ 1), so they fit `f16`
/// whenever the material's packed weight rows do; the irradiance, the HDR part, stays `f32`.
/// `⌈(1 + 2G)/4⌉` loads per entry: one at `G = 1`, against three for [`pack_f16`].
pub fn pack_scalars_f16(coef: &[[f32; 4]], groups: usize) -> Vec<[u32; 4]> {
    use half::f16;
    let (k, p) = (scalar_stride(groups), packed_scalar_stride(groups));
    let half = |v: f32| u32::from(f16::from_f32(v).to_bits());
    let pair = |a: f32, b: f32| half(a) | (half(b) << 16);
    let mut out = vec![[0u32; 4]; coef.len() / k * p];
    let mut words = vec![0u32; 4 * p];
    for (entry, dst) in coef.chunks_exact(k).zip(out.chunks_exact_mut(p)) {
        words.fill(0);
        words[0] = pair(entry[0][0], entry[0][1]);
        for (g, gam) in entry[1..].iter().enumerate() {
            words[1 + 2 * g] = pair(gam[0], gam[1]);
            words[2 + 2 * g] = pair(gam[2], gam[3]);
        }
        for (d, w) in dst.iter_mut().zip(words.chunks_exact(4)) {
            d.copy_from_slice(w);
        }
    }
    out
}

/// `vec4<u32>` per (vertex, light, slot) in the packed layout of [`pack_f16`].
pub fn packed_stride(groups: usize) -> usize {
    (4 + 6 * groups).div_ceil(4)
}

/// The coefficients as `f16` halves with one `f32` scale per (vertex, light, slot) entry:
/// `[scale bits, mean coefficient and bias (6 halves)]`, then each group's 12 coefficients
/// (6 `u32`), all divided by the entry's largest magnitude, so that any HDR irradiance fits.
/// Fewer loads for the shader (llvmpipe pays per load, lane by lane): `⌈(4 + 6G)/4⌉`
/// instead of `2 + 3G`; the error is ≤ 2⁻¹¹ of the entry's largest coefficient.
pub fn pack_f16(coef: &[[f32; 4]], groups: usize) -> Vec<[u32; 4]> {
    use half::f16;
    let (k, p) = (stride(groups), packed_stride(groups));
    let mut out = vec![[0u32; 4]; coef.len() / k * p];
    let mut words = vec![0u32; 4 * p];
    for (entry, dst) in coef.chunks_exact(k).zip(out.chunks_exact_mut(p)) {
        let max = entry.iter().flatten().fold(0f32, |m, v| m.max(v.abs()));
        let scale = if max > 0.0 && max.is_finite() { max } else { 1.0 };
        let half = |v: f32| u32::from(f16::from_f32(v / scale).to_bits());
        let pair = |a: f32, b: f32| half(a) | (half(b) << 16);
        let (m, b) = (entry[0], entry[1]);
        words.fill(0);
        words[..4].copy_from_slice(&[
            scale.to_bits(),
            pair(m[0], m[1]),
            pair(m[2], b[0]),
            pair(b[1], b[2]),
        ]);
        let values: Vec<f32> = entry[2..].iter().flatten().copied().collect();
        for (w, two) in words[4..].iter_mut().zip(values.chunks_exact(2)) {
            *w = pair(two[0], two[1]);
        }
        for (d, w) in dst.iter_mut().zip(words.chunks_exact(4)) {
            d.copy_from_slice(w);
        }
    }
    out
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
    let k = if input.separable {
        scalar_stride(input.groups_stride)
    } else {
        stride(input.groups_stride)
    };
    let per_vertex = n_l * 4 * k;
    let mut out = VertexCoefficients {
        slots: vec![[NO_SLOT; 4]; positions.len()],
        coef: vec![[0.0; 4]; positions.len() * per_vertex],
        irradiance: vec![[0.0; 4]; if input.separable { positions.len() * n_l } else { 0 }],
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
            if input.separable {
                out.irradiance[v * n_l + l] = [e[0], e[1], e[2], 0.0];
            }
            for (m, &(j, omega)) in vw.as_slice().iter().enumerate() {
                let base = ((v * n_l + l) * 4 + m) * k;
                let dst = &mut out.coef[base..base + k];
                if input.separable {
                    fold_slot_scalars(mat, j, omega as f32, &lw, dst);
                } else {
                    fold_slot(mat, j, omega as f32, &lw, e, dst);
                }
            }
        }
    }
    out
}

/// `ωΣτ`, `ωΣτ b_ij` and group `g`'s `ωΣτ γ` of slot `j` for one light ([S03 eq. 3–4]).
fn slot_scalars<'a>(
    mat: &'a MaterialData,
    j: usize,
    omega: f32,
    lw: &'a btf_core::Weights,
) -> (f32, f32, impl Fn(usize) -> [f32; 4] + 'a) {
    let mut tau_sum = 0f32;
    let mut bias = 0f32;
    for &(i, tau) in lw.as_slice() {
        tau_sum += tau as f32;
        bias += tau as f32 * mat.bias(j, i);
    }
    let group = move |g: usize| {
        let mut gam = [0f32; 4];
        for &(i, tau) in lw.as_slice() {
            let w = mat.weight_group(j, i, g);
            for c in 0..4 {
                gam[c] += omega * tau as f32 * w[c];
            }
        }
        gam
    };
    (omega * tau_sum, omega * bias, group)
}

/// Writes the separable entry `[ωΣτ, ωΣτ b, 0, 0], γ_0 … γ_{G−1}` of slot `j`.
fn fold_slot_scalars(
    mat: &MaterialData,
    j: usize,
    omega: f32,
    lw: &btf_core::Weights,
    dst: &mut [[f32; 4]],
) {
    let (s, sb, group) = slot_scalars(mat, j, omega, lw);
    dst[0] = [s, sb, 0.0, 0.0];
    for g in 0..mat.groups {
        dst[1 + g] = group(g);
    }
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
    let (s, sb, group) = slot_scalars(mat, j, omega, lw);
    dst[0] = [s * e[0], s * e[1], s * e[2], 0.0];
    dst[1] = [sb * e[0], sb * e[1], sb * e[2], 0.0];
    for g in 0..mat.groups {
        let gam = group(g);
        dst[2 + 3 * g] = [gam[0] * e[0], gam[0] * e[1], gam[0] * e[2], gam[1] * e[0]];
        dst[3 + 3 * g] = [gam[1] * e[1], gam[1] * e[2], gam[2] * e[0], gam[2] * e[1]];
        dst[4 + 3 * g] = [gam[2] * e[2], gam[3] * e[0], gam[3] * e[1], gam[3] * e[2]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    /// Unpacks entry `e` of `pack_f16`'s output back to `stride(groups)` vec4 (mirrors the
    /// shader's `slot_fixed` / `group_coefficients`).
    fn unpack(p: &[[u32; 4]], groups: usize, e: usize) -> Vec<[f32; 4]> {
        let words: Vec<u32> = p[e * packed_stride(groups)..][..packed_stride(groups)]
            .iter()
            .flatten()
            .copied()
            .collect();
        let scale = f32::from_bits(words[0]);
        let h = |k: usize| f16::from_bits((words[k / 2] >> (16 * (k % 2))) as u16).to_f32() * scale;
        let mut out = vec![[h(2), h(3), h(4), 0.0], [h(5), h(6), h(7), 0.0]];
        for g in 0..groups {
            for q in 0..3 {
                let at = 8 + 12 * g + 4 * q;
                out.push([h(at), h(at + 1), h(at + 2), h(at + 3)]);
            }
        }
        out
    }

    #[test]
    fn packed_coefficients_round_trip_within_f16_of_each_entry_across_hdr_scales() {
        for groups in 1..=4 {
            let k = stride(groups);
            // three entries: ordinary, HDR (beyond f16's range), and all zero
            let mut coef = vec![[0.0f32; 4]; 3 * k];
            for (i, v) in coef[..2 * k].iter_mut().flatten().enumerate() {
                let base = ((i * 37 % 101) as f32 - 50.0) / 7.0;
                *v = if i < 4 * k { base } else { base * 1e6 };
            }
            for e in 0..3 {
                coef[e * k][3] = 0.0; // the unused lanes of the mean and bias rows
                coef[e * k + 1][3] = 0.0;
            }
            let packed = pack_f16(&coef, groups);
            assert_eq!(packed.len(), 3 * packed_stride(groups));
            for e in 0..3 {
                let entry = &coef[e * k..(e + 1) * k];
                let max = entry.iter().flatten().fold(0f32, |m, v| m.max(v.abs()));
                for (a, b) in
                    unpack(&packed, groups, e).iter().flatten().zip(entry.iter().flatten())
                {
                    assert!(
                        (a - b).abs() <= max * 2f32.powi(-11),
                        "G {groups} entry {e}: {a} vs {b}"
                    );
                    assert!(a.is_finite());
                }
            }
        }
    }
}
