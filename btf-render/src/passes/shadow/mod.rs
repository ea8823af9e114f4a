//! Macroscopic shadows of point and directional lights (`[S03 §4.3]`): chooses shadow
//! volumes (`volume.rs`) or shadow maps (`map.rs`, with cube maps for point lights inside
//! the scene, `cube.rs`), assigns each shadowing light a mask/map layer and hands the BTF
//! pass its inputs. Built only when the scene has a shadowing light and asks for shadows;
//! the smooth boundary of `[S03 eq. 6]` is applied in the BTF pass
//! (`super::smooth_boundary`).

pub mod cube;
pub mod map;
pub mod volume;

use crate::camera::CameraSetup;
use crate::math::{self, Vec3, v3};
use crate::scene::{Light, Scene, Shadows};
use crate::timer::PassTimer;
use crate::uniforms::{LightRaw, LightShadow};
use crate::{Gpu, Result};
use btf_light::mesh::Mesh;
use map::ShadowMaps;
use volume::ShadowVolumes;

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
            maps: array_view(&tex(map::FORMAT)),
            compare: compare_sampler(gpu),
        }
    }
}

/// The shadow technique of a scene with its per-light layers.
pub struct Shadowing {
    technique: Technique,
    /// Layer of each scene light (`None` = does not cast shadows).
    layer_of: Vec<Option<usize>>,
}

enum Technique {
    Map(ShadowMaps),
    Volume(ShadowVolumes),
}

impl Shadowing {
    /// Builds the shadow passes for the scene's shadowing lights (shadow volumes: their
    /// prisms too, which depend on the lights and the mesh, not on the camera).
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
        let (w, h) = (scene.output.width, scene.output.height);
        let technique = gpu.scoped("building shadow passes", || match scene.effects.shadows {
            Shadows::Map => Technique::Map(ShadowMaps::new(
                gpu,
                &casting,
                center,
                radius,
                scene.effects.shadow_map_size,
            )),
            _ => Technique::Volume(ShadowVolumes::new(gpu, &casting, mesh, radius, w, h)),
        })?;
        Ok(Shadowing { technique, layer_of })
    }

    /// Whether the technique keeps per-pixel textures (shadow-volume masks), which a new
    /// frame size must rebuild.
    pub fn sized_by_frame(&self) -> bool {
        matches!(self.technique, Technique::Volume(_))
    }

    /// How far the camera's far plane must move back (shadow-volume back caps).
    pub fn extra_camera_depth(&self) -> f32 {
        match &self.technique {
            Technique::Volume(v) => v.extrusion(),
            Technique::Map(_) => 0.0,
        }
    }

    /// Texture views and sampler for the BTF pass.
    pub fn inputs(&self, gpu: &Gpu) -> ShadowInputs {
        let dummy = ShadowInputs::dummy(gpu);
        match &self.technique {
            Technique::Map(m) => ShadowInputs { maps: array_view(&m.texture), ..dummy },
            Technique::Volume(v) => ShadowInputs { masks: array_view(&v.masks), ..dummy },
        }
    }

    /// Scene light `l`'s record with its shadow look-up: the technique's code, layer, texel
    /// size, bias and light matrix (unchanged for a light that casts no shadow).
    pub fn light_raw(&self, l: usize, raw: LightRaw) -> LightRaw {
        let Some(layer) = self.layer_of.get(l).copied().flatten() else { return raw };
        match &self.technique {
            Technique::Volume(_) => raw.with_shadow(
                LightShadow::VolumeMask,
                [layer as f32, 0.0, 0.0, 0.0],
                [[0.0; 4]; 4],
            ),
            Technique::Map(m) => {
                let ml = &m.lights[layer];
                let (kind, bias) = if ml.cube {
                    (LightShadow::CubeMap, cube::relative_bias(m.size()))
                } else {
                    (LightShadow::Map, map::DEPTH_BIAS)
                };
                let shadow = [ml.base_layer as f32, m.texel(), bias, 0.0];
                raw.with_shadow(kind, shadow, math::to_cols(&ml.matrix))
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
        gpu.scoped("shadow passes", || match &self.technique {
            Technique::Map(m) => m.encode(timer, corners, n_corners),
            Technique::Volume(v) => v.encode(gpu, timer, corners, n_corners, &camera.view_proj),
        })?
    }
}
