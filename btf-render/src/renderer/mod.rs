//! Builds the runtime objects of a [`Scene`] — merged mesh with tangent frames
//! (`geometry.rs`), uploaded materials (`materials.rs`), the passes the scene asks for
//! (`passes.rs`), the frame's bindings and cached targets — and encodes frames, into a
//! caller's texture ([`Renderer::encode`], what the viewer presents) or read back
//! ([`Renderer::render`], what files, sweeps and tests use).
//!
//! Only what the scene calls for is built and run (DESIGN.md §3): the smooth shadow
//! boundary (`[S03 eq. 6]`) and a shadow pass only with a shadowing light and
//! `shadows ≠ none`; per-vertex coefficients only in per-vertex mode or with an environment
//! light; visibility maps, gathers and eigenweightsets only with an environment light;
//! blending work only with `four`.
//!
//! An environment light is always evaluated per vertex, as in the paper (`[S03 §5.3]`:
//! `f · ω_m · γ*_{k j_m}` per vertex, `[S03 eq. 11]` with the view blending of
//! `[S03 eq. 5]`). Its contribution is *added* to the other lights': in per-vertex mode it
//! is one more light of the per-vertex layout; in per-pixel mode the point/directional
//! lights stay per pixel and the fragment shader adds the environment's per-vertex
//! reconstruction (`fs_pixel_env`). The environment can be turned or swapped without
//! recomputing visibility ([`Renderer::set_environment_rotation`],
//! [`Renderer::set_environment`]).
//!
//! Between frames a viewer changes only what it must: a camera move rewrites the frame
//! uniform at the next frame, a light move rebuilds only the shadow pass (shadow-map
//! matrices and shadow-volume prisms depend on the light), the offset `α` of `[S03 eq. 6]`
//! is a uniform. Effects that select pipelines or material data (evaluation mode,
//! blending, components, shadow technique) need [`Renderer::new`].

mod environment;
mod frame_group;
mod geometry;
mod materials;
mod overlay;
mod passes;
mod targets;
mod vertex_buffers;

use crate::camera::CameraSetup;
use crate::frame::{Frame, PassStat, Stats, push_linear_rgb};
use crate::passes::background::BackgroundView;
use crate::passes::baselines::Baseline;
use crate::passes::btf::{BtfPass, BtfPassKey, MeshDraws};
use crate::passes::mesh::{cleared_depth, color_format};
use crate::passes::shadow::Shadowing;
use crate::per_vertex::{self, VertexEvalInput, VertexLight};
use crate::scene::{Camera, Evaluation, Light, MAX_LIGHTS, Scene, Shadows};
use crate::timer::{Clock, PassRecord, PassTimer};
use crate::uniforms::FrameRaw;
use crate::{Error, Gpu, Result};
use btf_core::InterpMode;
use btf_image::EnvMap;
use btf_light::{SceneEnvironment, Slots};
use environment::{EnvInputs, EnvState};
use frame_group::FrameGroup;
use geometry::SceneGeometry;
use materials::Materials;
pub use overlay::{Overlay, OverlayEnvironment, OverlayTargets, OverlayView};
use passes::Passes;
use std::time::Instant;
use targets::FrameTargets;
use vertex_buffers::VertexBuffers;

/// Extra knobs for tests and measurements.
#[derive(Debug, Clone, Copy, Default)]
pub struct RenderOptions {
    /// Count texture reads per pixel in the BTF pass (atomics; slows the pass).
    pub count_reads: bool,
    /// Draw a cost baseline instead of the BTF shader (same mesh, targets and textures).
    pub baseline: Option<Baseline>,
    /// Compute an environment light's visibility for every vertex side, not only for the
    /// sides the scene's camera shows (for a viewer whose camera moves; a fixed camera
    /// needs only its own, see [`crate::passes::corner_ids`]).
    pub all_env_sides: bool,
    /// Keep the full RGB per-vertex layout where the separable one applies (per-vertex mode
    /// under point and directional lights; `per_vertex.rs`): for comparing the two, slower.
    pub full_vertex_layout: bool,
    /// World bounds `(lo, hi)` of what overlays will draw ([`Renderer::add_overlay`]), so
    /// that the camera's near and far planes cover it as well as the meshes.
    pub extra_bounds: Option<([f32; 3], [f32; 3])>,
}

