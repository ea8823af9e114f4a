//! The passes a scene asks for, built from its pass key: the BTF pass (or a cost baseline
//! drawn in its place), the shadow pass (`[S03 §4.3]`, only with a shadowing light), the
//! thin-cloth pass (`[TC eq. 7–9]`, only with a transmissive material). A pass the scene
//! does not need is never built (DESIGN.md §3).

use super::RenderOptions;
use super::geometry::SceneGeometry;
use super::materials::Materials;
use crate::passes::baselines::{self, Baseline, BaselinePass};
use crate::passes::btf::BtfPass;
use crate::passes::shadow::Shadowing;
use crate::passes::thin::{ThinEnv, ThinPass};
use crate::scene::{Evaluation, Scene};
use crate::{Gpu, Result};

/// The built passes.
pub(crate) struct Passes {
    /// The BTF pass.
    pub btf: BtfPass,
    /// A cost baseline drawn instead of the BTF shader.
    pub baseline: Option<BaselinePass>,
    /// The shadow pass.
    pub shadowing: Option<Shadowing>,
    /// The thin-cloth pass.
    pub thin: Option<ThinPass>,
}

impl Passes {
    /// Builds the passes besides `btf` that `scene` and `options` ask for.
    pub fn build(
        gpu: &Gpu,
        scene: &Scene,
        options: &RenderOptions,
        btf: BtfPass,
        materials: &Materials,
        geometry: &SceneGeometry,
    ) -> Result<Passes> {
        let thin = thin_pass(gpu, scene, &btf, materials, geometry)?;
        let baseline = match options.baseline {
            None => None,
            Some(Baseline::Plain) => Some(baselines::plain(gpu, &btf)?),
            Some(Baseline::ReadBound { reads_per_pixel, form }) => {
                let m = &materials.data()[0];
                let views = m.view_sampling.len();
                Some(baselines::read_bound(gpu, &btf, reads_per_pixel, m.groups, views, form)?)
            }
        };
        let shadowing = if scene.wants_shadow_pass() {
            Some(Shadowing::new(gpu, scene, &geometry.mesh)?)
        } else {
            None
        };
        Ok(Passes { btf, baseline, shadowing, thin })
    }

    /// The pipeline of the frame's main pass: the BTF pass's or the baseline's.
    pub fn main_pipeline(&self) -> &wgpu::RenderPipeline {
        self.baseline.as_ref().map_or(&self.btf.pipeline, |b| &b.pipeline)
    }

    /// The main pass's name in the statistics.
    pub fn main_name(&self) -> &str {
        match (&self.baseline, self.btf.key.evaluation) {
            (Some(b), _) => b.name.as_str(),
            (None, Evaluation::PerPixel) => "btf (per-pixel)",
            (None, Evaluation::PerVertex) => "btf (per-vertex)",
        }
    }

    /// How far the camera's far plane moves back for the shadow pass.
    pub fn extra_camera_depth(&self) -> f32 {
        self.shadowing.as_ref().map_or(0.0, |s| s.extra_camera_depth())
    }
}

/// The thin-cloth pass, when some material used has a `transmission` effect.
fn thin_pass(
    gpu: &Gpu,
    scene: &Scene,
    btf: &BtfPass,
    materials: &Materials,
    geometry: &SceneGeometry,
) -> Result<Option<ThinPass>> {
    let descs: Vec<_> = materials
        .data()
        .iter()
        .enumerate()
        .map(|(k, data)| {
            let desc = &scene.materials[materials.scene_index(k)];
            (desc.transmission.as_ref(), data, desc.store.display().to_string())
        })
        .collect();
    if descs.iter().all(|d| d.0.is_none()) {
        return Ok(None);
    }
    let env = match scene.environment() {
        None => None,
        Some((light, e)) => {
            for (desc, _, name) in &descs {
                if let Some(d) = desc {
                    d.check_environment(name, e.two_sided)?;
                }
            }
            let entry = if btf.key.evaluation == Evaluation::PerVertex { light as u32 } else { 0 };
            Some(ThinEnv { vertices: geometry.mesh.positions.len(), entry })
        }
    };
    let (corners, slots) = (&geometry.corners, &geometry.slot_of_triangle);
    Ok(Some(ThinPass::new(gpu, btf, btf.key, &descs, corners, slots, env)?))
}
