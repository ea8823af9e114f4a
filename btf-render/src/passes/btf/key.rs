//! The BTF pass's pipeline key (Bevy's `SpecializedRenderPipeline` key): everything that
//! selects a variant of `btf_pass.wgsl` — evaluation per pixel or per vertex (`[S03 §4.2]`),
//! four or nearest view slots and lights (`[S03 eq. 3, 5]`), the shadow technique and the
//! smooth boundary (`[S03 eq. 6]`), the constant group count and weight packing — turned
//! into WGSL override constants so that unused branches are compiled out.

use crate::scene::{Evaluation, Shadows};

/// What selects a pipeline variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BtfPassKey {
    /// Per-vertex (paper) or per-pixel evaluation.
    pub evaluation: Evaluation,
    /// Four-slot view blending (else nearest slot).
    pub view_four: bool,
    /// Four-light interpolation (else nearest light).
    pub light_four: bool,
    /// Samples per pixel.
    pub msaa: u32,
    /// Count texture reads per fragment into the counter buffer (for tests and stats).
    pub count_reads: bool,
    /// The scene has an environment light (per-vertex coefficients even in per-pixel mode).
    pub environment: bool,
    /// Shadow technique whose visibility code the shader contains ([`Shadows::None`] when
    /// no light casts a shadow).
    pub shadows: Shadows,
    /// The smooth shadow boundary (`[S03 eq. 6]`) is applied to shadowing lights.
    pub smooth_boundary: bool,
    /// Lights of the scene (`≤ MAX_LIGHTS`; fixed for a renderer's life).
    pub lights: u32,
    /// Groups of four components shared by every material drawn, or 0 when they differ
    /// (the shader then reads each material's own count at run time, which is slower).
    pub groups: u32,
    /// The materials' weights are in the packed `f16` layout (`material/pack.rs`; only with
    /// `groups > 0`).
    pub packed: bool,
    /// Keep the full per-vertex layout even where the separable one applies
    /// (`RenderOptions::full_vertex_layout`).
    pub full_vertex_layout: bool,
}

impl BtfPassKey {
    /// Whether the per-vertex coefficients are in the separable layout (`per_vertex.rs`):
    /// per-vertex mode with only point and directional lights (unless the full layout is
    /// asked for).
    pub fn separable(&self) -> bool {
        self.evaluation == Evaluation::PerVertex && !self.environment && !self.full_vertex_layout
    }

    /// Whether the pass reads per-vertex coefficients (group 2).
    pub fn uses_vertex_coefficients(&self) -> bool {
        self.evaluation == Evaluation::PerVertex || self.environment
    }

    /// The pipeline-overridable constants of the shader for this key.
    pub(crate) fn constants(&self) -> [(&'static str, f64); 9] {
        [
            ("VIEW_FOUR", self.view_four as u32 as f64),
            ("LIGHT_FOUR", self.light_four as u32 as f64),
            ("COUNT_READS", self.count_reads as u32 as f64),
            ("SHADOWS", self.shadows.shader_constant()),
            ("SMOOTH_BOUNDARY", self.smooth_boundary as u32 as f64),
            ("N_LIGHTS", self.lights as f64),
            ("GROUPS", self.groups as f64),
            ("PACKED", self.packed as u32 as f64),
            ("SEPARABLE", self.separable() as u32 as f64),
        ]
    }

    /// The vertex entry point: with per-vertex coefficients, the one that hands the three
    /// vertices' slots to the fragments.
    pub(crate) fn vertex_entry(&self) -> &'static str {
        if self.uses_vertex_coefficients() { "vs_vertex" } else { "vs_main" }
    }

    pub(crate) fn fragment_entry(&self) -> &'static str {
        match (self.evaluation, self.environment) {
            (Evaluation::PerVertex, _) => "fs_vertex",
            (Evaluation::PerPixel, false) => "fs_pixel",
            (Evaluation::PerPixel, true) => "fs_pixel_env",
        }
    }
}
