//! Builds the runtime objects of a [`Scene`] — merged mesh with tangent frames, uploaded
//! materials, the passes the scene asks for — and renders frames.
//!
//! Only what the scene calls for is built and run (DESIGN.md §3): the smooth shadow
//! boundary (eq. 6) and a shadow pass only with a shadowing light and `shadows ≠ none`;
//! per-vertex coefficients only in per-vertex mode or with an environment light; visibility
//! maps, gathers and eigenweightsets only with an environment light; blending work only
//! with `four`.
//!
//! An environment light is always evaluated per vertex, as in the paper (§5.3: `f · ω_m ·
//! γ*_{k j_m}` per vertex, eq. 11 with the view blending of eq. 5). Its contribution is
//! *added* to the other lights': in per-vertex mode it is one more light of the per-vertex
//! layout; in per-pixel mode the point/directional lights stay per pixel and the fragment
//! shader adds the environment's per-vertex reconstruction (`fs_pixel_env`). The
//! environment can be turned or swapped without recomputing visibility
//! ([`Renderer::set_environment_rotation`], [`Renderer::set_environment`]).

use crate::btf_pass::{
    BtfPass, BtfPassKey, CornerVertex, DEPTH_FORMAT, FrameRaw, LightRaw, color_format,
};
use crate::envlight::scene_env::{EnvMesh, ViewInput};
use crate::envlight::{EnvMap, SceneEnvironment};
use crate::frame::{Frame, PassStat, Stats};
use crate::material::{MaterialData, MaterialGpu};
use crate::math::{self, Mat4, Vec3, v3};
use crate::mesh::Mesh;
use crate::per_vertex::{self, VertexEvalInput, VertexLight};
use crate::plain_texture::{Baseline, BaselinePass};
use crate::scene::{Evaluation, Light, Projection, Scene, Shadows};
use crate::shadow::{ShadowInputs, Shadowing};
use crate::timer::PassTimer;
use crate::transmission::{ThinEnv, ThinPass};
use crate::{Error, Gpu, Result, tangent, terminator};
use btf_core::InterpMode;
use std::sync::Mutex;
use std::time::Instant;
use wgpu::util::DeviceExt;

mod live;

/// Extra knobs for tests and measurements.
#[derive(Debug, Clone, Copy, Default)]
pub struct RenderOptions {
    /// Count texture reads per pixel in the BTF pass (atomics; slows the pass).
    pub count_reads: bool,
    /// Draw a cost baseline instead of the BTF shader (same mesh, targets and textures).
    pub baseline: Option<Baseline>,
    /// Compute an environment light's visibility for every vertex side, not only for the
    /// sides the scene's camera shows (for a viewer whose camera moves; a fixed camera
    /// needs only its own, see [`crate::camera_sides`]).
    pub all_env_sides: bool,
}

struct LoadedMaterial {
    data: MaterialData,
    _gpu: MaterialGpu,
    bind_group: wgpu::BindGroup,
}

struct Draw {
    material: usize,
    first: u32,
    count: u32,
}

/// Camera matrices and the quantities shaders need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSetup {
    /// World → clip.
    pub view_proj: Mat4,
    /// Eye position.
    pub eye: Vec3,
    /// Direction towards the camera for orthographic projections.
    pub ortho_to_camera: Option<Vec3>,
}

/// A scene ready to render.
pub struct Renderer {
    scene: Scene,
    mesh: Mesh,
    tangents: Vec<[f32; 4]>,
    vertex_material: Vec<usize>,
    corners: wgpu::Buffer,
    draws: Vec<Draw>,
    materials: Vec<LoadedMaterial>,
    btf: BtfPass,
    baseline: Option<BaselinePass>,
    frame_uniform: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    counters: wgpu::Buffer,
    shadowing: Option<Shadowing>,
    environment: Option<EnvState>,
    thin: Option<ThinPass>,
    /// `(rotation, exposure, revision)` of the environment the thin-cloth tables were
    /// computed for.
    thin_env_key: Mutex<Option<(f64, f32, u64)>>,
    camera: CameraSetup,
    options: RenderOptions,
    /// Bytes of material data on the GPU.
    pub material_bytes: u64,
}