/// The camera of `scene` around the mesh and the overlays' bounds.
fn camera_setup(
    scene: &Scene,
    mesh: &btf_light::mesh::Mesh,
    options: &RenderOptions,
    extra_depth: f32,
) -> CameraSetup {
    let (mut lo, mut hi) = mesh.bounds();
    if let Some((a, b)) = options.extra_bounds {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    }
    CameraSetup::with_bounds(scene, (lo, hi), extra_depth)
}

/// A scene ready to render.
pub struct Renderer {
    /// The scene as built, with the camera, lights, `α` and background switch of the
    /// updates made since.
    scene: Scene,
    options: RenderOptions,
    geometry: SceneGeometry,
    materials: Materials,
    passes: Passes,
    frame: FrameGroup,
    vertex: Option<VertexBuffers>,
    environment: Option<EnvState>,
    camera: CameraSetup,
    targets: Option<FrameTargets>,
    /// The passes of the last frame encoded.
    last: PassRecord,
    /// Geometry drawn after the BTF pass into the same targets (`[[yarns]]`).
    overlays: Vec<Box<dyn Overlay>>,
}

/// The BTF pass's key for `scene`: evaluation, blending, shadows, lights, constant group
/// count and packed weights of the loaded materials.
fn pass_key(scene: &Scene, options: &RenderOptions, materials: &Materials) -> BtfPassKey {
    let fx = &scene.effects;
    let shadowing = scene.wants_shadow_pass();
    BtfPassKey {
        evaluation: fx.evaluation,
        view_four: fx.view_blend == InterpMode::Four,
        light_four: fx.light_interp == InterpMode::Four,
        msaa: fx.msaa,
        count_reads: options.count_reads,
        environment: scene.environment().is_some(),
        shadows: if shadowing { fx.shadows } else { Shadows::None },
        smooth_boundary: shadowing && fx.smooth_boundary,
        lights: scene.lights.len() as u32,
        groups: materials.constant_groups(),
        packed: materials.packed(),
        full_vertex_layout: options.full_vertex_layout,
    }
}

