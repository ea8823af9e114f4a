//! The environment light of a [`Renderer`] (Sattler et al. 2003, §5): building it for the
//! vertex sides the camera shows (`camera_sides.rs`, then §5.2's visibility and eq. 10's
//! gathers for those frames only), changing map, rotation and exposure, the setup costs it
//! reports, the environment background and the thin-cloth environment tables.

use super::*;

/// The environment light at run time and its index in the scene's lights.
pub(super) struct EnvState {
    pub(super) light: usize,
    pub(super) env: SceneEnvironment,
    /// The per-vertex fill and the camera's `γ*` bases it keeps.
    pub(super) fill: Mutex<EnvCoefficients>,
    /// The map itself, kept when the scene draws it as the background.
    pub(super) map: Option<EnvMap>,
}

impl Renderer {
    /// Loads the environment map of the scene's environment light (if any) and computes
    /// the visibility maps and weights — for the vertex sides this camera shows (the
    /// corner-id pass, [`crate::camera_sides`]) unless every side is asked for or a thin
    /// material needs the far sides too.
    pub(super) fn build_environment(&self, gpu: &Gpu) -> Result<Option<EnvState>> {
        let scene = &self.scene;
        let Some((light, desc)) = scene.environment() else { return Ok(None) };
        let map = EnvMap::load(&desc.path)?;
        let mesh = &self.mesh;
        let env_mesh = EnvMesh {
            positions: &mesh.positions,
            normals: &mesh.normals,
            tangents: &self.tangents,
            triangles: &mesh.triangles,
        };
        let params = desc.params();
        let camera_sides = !(self.options.all_env_sides
            || self.thin.is_some()
            || mesh.positions.len() >= crate::passes::corner_ids::MAX_VERTICES);
        let t = Instant::now();
        let wanted = if camera_sides && !SceneEnvironment::cache_holds_all(&params, &env_mesh)? {
            Some(self.camera_frames(gpu, params.two_sided)?)
        } else {
            None
        };
        let sides_ms = if wanted.is_some() { t.elapsed().as_secs_f64() * 1e3 } else { 0.0 };
        let lights = &self.materials[0].data.light_sampling;
        if self.materials.iter().any(|m| &m.data.light_sampling != lights) {
            return Err(Error::Unsupported(
                "environment lighting with materials of different light samplings".into(),
            ));
        }
        let coefficients = self.materials.iter().map(|m| m.data.coefficient_matrix()).collect();
        let mut env =
            SceneEnvironment::with_frames(params, &map, &env_mesh, lights, coefficients, wanted)?;
        env.timings.sides_ms = sides_ms;
        let map = scene.output.show_environment.then_some(map);
        Ok(Some(EnvState { light, env, fill: Mutex::default(), map }))
    }

    /// The hemicube frames this camera reads: the shown side of every vertex that some
    /// sample of the frame sees.
    fn camera_frames(&self, gpu: &Gpu, two_sided: bool) -> Result<Vec<bool>> {
        gpu.queue.write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&self.frame_raw()));
        let draws = self
            .draws
            .iter()
            .map(|d| (&self.materials[d.material].bind_group, d.first, d.count))
            .collect();
        let seen = crate::passes::corner_ids::seen_vertices(
            gpu,
            &crate::passes::corner_ids::CornerDraws {
                btf: &self.btf,
                corners: &self.corners,
                frame_group: &self.frame_group,
                draws,
                vertices: self.mesh.positions.len(),
                width: self.scene.output.width,
                height: self.scene.output.height,
            },
        )?;
        let samplings = self.view_samplings();
        let view = self.view_input(&samplings);
        Ok(btf_light::shown_frames(&view, two_sided, &seen))
    }

    /// The view sampling of every material.
    pub(super) fn view_samplings(&self) -> Vec<&btf_core::Sampling> {
        self.materials.iter().map(|m| &m.data.view_sampling).collect()
    }

    /// The camera and mesh inputs of the environment's per-vertex fill.
    pub(super) fn view_input<'a>(
        &'a self,
        samplings: &'a [&'a btf_core::Sampling],
    ) -> ViewInput<'a> {
        ViewInput {
            eye: self.camera.eye,
            ortho_to_camera: self.camera.ortho_to_camera,
            view_mode: self.scene.effects.view_blend,
            positions: &self.mesh.positions,
            normals: &self.mesh.normals,
            tangents: &self.tangents,
            material_of: &self.vertex_material,
            view_samplings: samplings,
        }
    }
}

impl Renderer {
    /// The environment light's run-time state, when the scene has one.
    pub fn environment(&self) -> Option<&SceneEnvironment> {
        self.environment.as_ref().map(|e| &e.env)
    }

    /// Mutable access to the environment (exact or eigenweightset rotations, weights).
    pub fn environment_mut(&mut self) -> Option<&mut SceneEnvironment> {
        self.environment.as_mut().map(|e| &mut e.env)
    }

