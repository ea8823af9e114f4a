//! `LumisliceRenderer`: Chen et al.'s lumislice knitwear [C03 §5] on wgpu, in the form
//! DESIGN §1.4 recommends — ray-marched straight yarn pieces instead of instanced slices:
//!
//! - `lumislice_centerline` (`shaders/lumislice_centerline.wgsl`): one map per directional
//!   light (up to 4) of every piece's centre line as a light-facing strip of half width
//!   `R_y`, keeping per texel the yarn nearest the light — its distance from the centre
//!   line, its piece and its depth ([C03 §5.2.1]'s shadow map with centre lines);
//! - `lumislice_march` (`shaders/lumislice_march.wgsl`): each Catmull–Rom segment cut into
//!   `n_sub` straight pieces, one instance per piece in back-to-front order (sorted on the
//!   CPU per frame by the piece centre's depth, [C03 §5.2.3] step 5), drawn as the back faces
//!   of its bounding box; the fragment intersects its ray with the piece's tube and marches
//!   [C03 eq. 9] through it with the table of [`yarn_precompute::Lumislice`] (the level
//!   chosen per piece from its projected size, [C03 §5.2.2]) and the shadow of other yarns
//!   by [C03 eq. 10] ([`yarn_precompute::YarnShadowLut`], empirical or physical); output is
//!   premultiplied colour and coverage, blended "over".
//!
//! **Deviations from [C03], each for a reason** (DESIGN §1.3):
//! - a ray march per piece instead of slices: no edge-on degeneracy and no per-slice
//!   opacity that ignores the path length through a slice (item 12); the paper's instanced
//!   slices are kept for comparison ([`LumisliceRenderSettings::slices`] per piece, back to
//!   front within a piece, opacity corrected for the path length through the slab) — at
//!   70–90° from the yarn axis they show gaps and ghosts where the march does not
//!   (`tests/gpu/lumislice.rs`, BENCHMARKS.md);
//! - the shadow test per march step, not per slice vertex, and only where the occluding
//!   centre line is another piece (not this or a neighbouring one) more than `R_y` nearer
//!   the light — the table already holds the yarn's own attenuation (item 13's double count);
//! - opaque objects are depth-tested read-only against the piece's box (its back faces):
//!   a yarn wholly behind an object is hidden exactly, one that pierces it is kept or
//!   hidden whole per pixel (the paper's ID buffers resolve that per pixel; item 15's
//!   depth-tested compositing, at box granularity);
//! - the yarn colour is the table's ϖ (per yarn type), not the curve's colour: multiple
//!   scattering is not linear in it;
//! - one eq. 10 table per frame, from the first yarn type's density profile, read by every
//!   type at its own reach `R_y`.

use crate::gpu_data::YarnBuffers;
use crate::pack::PackedYarns;
use crate::passes::draw::{DEPTH, FrameTargets, color_format};
use crate::passes::shadow::{MAX_SHADOW_MAPS, light_views};
use crate::renderer::{FiberImage, FiberStats};
use crate::view::{FiberCamera, FiberLight, ViewRaw, ViewSetup, lights_raw, to_cols};
use crate::{Error, Result};
use btf_render::Gpu;
use wgpu::util::DeviceExt;
use yarn_precompute::lumislice::ShadowVariant;
use yarn_precompute::{Lumislice, YarnShadowLut};

const MARCH_WGSL: &str = include_str!("shaders/lumislice_march.wgsl");
const CENTRE_WGSL: &str = include_str!("shaders/lumislice_centerline.wgsl");

/// The albedo ϖ a yarn set's lumislice table is computed for: its first curve's colour,
/// clamped to [0, 1] (mid grey 0.8 without curves). The table carries the colour, one per
/// yarn type (multiple scattering is not linear in ϖ).
pub fn table_albedo(set: &yarn::YarnSet) -> [f32; 3] {
    set.curves
        .first()
        .and_then(|c| c.colors.first().copied())
        .unwrap_or([0.8; 3])
        .map(|v| v.clamp(0.0, 1.0))
}

/// The march pass's WGSL (generator and view in front).
pub fn source() -> String {
    format!("{}\n{}\n{MARCH_WGSL}", crate::FIBER_GEN_WGSL, crate::FIBER_VIEW_WGSL)
}

