//! The smooth shadow boundary of `[S03 eq. 6]` (was `terminator.rs`): the 1-D step texture
//! the BTF pass looks the boundary up in.
//!
//! Per vertex and light, `u_V = (1 + cos(α + ∠(n_V, l_V))) / 2` is a 1-D texture
//! coordinate; interpolated across a triangle it indexes a 1024-texel texture that is black
//! below `u = 0.5` and white above, so the boundary runs where the *interpolated* angle
//! crosses `90° − α`, i.e. on the smooth surface the vertex normals describe rather than
//! along the zig-zag of silhouette edges. `α` (default 15°) pulls the boundary onto the lit
//! side, ahead of the shadow volume's silhouette; a blur makes the edge soft. The vertex
//! shader computes `u` for both sides of a two-sided sheet (`btf/btf_pass.wgsl`).

use crate::Gpu;
use wgpu::util::DeviceExt;

/// Texels of the 1-D boundary texture (as in the paper).
pub const TEXELS: usize = 1024;

/// The boundary texture: texel `i` (centre `u = (i + ½)/1024`) is 1 for `u ≥ ½`, else 0,
/// box-blurred twice with radius `blur` texels (a smooth ramp `4·blur` texels wide).
pub fn texels(blur: u32) -> Vec<f32> {
    let mut t: Vec<f32> = (0..TEXELS).map(|i| if i >= TEXELS / 2 { 1.0 } else { 0.0 }).collect();
    let r = blur as i64;
    if r > 0 {
        for _ in 0..2 {
            t = (0..TEXELS as i64)
                .map(|i| {
                    let sum: f32 =
                        (i - r..=i + r).map(|k| t[k.clamp(0, TEXELS as i64 - 1) as usize]).sum();
                    sum / (2 * r + 1) as f32
                })
                .collect();
        }
    }
    t
}

#[cfg(test)]
/// `u` of `[S03 eq. 6]` for the angle between normal and light (radians) and offset `α`.
pub fn u_coordinate(angle_rad: f32, alpha_rad: f32) -> f32 {
    0.5 * (1.0 + (alpha_rad + angle_rad).cos())
}

/// Uploads the boundary texture (`R8Unorm`, 1024 × 1).
pub fn texture(gpu: &Gpu, blur: u32) -> wgpu::Texture {
    let bytes: Vec<u8> = texels(blur).iter().map(|v| (v * 255.0).round() as u8).collect();
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("smooth shadow boundary"),
            size: wgpu::Extent3d { width: TEXELS as u32, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &bytes,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boundary_sits_at_90_minus_alpha() {
        let alpha = 15f32.to_radians();
        // u crosses 1/2 exactly where angle + α = 90°.
        assert!((u_coordinate(75f32.to_radians(), alpha) - 0.5).abs() < 1e-6);
        assert!(u_coordinate(74f32.to_radians(), alpha) > 0.5);
        assert!(u_coordinate(76f32.to_radians(), alpha) < 0.5);
        // Facing the light is white, facing away black, also past 180° − α.
        assert!((u_coordinate(0.0, alpha) - 0.983).abs() < 1e-3);
        assert!(u_coordinate(179f32.to_radians(), alpha) < 0.05);
    }

    #[test]
    fn texture_is_a_step_and_blur_keeps_the_midpoint() {
        let hard = texels(0);
        assert_eq!((hard[511], hard[512]), (0.0, 1.0));
        let soft = texels(8);
        assert!((soft[511] + soft[512] - 1.0).abs() < 1e-5, "symmetric around the middle");
        assert!(soft[500] > 0.0 && soft[500] < 0.5 && soft[480] == 0.0 && soft[1023] == 1.0);
        assert!(soft.windows(2).all(|w| w[1] >= w[0]));
    }
}
