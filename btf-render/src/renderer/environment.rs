//! The environment light of a renderer at run time (`[S03 §5]`): built for the vertex sides
//! the camera shows (the corner-id pass, then `[S03 §5.2]`'s visibility and `[S03 eq. 10]`'s
//! gathers for those frames only, in `btf_light`), the per-vertex fill of `[S03 eq. 11]`,
//! changes of map, rotation and exposure, the setup costs it reports, the map kept for the
//! background, and when the thin-cloth tables (`[TC eq. 7–8]` under the environment) are due.

use super::geometry::SceneGeometry;
use super::materials::Materials;
use crate::camera::CameraSetup;
use crate::frame::PassStat;
use crate::passes::background::BackgroundPass;
use crate::passes::btf::BtfPass;
use crate::passes::corner_ids::{self, CornerDraws};
use crate::scene::Scene;
use crate::{Error, Gpu, Result};
use btf_image::EnvMap;
use btf_light::{EnvCoefficients, SceneEnvironment, Slots, ViewInput};
use std::time::Instant;

/// What building the environment reads of the renderer.
pub(crate) struct EnvInputs<'a> {
    /// The scene (its environment light and `show_environment`).
    pub scene: &'a Scene,
    /// Mesh, tangents, corners and draws.
    pub geometry: &'a SceneGeometry,
    /// The materials (light samplings, coefficient matrices, bind groups).
    pub materials: &'a Materials,
    /// The BTF pass (the corner-id pass rasterises with it).
    pub btf: &'a BtfPass,
    /// Group 0, its uniform holding this frame's camera.
    pub frame_group: &'a wgpu::BindGroup,
    /// The camera.
    pub camera: &'a CameraSetup,
    /// Compute every vertex side, not only those the camera shows.
    pub all_sides: bool,
}

/// The environment light at run time and its index in the scene's lights.
pub(crate) struct EnvState {
    light: usize,
    env: SceneEnvironment,
    /// The per-vertex fill and the camera's `γ*` bases it keeps.
    fill: EnvCoefficients,
    /// The background pass, when the scene draws the map behind it.
    background: Option<BackgroundPass>,
    /// A map set since the background last uploaded one.
    pending_map: Option<EnvMap>,
    /// `(rotation, exposure, revision)` the thin-cloth tables were computed for.
    thin_key: Option<(f64, f32, u64)>,
}

impl EnvState {
    /// Loads the map of the scene's environment light (if any) and computes the visibility
    /// maps and radiances — for the vertex sides this camera shows (the corner-id pass)
    /// unless every side is asked for.
    pub fn build(gpu: &Gpu, input: &EnvInputs) -> Result<Option<EnvState>> {
        let scene = input.scene;
        let Some((light, desc)) = scene.environment() else { return Ok(None) };
        let map = EnvMap::load(&desc.path)?;
        let geometry = input.geometry;
        let env_mesh = geometry.env_mesh();
        let params = desc.params();
        let camera_sides =
            !(input.all_sides || geometry.mesh.positions.len() >= corner_ids::MAX_VERTICES);
        let t = Instant::now();
        let wanted = if camera_sides && !SceneEnvironment::cache_holds_all(&params, &env_mesh)? {
            Some(camera_frames(gpu, input, params.two_sided)?)
        } else {
            None
        };
        let sides_ms = if wanted.is_some() { t.elapsed().as_secs_f64() * 1e3 } else { 0.0 };
        let data = input.materials.data();
        let lights = &data[0].light_sampling;
        if data.iter().any(|m| &m.light_sampling != lights) {
            return Err(Error::Unsupported(
                "environment lighting with materials of different light samplings".into(),
            ));
        }
        let coefficients = data.iter().map(|m| m.coefficient_matrix()).collect();
        let mut env =
            SceneEnvironment::with_frames(params, &map, &env_mesh, lights, coefficients, wanted)?;
        env.timings.sides_ms = sides_ms;
        let background = match scene.output.show_environment {
            true => Some(BackgroundPass::new(gpu, &map, scene.effects.msaa)?),
            false => None,
        };
        Ok(Some(EnvState {
            light,
            env,
            fill: EnvCoefficients::default(),
            background,
            pending_map: None,
            thin_key: None,
        }))
    }

    /// The light's index in the scene's lights.
    pub fn light(&self) -> usize {
        self.light
    }

    /// The run-time environment.
    pub fn env(&self) -> &SceneEnvironment {
        &self.env
    }