/// The environment light at run time and its index in the scene's lights.
struct EnvState {
    light: usize,
    env: SceneEnvironment,
    /// The map itself, kept when the scene draws it as the background.
    map: Option<EnvMap>,
}

impl Renderer {
    /// Loads the environment map of the scene's environment light (if any) and computes
    /// the visibility maps and weights — for the vertex sides this camera shows (the
    /// corner-id pass, [`crate::camera_sides`]) unless every side is asked for or a thin
    /// material needs the far sides too.
    fn build_environment(&self, gpu: &Gpu) -> Result<Option<EnvState>> {
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
        let t = Instant::now();
        let wanted = if self.options.all_env_sides
            || self.thin.is_some()
            || mesh.positions.len() >= crate::camera_sides::MAX_VERTICES
        {
            None
        } else {
            Some(self.camera_frames(gpu, params.two_sided)?)
        };
        let mats: Vec<&MaterialData> = self.materials.iter().map(|m| &m.data).collect();
        let sides_ms = if wanted.is_some() { t.elapsed().as_secs_f64() * 1e3 } else { 0.0 };
        let mut env = SceneEnvironment::with_frames(params, &map, &env_mesh, &mats, wanted)?;
        env.timings.sides_ms = sides_ms;
        let map = scene.output.show_environment.then_some(map);
        Ok(Some(EnvState { light, env, map }))
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
        let seen = crate::camera_sides::seen_vertices(
            gpu,
            &crate::camera_sides::CornerDraws {
                btf: &self.btf,
                corners: &self.corners,
                frame_group: &self.frame_group,
                draws,
                vertices: self.mesh.positions.len(),
                width: self.scene.output.width,
                height: self.scene.output.height,
            },
        )?;
        let mats: Vec<&MaterialData> = self.materials.iter().map(|m| &m.data).collect();
        let view = self.view_input(&mats);
        Ok(crate::envlight::shown_frames(&view, two_sided, &seen))
    }

    /// The camera and mesh inputs of the environment's per-vertex fill.
    fn view_input<'a>(&'a self, mats: &'a [&'a MaterialData]) -> ViewInput<'a> {
        ViewInput {
            eye: self.camera.eye,
            ortho_to_camera: self.camera.ortho_to_camera,
            view_mode: self.scene.effects.view_blend,
            positions: &self.mesh.positions,
            normals: &self.mesh.normals,
            tangents: &self.tangents,
            material_of: &self.vertex_material,
            materials: mats,
        }
    }
}

/// Merges the scene's meshes and assigns each triangle a scene material index.
fn load_meshes(scene: &Scene) -> Result<(Mesh, Vec<usize>)> {
    let mut mesh = Mesh::default();
    let mut tri_desc = Vec::new();
    for desc in &scene.meshes {
        let m = Mesh::load_obj(&desc.path, desc.planar_uv)?;
        let base = mesh.positions.len() as u32;
        let mut mat_of_name = Vec::new();
        for name in &m.material_names {
            let found = scene
                .materials
                .iter()
                .position(|md| md.name.as_deref() == Some(name.as_str()))
                .or_else(|| scene.materials.iter().position(|md| md.name.is_none()));
            let Some(i) = found else {
                let what = if name.is_empty() {
                    "faces without `usemtl`".to_string()
                } else {
                    format!("material '{name}'")
                };
                return Err(Error::Invalid(format!(
                    "{}: {what} has no [[materials]] entry (add one with that name, or one without a name as default)",
                    desc.path.display()
                )));
            };
            mat_of_name.push(i);
        }
        mesh.triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        tri_desc.extend(m.triangle_material.iter().map(|&id| mat_of_name[id as usize]));
        mesh.positions.extend(m.positions);
        mesh.normals.extend(m.normals);
        mesh.uvs.extend(m.uvs);
        mesh.repaired_normals += m.repaired_normals;
    }
    Ok((mesh, tri_desc))
}

