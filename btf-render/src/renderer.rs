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

use crate::camera::CameraSetup;
use crate::frame::{Frame, PassStat, Stats};
use crate::material::{MaterialData, MaterialGpu, SamplingsRaw};

use crate::passes::baselines::{self, Baseline, BaselinePass};
use crate::passes::btf::{BtfPass, BtfPassKey};
use crate::passes::mesh::{CornerVertex, DEPTH_FORMAT, cleared_depth, color_format};
use crate::passes::shadow::{ShadowInputs, Shadowing};
use crate::passes::smooth_boundary;
use crate::passes::thin::{ThinEnv, ThinPass};
use crate::per_vertex::{self, VertexEvalInput, VertexLight};
use crate::scene::{Evaluation, Scene, Shadows};
use crate::timer::PassTimer;
use crate::uniforms::FrameRaw;
use crate::{Error, Gpu, Result};
use btf_core::InterpMode;
use btf_image::EnvMap;
use btf_light::mesh::Mesh;
use btf_light::tangent;
use btf_light::{EnvCoefficients, EnvMesh, SceneEnvironment, Slots, ViewInput};
use std::sync::Mutex;
use std::time::Instant;
use wgpu::util::DeviceExt;

mod environment;
mod live;
mod setup;

use environment::EnvState;
use setup::{frame_bind_group, load_meshes, thin_pass};

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
    /// Keep the full RGB per-vertex layout where the separable one applies (per-vertex mode
    /// under point and directional lights; `per_vertex.rs`): for comparing the two, slower.
    pub full_vertex_layout: bool,
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

/// Largest group count compiled into the BTF pass as a constant (`BtfPassKey::groups`;
/// BENCHMARKS.md #5 has the measurements behind it). `slot_fixed` in `btf_vertex.wgsl` holds
/// at most four groups in registers, so this must not exceed 4.
const MAX_CONSTANT_GROUPS: usize = 4;
const _: () = assert!(MAX_CONSTANT_GROUPS <= 4, "slot_fixed holds at most four groups");

impl Renderer {
    /// The BTF pass's pipeline key: which variant the scene built (evaluation, blending,
    /// constant group count, packed weights, …).
    pub fn pass_key(&self) -> BtfPassKey {
        self.btf.key
    }

    /// Loads meshes and materials and builds the passes the scene asks for.
    pub fn new(gpu: &Gpu, scene: &Scene, options: RenderOptions) -> Result<Renderer> {
        gpu.check_frame(scene.output.width, scene.output.height, scene.effects.msaa)?;
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
        let groups = match datas.first() {
            Some(first) if datas.iter().all(|d| d.groups == first.groups) => first.groups,
            _ => 0,
        };
        // a constant group count up to 4 (c ≤ 16); beyond, llvmpipe runs the loop faster
        let groups = if groups <= MAX_CONSTANT_GROUPS { groups as u32 } else { 0 };
        // f16 weight rows where every material's fit (else all keep f32 rows)
        let packed: Option<Vec<Vec<[u32; 4]>>> =
            if groups > 0 { datas.iter().map(|d| d.packed_weights()).collect() } else { None };
        let key = BtfPassKey {
            evaluation: fx.evaluation,
            view_four: fx.view_blend == InterpMode::Four,
            light_four: fx.light_interp == InterpMode::Four,
            msaa: fx.msaa,
            count_reads: options.count_reads,
            environment: scene.environment().is_some(),
            shadows: if scene.wants_shadow_pass() { fx.shadows } else { Shadows::None },
            smooth_boundary: scene.wants_shadow_pass() && fx.smooth_boundary,
            lights: scene.lights.len() as u32,
            groups,
            packed: packed.is_some(),
            full_vertex_layout: options.full_vertex_layout,
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
                packed.as_ref().map(|p| p[k].as_slice()),
            )?;
            material_bytes += gpu_mat.bytes;
            let samplings = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("samplings"),
                contents: bytemuck::bytes_of(&SamplingsRaw::of_material(&data, desc.uv_scale)),
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
            Some(Baseline::Plain) => Some(baselines::plain(gpu, &btf)?),
            Some(Baseline::ReadBound { reads_per_pixel, form }) => {
                let m = &materials[0].data;
                let views = m.view_sampling.len();
                Some(baselines::read_bound(gpu, &btf, reads_per_pixel, m.groups, views, form)?)
            }
        };
        let shadowing =
            if scene.wants_shadow_pass() { Some(Shadowing::new(gpu, scene, &mesh)?) } else { None };
        let extra_depth = shadowing.as_ref().map_or(0.0, |s| s.extra_camera_depth());
        let camera = CameraSetup::new(scene, &mesh, extra_depth);
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
            Some(s) => s.inputs(gpu),
            None => ShadowInputs::dummy(gpu),
        };
        let boundary = if shadowing.is_some() {
            smooth_boundary::texture(gpu, fx.terminator_blur)
        } else {
            smooth_boundary::texture(gpu, 0) // 1 KiB placeholder; never sampled without a shadowing light
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
            camera: self.camera.to_raw(),
            info: [
                self.scene.lights.len() as u32,
                (self.shadowing.is_some() && fx.smooth_boundary) as u32,
                self.materials.iter().map(|m| m.data.groups).max().unwrap_or(1) as u32,
                self.vertex_entries() as u32,
            ],
            terminator: [fx.terminator_deg.to_radians(), 0.0, 0.0, 0.0],
            ..Default::default()
        };
        for (l, light) in self.scene.lights.iter().enumerate() {
            let lr = light.to_raw();
            raw.lights[l] = match &self.shadowing {
                Some(s) => s.light_raw(l, lr),
                None => lr,
            };
        }
        raw
    }

    fn vertex_lights(&self) -> Vec<VertexLight> {
        self.scene.lights.iter().map(VertexLight::from_light).collect()
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
        let target =
            |format, samples, usage| gpu.target("btf target", (w, h), samples, format, usage);
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
                    depth_stencil_attachment: Some(cleared_depth(&depth_view, false)),
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
