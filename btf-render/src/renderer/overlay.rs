//! Geometry that another crate draws into a frame's own colour and depth targets, after the
//! BTF pass and with the same camera — how `yarn-render` puts the `[[yarns]]` of a scene
//! next to its BTF meshes (btf-render cannot depend on yarn-render, so the dependency is
//! turned around: the overlay implements this trait and is handed to
//! [`super::Renderer::add_overlay`]). No equation of the papers lives here.
//!
//! Contract: the BTF pass stores its depth when an overlay is present; each overlay loads
//! colour and depth (never clears), depth-tests with `Less` against
//! [`crate::passes::mesh::DEPTH_FORMAT`] in wgpu's `[0, 1]` convention with the matrix of
//! [`OverlayView::camera`], draws linear radiance (the exposure is applied once, when the
//! frame is written) and, under MSAA, resolves into [`OverlayTargets::resolve`] again.

use crate::camera::CameraSetup;
use crate::scene::Scene;
use crate::{Gpu, Result};

/// The frame's targets as an overlay sees them.
pub struct OverlayTargets<'a> {
    /// Colour attachment: multisampled under MSAA, else the frame's target itself.
    pub color: &'a wgpu::TextureView,
    /// The frame's target to resolve into under MSAA.
    pub resolve: Option<&'a wgpu::TextureView>,
    /// Depth attachment (`DEPTH_FORMAT`, same sample count), holding the meshes' depth.
    pub depth: &'a wgpu::TextureView,
    /// Colour format (`passes::mesh::color_format(samples)`).
    pub format: wgpu::TextureFormat,
    /// Samples per pixel.
    pub samples: u32,
    /// `(width, height)`.
    pub size: (u32, u32),
}

/// The environment light as an overlay may use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverlayEnvironment {
    /// `∫ L_env dω` per channel (before the exposure): the power of the current map.
    pub total_power: [f64; 3],
    /// Exposure factor of the environment light.
    pub exposure: f32,
    /// Rotation about world `+z`, degrees.
    pub rotation_deg: f64,
    /// Changes with every new map ([`btf_light::SceneEnvironment::revision`]).
    pub revision: u64,
}

impl OverlayEnvironment {
    /// The constant radiance of the same power, times the exposure:
    /// `f · (1/4π) ∫ L_env dω` — what a renderer with only a constant ambient light uses.
    pub fn mean_radiance(&self) -> [f64; 3] {
        self.total_power.map(|p| p * self.exposure as f64 / (4.0 * std::f64::consts::PI))
    }
}

/// What an overlay draws with: the camera matrices of the frame and the scene as it is now
/// (camera, lights, output), the environment when the scene has one.
pub struct OverlayView<'a> {
    /// The camera of the BTF pass (its `view_proj` is the one the depth was written with).
    pub camera: &'a CameraSetup,
    /// The scene with the updates made since the renderer was built.
    pub scene: &'a Scene,
    /// The environment light's current state.
    pub environment: Option<OverlayEnvironment>,
}

/// Geometry drawn into the frame after the BTF pass (see the module documentation).
pub trait Overlay {
    /// Name in the pass statistics.
    fn name(&self) -> &str;
    /// Records the overlay's passes into `encoder`.
    fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        targets: &OverlayTargets<'_>,
        view: &OverlayView<'_>,
    ) -> Result<()>;
}