    fn env_or_err(&mut self) -> Result<&mut SceneEnvironment> {
        self.environment_mut()
            .ok_or_else(|| Error::Invalid("the scene has no environment light".into()))
    }

    /// Turns the environment to `delta_deg` about world `+z` (eigenweightsets: `e` vector
    /// additions; else one gather). Visibility is kept.
    pub fn set_environment_rotation(&mut self, delta_deg: f64) -> Result<()> {
        self.env_or_err()?.set_rotation(delta_deg);
        Ok(())
    }

    /// Replaces the environment map (one gather, plus the eigenweightsets when the scene
    /// asks for them); visibility maps are kept.
    pub fn set_environment(&mut self, map: &EnvMap) -> Result<()> {
        self.env_or_err()?.set_environment(map)?;
        if let Some(e) = self.environment.as_mut().filter(|e| e.map.is_some()) {
            e.map = Some(map.clone());
        }
        Ok(())
    }

    /// Sets the environment's exposure `f`.
    pub fn set_environment_exposure(&mut self, f: f32) -> Result<()> {
        self.env_or_err()?.set_exposure(f);
        Ok(())
    }

    /// One-off costs of preparing the scene (visibility maps, gathers, eigenweightsets).
    pub fn setup_stats(&self) -> Vec<PassStat> {
        let Some(e) = &self.environment else { return Vec::new() };
        let t = &e.env.timings;
        let mut out = Vec::new();
        if t.sides_ms > 0.0 {
            out.push(PassStat { name: "env camera sides (corner-id pass)".into(), ms: t.sides_ms });
        }
        out.push(PassStat {
            name: match (t.visibility_cached, e.env.computed_frames(), e.env.frames()) {
                (true, _, _) => "env visibility maps (cache)".into(),
                (false, c, all) if c == all => format!("env visibility maps ({all} frames, cpu)"),
                (false, c, all) => {
                    format!("env visibility maps ({c} of {all} frames the camera sees, cpu)")
                }
            },
            ms: t.visibility_ms,
        });
        out.push(PassStat { name: "env gather g (cpu)".into(), ms: t.weights_ms });
        if let Some(ews) = e.env.eigenweightsets() {
            out.push(PassStat {
                name: format!("env eigenweightsets (A = {}, cpu)", ews.rotations),
                ms: t.eigen_ms,
            });
        }
        out
    }

    /// Writes the environment background into `color` when the scene shows it; returns
    /// whether it did.
    pub(super) fn write_env_background(
        &self,
        gpu: &Gpu,
        color: &wgpu::Texture,
        timer: &mut PassTimer,
    ) -> bool {
        let Some((e, map)) = self.environment.as_ref().and_then(|e| Some((e, e.map.as_ref()?)))
        else {
            return false;
        };
        if !self.scene.output.show_environment {
            return false;
        }
        let t = Instant::now();
        let (w, h) = (self.scene.output.width, self.scene.output.height);
        let rot = e.env.rotation_deg();
        let img =
            crate::passes::background::image(map, &self.camera, (w, h), rot, e.env.exposure());
        gpu.queue.write_texture(
            color.as_image_copy(),
            bytemuck::cast_slice(&img),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 16),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        timer.cpu("environment background (cpu)", t.elapsed().as_secs_f64() * 1e3);
        true
    }

    /// The environment background of the current camera, rotation and exposure (linear
    /// RGB, row-major from the top), when the scene shows it.
    pub fn environment_background(&self) -> Option<Vec<f32>> {
        let e = self.environment.as_ref()?;
        let map = e.map.as_ref()?;
        let size = (self.scene.output.width, self.scene.output.height);
        let img = crate::passes::background::image(
            map,
            &self.camera,
            size,
            e.env.rotation_deg(),
            e.env.exposure(),
        );
        Some(img.iter().flat_map(|p| [p[0], p[1], p[2]]).collect())
    }

    /// Recomputes and uploads the thin-cloth environment tables when the environment,
    /// its rotation or its exposure changed since the last frame.
    pub(super) fn update_thin_env_tables(&self, gpu: &Gpu, timer: &mut PassTimer) -> Result<()> {
        let (Some(thin), Some(e)) = (&self.thin, &self.environment) else { return Ok(()) };
        let key = (e.env.rotation_deg(), e.env.exposure(), e.env.revision());
        let mut last = self.thin_env_key.lock().map_err(|_| Error::Gpu("poisoned lock".into()))?;
        if *last == Some(key) {
            return Ok(());
        }
        let t = Instant::now();
        let slab_of: Vec<_> = self
            .vertex_material
            .iter()
            .map(|&m| if m == usize::MAX { None } else { thin.slab(m) })
            .collect();
        let tables = btf_light::thin_tables::tables(&e.env, &slab_of)?;
        thin.write_env_tables(gpu, &tables)?;
        timer.cpu("thin-cloth env tables (cpu)", t.elapsed().as_secs_f64() * 1e3);
        *last = Some(key);
        Ok(())
    }
}
