//! Shadow maps, the alternative to shadow volumes (Williams 1978; `[S03 §4.3]` discuss
//! their aliasing): one depth layer per shadowing light, rendered from the light —
//! orthographic around the scene's bounding sphere for a directional light, a perspective
//! frustum just enclosing the sphere for a point light. Cloth is two-sided, so nothing is
//! culled. The BTF pass compares with a small depth bias and 3×3 PCF; the smooth boundary
//! of `[S03 eq. 6]` hides the acne at grazing angles as it hides the volume's zig-zag. A point light
//! inside the scene's bounding sphere gets a cube map instead (`cube.rs`, six layers).

use super::cube;
use crate::bind::{self, uniform};
use crate::math::{self, Mat4, Vec3};
use crate::passes::mesh::{cleared_depth, position_only_layout};
use crate::scene::Light;
use crate::timer::PassTimer;
use crate::{Gpu, Result};
use wgpu::util::DeviceExt;

/// WGSL of the pass.
pub const SOURCE: &str = include_str!("map.wgsl");
/// Depth format of the maps.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Bias subtracted from the receiver's depth (normalised depth units).
pub const DEPTH_BIAS: f32 = 0.002;

/// How one shadowing light's depth is stored.
#[derive(Debug, Clone, Copy)]
pub struct MapLight {
    /// First layer (the only one, or face +x of a cube).
    pub base_layer: u32,
    /// World → light clip (single map), or the faces' shared projection (cube).
    pub matrix: Mat4,
    /// Six cube faces (a point light inside the scene's bounding sphere).
    pub cube: bool,
}

/// The maps of all shadowing lights.
pub struct ShadowMaps {
    /// One layer per directional or outside point light, six per inside point light.
    pub texture: wgpu::Texture,
    /// Per shadowing light, in order.
    pub lights: Vec<MapLight>,
    size: u32,
    pipeline: wgpu::RenderPipeline,
    groups: Vec<wgpu::BindGroup>,
}

/// World → clip of a light's shadow camera around the sphere `(center, radius)`.
pub fn light_matrix(light: &Light, center: Vec3, radius: f32) -> Mat4 {
    let r = radius.max(1e-6);
    match light {
        Light::Directional { direction, .. } => {
            let d = math::v3(*direction).normalize();
            let eye = center + d * (2.0 * r);
            let view = math::look_at(eye, center, math::safe_up(-d, Vec3::y()));
            math::orthographic(2.2 * r, 2.2 * r, 0.5 * r, 3.5 * r) * view
        }
        Light::Point { position, .. } => {
            let q = math::v3(*position);
            let dist = (center - q).norm();
            let view = math::look_at(q, center, math::safe_up(center - q, Vec3::y()));
            if dist > 1.05 * r {
                let half = (r * 1.05 / dist).asin().to_degrees() * 1.1;
                math::perspective(
                    (2.0 * half).min(170.0),
                    1.0,
                    (dist - 1.05 * r).max(dist * 1e-3),
                    dist + 1.05 * r,
                ) * view
            } else {
                // Light inside the scene: cover what lies in front of it.
                math::perspective(150.0, 1.0, r * 1e-3, dist + 1.05 * r) * view
            }
        }
        // Environment lights never cast shadow maps (their visibility maps do the job).
        Light::Environment(_) => Mat4::identity(),
    }
}

/// Whether a point light at `q` sits inside the scene sphere and so gets a cube map.
pub fn needs_cube(light: &Light, center: Vec3, radius: f32) -> bool {
    match light {
        Light::Point { position, .. } => (math::v3(*position) - center).norm() <= 1.05 * radius,
        Light::Directional { .. } | Light::Environment(_) => false,
    }
}

/// Layer matrices of all maps, and where each light's layers are.
fn layer_matrices(lights: &[&Light], center: Vec3, radius: f32) -> (Vec<Mat4>, Vec<MapLight>) {
    let mut matrices = Vec::new();
    let mut out = Vec::new();
    for l in lights {
        let base_layer = matrices.len() as u32;
        if let (true, Light::Point { position, .. }) = (needs_cube(l, center, radius), l) {
            let q = math::v3(*position);
            let (near, far) = cube::near_far((q - center).norm(), radius);
            let proj = cube::projection(near, far);
            matrices.extend((0..cube::FACES).map(|f| proj * cube::face_view(q, f)));
            out.push(MapLight { base_layer, matrix: proj, cube: true });
        } else {
            let m = light_matrix(l, center, radius);
            matrices.push(m);
            out.push(MapLight { base_layer, matrix: m, cube: false });
        }
    }
    (matrices, out)
}

impl ShadowMaps {
    /// Builds the maps for `lights` (the shadowing ones, in layer order).
    pub fn new(gpu: &Gpu, lights: &[&Light], center: Vec3, radius: f32, size: u32) -> ShadowMaps {
        let dev = &gpu.device;
        let (matrices, map_lights) = layer_matrices(lights, center, radius);
        let layers = matrices.len().max(1) as u32;
        let texture = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow maps"),
            size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow_map.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SOURCE.into()),
        });
        let layout =
            bind::layout_seen_by(dev, "shadow map", wgpu::ShaderStages::VERTEX, &[uniform()]);
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow map"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("shadow map"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_light"),
                compilation_options: Default::default(),
                buffers: &[Some(position_only_layout())],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: wgpu::DepthBiasState { constant: 0, slope_scale: 1.5, clamp: 0.0 },
            }),
            multisample: Default::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
        let groups = matrices
            .iter()
            .map(|m| {
                let buf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("light camera"),
                    contents: bytemuck::bytes_of(&math::to_cols(m)),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                bind::group(dev, "light camera", &layout, &[buf.as_entire_binding()])
            })
            .collect();
        ShadowMaps { texture, lights: map_lights, size, pipeline, groups }
    }

    /// Texel size in texture coordinates (PCF step).
    pub fn texel(&self) -> f32 {
        1.0 / self.size as f32
    }

    /// Texels per side of each layer.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Renders every layer.
    pub fn encode(
        &self,
        timer: &mut PassTimer,
        corners: &wgpu::Buffer,
        n_corners: u32,
    ) -> Result<()> {
        for (layer, group) in self.groups.iter().enumerate() {
            let view = self.texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer as u32,
                array_layer_count: Some(1),
                ..Default::default()
            });
            timer.pass(&format!("shadow map L{layer}"), |enc, ts| {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("shadow map"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(cleared_depth(&view, true)),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.set_vertex_buffer(0, corners.slice(..));
                pass.draw(0..n_corners, 0..1);
            })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector4;

    #[test]
    fn wgsl_validates() {
        crate::gpu::validate_wgsl("shadow_map.wgsl", SOURCE).unwrap();
    }

    #[test]
    fn light_frusta_enclose_the_scene() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let lights = [
            Light::Directional { direction: [0.3, 1.0, 0.2], irradiance: [1.0; 3], shadows: true },
            Light::Point { position: [1.0, 8.0, 3.0], intensity: [1.0; 3], shadows: true },
        ];
        for l in &lights {
            let m = light_matrix(l, c, 1.0);
            for d in [Vec3::x(), -Vec3::x(), Vec3::y(), -Vec3::y(), Vec3::z(), -Vec3::z()] {
                let p = m * Vector4::new(c.x + d.x, c.y + d.y, c.z + d.z, 1.0);
                let n = p.xyz() / p.w;
                assert!(
                    n.x.abs() <= 1.0 && n.y.abs() <= 1.0 && (0.0..=1.0).contains(&n.z),
                    "{l:?} {d:?} {n:?}"
                );
            }
        }
    }
}