/// The centre-line pass's WGSL (generator in front).
pub fn centerline_source() -> String {
    crate::with_generator(CENTRE_WGSL)
}

/// MSAA samples of the lumislice targets (blending needs the 16-bit float format, which
/// WebGPU guarantees blendable and multisampled; the march shades per pixel).
pub const SAMPLES: u32 = 4;

/// Accuracy/time knobs of a lumislice frame (DESIGN §1.5's sweep).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumisliceRenderSettings {
    /// Straight pieces per yarn segment.
    pub n_sub: u32,
    /// March step in cells of the piece's level.
    pub step_cells: f32,
    /// Most march steps per piece and pixel.
    pub max_steps: u32,
    /// Level bias (+1: one level coarser than [C03 §5.2.2]'s rule; −1 finer).
    pub level_bias: i32,
    /// Shadows of other yarns by [C03 eq. 10].
    pub shadows: bool,
    /// Which eq. 10.
    pub shadow_variant: ShadowVariant,
    /// `k0` of the empirical variant ([C03]: 0.8).
    pub k0: f64,
    /// Side of the centre-line maps (texels).
    pub shadow_map: u32,
    /// The paper's instanced slices, this many per piece (0: the ray march, the default;
    /// DESIGN §1.3 item 12: slices vanish edge-on).
    pub slices: u32,
}

