//! The `[effects]` of a scene: what to compute and how — evaluation per pixel or per vertex
//! (`[S03 §4.2]`), light interpolation and view blending (`[S03 eq. 3, 5]`), components,
//! the shadow technique with the smooth boundary of `[S03 eq. 6]`, MSAA, mipmaps. Only the
//! passes these ask for are built.

use btf_core::InterpMode;
use serde::{Deserialize, Serialize};

/// Where the BTF is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Evaluation {
    /// As the paper: slots, ω and γ per vertex, blended across each triangle.
    PerVertex,
    /// Directions, slots and weights per fragment.
    #[default]
    PerPixel,
}

/// Macroscopic shadow technique.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Shadows {
    /// No shadows, no smooth shadow boundary.
    #[default]
    None,
    /// Stencil shadow volumes (the paper's choice) with the `[S03 eq. 6]` boundary.
    Volume,
    /// Shadow maps with the `[S03 eq. 6]` boundary.
    Map,
}

/// The effects a scene asks for; only the corresponding passes are built.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Effects {
    /// Light interpolation (`[S03 eq. 3]`): nearest or four nearest.
    pub light_interp: InterpMode,
    /// View blending (`[S03 eq. 5]`): nearest or four nearest slots.
    pub view_blend: InterpMode,
    /// Per-vertex (paper) or per-pixel evaluation.
    pub evaluation: Evaluation,
    /// Components used (`None` = all stored).
    pub components: Option<usize>,
    /// Shadow technique.
    pub shadows: Shadows,
    /// Offset `α` of the smooth shadow boundary (`[S03 eq. 6]`), degrees.
    pub terminator_deg: f32,
    /// Blur radius of the 1-D boundary texture, in texels of 1024 (0 = hard).
    pub terminator_blur: u32,
    /// Shadow-map resolution (texels per side).
    pub shadow_map_size: u32,
    /// Samples per pixel (1 or 4).
    pub msaa: u32,
    /// The smooth shadow boundary of `[S03 eq. 6]` (off: shadow volume / map alone, for comparison).
    pub smooth_boundary: bool,
    /// Mip-mapped eigentextures and means, trilinear + anisotropic (off: base level only).
    pub mipmaps: bool,
    /// Anisotropic filtering with mipmaps, most samples (1 = trilinear, up to 16).
    pub anisotropy: u16,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            light_interp: InterpMode::Four,
            view_blend: InterpMode::Four,
            evaluation: Evaluation::PerPixel,
            components: None,
            shadows: Shadows::None,
            terminator_deg: 15.0,
            terminator_blur: 0,
            shadow_map_size: 1024,
            msaa: 1,
            smooth_boundary: true,
            mipmaps: true,
            anisotropy: 1,
        }
    }
}

impl Shadows {
    /// The `SHADOWS` override constant of `btf_pass.wgsl`: which visibility code the shader
    /// contains (0 none, 1 shadow-volume masks, 2 shadow maps, flat and cube).
    pub fn shader_constant(self) -> f64 {
        match self {
            Shadows::None => 0.0,
            Shadows::Volume => 1.0,
            Shadows::Map => 2.0,
        }
    }
}