fn camera_setup(scene: &Scene, mesh: &Mesh, extra_depth: f32) -> CameraSetup {
    let c = &scene.camera;
    let (lo, hi) = mesh.bounds();
    let center = (v3(lo) + v3(hi)) * 0.5;
    let radius = ((v3(hi) - v3(lo)).norm() * 0.5).max(1e-6);
    let (eye, target) = (v3(c.eye), v3(c.target));
    let dir = target - eye;
    let view = math::look_at(eye, target, math::safe_up(dir, v3(c.up)));
    let aspect = scene.output.width as f32 / scene.output.height as f32;
    let dist = (center - eye).norm();
    let far = dist + radius * 1.05 + extra_depth;
    match c.projection {
        Projection::Perspective => {
            let near = (dist - radius * 1.05).max(far * 1e-4);
            CameraSetup {
                view_proj: math::perspective(c.fov_y_deg, aspect, near, far) * view,
                eye,
                ortho_to_camera: None,
            }
        }
        Projection::Orthographic => {
            let near = dist - radius * 1.05 - extra_depth;
            let proj = math::orthographic(c.ortho_height * aspect, c.ortho_height, near, far);
            CameraSetup { view_proj: proj * view, eye, ortho_to_camera: Some(-dir.normalize()) }
        }
    }
}

