//! The lighting effects of [W19 §4] the fiber shader applies, and their precomputed data
//! (`yarn-precompute`) packed for the GPU:
//!
//! - **self-shadows** inside a yarn [W19 §4.1]: the optical-depth volume of
//!   `SelfShadowVolume`, read as its `optical_depth` does (two neighbouring angle slices,
//!   each bilinear at the point's own light-frame coordinates, blended), transmittance
//!   `exp(−D)` with `σ = 2 r_f n_A` per in-plane length (DESIGN §2.3 item 10);
//! - **ambient occlusion** [W19 §4.2]: the 2-D stratified texture or the distance cubic;
//! - **ambient light** [W19 eq. 7–8]: a constant environment radiance `L_amb` times the
//!   ambient integral `A(θ_o) = ∫ f cos θ_i dω_i` (tabulated over θ_o, `yarn::bcsdf::ambient`)
//!   times AO — eq. 7 as printed forgets the AO factor its text asks for (DESIGN §2.3
//!   item 12);
//! - **core fibers** [W19 §3.2]: the core texture of `CoreTexture` (two RGBA layers, read
//!   bilinearly with u repeating and v clamped, as `CoreTexture::sample`);
//! - **yarn shadows** [W19 §4.1]: a shadow map of the yarns as thick tubes per directional
//!   light (`passes::shadow`).
//!
//! All data of one yarn description sit in one f32 array; `EffectsRaw` says where.

use crate::{Error, Result};
use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};
use yarn::YarnParams;
use yarn::bcsdf::{AmbientTable, FiberBcsdf};
use yarn_precompute::{BakeSettings, Precomputed};

/// The precomputation of `params`, baked once per process (and read from or written to
/// `cache_dir` when given): renderers of the same yarn share it.
pub fn precomputed(
    params: &YarnParams,
    bake: &BakeSettings,
    cache_dir: Option<&Path>,
) -> Result<Arc<Precomputed>> {
    static MEMO: Mutex<Option<HashMap<String, Arc<Precomputed>>>> = Mutex::new(None);
    let key = Precomputed::cache_key(params, bake).map_err(|e| Error::Invalid(e.to_string()))?;
    // Held while baking: renderers created at once (threads, tests) bake a yarn once.
    let mut memo = MEMO.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let memo = memo.get_or_insert_with(HashMap::new);
    if let Some(p) = memo.get(&key) {
        return Ok(p.clone());
    }
    let p = Arc::new(
        Precomputed::for_params(params, bake, cache_dir)
            .map_err(|e| Error::Invalid(format!("yarn '{}': precomputation: {e}", params.name)))?,
    );
    memo.insert(key, p.clone());
    Ok(p)
}

/// How ambient occlusion is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AoMode {
    /// None (AO = 1).
    Off,
    /// [W19]'s default: the cubic in the distance to the yarn centre.
    Cubic,
    /// The stratified 2-D texture over the cross-section.
    Texture,
}

/// Which effects a frame computes (DESIGN's promise: compute only what the scene calls for).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberEffects {
    /// Core fibers [W19 §3.2]: the innermost fibers of each ply drawn as one textured strip
    /// (widened towards the ply as λ falls, DESIGN §2.3 item 7), the rest explicit.
    pub core: bool,
    /// Self-shadows inside each yarn.
    pub self_shadow: bool,
    /// Self-shadows marched through the twisted cross-section (ours): the ply pattern turns
    /// by `2π·Δz/α_ply` along a ray that rises out of the cross-section plane, which
    /// [W19]'s slices (light ⟂ yarn) miss — by up to 0.96 in transmittance at 30°–80°
    /// elevation for cotton (`yarn-precompute`'s measurement). Off (default): the slice
    /// volume. Measured on the stockinette patch and the yarn BTF against the reference it
    /// changes little (patch rel. RMSE 0.623 → 0.631, mean 0.0215 → 0.0219 of 0.0237; BTF
    /// off-diagonal worst 0.177 → 0.184, hot spot 0.89–1.05 → 0.92–1.06) for 48 σ reads per
    /// light and fragment instead of 4, so it stays an option until a scene shows the
    /// difference; it has no GPU-against-CPU test yet.
    pub helix_shadows: bool,
    /// Shadow hiding in the self-shadows (ours): the light's optical depth in the corridor
    /// the eye's ray proves empty is removed, which gives the hot spot at light = view
    /// (`fiber_draw.wgsl`, `self_transmittance`).
    pub shadow_hiding: bool,
    /// Ambient occlusion.
    pub ao: AoMode,
    /// Shadows of other yarns (tube shadow maps, directional lights).
    pub yarn_shadows: bool,
    /// Shadows of every fiber (ours, `crate::passes::fiber_shadow`): with `yarn_shadows`,
    /// the delta lights' maps are drawn from the fibers themselves (hairs and core strips
    /// included), fitted to what the camera sees, and replace both the tube maps and the
    /// self-shadow volume for those lights (the environment's lobes keep them). One more
    /// fiber pass per light, at full detail whatever the frame's LoD; the map must resolve
    /// the fibers ([`crate::FiberSettings::shadow_map`] texels across the seen part of the
    /// yarns).
    pub fiber_shadows: bool,
    /// Constant environment radiance (linear RGB); zero turns the ambient term off.
    pub ambient: [f32; 3],
}