impl Renderer {
    /// Loads meshes and materials and builds the passes the scene asks for.
    pub fn new(gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Renderer> {
        let fx = &scene.effects;
        gpu.check_frame(scene.output.width, scene.output.height, fx.msaa)?;
        let (mesh, tri_desc) = geometry::load_meshes(scene)?;
        let mut materials = Materials::load(scene, &tri_desc)?;
        let btf = BtfPass::new(gpu, pass_key(scene, &options, &materials))?;
        materials.upload(gpu, scene, &btf)?;
        let geometry = SceneGeometry::build(gpu, mesh, &tri_desc, materials.slot_of_desc());
        let passes = Passes::build(gpu, scene, &options, btf, &materials, &geometry)?;
        let camera = camera_setup(scene, &geometry.mesh, &options, passes.extra_camera_depth());
        let blur = fx.terminator_blur;
        let frame = FrameGroup::new(gpu, &passes.btf, passes.shadowing.as_ref(), blur);
        let mut renderer = Renderer {
            scene: scene.clone(),
            options,
            geometry,
            materials,
            passes,
            frame,
            vertex: None,
            environment: None,
            camera,
            targets: None,
            last: PassRecord::default(),
            overlays: Vec::new(),
        };
        if scene.environment().is_some() {
            // the corner-id pass reads this camera from the frame uniform
            let raw = renderer.frame_raw();
            gpu.queue.write_buffer(&renderer.frame.uniform, 0, bytemuck::bytes_of(&raw));
            let input = EnvInputs {
                scene,
                geometry: &renderer.geometry,
                materials: &renderer.materials,
                btf: &renderer.passes.btf,
                frame_group: &renderer.frame.group,
                camera: &renderer.camera,
                // thin cloth shows the far sides too
                all_sides: options.all_env_sides || renderer.passes.thin.is_some(),
            };
            renderer.environment = EnvState::build(gpu, &input)?;
        }
        Ok(renderer)
    }

    /// Adds geometry drawn after the BTF pass into the frame's colour and depth targets with
    /// the same camera (see [`Overlay`]); its bounds belong in
    /// [`RenderOptions::extra_bounds`]. The BTF pass then keeps its depth for it.
    pub fn add_overlay(&mut self, overlay: Box<dyn Overlay>) {
        self.overlays.push(overlay);
    }

    /// Overlays added.
    pub fn overlay_count(&self) -> usize {
        self.overlays.len()
    }

    /// The BTF pass's pipeline key: which variant the scene built (evaluation, blending,
    /// constant group count, packed weights, …).
    pub fn pass_key(&self) -> BtfPassKey {
        self.passes.btf.key
    }

    /// The scene this renderer was built from, with the updates made since.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The merged mesh.
    pub fn mesh(&self) -> &btf_light::mesh::Mesh {
        &self.geometry.mesh
    }

    /// Camera matrices in use.
    pub fn camera(&self) -> &CameraSetup {
        &self.camera
    }

    /// Components the materials use (the smallest over materials).
    pub fn components(&self) -> usize {
        self.materials.components()
    }

    /// Bytes of material data on the GPU.
    pub fn material_bytes(&self) -> u64 {
        self.materials.bytes()
    }

    /// Format of the texture [`Renderer::encode`] draws into: linear HDR RGBA, `f32`
    /// without MSAA and `f16` with it.
    pub fn target_format(&self) -> wgpu::TextureFormat {
        color_format(self.scene.effects.msaa)
    }

    /// Size of the frames, `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.output.width, self.scene.output.height)
    }

