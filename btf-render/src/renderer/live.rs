//! Updates of a built [`Renderer`] that an interactive viewer makes between frames, each
//! recomputing only what depends on it: a camera move rewrites the frame uniform at the next
//! [`Renderer::render`] (nothing else is rebuilt), a light move rebuilds only the shadow
//! pass (shadow-map matrices and shadow-volume prisms depend on the light), the offset `α`
//! of the smooth shadow boundary (eq. 6) is a uniform. Effects that select pipelines or
//! material data (evaluation mode, blending, components, shadow technique) need
//! [`Renderer::new`].

use super::{Renderer, frame_bind_group};
use crate::camera::CameraSetup;
use crate::passes::shadow::{ShadowInputs, Shadowing};
use crate::passes::smooth_boundary;
use crate::scene::{Camera, Light, MAX_LIGHTS};
use crate::{Error, Gpu, Result};

impl Renderer {
    /// Replaces the camera; the next frame uses it and nothing else is recomputed — except,
    /// the first time the camera really moves, the visibility of the vertex sides an
    /// environment light had left out for the old camera (all of them, then the gathers:
    /// [`SceneEnvironment::complete`](btf_light::SceneEnvironment::complete)).
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        self.scene.camera = camera.clone();
        let extra_depth = self.shadowing.as_ref().map_or(0.0, |s| s.extra_camera_depth());
        let setup = CameraSetup::new(&self.scene, &self.mesh, extra_depth);
        if setup != self.camera
            && let Some(e) = self.environment.as_mut()
        {
            let mesh = btf_light::EnvMesh {
                positions: &self.mesh.positions,
                normals: &self.mesh.normals,
                tangents: &self.tangents,
                triangles: &self.mesh.triangles,
            };
            e.env.complete(&mesh)?;
        }
        self.camera = setup;
        Ok(())
    }

    /// Replaces the lights (same count and kinds of light as before, so the passes the
    /// scene asked for stay valid); rebuilds the shadow pass when there is one.
    pub fn set_lights(&mut self, gpu: &Gpu, lights: &[Light]) -> Result<()> {
        if lights.len() != self.scene.lights.len() || lights.len() > MAX_LIGHTS {
            return Err(Error::Invalid(format!(
                "set_lights: {} lights given, the scene was built with {}",
                lights.len(),
                self.scene.lights.len()
            )));
        }
        let same_shadowing = lights
            .iter()
            .zip(&self.scene.lights)
            .all(|(a, b)| a.casts_shadows() == b.casts_shadows());
        if !same_shadowing {
            return Err(Error::Invalid(
                "set_lights: which lights cast shadows must not change".into(),
            ));
        }
        self.scene.lights = lights.to_vec();
        if self.shadowing.is_some() {
            let shadowing = Shadowing::new(gpu, &self.scene, &self.mesh)?;
            let inputs: ShadowInputs = shadowing.inputs(gpu);
            let boundary = smooth_boundary::texture(gpu, self.scene.effects.terminator_blur);
            self.frame_group = frame_bind_group(
                gpu,
                &self.btf,
                &self.frame_uniform,
                &boundary,
                &inputs,
                &self.counters,
            );
            self.shadowing = Some(shadowing);
        }
        Ok(())
    }

    /// Sets the offset `α` of the smooth shadow boundary (eq. 6), degrees in `[0, 90)`.
    pub fn set_terminator_deg(&mut self, alpha_deg: f32) -> Result<()> {
        if !(alpha_deg.is_finite() && (0.0..90.0).contains(&alpha_deg)) {
            return Err(Error::Invalid(format!("terminator offset {alpha_deg}° not in [0, 90)")));
        }
        self.scene.effects.terminator_deg = alpha_deg;
        Ok(())
    }

    /// Switches between the environment background and `output.background` (only for a
    /// scene built with `output.show_environment = true`, which keeps the map).
    pub fn set_show_environment(&mut self, on: bool) -> Result<()> {
        if self.environment.as_ref().is_none_or(|e| e.map.is_none()) {
            return Err(Error::Invalid(
                "set_show_environment: the scene was built without output.show_environment".into(),
            ));
        }
        self.scene.output.show_environment = on;
        Ok(())
    }
}
