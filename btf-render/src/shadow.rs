//! Macroscopic shadows of point and directional lights (Sattler et al. 2003 §4.3): chooses
//! shadow volumes or shadow maps, assigns each shadowing light a mask/map layer and hands
//! the BTF pass its inputs. Built only when the scene has a shadowing light and asks for
//! shadows; the smooth boundary of eq. 6 is applied in the BTF pass (`terminator`).

use crate::btf_pass::LightRaw;
use crate::math::{self, Vec3, v3};
use crate::renderer::CameraSetup;
use crate::scene::{Light, Scene, Shadows};
use crate::shadow_map::{self, ShadowMaps};
use crate::shadow_volume::{self, ShadowVolumes};
use crate::timer::PassTimer;
use crate::{Gpu, Result};
use btf_light::mesh::Mesh;

/// Vertex layout reading only the position of a [`crate::btf_pass::CornerVertex`].
pub fn position_only_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<crate::btf_pass::CornerVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRS,
    }
}

/// What the BTF pass binds for shadows.
pub struct ShadowInputs {
    /// Shadow-volume masks (array view).
    pub masks: wgpu::TextureView,
    /// Shadow maps (array view).
    pub maps: wgpu::TextureView,
    /// Comparison sampler for the maps.
    pub compare: wgpu::Sampler,
}

fn compare_sampler(gpu: &Gpu) -> wgpu::Sampler {
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadow compare"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    })
}

fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

impl ShadowInputs {
    /// 1×1 placeholders for scenes without shadows (never sampled).
    pub fn dummy(gpu: &Gpu) -> ShadowInputs {
        let tex = |format| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("no shadows"),
                size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        ShadowInputs {
            masks: array_view(&tex(wgpu::TextureFormat::R8Unorm)),
            maps: array_view(&tex(shadow_map::FORMAT)),
            compare: compare_sampler(gpu),
        }
    }
}

/// The shadow technique of a scene with its per-light layers.
pub struct Shadowing {
    kind: Shadowing_,
    /// Layer of each scene light (`None` = does not cast shadows).
    layer_of: Vec<Option<usize>>,
    mesh: Mesh,
}

#[allow(non_camel_case_types)]
enum Shadowing_ {
    Map(ShadowMaps),
    Volume(ShadowVolumes, f32),
}

impl Shadowing {
    /// Builds the shadow passes for the scene's shadowing lights.
    pub fn new(gpu: &Gpu, scene: &Scene, mesh: &Mesh) -> Result<Shadowing> {
        let (lo, hi) = mesh.bounds();
        let center: Vec3 = (v3(lo) + v3(hi)) * 0.5;
        let radius = ((v3(hi) - v3(lo)).norm() * 0.5).max(1e-6);
        let mut layer_of = Vec::new();
        let mut casting: Vec<&Light> = Vec::new();
        for l in &scene.lights {
            layer_of.push(l.casts_shadows().then_some(casting.len()));
            if l.casts_shadows() {
                casting.push(l);
            }
        }
        let kind = gpu.scoped("building shadow passes", || match scene.effects.shadows {
            Shadows::Map => Shadowing_::Map(ShadowMaps::new(
                gpu,
                &casting,
                center,
                radius,
                scene.effects.shadow_map_size,
            )),
            _ => Shadowing_::Volume(
                ShadowVolumes::new(gpu, &casting, radius, scene.output.width, scene.output.height),
                shadow_volume::extrusion(radius),
            ),
        })?;
        Ok(Shadowing { kind, layer_of, mesh: mesh.clone() })
    }

    /// How far the camera's far plane must move back (shadow-volume back caps).
    pub fn extra_camera_depth(&self) -> f32 {
        match &self.kind {
            Shadowing_::Volume(_, d) => *d,
            Shadowing_::Map(_) => 0.0,
        }
    }

    /// Texture views and sampler for the BTF pass.
    pub fn inputs(&self, gpu: &Gpu, _width: u32, _height: u32) -> ShadowInputs {
        let dummy = ShadowInputs::dummy(gpu);
        match &self.kind {
            Shadowing_::Map(m) => ShadowInputs { maps: array_view(&m.texture), ..dummy },
            Shadowing_::Volume(v, _) => ShadowInputs { masks: array_view(&v.masks), ..dummy },
        }
    }

    /// Sets the layer, texel size, bias and light matrix of scene light `l`.
    pub fn fill_light_raw(&self, l: usize, raw: &mut LightRaw) {
        let Some(layer) = self.layer_of.get(l).copied().flatten() else { return };
        raw.shadow[0] = layer as f32;
        if let Shadowing_::Map(m) = &self.kind {
            let ml = &m.lights[layer];
            raw.shadow[0] = ml.base_layer as f32;
            raw.shadow[1] = m.texel();
            raw.shadow[2] = shadow_map::DEPTH_BIAS;
            raw.view_proj = math::to_cols(&ml.matrix);
            if ml.cube {
                raw.color[3] = 3.0; // cube map: six layers from base_layer
                raw.shadow[2] = crate::shadow_cube::relative_bias(m.size());
            }
        }
    }

    /// Encodes the shadow passes of one frame.
    pub fn encode(
        &self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        corners: &wgpu::Buffer,
        n_corners: u32,
        camera: &CameraSetup,
    ) -> Result<()> {
        gpu.scoped("shadow passes", || match &self.kind {
            Shadowing_::Map(m) => m.encode(timer, corners, n_corners),
            Shadowing_::Volume(v, _) => {
                v.encode(gpu, timer, &self.mesh, corners, n_corners, &camera.view_proj)
            }
        })?
    }
}