impl Renderer {
    /// Loads meshes and materials and builds the passes the scene asks for.
    pub fn new(gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Renderer> {
        let (mesh, tri_desc) = load_meshes(scene)?;
        let tangents = tangent::compute_tangents(&mesh);
        // Materials actually used, each loaded once.
        let mut used: Vec<usize> = tri_desc.clone();
        used.sort_unstable();
        used.dedup();
        let mut slot_of_desc = vec![usize::MAX; scene.materials.len()];
        let mut datas = Vec::new();
        for &d in &used {
            slot_of_desc[d] = datas.len();
            datas.push(MaterialData::load(&scene.materials[d].store, scene.effects.components)?);
        }
        let fx = &scene.effects;
        let key = BtfPassKey {
            evaluation: fx.evaluation,
            view_four: fx.view_blend == InterpMode::Four,
            light_four: fx.light_interp == InterpMode::Four,
            msaa: fx.msaa,
            count_reads: options.count_reads,
            environment: scene.environment().is_some(),
            shadows: match (scene.wants_shadow_pass(), fx.shadows) {
                (false, _) | (_, Shadows::None) => 0,
                (true, Shadows::Volume) => 1,
                (true, Shadows::Map) => 2,
            },
            smooth_boundary: scene.wants_shadow_pass() && fx.smooth_boundary,
            lights: scene.lights.len() as u32,
        };
        let btf = BtfPass::new(gpu, key)?;
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("btf texels"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: if fx.mipmaps { fx.anisotropy } else { 1 },
            ..Default::default()
        });
        let mut materials = Vec::new();
        let mut material_bytes = 0;
        for (k, data) in datas.into_iter().enumerate() {
            let desc = &scene.materials[used[k]];
            let gpu_mat = MaterialGpu::upload_with(
                gpu,
                &data,
                &desc.store.display().to_string(),
                fx.mipmaps,
            )?;
            material_bytes += gpu_mat.bytes;
            let samplings = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("samplings"),
                contents: bytemuck::bytes_of(&data.samplings_raw(desc.uv_scale)),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind_group = btf.material_bind_group(gpu, &gpu_mat, &samplings, &sampler);
            materials.push(LoadedMaterial { data, _gpu: gpu_mat, bind_group });
        }
        // Corners sorted by material, one draw per material.
        let mut order: Vec<usize> = (0..mesh.triangles.len()).collect();
        order.sort_by_key(|&t| slot_of_desc[tri_desc[t]]);
        let mut corners = Vec::with_capacity(order.len() * 3);
        let mut draws: Vec<Draw> = Vec::new();
        let mut vertex_material = vec![usize::MAX; mesh.positions.len()];
        for &t in &order {
            let m = slot_of_desc[tri_desc[t]];
            match draws.last_mut() {
                Some(d) if d.material == m => d.count += 3,
                _ => draws.push(Draw { material: m, first: corners.len() as u32, count: 3 }),
            }
            let tri = mesh.triangles[t];
            for (corner, &v) in tri.iter().enumerate() {
                let v = v as usize;
                vertex_material[v] = m;
                corners.push(CornerVertex {
                    position: mesh.positions[v],
                    normal: mesh.normals[v],
                    tangent: tangents[v],
                    uv: mesh.uvs[v],
                    tri,
                    corner: corner as u32,
                });
            }
        }
        let thin = thin_pass(
            gpu,
            scene,
            &btf,
            key,
            &materials,
            &used,
            &corners,
            &order,
            &slot_of_desc,
            &tri_desc,
            mesh.positions.len(),
        )?;
        let corners = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("corners"),
            contents: bytemuck::cast_slice(&corners),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let baseline = match options.baseline {
            None => None,
            Some(Baseline::Plain) => Some(crate::plain_texture::build(gpu, &btf)?),
            Some(Baseline::ReadBound { reads_per_pixel }) => {
                let m = &materials[0].data;
                let views = m.view_sampling.len();
                Some(crate::read_bound::build(gpu, &btf, reads_per_pixel, m.groups, views)?)
            }
        };
        let shadowing =
            if scene.wants_shadow_pass() { Some(Shadowing::new(gpu, scene, &mesh)?) } else { None };
        let extra_depth = shadowing.as_ref().map_or(0.0, |s| s.extra_camera_depth());
        let camera = camera_setup(scene, &mesh, extra_depth);
        let frame_uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read counters"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let inputs = match &shadowing {
            Some(s) => s.inputs(gpu, scene.output.width, scene.output.height),
            None => ShadowInputs::dummy(gpu),
        };
        let boundary = if shadowing.is_some() {
            terminator::texture(gpu, fx.terminator_blur)
        } else {
            terminator::texture(gpu, 0) // 1 KiB placeholder; never sampled without a shadowing light
        };
        let frame_group =
            frame_bind_group(gpu, &btf, &frame_uniform, &boundary, &inputs, &counters);
        let mut renderer = Renderer {
            scene: scene.clone(),
            mesh,
            tangents,
            vertex_material,
            corners,
            draws,
            materials,
            btf,
            baseline,
            frame_uniform,
            frame_group,
            counters,
            shadowing,
            environment: None,
            thin,
            thin_env_key: Mutex::new(None),
            camera,
            options,
            material_bytes,
        };
        renderer.environment = renderer.build_environment(gpu)?;
        Ok(renderer)
    }

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

    /// The scene this renderer was built from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The merged mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Camera matrices in use.
    pub fn camera(&self) -> &CameraSetup {
        &self.camera
    }

    /// Components the materials use (the smallest over materials).
    pub fn components(&self) -> usize {
        self.materials.iter().map(|m| m.data.components).min().unwrap_or(0)
    }

    fn frame_raw(&self) -> FrameRaw {
        let fx = &self.scene.effects;
        let mut raw = FrameRaw {
            view_proj: math::to_cols(&self.camera.view_proj),
            eye: [self.camera.eye.x, self.camera.eye.y, self.camera.eye.z, 1.0],
            info: [
                self.scene.lights.len() as u32,
                (self.shadowing.is_some() && fx.smooth_boundary) as u32,
                self.materials.iter().map(|m| m.data.groups).max().unwrap_or(1) as u32,
                self.vertex_entries() as u32,
            ],
            terminator: [fx.terminator_deg.to_radians(), 0.0, 0.0, 0.0],
            ..Default::default()
        };
        if let Some(d) = self.camera.ortho_to_camera {
            raw.eye[3] = 0.0;
            raw.to_camera = [d.x, d.y, d.z, 0.0];
        }
        for (l, light) in self.scene.lights.iter().enumerate() {
            let shadow_kind = match (&self.shadowing, light.casts_shadows(), fx.shadows) {
                (Some(_), true, Shadows::Volume) => 1.0,
                (Some(_), true, Shadows::Map) => 2.0,
                _ => 0.0,
            };
            let mut lr = match light {
                Light::Directional { direction, irradiance, .. } => {
                    let d = v3(*direction).normalize();
                    LightRaw {
                        pos: [d.x, d.y, d.z, 0.0],
                        color: [irradiance[0], irradiance[1], irradiance[2], shadow_kind],
                        ..Default::default()
                    }
                }
                Light::Point { position, intensity, .. } => LightRaw {
                    pos: [position[0], position[1], position[2], 1.0],
                    color: [intensity[0], intensity[1], intensity[2], shadow_kind],
                    ..Default::default()
                },
                // Zero power per pixel; its light comes from the per-vertex coefficients.
                Light::Environment(_) => {
                    LightRaw { pos: [0.0, 0.0, 1.0, 0.0], ..Default::default() }
                }
            };
            if let Some(s) = &self.shadowing {
                s.fill_light_raw(l, &mut lr);
            }
            raw.lights[l] = lr;
        }
        raw
    }

    fn vertex_lights(&self) -> Vec<VertexLight> {
        self.scene
            .lights
            .iter()
            .map(|l| match l {
                Light::Directional { direction, irradiance, .. } => VertexLight {
                    pos_or_dir: v3(*direction).normalize(),
                    point: false,
                    color: *irradiance,
                },
                Light::Point { position, intensity, .. } => {
                    VertexLight { pos_or_dir: v3(*position), point: true, color: *intensity }
                }
                // Filled by the environment's own coefficients (zero power skips the fold).
                Light::Environment(_) => {
                    VertexLight { pos_or_dir: Vec3::z(), point: false, color: [0.0; 3] }
                }
            })
            .collect()
    }

    /// Lights per vertex in the per-vertex layout: all lights in per-vertex mode, the
    /// environment alone in per-pixel mode.
    fn vertex_entries(&self) -> usize {
        match (self.scene.effects.evaluation, &self.environment) {
            (Evaluation::PerVertex, _) => self.scene.lights.len(),
            (Evaluation::PerPixel, Some(_)) => 1,
            (Evaluation::PerPixel, None) => 0,
        }
    }

    /// Renders one frame and reads it back.
    pub fn render(&self, gpu: &Gpu) -> Result<Frame> {
        let (w, h) = (self.scene.output.width, self.scene.output.height);
        let msaa = self.scene.effects.msaa;
        let start = Instant::now();
        let mut timer = PassTimer::new(gpu, 16);
        gpu.queue.write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&self.frame_raw()));
        gpu.queue.write_buffer(&self.counters, 0, &[0u8; 16]);
        let per_vertex_group = if self.btf.key.uses_vertex_coefficients() && self.baseline.is_none()
        {
            Some(self.per_vertex_bind_group(gpu, &mut timer)?)
        } else {
            None
        };
        if let Some(s) = &self.shadowing {
            s.encode(
                gpu,
                &mut timer,
                &self.corners,
                self.mesh.triangles.len() as u32 * 3,
                &self.camera,
            )?;
        }
        let target = |format, samples, usage| {
            gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("btf target"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color = target(
            color_format(msaa),
            1,
            att | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        );
        let background = self.write_env_background(gpu, &color, &mut timer);
        let color_ms = (msaa > 1).then(|| target(color_format(msaa), msaa, att));
        let depth = target(DEPTH_FORMAT, msaa, att);
        let color_view = color.create_view(&Default::default());
        let ms_view = color_ms.as_ref().map(|t| t.create_view(&Default::default()));
        let depth_view = depth.create_view(&Default::default());
        self.update_thin_env_tables(gpu, &mut timer)?;
        let thin_draws = self.thin.as_ref().map(|t| {
            let t0 = Instant::now();
            let draws = t.prepare(gpu, &self.camera);
            timer.cpu("thin-cloth sort (cpu)", t0.elapsed().as_secs_f64() * 1e3);
            draws
        });
        let bg = self.scene.output.background;
        let name = match (&self.baseline, self.scene.effects.evaluation) {
            (Some(b), _) => b.name.as_str(),
            (None, Evaluation::PerPixel) => "btf (per-pixel)",
            (None, Evaluation::PerVertex) => "btf (per-vertex)",
        };
        gpu.scoped("BTF pass", || {
            timer.pass(name, |enc, ts| {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(name),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: ms_view.as_ref().unwrap_or(&color_view),
                        depth_slice: None,
                        resolve_target: ms_view.as_ref().map(|_| &color_view),
                        ops: wgpu::Operations {
                            load: if background {
                                wgpu::LoadOp::Load
                            } else {
                                wgpu::LoadOp::Clear(wgpu::Color {
                                    r: bg[0] as f64,
                                    g: bg[1] as f64,
                                    b: bg[2] as f64,
                                    a: 1.0,
                                })
                            },
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(
                    self.baseline.as_ref().map_or(&self.btf.pipeline, |b| &b.pipeline),
                );
                pass.set_bind_group(0, &self.frame_group, &[]);
                if let Some(g) = &per_vertex_group {
                    pass.set_bind_group(2, &g.2, &[]);
                }
                if let Some(g) = self.baseline.as_ref().and_then(|b| b.group.as_ref()) {
                    pass.set_bind_group(2, g, &[]);
                }
                pass.set_vertex_buffer(0, self.corners.slice(..));
                for d in &self.draws {
                    if self.thin.as_ref().is_some_and(|t| t.is_thin(d.material)) {
                        continue;
                    }
                    pass.set_bind_group(1, &self.materials[d.material].bind_group, &[]);
                    pass.draw(d.first..d.first + d.count, 0..1);
                }
                if let (Some(t), Some(d)) = (&self.thin, &thin_draws) {
                    let vertex_group = per_vertex_group.as_ref().map(|g| &g.2);
                    let material = |m: usize| &self.materials[m].bind_group;
                    t.draw(&mut pass, &self.frame_group, vertex_group, material, d);
                }
            })
        })??;
        let passes = timer.finish()?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let rgb = read_rgb(gpu, &color, msaa)?;
        let mut stats = Stats {
            passes,
            frame_ms,
            timing: if gpu.timestamps { "gpu-timestamps" } else { "cpu" }.into(),
            setup: self.setup_stats(),
            ..Default::default()
        };
        if self.options.count_reads {
            let read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: 16,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(&self.counters, 0, &read, 0, 16);
            gpu.queue.submit([enc.finish()]);
            let c: Vec<u32> = bytemuck::cast_slice(&gpu.read_buffer(&read)?).to_vec();
            stats.shaded_pixels = Some(c[1] as u64);
            stats.reads_per_pixel = Some(if c[1] > 0 { c[0] as f64 / c[1] as f64 } else { 0.0 });
        }
        Ok(Frame { width: w, height: h, rgb, stats })
    }

    /// Writes the environment background into `color` when the scene shows it; returns
    /// whether it did.
    fn write_env_background(
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
        let img = crate::env_background::image(map, &self.camera, (w, h), rot, e.env.exposure());
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
        let img = crate::env_background::image(
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
    fn update_thin_env_tables(&self, gpu: &Gpu, timer: &mut PassTimer) -> Result<()> {
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
        let tables = crate::transmission::env::tables(&e.env, &slab_of)?;
        thin.write_env_tables(gpu, &tables)?;
        timer.cpu("thin-cloth env tables (cpu)", t.elapsed().as_secs_f64() * 1e3);
        *last = Some(key);
        Ok(())
    }

    fn per_vertex_bind_group(
        &self,
        gpu: &Gpu,
        timer: &mut PassTimer,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer, wgpu::BindGroup)> {
        let t = Instant::now();
        let per_vertex = self.scene.effects.evaluation == Evaluation::PerVertex;
        let lights = if per_vertex { self.vertex_lights() } else { Vec::new() };
        let mats: Vec<&MaterialData> = self.materials.iter().map(|m| &m.data).collect();
        let input = VertexEvalInput {
            eye: self.camera.eye,
            ortho_to_camera: self.camera.ortho_to_camera,
            lights: &lights,
            view_mode: self.scene.effects.view_blend,
            light_mode: self.scene.effects.light_interp,
            groups_stride: mats.iter().map(|m| m.groups).max().unwrap_or(1),
        };
        let mut vc = per_vertex::compute(
            &self.mesh.positions,
            &self.mesh.normals,
            &self.tangents,
            &self.vertex_material,
            &mats,
            &input,
        );
        if per_vertex {
            timer.cpu("per-vertex coefficients (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        if let Some(e) = &self.environment {
            let t = Instant::now();
            let view = self.view_input(&mats);
            let (l, entries) = if per_vertex { (e.light, lights.len()) } else { (0, 1) };
            let stride = per_vertex::stride(input.groups_stride);
            e.env.fill(&mut vc, &view, l, entries, stride);
            timer.cpu("env coefficients per vertex (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        let mk = |label, bytes: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let coef = mk("vertex coefficients", bytemuck::cast_slice(&vc.coef));
        let slots = mk("vertex slots", bytemuck::cast_slice(&vc.slots));
        let layout = self
            .btf
            .vertex_layout
            .as_ref()
            .ok_or_else(|| Error::Gpu("per-vertex layout missing".into()))?;
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("per-vertex"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: coef.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: slots.as_entire_binding() },
            ],
        });
        Ok((coef, slots, group))
    }
}

/// The thin-cloth pass, when some material used has a `transmission` effect.
fn thin_pass(
    gpu: &Gpu,
    scene: &Scene,
    btf: &BtfPass,
    key: BtfPassKey,
    materials: &[LoadedMaterial],
    used: &[usize],
    corners: &[CornerVertex],
    order: &[usize],
    slot_of_desc: &[usize],
    tri_desc: &[usize],
    vertices: usize,
) -> Result<Option<ThinPass>> {
    let descs: Vec<_> = materials
        .iter()
        .zip(used)
        .map(|(m, &d)| {
            let desc = &scene.materials[d];
            (desc.transmission.as_ref(), &m.data, desc.store.display().to_string())
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
                    crate::transmission::env::check_supported(d, name, e.two_sided)?;
                }
            }
            let entry = if key.evaluation == Evaluation::PerVertex { light as u32 } else { 0 };
            Some(ThinEnv { vertices, entry })
        }
    };
    let slot_of_triangle: Vec<usize> = order.iter().map(|&t| slot_of_desc[tri_desc[t]]).collect();
    Ok(Some(ThinPass::new(gpu, btf, key, &descs, corners, &slot_of_triangle, env)?))
}

fn frame_bind_group(
    gpu: &Gpu,
    btf: &BtfPass,
    frame: &wgpu::Buffer,
    boundary: &wgpu::Texture,
    shadow: &ShadowInputs,
    counters: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let clamp = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("linear clamp"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let boundary_view = boundary.create_view(&Default::default());
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("btf frame"),
        layout: &btf.frame_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: frame.as_entire_binding() },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&boundary_view),
            },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&clamp) },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(&shadow.masks),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::TextureView(&shadow.maps),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::Sampler(&shadow.compare),
            },
            wgpu::BindGroupEntry { binding: 6, resource: counters.as_entire_binding() },
        ],
    })
}

fn read_rgb(gpu: &Gpu, color: &wgpu::Texture, msaa: u32) -> Result<Vec<f32>> {
    if msaa > 1 {
        let raw = gpu.read_texture(color, 8)?;
        let halves: &[half::f16] = bytemuck::cast_slice(&raw);
        Ok(halves
            .chunks_exact(4)
            .flat_map(|p| [p[0].to_f32(), p[1].to_f32(), p[2].to_f32()])
            .collect())
    } else {
        let raw = gpu.read_texture(color, 16)?;
        let f: &[f32] = bytemuck::cast_slice(&raw);
        Ok(f.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect())
    }
}

/// Loads a scene, renders one frame and returns it (what `btf render` and `btf demo` call).
pub fn render_scene(gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Frame> {
    Renderer::new(gpu, scene, options)?.render(gpu)
}