    /// The run-time environment, to turn or re-expose.
    pub fn env_mut(&mut self) -> &mut SceneEnvironment {
        &mut self.env
    }

    /// Replaces the map (one gather over the kept visibility, and the eigenweightsets; the
    /// background takes it at its next frame).
    pub fn set_map(&mut self, map: &EnvMap) -> Result<()> {
        self.env.set_environment(map)?;
        if self.background.is_some() {
            self.pending_map = Some(map.clone());
        }
        Ok(())
    }

    /// Whether the scene was built to draw the map behind it.
    pub fn has_background(&self) -> bool {
        self.background.is_some()
    }

    /// The background pass with the current map, when the scene draws one.
    pub fn background(&mut self, gpu: &Gpu) -> Result<Option<&BackgroundPass>> {
        if let (Some(bg), Some(map)) = (self.background.as_mut(), self.pending_map.take()) {
            bg.set_map(gpu, &map)?;
        }
        Ok(self.background.as_ref())
    }

    /// Writes `f · ω_m · γ*` (`[S03 eq. 11]`) of every vertex for this camera into `coef`.
    pub fn fill(&mut self, coef: &mut [[f32; 4]], view: &ViewInput, at: Slots) {
        self.fill.fill(&self.env, coef, view, at);
    }

    /// Makes the visibility of the vertex sides the first camera left out (a camera move);
    /// true when there were any.
    pub fn complete(&mut self, geometry: &SceneGeometry) -> Result<bool> {
        Ok(self.env.complete(&geometry.env_mesh())?)
    }

    /// The thin-cloth environment tables for the current map, rotation and exposure, when
    /// they changed since the last call (`slab_of[v]`: the slab of vertex `v`'s material).
    pub fn thin_tables_if_changed(
        &mut self,
        slab_of: impl FnOnce() -> Vec<Option<btf_light::thin_tables::SlabParams>>,
    ) -> Result<Option<Vec<[f32; 4]>>> {
        let key = (self.env.rotation_deg(), self.env.exposure(), self.env.revision());
        if self.thin_key == Some(key) {
            return Ok(None);
        }
        let tables = btf_light::thin_tables::tables(&self.env, &slab_of())?;
        self.thin_key = Some(key);
        Ok(Some(tables))
    }

    /// One-off costs of preparing the scene (visibility maps, gathers, eigenweightsets).
    pub fn setup_stats(&self) -> Vec<PassStat> {
        let (e, t) = (&self.env, &self.env.timings);
        let mut out = Vec::new();
        if t.sides_ms > 0.0 {
            out.push(PassStat { name: "env camera sides (corner-id pass)".into(), ms: t.sides_ms });
        }
        out.push(PassStat {
            name: match (t.visibility_cached, e.computed_frames(), e.frames()) {
                (true, _, _) => "env visibility maps (cache)".into(),
                (false, c, all) if c == all => format!("env visibility maps ({all} frames, cpu)"),
                (false, c, all) => {
                    format!("env visibility maps ({c} of {all} frames the camera sees, cpu)")
                }
            },
            ms: t.visibility_ms,
        });
        out.push(PassStat { name: "env gather g (cpu)".into(), ms: t.weights_ms });
        if let Some(ews) = e.eigenweightsets() {
            out.push(PassStat {
                name: format!("env eigenweightsets (A = {}, cpu)", ews.rotations),
                ms: t.eigen_ms,
            });
        }
        out
    }
}

/// The hemicube frames this camera reads: the shown side of every vertex that some sample
/// of the frame sees (the corner-id pass; group 0 must hold this camera).
fn camera_frames(gpu: &Gpu, input: &EnvInputs, two_sided: bool) -> Result<Vec<bool>> {
    let g = input.geometry;
    let draws = g
        .draws
        .iter()
        .map(|d| (input.materials.bind_group(d.material), d.first, d.count))
        .collect();
    let seen = corner_ids::seen_vertices(
        gpu,
        &CornerDraws {
            btf: input.btf,
            corners: &g.corner_buffer,
            frame_group: input.frame_group,
            draws,
            vertices: g.mesh.positions.len(),
            width: input.scene.output.width,
            height: input.scene.output.height,
        },
    )?;
    let samplings = input.materials.view_samplings();
    let view = g.view_input(input.camera, input.scene.effects.view_blend, &samplings);
    Ok(btf_light::shown_frames(&view, two_sided, &seen))
}
