//! The thin-cloth pass (was `transmission/`): front-lit vs back-lit appearance and
//! view-dependent transparency of thin semi-transparent cloth (`[TC eq. 7–9]`), on top of
//! the BTF's reflection. The scene description is `crate::scene::TransmissionDesc`.
//!
//! The fabric is an optically thin, locally plane-parallel slab of optical thickness `τ₁`
//! (scalar or per texel), single-scattering albedo `ϖ₀` and isotropic or Henyey–Greenstein
//! phase function; the physics (first-order reflection and transmission, their removable
//! singularity at `μ = μ₀`, the Monte-Carlo check) is [`btf_core::thin_slab`]. For each
//! fragment of a transmissive material, with `μ` the view cosine on the face the eye sees
//! and, per light, `μ₀` the light cosine on the face the light is on:
//!
//! - **front-lit** (light on the eye's side, `[TC eq. 7]`): the BTF reflection `BTF · E` scaled by
//!   `f_r(τ₁)/f_r(∞) = 1 − e^{−τ₁(1/μ + 1/μ₀)}`. The BTF is a measured reflection of the
//!   fabric, which already contains the light its volume scatters back; we take it as the
//!   thick-cloth (`τ₁ → ∞`) limit and let the slab say how much of it a sheet of thickness
//!   `τ₁` reflects, keeping the BTF's texture and angular shape. (Adding `f_r` on top of
//!   the BTF would count the volume reflection twice and break both limits below.)
//! - **back-lit** (light on the far side, `[TC eq. 8]`): `ϖ₀ p(cos Θ)/(4π) · F_t(τ₁, μ, μ₀) · μ₀ · E`
//!   with `F_t = [e^{−τ₁/μ} − e^{−τ₁/μ₀}]/(μ − μ₀)`, i.e. `f_t · μ₀ · E` with `E` the
//!   irradiance perpendicular to the light (DESIGN.md §3: BSDFs are per unit irradiance
//!   `πF μ₀` on the surface), `cos Θ = −l·v`.
//! - **what lies behind** shows through with `alpha = e^{−τ₁/μ}` (`[TC eq. 9]`), the same for
//!   front- and back-lit sheets: `L = L_behind · alpha + L_sheet`.
//!
//! Limits (tested): `τ₁ → 0` leaves what is behind unchanged (alpha 1, both terms 0);
//! `τ₁ → ∞` gives the opaque BTF render (alpha 0, share 1, `F_t → 0`).
//!
//! **Compositing: sorted, not order-independent.** `[TC eq. 9]` is the "over" operator with
//! premultiplied colour, which does not commute: `(B·T₁ + S₁)·T₂ + S₂ ≠ (B·T₂ + S₂)·T₁ + S₁`
//! for a bright sheet over a dark one. Weighted-blended OIT gets the product of
//! transmittances right but weights the colours by a heuristic, so a scarf over a shirt
//! would take colour from the wrong layer; depth peeling is exact but costs a pass per
//! layer. Garments have few layers and few thin triangles, so [`ThinPass`] sorts
//! the thin triangles back to front on the CPU every frame (centroid distance) and draws
//! them after the opaque geometry with depth test and no depth write: exact for layers
//! that do not interpenetrate (a triangle straddling another can be wrong by one layer).
//!
//! **Environment lights** (`btf_light::thin_tables`): per vertex side, the transmission through the slab
//! (`∫ f_t L V μ₀ dω₀` over the far hemisphere, tabulated at 16 view cosines) and the
//! irradiance-weighted `e^{−τ₁/μ₀}` that scales the BTF's environment term on the near
//! side, from the environment's visibility maps; a `tau_texture` gets the tables at 8
//! thicknesses, interpolated in `τ` per texel; isotropic scattering only.
//!
//! Limitations: thin cloth casts opaque shadows (shadow passes treat every triangle
//! alike); the transmitted term is shadowed by shadow maps only; transmissive materials
//! are always evaluated per pixel; multiple scattering between layers is not modelled
//! (`[TC eq. 7–8]` are local).

mod pass;
mod pipeline;
mod thickness;

pub use pass::{ThinEnv, ThinPass};