impl Default for LumisliceRenderSettings {
    fn default() -> Self {
        LumisliceRenderSettings {
            n_sub: 4,
            step_cells: 1.0,
            max_steps: 96,
            level_bias: 0,
            shadows: true,
            shadow_variant: ShadowVariant::Physical,
            k0: 0.8,
            shadow_map: 1024,
            slices: 0,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SliceHeaderRaw {
    dims: [u32; 4],
    size: [f32; 4],
    sig_off: [[u32; 4]; 2],
    vrf_off: [[u32; 4]; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct MarchParamsRaw {
    n: [u32; 4],
    f: [f32; 4],
    view_proj: [[[f32; 4]; 4]; MAX_SHADOW_MAPS],
    light: [u32; 4],
    dpm: [f32; 4],
    slices: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CentreParamsRaw {
    view_proj: [[f32; 4]; 4],
    to_light: [f32; 4],
    n: [u32; 4],
}

const CENTRE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The lumislice renderer of one packed yarn set.
pub struct LumisliceRenderer {
    data: YarnBuffers,
    march: wgpu::RenderPipeline,
    centre: wgpu::RenderPipeline,
    march_layout: wgpu::BindGroupLayout,
    centre_layout: wgpu::BindGroupLayout,
    headers: wgpu::Buffer,
    sigma: wgpu::Buffer,
    vrf: wgpu::Buffer,
    lut: wgpu::Buffer,
    lut_entries: u32,
    /// Piece centres (origin-relative), in piece order.
    pieces: Vec<[f64; 3]>,
    reach: f64,
    settings: LumisliceRenderSettings,
    origin: [f64; 3],
    scene_centre: [f64; 3],
    radius: f64,
    table_bytes: u64,
}

fn entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
}

fn catmull_rom(p: &[[f32; 4]; 4], t: f64) -> [f64; 3] {
    let (t2, t3) = (t * t, t * t * t);
    let w = [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ];
    [0, 1, 2].map(|a| (0..4).map(|k| w[k] * p[k][a] as f64).sum())
}

impl LumisliceRenderer {
    /// Uploads `packed` and `slices` (one per entry of `packed.yarn_params`) and compiles
    /// the passes. The eq. 10 tables are built from each slice's finest level.
    pub fn new(
        gpu: &Gpu,
        packed: &PackedYarns,
        slices: &[Lumislice],
        settings: LumisliceRenderSettings,
    ) -> Result<Self> {
        let s = &settings;
        if s.n_sub == 0 || s.n_sub > 64 {
            return Err(Error::Invalid(format!("lumislice: n_sub {} (1..=64)", s.n_sub)));
        }
        if !(s.step_cells.is_finite() && (0.05..=8.0).contains(&s.step_cells)) {
            return Err(Error::Invalid(format!(
                "lumislice: step_cells {} (0.05..=8)",
                s.step_cells
            )));
        }
        if s.max_steps == 0 || s.max_steps > 4096 {
            return Err(Error::Invalid(format!("lumislice: max_steps {} (1..=4096)", s.max_steps)));
        }
        if !(-4..=4).contains(&s.level_bias) {
            return Err(Error::Invalid(format!("lumislice: level_bias {} (−4..=4)", s.level_bias)));
        }
        if s.slices > 256 {
            return Err(Error::Invalid(format!("lumislice: slices {} (0..=256)", s.slices)));
        }
        if s.shadow_map < 16 || s.shadow_map > 8192 {
            return Err(Error::Invalid(format!(
                "lumislice: shadow_map {} (16..=8192)",
                s.shadow_map
            )));
        }
        if slices.len() != packed.yarn_params.len() {
            return Err(Error::Invalid(format!(
                "lumislice: {} tables for {} yarn types",
                slices.len(),
                packed.yarn_params.len()
            )));
        }
        let dev = &gpu.device;
        let data = YarnBuffers::new(gpu, packed)?;
        let mut headers = Vec::new();
        let mut sigma: Vec<f32> = Vec::new();
        let mut vrf: Vec<f32> = Vec::new();
        let mut lut: Vec<f32> = Vec::new();
        let mut reach: f64 = 0.0;
        for (i, l) in slices.iter().enumerate() {
            if l.levels.is_empty() || l.levels.len() > 8 {
                return Err(Error::Invalid(format!(
                    "lumislice of yarn {i}: {} levels (1..=8)",
                    l.levels.len()
                )));
            }
            let mut h = SliceHeaderRaw {
                dims: [
                    l.levels.len() as u32,
                    l.levels[0].res as u32,
                    (l.settings.extinction == yarn::density::Extinction::Isotropic) as u32,
                    0,
                ],
                size: [l.half_width as f32, l.reach() as f32, 0.0, 0.0],
                ..Default::default()
            };
            for (k, lv) in l.levels.iter().enumerate() {
                h.sig_off[k / 4][k % 4] = sigma.len() as u32;
                h.vrf_off[k / 4][k % 4] = (vrf.len() / 4) as u32;
                sigma.extend(&lv.sigma);
                for c in &lv.vrf {
                    vrf.extend([c[0], c[1], c[2], 0.0]);
                }
            }
            headers.push(h);
            reach = reach.max(l.reach());
            // The eq. 10 tables of the first yarn type (both variants, so the flag picks); the
            // other types read them at their own reach (one occluder profile per frame).
            if i == 0 {
                let prof = radial_profile(l, 512);
                let n = prof.len() - 1;
                let reach = l.reach();
                let sig = |r: f64| {
                    let x = (r / reach).clamp(0.0, 1.0) * n as f64;
                    let k = (x.floor() as usize).min(n - 1);
                    prof[k] + (x - k as f64) * (prof[k + 1] - prof[k])
                };
                let [emp, phys] = YarnShadowLut::both(&sig, l.reach(), settings.k0)
                    .map_err(|e| Error::Invalid(format!("lumislice shadow table: {e}")))?;
                lut.extend(&emp.values);
                lut.extend(&phys.values);
            }
        }
        let max = dev.limits().max_storage_buffer_binding_size;
        if vrf.len() as u64 * 4 > max {
            return Err(Error::Limit(format!(
                "lumislice tables of {} bytes exceed the storage binding limit {max}; \
                 use a smaller lumislice resolution",
                vrf.len() * 4
            )));
        }
        let table_bytes = (vrf.len() + sigma.len()) as u64 * 4;
        if headers.is_empty() {
            headers.push(SliceHeaderRaw::default());
        }
        for v in [&mut sigma, &mut vrf, &mut lut] {
            if v.is_empty() {
                v.extend([0.0; 4]);
            }
        }
        let lut_entries =
            if lut.len() >= 2 * YarnShadowLut::ENTRIES { YarnShadowLut::ENTRIES as u32 } else { 2 };
        let storage = |label, contents: &[u8]| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let buf = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let vf = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let uni = wgpu::BufferBindingType::Uniform;
        let march_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lumislice_march"),
            entries: &[
                buf(0, vf, uni),
                buf(1, vf, uni),
                buf(2, vf, ro),
                buf(3, vf, ro),
                buf(4, vf, ro),
                buf(5, vf, ro),
                buf(6, vf, ro),
                wgpu::BindGroupLayoutEntry {
                    binding: 7,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let centre_layout = btf_render::gpu::uniform_layout(dev, "lumislice_centerline", vf);
        let march_src = source();
        let centre_src = centerline_source();
        let pipeline = |label: &'static str,
                        src: &str,
                        layout: &wgpu::BindGroupLayout,
                        vs: &'static str,
                        fs: &'static str,
                        march: bool,
                        strip: bool| {
            gpu.scoped(label, || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(label),
                    bind_group_layouts: &[Some(&data.layout), Some(layout)],
                    immediate_size: 0,
                });
                let over = wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                    operation: wgpu::BlendOperation::Add,
                };
                dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: if strip {
                        wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleStrip,
                            cull_mode: None,
                            ..Default::default()
                        }
                    } else if march {
                        wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleList,
                            front_face: wgpu::FrontFace::Ccw,
                            cull_mode: Some(wgpu::Face::Front),
                            ..Default::default()
                        }
                    } else {
                        wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleStrip,
                            cull_mode: None,
                            ..Default::default()
                        }
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(!march),
                        depth_compare: Some(if march {
                            wgpu::CompareFunction::LessEqual
                        } else {
                            wgpu::CompareFunction::Less
                        }),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: wgpu::MultisampleState {
                        count: if march { SAMPLES } else { 1 },
                        mask: !0,
                        alpha_to_coverage_enabled: false,
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: if march { color_format(SAMPLES) } else { CENTRE_FORMAT },
                            blend: march.then_some(wgpu::BlendState { color: over, alpha: over }),
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
            .map_err(|e| Error::Gpu(e.to_string()))
        };
        let (vs, fs, strip) = if s.slices > 0 {
            ("vs_slice", "fs_slice", true)
        } else {
            ("vs_piece", "fs_piece", false)
        };
        let march = pipeline("lumislice_march", &march_src, &march_layout, vs, fs, true, strip)?;
        let centre = pipeline(
            "lumislice_centerline",
            &centre_src,
            &centre_layout,
            "vs_centre",
            "fs_centre",
            false,
            true,
        )?;
        let n_sub = s.n_sub as usize;
        let pieces = packed
            .segments
            .iter()
            .flat_map(|seg| {
                (0..n_sub).map(move |k| catmull_rom(&seg.p, (k as f64 + 0.5) / n_sub as f64))
            })
            .collect();
        let (lo, hi) = packed.bounds;
        let (scene_centre, extent) = if packed.segments.is_empty() {
            ([0.0; 3], 1.0)
        } else {
            let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - packed.origin[a]);
            let r = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt() * 0.5;
            (c, r)
        };
        Ok(LumisliceRenderer {
            headers: storage("lumislice headers", bytemuck::cast_slice(&headers)),
            sigma: storage("lumislice sigma", bytemuck::cast_slice(&sigma)),
            vrf: storage("lumislice vrf", bytemuck::cast_slice(&vrf)),
            lut: storage("lumislice eq. 10", bytemuck::cast_slice(&lut)),
            lut_entries,
            data,
            march,
            centre,
            march_layout,
            centre_layout,
            pieces,
            reach,
            settings,
            origin: packed.origin,
            scene_centre,
            radius: extent + reach,
            table_bytes,
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &LumisliceRenderSettings {
        &self.settings
    }

    /// Bytes of the tables on the GPU.
    pub fn table_bytes(&self) -> u64 {
        self.table_bytes
    }

    /// Pieces drawn per frame.
    pub fn pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Piece indices back to front for the camera (farthest first; ties by index).
    fn order(&self, setup: &ViewSetup) -> Vec<u32> {
        let eye = [setup.eye.x, setup.eye.y, setup.eye.z];
        let fwd = [setup.forward.x, setup.forward.y, setup.forward.z];
        let key: Vec<f64> = self
            .pieces
            .iter()
            .map(|c| {
                let d = [c[0] - eye[0], c[1] - eye[1], c[2] - eye[2]];
                if setup.orthographic {
                    d[0] * fwd[0] + d[1] * fwd[1] + d[2] * fwd[2]
                } else {
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                }
            })
            .collect();
        let mut idx: Vec<u32> = (0..self.pieces.len() as u32).collect();
        idx.sort_by(|a, b| key[*b as usize].total_cmp(&key[*a as usize]).then(a.cmp(b)));
        idx
    }

    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        cam: &FiberCamera,
        lights: &[FiberLight],
        size: (u32, u32),
        (color, resolve, depth): (
            &wgpu::TextureView,
            Option<&wgpu::TextureView>,
            &wgpu::TextureView,
        ),
        clear: Option<[f64; 4]>,
    ) -> Result<()> {
        let dev = &gpu.device;
        let s = &self.settings;
        let setup = ViewSetup::new(cam, self.origin, self.scene_centre, self.radius, size)?;
        let f3 = |v: nalgebra::Vector3<f64>, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        let view = ViewRaw {
            view_proj: to_cols(&setup.view_proj),
            eye: f3(setup.eye, if setup.orthographic { 0.0 } else { 1.0 }),
            forward: f3(setup.forward, 0.0),
            viewport: [size.0 as f32, size.1 as f32, setup.px_per_metre as f32, 0.0],
            planes: setup.planes().map(|p| p.map(|x| x as f32)),
            lod: [0, s.n_sub, 0, 0],
            counts: [lights.len() as u32, 0, self.data.segment_count, 0],
            strip: [0.0; 4],
            lights: lights_raw(lights, self.origin)?,
            ambient: [0.0; 4],
        };
        // Centre-line maps of the directional lights.
        let mut maps: Vec<([f64; 3], u32)> = Vec::new();
        if s.shadows {
            for (i, l) in lights.iter().enumerate() {
                if let FiberLight::Directional { to_light, .. } = *l
                    && maps.len() < MAX_SHADOW_MAPS
                {
                    maps.push((to_light, i as u32));
                }
            }
        }
        let dirs: Vec<[f64; 3]> = maps.iter().map(|m| m.0).collect();
        let views = light_views(&dirs, self.origin, self.scene_centre, self.radius, s.shadow_map)?;
        let mut mp = MarchParamsRaw {
            n: [
                s.n_sub,
                s.max_steps,
                (!maps.is_empty()) as u32
                    | ((s.shadow_variant == ShadowVariant::Physical) as u32) << 1,
                maps.len() as u32,
            ],
            f: [s.step_cells, s.level_bias as f32, s.shadow_map as f32, self.lut_entries as f32],
            slices: [s.slices, 0, 0, 0],
            ..Default::default()
        };
        for (m, ((pass, dpm), (_, light))) in views.iter().zip(&maps).enumerate() {
            mp.view_proj[m] = pass.view_proj;
            mp.light[m] = *light;
            mp.dpm[m] = *dpm as f32;
        }
        let side = if maps.is_empty() { 1 } else { s.shadow_map };
        let layers = maps.len().max(1) as u32;
        let extent = wgpu::Extent3d { width: side, height: side, depth_or_array_layers: layers };
        let centre_tex = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("lumislice centre-line maps"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: CENTRE_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let centre_depth = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("lumislice centre-line depth"),
            size: wgpu::Extent3d { width: side, height: side, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let cdv = centre_depth.create_view(&Default::default());
        for layer in 0..layers {
            let lv = centre_tex.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            });
            let group = views.get(layer as usize).map(|(pass, _)| {
                let raw = CentreParamsRaw {
                    view_proj: pass.view_proj,
                    to_light: [
                        pass.to_light[0],
                        pass.to_light[1],
                        pass.to_light[2],
                        self.reach as f32,
                    ],
                    n: [s.n_sub, 0, 0, 0],
                };
                let b = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("lumislice centre-line view"),
                    contents: bytemuck::bytes_of(&raw),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                dev.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("lumislice_centerline"),
                    layout: &self.centre_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: b.as_entire_binding(),
                    }],
                })
            });
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lumislice_centerline"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &lv,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &cdv,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let Some(g) = &group {
                pass.set_pipeline(&self.centre);
                pass.set_bind_group(0, &self.data.bind_group, &[]);
                pass.set_bind_group(1, g, &[]);
                pass.draw(0..4, 0..self.pieces.len() as u32);
            }
        }
        let order = self.order(&setup);
        let order = if order.is_empty() { vec![0] } else { order };
        let ubuf = |label, contents: &[u8]| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let vbuf = ubuf("lumislice view", bytemuck::bytes_of(&view));
        let mbuf = ubuf("lumislice march", bytemuck::bytes_of(&mp));
        let obuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lumislice order"),
            contents: bytemuck::cast_slice(&order),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let maps_view = centre_tex.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lumislice_march"),
            layout: &self.march_layout,
            entries: &[
                entry(0, &vbuf),
                entry(1, &mbuf),
                entry(2, &self.headers),
                entry(3, &self.sigma),
                entry(4, &self.vrf),
                entry(5, &obuf),
                entry(6, &self.lut),
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: wgpu::BindingResource::TextureView(&maps_view),
                },
            ],
        });
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lumislice_march"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: match clear {
                        Some(c) => {
                            wgpu::LoadOp::Clear(wgpu::Color { r: c[0], g: c[1], b: c[2], a: c[3] })
                        }
                        None => wgpu::LoadOp::Load,
                    },
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: if clear.is_some() {
                        wgpu::LoadOp::Clear(1.0)
                    } else {
                        wgpu::LoadOp::Load
                    },
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if !self.pieces.is_empty() {
            pass.set_pipeline(&self.march);
            pass.set_bind_group(0, &self.data.bind_group, &[]);
            pass.set_bind_group(1, &group, &[]);
            if s.slices > 0 {
                pass.draw(0..4, 0..self.pieces.len() as u32 * s.slices);
            } else {
                pass.draw(0..36, 0..self.pieces.len() as u32);
            }
        }
        Ok(())
    }

    /// Records one frame into another renderer's targets (loaded; depth-tested read-only
    /// against what is there), as [`crate::StripRenderer::encode_into`] does; nothing is
    /// submitted. The targets must be [`SAMPLES`]-sampled.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_into(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        targets: (&wgpu::TextureView, Option<&wgpu::TextureView>, &wgpu::TextureView),
        size: (u32, u32),
        cam: &FiberCamera,
        lights: &[FiberLight],
    ) -> Result<()> {
        crate::passes::draw::check_targets("lumislice", targets, size, SAMPLES)?;
        gpu.scoped("lumislice frame (into targets)", || {
            self.record(gpu, enc, cam, lights, size, targets, None)
        })??;
        Ok(())
    }

    /// Renders one `width × height` frame over a background of `clear` (linear RGBA; the
    /// yarn is composited "over" it).
    pub fn render(
        &self,
        gpu: &Gpu,
        cam: &FiberCamera,
        lights: &[FiberLight],
        (width, height): (u32, u32),
        clear: [f64; 4],
    ) -> Result<FiberImage> {
        let t = FrameTargets::new(gpu, "lumislice", (width, height), SAMPLES)?;
        let (cv, rv, dv) = t.views();
        gpu.scoped("lumislice frame", || -> Result<()> {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            let targets = (&cv, rv.as_ref(), &dv);
            self.record(gpu, &mut enc, cam, lights, (width, height), targets, Some(clear))?;
            gpu.queue.submit([enc.finish()]);
            Ok(())
        })??;
        let pixels = t.read(gpu)?;
        let n = self.pieces.len() as u32;
        let stats = FiberStats {
            segments: self.data.segment_count,
            culled: 0,
            instances: n,
            hairs: 0,
            shadow_instances: 0,
            overflow: 0,
            triangles: n as u64 * 12,
            yarn_bytes: self.data.bytes + self.table_bytes,
        };
        Ok(FiberImage { width, height, pixels, stats })
    }
}

/// σ⊥ of `l`'s finest level averaged over circles of radius `reach·k/n`, `k = 0..=n` (the
/// azimuthal mean eq. 10 uses, DESIGN §1.3 item 13).
fn radial_profile(l: &Lumislice, n: usize) -> Vec<f64> {
    let lv = &l.levels[0];
    let grid = yarn_precompute::lumislice::SliceGrid {
        res: lv.res,
        half_width: l.half_width,
        sigma: lv.sigma.iter().map(|v| *v as f64).collect(),
    };
    let m = 128;
    (0..=n)
        .map(|k| {
            let r = l.reach() * k as f64 / n as f64;
            (0..m)
                .map(|j| {
                    let a = std::f64::consts::TAU * (j as f64 + 0.5) / m as f64;
                    grid.at(r * a.cos(), r * a.sin())
                })
                .sum::<f64>()
                / m as f64
        })
        .collect()
}
