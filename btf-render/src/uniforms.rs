//! GPU mirrors (`#[repr(C)]`, WGSL layout) of the per-frame uniform block every mesh pass
//! reads: `FrameRaw` with its camera (`CameraRaw`) and up to four lights (`LightRaw`), as
//! declared in `passes/btf/btf_pass.wgsl`. The CPU descriptions turn into them with
//! `to_raw()` ([`crate::scene::Light::to_raw`], [`crate::camera::CameraSetup::to_raw`]), as
//! wgpu's examples pair `Light` with `LightRaw`. No equation lives here; the numbers the
//! shaders branch on are named below instead of written as bare floats.

/// Most lights one scene may have (the shader's fixed light array).
pub const MAX_LIGHTS: usize = 4;

/// `LightRaw.pos.w` of a point light (`pos.xyz` is its position).
pub const POINT: f32 = 1.0;
/// `LightRaw.pos.w` of a directional light (`pos.xyz` points towards it).
pub const DIRECTIONAL: f32 = 0.0;

/// How a light's visibility is looked up per fragment: `LightRaw.color.w` (`visibility`
/// in `btf_pass.wgsl` and `transmission.wgsl` compare against these codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightShadow {
    /// No shadow: the light is always visible (and no smooth boundary, eq. 6).
    Unshadowed,
    /// The light's shadow-volume mask (layer `shadow.x`).
    VolumeMask,
    /// A flat shadow map (layer `shadow.x`, matrix `view_proj`).
    Map,
    /// A cube shadow map: six layers from `shadow.x` (`view_proj` is the faces' projection).
    CubeMap,
}

impl LightShadow {
    /// The float the shaders read from `LightRaw.color.w`.
    pub const fn code(self) -> f32 {
        match self {
            LightShadow::Unshadowed => 0.0,
            LightShadow::VolumeMask => 1.0,
            LightShadow::Map => 2.0,
            LightShadow::CubeMap => 3.0,
        }
    }
}

/// GPU mirror of one light (`LightRaw` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightRaw {
    /// Position (`w` = [`POINT`]) or direction towards the light (`w` = [`DIRECTIONAL`]).
    pub pos: [f32; 4],
    /// RGB power; `w`: the [`LightShadow::code`].
    pub color: [f32; 4],
    /// Mask/map layer, map texel size, depth bias.
    pub shadow: [f32; 4],
    /// World → light clip space (shadow maps).
    pub view_proj: [[f32; 4]; 4],
}

impl LightRaw {
    /// The light with its shadow look-up: the code in `color.w`, the layer, texel size and
    /// bias in `shadow`, the light's matrix.
    pub fn with_shadow(
        self,
        kind: LightShadow,
        shadow: [f32; 4],
        view_proj: [[f32; 4]; 4],
    ) -> LightRaw {
        let mut raw = self;
        raw.color[3] = kind.code();
        raw.shadow = shadow;
        raw.view_proj = view_proj;
        raw
    }
}

/// GPU mirror of the camera part of the frame uniform.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CameraRaw {
    /// World → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Eye position; `w = 1` perspective, 0 orthographic.
    pub eye: [f32; 4],
    /// Direction towards the camera (orthographic).
    pub to_camera: [f32; 4],
}

/// GPU mirror of the per-frame uniform (`FrameRaw` in WGSL).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameRaw {
    /// The camera.
    pub camera: CameraRaw,
    /// Number of lights, smooth boundary on (1/0), per-vertex group stride `G`, lights in
    /// the per-vertex layout.
    pub info: [u32; 4],
    /// `α` of eq. 6 in radians.
    pub terminator: [f32; 4],
    /// The lights.
    pub lights: [LightRaw; MAX_LIGHTS],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_match_the_wgsl_structs() {
        assert_eq!(std::mem::size_of::<LightRaw>(), 48 + 64);
        assert_eq!(std::mem::size_of::<CameraRaw>(), 64 + 16 + 16);
        assert_eq!(std::mem::size_of::<FrameRaw>(), 64 + 4 * 16 + 4 * (48 + 64));
        assert_eq!(std::mem::offset_of!(FrameRaw, info), 96);
    }
}