impl FiberEffects {
    /// Nothing but direct light.
    pub fn none() -> Self {
        FiberEffects {
            core: false,
            self_shadow: false,
            helix_shadows: false,
            shadow_hiding: false,
            ao: AoMode::Off,
            yarn_shadows: false,
            fiber_shadows: false,
            ambient: [0.0; 3],
        }
    }

    /// Whether any precomputed data is needed.
    pub fn needs_bake(&self) -> bool {
        self.core || self.self_shadow || self.ao != AoMode::Off
    }
}

impl Default for FiberEffects {
    fn default() -> Self {
        FiberEffects {
            core: true,
            self_shadow: true,
            helix_shadows: false,
            shadow_hiding: true,
            ao: AoMode::Cubic,
            yarn_shadows: true,
            fiber_shadows: false,
            ambient: [0.0; 3],
        }
    }
}

/// Where one yarn description's effect data start (std430, 160 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EffectsRaw {
    /// Self-shadow: first value, texels per side, slices, plies.
    pub shadow: [u32; 4],
    /// Self-shadow: half width (m), slice step (rad), period 2π/n_ply, present (1/0).
    pub shadow_f: [f32; 4],
    /// AO texture: first value, texels per side; ambient table: first value, entries.
    pub ao: [u32; 4],
    /// AO texture half width (m), AO cubic's yarn radius (m), present (1/0), unused.
    pub ao_f: [f32; 4],
    /// AO cubic coefficients `c₀…c₃` of `d = |q|/R_yarn`.
    pub cubic: [f32; 4],
    /// Core texture: first value of texture A, of texture B, width (u), height (v).
    pub core: [u32; 4],
    /// Core strip half-width `H` in circular space (m), ply ellipse `e_N`, `e_B`, present.
    pub core_f: [f32; 4],
    /// The cross-section extinction σ (ply-symmetrised): first value, cells per side,
    /// present, unused.
    pub sigma: [u32; 4],
    /// σ grid half width (m), the yarn's ply pitch α_ply (signed, m; always set), unused ×2.
    pub sigma_f: [f32; 4],
}

/// Effect data of every yarn description: headers and one f32 array.
#[derive(Debug, Clone, Default)]
pub struct PackedEffects {
    /// One header per yarn description.
    pub headers: Vec<EffectsRaw>,
    /// Self-shadow depths, AO texels and ambient tables (RGB + pad per entry).
    pub data: Vec<f32>,
}

/// Packs `pre[i]` (the precomputation of yarn description `i`, or `None`) and the ambient
/// table of `bcsdf` (shared by all; `entries` values over θ_o ∈ [−π/2, π/2]).
pub fn pack(
    pre: &[Option<Arc<Precomputed>>],
    sigma: &[Option<(yarn_precompute::SigmaField, f64)>],
    ply_pitches: &[f64],
    bcsdf: &FiberBcsdf,
    entries: usize,
) -> Result<PackedEffects> {
    if entries < 2 {
        return Err(Error::Invalid(format!("ambient table of {entries} entries (at least 2)")));
    }
    let mut out = PackedEffects::default();
    let table = AmbientTable::build(bcsdf, entries);
    let ambient_at = out.data.len() as u32;
    for v in &table.values {
        out.data.extend([v[0] as f32, v[1] as f32, v[2] as f32, 0.0]);
    }
    for (k, p) in pre.iter().enumerate() {
        let mut h = EffectsRaw { ao: [0, 0, ambient_at, entries as u32], ..Default::default() };
        if let Some(p) = p {
            let s = &p.self_shadow;
            h.shadow = [out.data.len() as u32, s.res as u32, s.slices as u32, s.ply_count as u32];
            h.shadow_f = [
                s.half_width as f32,
                s.slice_step() as f32,
                (std::f64::consts::TAU / s.ply_count as f64) as f32,
                1.0,
            ];
            out.data.extend_from_slice(&s.depth);
            let a = &p.ao_texture;
            h.ao[0] = out.data.len() as u32;
            h.ao[1] = a.res as u32;
            h.ao_f = [a.half_width as f32, p.ao_cubic.yarn_radius as f32, 1.0, 0.0];
            out.data.extend_from_slice(&a.ao);
            h.cubic = p.ao_cubic.coeffs.map(|c| c as f32);
            let c = &p.core;
            let (a, b) = c.to_rgba_f32();
            h.core = [
                out.data.len() as u32,
                (out.data.len() + a.len()) as u32,
                c.width as u32,
                c.height as u32,
            ];
            out.data.extend_from_slice(a);
            out.data.extend_from_slice(b);
            h.core_f = [
                c.half_width_circ as f32,
                c.ellipse[0] as f32,
                c.ellipse[1] as f32,
                if c.core_fibers > 0 { 1.0 } else { 0.0 },
            ];
        }
        // The ply pitch is always there: shadow hiding's helix parting reads it.
        h.sigma_f[1] = ply_pitches.get(k).copied().unwrap_or(0.0) as f32;
        if let Some(Some((field, ply_pitch))) = sigma.get(k) {
            // The rotational mean baked into a plain grid: the shader's bilinear lookup
            // is then `SigmaField::at`.
            let g = field.symmetrized();
            h.sigma = [out.data.len() as u32, g.res as u32, 1, 0];
            h.sigma_f = [g.half_width as f32, *ply_pitch as f32, 0.0, 0.0];
            out.data.extend(g.sigma.iter().map(|&v| v as f32));
        }
        out.headers.push(h);
    }
    if out.data.len() > u32::MAX as usize {
        return Err(Error::Limit("effect data beyond 2³² values".into()));
    }
    Ok(out)
}