    /// Encodes one frame into `target`, a view of a [`Renderer::size`] texture of
    /// [`Renderer::target_format`] usable as a render attachment: the per-frame CPU work
    /// (coefficients, sorting) is done and its buffers are written with
    /// `queue.write_buffer`, which takes effect at the next submit — submit `encoder` before
    /// encoding another frame. Pass times (GPU timestamps, when the adapter has them) are
    /// read by [`Renderer::last_stats`] after that submit.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
    ) -> Result<()> {
        let t = target.texture();
        if (t.width(), t.height()) != self.size() || t.format() != self.target_format() {
            return Err(Error::Invalid(format!(
                "encode: a {}×{} {:?} target for a {}×{} {:?} frame",
                t.width(),
                t.height(),
                t.format(),
                self.scene.output.width,
                self.scene.output.height,
                self.target_format()
            )));
        }
        let (size, msaa) = (self.size(), self.scene.effects.msaa);
        let timestamps = FrameTargets::ensure(&mut self.targets, gpu, size, msaa)
            .timestamps
            .as_ref()
            .map(|t| (t.query.clone(), t.resolve.clone(), t.read.clone()));
        let clock = match &timestamps {
            Some((query, ..)) => Clock::Timestamps(query),
            None => Clock::Untimed,
        };
        let mut timer = PassTimer::new(gpu, encoder, clock);
        self.encode_frame(gpu, &mut timer, target)?;
        self.last = timer.finish(timestamps.as_ref().map(|(_, r, read)| (r, read)));
        Ok(())
    }

    /// The pass times of the last frame [`Renderer::encode`]d (waits until its submission
    /// has run when GPU timestamps are read).
    pub fn last_stats(&self, gpu: &Gpu) -> Result<Stats> {
        let read = self.targets.as_ref().and_then(|t| t.timestamps.as_ref()).map(|t| &t.read);
        let passes = self.last.stats(gpu, read)?;
        Ok(Stats {
            passes,
            timing: self.timing(gpu),
            setup: self.setup_stats(),
            ..Default::default()
        })
    }

    fn timing(&self, gpu: &Gpu) -> String {
        if gpu.timestamps { "gpu-timestamps" } else { "cpu" }.into()
    }

    /// Renders one frame into the renderer's own target and reads it back.
    pub fn render(&mut self, gpu: &Gpu) -> Result<Frame> {
        let (w, h) = self.size();
        let start = Instant::now();
        let targets = FrameTargets::ensure(&mut self.targets, gpu, (w, h), self.scene.effects.msaa);
        let timestamps = targets
            .timestamps
            .as_ref()
            .map(|t| (t.query.clone(), t.resolve.clone(), t.read.clone()));
        let counters_read = targets.counters_read.clone();
        let own = targets.own(gpu);
        let (texture, view, readback, padded_row) =
            (own.texture.clone(), own.view.clone(), own.readback.clone(), own.padded_row);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let clock = match &timestamps {
            Some((query, ..)) => Clock::Timestamps(query),
            None => Clock::SubmitEach,
        };
        let mut timer = PassTimer::new(gpu, &mut encoder, clock);
        self.encode_frame(gpu, &mut timer, &view)?;
        let record = timer.finish(timestamps.as_ref().map(|(_, r, read)| (r, read)));
        copy_to_readback(&mut encoder, &texture, &readback, padded_row);
        let commands = gpu.scoped("encoding the frame", || encoder.finish())?;
        gpu.scoped("submitting the frame", || gpu.queue.submit([commands]))?;
        if timestamps.is_none() {
            gpu.wait()?;
        }
        let passes = record.stats(gpu, timestamps.as_ref().map(|(_, _, read)| read))?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let rgb = read_rgb(gpu, &readback, (w, h), padded_row, self.target_format())?;
        let mut stats = Stats {
            passes,
            frame_ms,
            timing: self.timing(gpu),
            setup: self.setup_stats(),
            ..Default::default()
        };
        if self.options.count_reads {
            let c: Vec<u32> = bytemuck::cast_slice(&gpu.read_buffer(&counters_read)?).to_vec();
            stats.shaded_pixels = Some(c[1] as u64);
            stats.reads_per_pixel = Some(if c[1] > 0 { c[0] as f64 / c[1] as f64 } else { 0.0 });
        }
        self.last = record;
        Ok(Frame { width: w, height: h, rgb, stats })
    }

    /// Encodes the passes of one frame into `timer`'s encoder, drawing into `target`.
    fn encode_frame(
        &mut self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        target: &wgpu::TextureView,
    ) -> Result<()> {
        let key = self.passes.btf.key;
        let size = self.size();
        let targets = FrameTargets::ensure(&mut self.targets, gpu, size, key.msaa);
        let (color_ms, depth) = (targets.color_ms.clone(), targets.depth.clone());
        let counters_read = targets.counters_read.clone();
        let raw = self.frame_raw();
        gpu.queue.write_buffer(&self.frame.uniform, 0, bytemuck::bytes_of(&raw));
        gpu.queue.write_buffer(&self.frame.counters, 0, &[0u8; 16]);
        let vertex_coefficients = key.uses_vertex_coefficients() && self.passes.baseline.is_none();
        if vertex_coefficients {
            self.write_vertex_coefficients(gpu, timer);
        }
        if let Some(s) = &self.passes.shadowing {
            let (corners, n) = (&self.geometry.corner_buffer, self.geometry.corner_count());
            s.encode(gpu, timer, corners, n, &self.camera)?;
        }
        // the background into the colour target the BTF pass then loads (and resolves)
        let background = self.encode_background(gpu, timer, color_ms.as_ref().unwrap_or(target))?;
        self.update_thin_env_tables(gpu, timer)?;
        let thin_draws = self.passes.thin.as_ref().map(|t| {
            let t0 = Instant::now();
            let draws = t.prepare(gpu, &self.camera);
            timer.cpu("thin-cloth sort (cpu)", t0.elapsed().as_secs_f64() * 1e3);
            draws
        });
        let load = if background {
            wgpu::LoadOp::Load
        } else {
            let [r, g, b] = self.scene.output.background.map(f64::from);
            wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 })
        };
        let vertex_group = if vertex_coefficients {
            Some(self.vertex.as_ref().expect("coefficients were just written").group())
        } else {
            None
        };
        let passes = &self.passes;
        let group2 = passes.baseline.as_ref().and_then(|b| b.group.as_ref()).or(vertex_group);
        let materials = &self.materials;
        let thin = passes.thin.as_ref();
        let draws = self
            .geometry
            .draws
            .iter()
            .filter(|d| !thin.is_some_and(|t| t.is_thin(d.material)))
            .map(|d| (materials.bind_group(d.material), d.first..d.first + d.count));
        let frame_group = &self.frame.group;
        let corners = &self.geometry.corner_buffer;
        let name = passes.main_name().to_string();
        let keep_depth = !self.overlays.is_empty();
        gpu.scoped("BTF pass", || {
            timer.pass(&name, |enc, ts| {
                let ms = color_ms.as_ref();
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&name),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: ms.unwrap_or(target),
                        depth_slice: None,
                        resolve_target: ms.map(|_| target),
                        ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
                    })],
                    depth_stencil_attachment: Some(cleared_depth(&depth, keep_depth)),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                let groups = MeshDraws { frame: frame_group, group2, corners };
                passes.btf.draw(&mut pass, passes.main_pipeline(), &groups, draws);
                if let (Some(t), Some(d)) = (thin, &thin_draws) {
                    let material = |m: usize| materials.bind_group(m);
                    t.draw(&mut pass, frame_group, vertex_group, material, d);
                }
            })
        })??;
        if self.options.count_reads {
            timer.encoder().copy_buffer_to_buffer(&self.frame.counters, 0, &counters_read, 0, 16);
        }
        self.encode_overlays(gpu, timer, target, color_ms.as_ref(), &depth)
    }

    /// Draws the overlays into the frame's targets after the BTF pass.
    fn encode_overlays(
        &mut self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        target: &wgpu::TextureView,
        color_ms: Option<&wgpu::TextureView>,
        depth: &wgpu::TextureView,
    ) -> Result<()> {
        if self.overlays.is_empty() {
            return Ok(());
        }
        let msaa = self.scene.effects.msaa;
        let targets = OverlayTargets {
            color: color_ms.unwrap_or(target),
            resolve: color_ms.map(|_| target),
            depth,
            format: self.target_format(),
            samples: msaa,
            size: self.size(),
        };
        let environment = self.environment.as_ref().map(|e| {
            let env = e.env();
            OverlayEnvironment {
                total_power: env.total_power(),
                exposure: env.exposure(),
                rotation_deg: env.rotation_deg(),
                revision: env.revision(),
            }
        });
        let view = OverlayView { camera: &self.camera, scene: &self.scene, environment };
        for o in &mut self.overlays {
            let name = o.name().to_string();
            timer.encoded(&name, |enc| o.encode(gpu, enc, &targets, &view))?;
        }
        Ok(())
    }

    /// Encodes the environment background into `target` when the scene shows it; returns
    /// whether it did.
    fn encode_background(
        &mut self,
        gpu: &Gpu,
        timer: &mut PassTimer,
        target: &wgpu::TextureView,
    ) -> Result<bool> {
        let Some(e) = self.environment.as_mut().filter(|_| self.scene.output.show_environment)
        else {
            return Ok(false);
        };
        let (rotation_deg, exposure) = (e.env().rotation_deg(), e.env().exposure());
        let Some(bg) = e.background(gpu)? else { return Ok(false) };
        let size = (self.scene.output.width, self.scene.output.height);
        let view = BackgroundView { camera: &self.camera, size, rotation_deg, exposure };
        bg.encode(gpu, timer, target, &view)?;
        Ok(true)
    }

    /// The frame uniform: camera, lights with their shadow look-ups, `α`.
    fn frame_raw(&self) -> FrameRaw {
        let fx = &self.scene.effects;
        let mut raw = FrameRaw {
            camera: self.camera.to_raw(),
            info: [
                self.scene.lights.len() as u32,
                (self.passes.shadowing.is_some() && fx.smooth_boundary) as u32,
                self.materials.max_groups() as u32,
                self.vertex_entries() as u32,
            ],
            terminator: [fx.terminator_deg.to_radians(), 0.0, 0.0, 0.0],
            ..Default::default()
        };
        for (l, light) in self.scene.lights.iter().enumerate() {
            let lr = light.to_raw();
            raw.lights[l] = match &self.passes.shadowing {
                Some(s) => s.light_raw(l, lr),
                None => lr,
            };
        }
        raw
    }

    /// Lights per vertex in the per-vertex layout: all lights in per-vertex mode, the
    /// environment alone in per-pixel mode.
    fn vertex_entries(&self) -> usize {
        match (self.scene.effects.evaluation, self.passes.btf.key.environment) {
            (Evaluation::PerVertex, _) => self.scene.lights.len(),
            (Evaluation::PerPixel, true) => 1,
            (Evaluation::PerPixel, false) => 0,
        }
    }

    /// Computes the per-vertex coefficients of this frame (`[S03 eq. 3–5]` per vertex, and
    /// the environment's `[S03 eq. 11]`) and writes them into group 2's buffers.
    fn write_vertex_coefficients(&mut self, gpu: &Gpu, timer: &mut PassTimer) {
        let t = Instant::now();
        let per_vertex = self.scene.effects.evaluation == Evaluation::PerVertex;
        let lights: Vec<VertexLight> = if per_vertex {
            self.scene.lights.iter().map(VertexLight::from_light).collect()
        } else {
            Vec::new()
        };
        let key = self.passes.btf.key;
        let mats: Vec<_> = self.materials.data().iter().collect();
        let input = VertexEvalInput {
            eye: self.camera.eye,
            ortho_to_camera: self.camera.ortho_to_camera,
            lights: &lights,
            view_mode: self.scene.effects.view_blend,
            light_mode: self.scene.effects.light_interp,
            groups_stride: self.materials.max_groups(),
            separable: key.separable(),
        };
        let g = &self.geometry;
        let mut vc = per_vertex::compute(
            &g.mesh.positions,
            &g.mesh.normals,
            &g.tangents,
            &g.vertex_material,
            &mats,
            &input,
        );
        if per_vertex {
            timer.cpu("per-vertex coefficients (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        if let Some(e) = &mut self.environment {
            let t = Instant::now();
            let samplings = self.materials.view_samplings();
            let view = g.view_input(&self.camera, self.scene.effects.view_blend, &samplings);
            let (l, n_lights) = if per_vertex { (e.light(), lights.len()) } else { (0, 1) };
            let at = Slots { l, n_lights, stride: per_vertex::stride(input.groups_stride) };
            e.fill(&mut vc.coef, &view, at);
            timer.cpu("env coefficients per vertex (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        // f16 where the pass has a constant group count (slot_fixed): the separable scalars
        // as they are where the weight rows fit f16, the full layout with a scale per entry
        let coef = match (key.separable(), key.packed, key.groups > 0) {
            (true, true, _) => per_vertex::pack_scalars_f16(&vc.coef, input.groups_stride),
            (false, _, true) => per_vertex::pack_f16(&vc.coef, input.groups_stride),
            _ => bytemuck::cast_slice(&vc.coef).to_vec(),
        };
        let layout =
            self.passes.btf.vertex_layout.as_ref().expect("a key with coefficients has group 2");
        let contents = [
            bytemuck::cast_slice(&coef),
            bytemuck::cast_slice(&vc.slots),
            bytemuck::cast_slice(&vc.irradiance),
        ];
        VertexBuffers::write(&mut self.vertex, gpu, layout, contents);
    }

    /// The environment background alone for the current camera, rotation and exposure
    /// (linear RGB, row-major from the top, as the frame shows it behind the scene), when
    /// the scene was built to show it.
    pub fn environment_background(&mut self, gpu: &Gpu) -> Result<Option<Vec<f32>>> {
        if !self.environment.as_ref().is_some_and(EnvState::has_background) {
            return Ok(None);
        }
        let (w, h) = self.size();
        let targets = FrameTargets::ensure(&mut self.targets, gpu, (w, h), self.scene.effects.msaa);
        let color_ms = targets.color_ms.clone();
        let own = targets.own(gpu);
        let (texture, view, readback, padded_row) =
            (own.texture.clone(), own.view.clone(), own.readback.clone(), own.padded_row);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let mut timer = PassTimer::new(gpu, &mut encoder, Clock::Untimed);
        let shown = self.scene.output.show_environment;
        self.scene.output.show_environment = true;
        let drawn = self.encode_background(gpu, &mut timer, color_ms.as_ref().unwrap_or(&view));
        self.scene.output.show_environment = shown;
        drawn?;
        if let Some(ms) = &color_ms {
            // resolve the multisampled background into the frame's own target
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("resolve background"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: ms,
                    depth_slice: None,
                    resolve_target: Some(&view),
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        copy_to_readback(&mut encoder, &texture, &readback, padded_row);
        let commands = gpu.scoped("encoding the background", || encoder.finish())?;
        gpu.scoped("submitting the background", || gpu.queue.submit([commands]))?;
        Ok(Some(read_rgb(gpu, &readback, (w, h), padded_row, self.target_format())?))
    }

    /// Recomputes and uploads the thin-cloth environment tables when the environment, its
    /// rotation or its exposure changed since the last frame.
    fn update_thin_env_tables(&mut self, gpu: &Gpu, timer: &mut PassTimer) -> Result<()> {
        let (Some(thin), Some(e)) = (&self.passes.thin, &mut self.environment) else {
            return Ok(());
        };
        let t = Instant::now();
        let vertex_material = &self.geometry.vertex_material;
        let slab_of = || {
            vertex_material
                .iter()
                .map(|&m| if m == usize::MAX { None } else { thin.slab(m) })
                .collect()
        };
        if let Some(tables) = e.thin_tables_if_changed(slab_of)? {
            thin.write_env_tables(gpu, &tables)?;
            timer.cpu("thin-cloth env tables (cpu)", t.elapsed().as_secs_f64() * 1e3);
        }
        Ok(())
    }

    /// The environment light's run-time state, when the scene has one.
    pub fn environment(&self) -> Option<&SceneEnvironment> {
        self.environment.as_ref().map(EnvState::env)
    }

    /// Mutable access to the environment (exact or eigenweightset rotations, weights).
    pub fn environment_mut(&mut self) -> Option<&mut SceneEnvironment> {
        self.environment.as_mut().map(EnvState::env_mut)
    }

    fn env_or_err(&mut self) -> Result<&mut EnvState> {
        self.environment
            .as_mut()
            .ok_or_else(|| Error::Invalid("the scene has no environment light".into()))
    }

    /// Turns the environment to `delta_deg` about world `+z` (eigenweightsets: `e` vector
    /// additions; else one gather). Visibility is kept.
    pub fn set_environment_rotation(&mut self, delta_deg: f64) -> Result<()> {
        self.env_or_err()?.env_mut().set_rotation(delta_deg);
        Ok(())
    }

    /// Replaces the environment map (one gather, plus the eigenweightsets when the scene
    /// asks for them); visibility maps are kept.
    pub fn set_environment(&mut self, map: &EnvMap) -> Result<()> {
        self.env_or_err()?.set_map(map)
    }

    /// Sets the environment's exposure `f`.
    pub fn set_environment_exposure(&mut self, f: f32) -> Result<()> {
        self.env_or_err()?.env_mut().set_exposure(f);
        Ok(())
    }

    /// One-off costs of preparing the scene (visibility maps, gathers, eigenweightsets).
    pub fn setup_stats(&self) -> Vec<PassStat> {
        self.environment.as_ref().map_or_else(Vec::new, EnvState::setup_stats)
    }

    /// Replaces the camera; the next frame uses it and nothing else is recomputed — except,
    /// the first time the camera really moves, the visibility of the vertex sides an
    /// environment light had left out for the old camera (all of them, then the gathers:
    /// [`SceneEnvironment::complete`]).
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        self.scene.camera = camera.clone();
        let extra_depth = self.passes.extra_camera_depth();
        let setup = camera_setup(&self.scene, &self.geometry.mesh, &self.options, extra_depth);
        if setup != self.camera
            && let Some(e) = self.environment.as_mut()
        {
            e.complete(&self.geometry)?;
        }
        self.camera = setup;
        Ok(())
    }

    /// Changes the frame size (a window resized): the camera's aspect follows, the frame
    /// targets are made anew at the next frame, and shadow-volume masks (one texel per
    /// pixel) are rebuilt; visibility, materials and the other passes are kept.
    pub fn set_size(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<()> {
        if (width, height) == self.size() {
            return Ok(());
        }
        gpu.check_frame(width, height, self.scene.effects.msaa)?;
        (self.scene.output.width, self.scene.output.height) = (width, height);
        let extra_depth = self.passes.extra_camera_depth();
        self.camera = camera_setup(&self.scene, &self.geometry.mesh, &self.options, extra_depth);
        if self.passes.shadowing.as_ref().is_some_and(Shadowing::sized_by_frame) {
            let shadowing = Shadowing::new(gpu, &self.scene, &self.geometry.mesh)?;
            let blur = self.scene.effects.terminator_blur;
            self.frame.rebind(gpu, &self.passes.btf, Some(&shadowing), blur);
            self.passes.shadowing = Some(shadowing);
        }
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
        if self.passes.shadowing.is_some() {
            let shadowing = Shadowing::new(gpu, &self.scene, &self.geometry.mesh)?;
            let blur = self.scene.effects.terminator_blur;
            self.frame.rebind(gpu, &self.passes.btf, Some(&shadowing), blur);
            self.passes.shadowing = Some(shadowing);
        }
        Ok(())
    }

    /// Sets the offset `α` of the smooth shadow boundary (`[S03 eq. 6]`), degrees in
    /// `[0, 90)`.
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
        if !self.environment.as_ref().is_some_and(EnvState::has_background) {
            return Err(Error::Invalid(
                "set_show_environment: the scene was built without output.show_environment".into(),
            ));
        }
        self.scene.output.show_environment = on;
        Ok(())
    }
}

/// Copies a frame's colour `texture` into `readback` (rows of `padded_row` bytes).
fn copy_to_readback(
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    readback: &wgpu::Buffer,
    padded_row: u32,
) {
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(texture.height()),
            },
        },
        texture.size(),
    );
}

/// Linear RGB of a frame read back into `buffer` (rows of `padded_row` bytes, texels of
/// `format`: `Rgba32Float` or `Rgba16Float`).
fn read_rgb(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    (w, h): (u32, u32),
    padded_row: u32,
    format: wgpu::TextureFormat,
) -> Result<Vec<f32>> {
    let raw = gpu.read_buffer(buffer)?;
    let texel = format.block_copy_size(None).expect("a colour format") as usize;
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for row in raw.chunks_exact(padded_row as usize).take(h as usize) {
        let linear = push_linear_rgb(&mut rgb, &row[..w as usize * texel], format);
        assert!(linear, "the renderer draws linear RGBA");
    }
    Ok(rgb)
}

/// Loads a scene, renders one frame and returns it (what `btf render` and `btf demo` call).
pub fn render_scene(gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Frame> {
    Renderer::new(gpu, scene, options)?.render(gpu)
}
