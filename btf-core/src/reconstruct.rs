//! CPU reconstruction of a texture for any view and light direction from an eigen store
//! ([S03 eq. 2–5]) — the reference the GPU renderer is tested against.
//!
//! For the light, interpolation weights `τ_n` over measured lights `i_n` fold the stored
//! weights into `γ_k = Σ_n τ_n p_{i_n k}` ([S03 eq. 3]); since every reconstructed image carries the
//! slot mean, the mean enters with `Σ_n τ_n` (1 inside the sampled cone, the horizon fade
//! beyond it). For the view, the textures of up to four slots `j_m` are blended with weights
//! `ω_m` ([S03 eq. 5]): `T = Σ_m ω_m (Σ_n τ_n · μ_{j_m} + Σ_k γ_{k j_m} B_{k j_m})`. Multiplying by
//! the light's irradiance gives radiance.

use crate::direction::Direction;
use crate::eigen::{EigenSlot, EigenStore};
use crate::interp::{InterpMode, Weights};
use crate::{Error, Result};

/// How to reconstruct.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReconstructParams {
    /// View blending.
    pub view_mode: InterpMode,
    /// Light interpolation.
    pub light_mode: InterpMode,
    /// Components to use (`None` = all stored).
    pub components: Option<usize>,
}

impl Default for ReconstructParams {
    fn default() -> Self {
        ReconstructParams {
            view_mode: InterpMode::Four,
            light_mode: InterpMode::Four,
            components: None,
        }
    }
}

/// `(Σ τ, γ)` of a slot for the given light weights, using the first `c` components ([S03 eq. 3]).
pub fn gamma(slot: &EigenSlot, light: &Weights, c: usize) -> (f32, Vec<f32>) {
    let mut g = vec![0f32; c];
    let mut tau_sum = 0f32;
    for &(i, tau) in light.as_slice() {
        let tau = tau as f32;
        tau_sum += tau;
        for (gk, pk) in g.iter_mut().zip(slot.weights_of(i)) {
            *gk += tau * pk;
        }
    }
    (tau_sum, g)
}

/// Adds `scale · T_j` of one slot to `out` ([S03 eq. 4]).
pub fn accumulate_slot(slot: &EigenSlot, light: &Weights, c: usize, scale: f32, out: &mut [f32]) {
    let (tau_sum, g) = gamma(slot, light, c);
    for (o, mu) in out.iter_mut().zip(&slot.mean) {
        *o += scale * tau_sum * mu;
    }
    for (k, gk) in g.iter().enumerate() {
        let s = scale * gk;
        if s != 0.0 {
            for (o, b) in out.iter_mut().zip(slot.basis_row(k)) {
                *o += s * b;
            }
        }
    }
}

/// Reconstructs the `h · w · 3` texture (BTF values) for a view and a light direction in
/// tangent space.
pub fn reconstruct(
    store: &EigenStore,
    view: Direction,
    light: Direction,
    params: ReconstructParams,
) -> Result<Vec<f32>> {
    let meta = store.meta();
    let c = params.components.unwrap_or(meta.components);
    if c == 0 || c > meta.components {
        return Err(Error::Invalid(format!(
            "components {c} not in 1..={} (stored)",
            meta.components
        )));
    }
    let vw = store.view_sampling().view_weights(view, params.view_mode);
    let lw = store.light_sampling().light_weights(light, params.light_mode);
    let mut out = vec![0f32; meta.btf.texel_values()];
    if lw.is_empty() {
        return Ok(out);
    }
    for &(j, omega) in vw.as_slice() {
        let slot = store.read_slot(j)?;
        accumulate_slot(&slot, &lw, c, omega as f32, &mut out);
    }
    Ok(out)
}

/// Reconstructs the stored light image `light` of slot `view` (no interpolation).
pub fn reconstruct_sample(slot: &EigenSlot, light: usize, c: usize) -> Vec<f32> {
    let mut out = slot.mean.clone();
    for (k, &p) in slot.weights_of(light)[..c].iter().enumerate() {
        for (o, b) in out.iter_mut().zip(slot.basis_row(k)) {
            *o += p * b;
        }
    }
    out
}
