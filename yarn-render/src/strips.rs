//! `StripRenderer`: Huang et al.'s fiber-textured yarn strips [H25 §4.3, §5.2] on wgpu —
//! the yarn curves drawn as camera-facing strips of the baked half-width, textured with a
//! [`StripBake`] (coverage, fiber tangents, AO, the factorised fiber-level shadowing
//! `Ψ^Fiber_G` and multiple-scattering correction `ξ` of [H25 eq. 9–11]), shadowed by the
//! strips' own shadow maps with PCSS, under point and directional lights and a constant
//! ambient term, with MSAA. Two passes per frame:
//!
//! - `yarn_tube_shadow` ([`crate::passes::shadow`]): the strip shadow pass of [H25 §5.2] —
//!   light-facing strips of the yarn radius, depth only, one map per directional light
//!   and SRBF, one perspective map (or six cube faces, hard) per point light;
//! - `strip_regular` (`shaders/strip_regular.wgsl`): one instance per yarn segment,
//!   vertex-pulled from the same control points as the fibers (`yarn_point`), in place of
//!   the paper's geometry shader (lavapipe has none).
//!
//! **Deviations from [H25], each for a reason** (see also `yarn_precompute::strip_bake`):
//! - texture u is the screw-symmetric `frac(z/α_ply − ψ_e/2π)`, not the arc length alone,
//!   so the plies seen from any azimuth are the baked ones;
//! - `K` fiber tangents per texel (default 4) instead of one, averaging the BCSDF over the
//!   spread of fiber directions in a texel; `K = 1` is the paper's tangent texture;
//! - PCSS light size is the light's angular radius [`StripSettings::light_angle_deg`]
//!   (a directional light has none in our scenes; 0 gives the hard map, one tap);
//! - environment light ([`StripRenderer::set_environment`]): [H25 eq. 17] with the SRBF
//!   fit and `I_M` table of `yarn_precompute::srbf` — per SRBF j its strip shadow map
//!   (PCSS of angular radius `1/√λ`), `Ψ` and `ξ` read at ω_j, and `I_M` averaged over the
//!   texel's K tangents; without one, a constant ambient term `ambient · A(θ_o) · AO`;
//! - the flyaway overlay [H25 §4.4] ([`StripRenderer::set_flyaways`]): a second draw of
//!   the same strips `H_f` wide with `yarn_precompute::FlyawayBake`'s textures (where a hair
//!   was the first fiber seen, its direction), one of the textures per segment by a hash,
//!   u = the ply turns (view-independent, as [H25]), shaded with the BCSDF alone (hairs
//!   stand apart: no Ψ, no ξ), passing at equal depth and biased towards the eye. [H25]'s
//!   "adjust the local scattering for the flyaway density" is in the regular bake's ξ,
//!   which is fitted without hairs (DESIGN §3.3 item 15's choice, inverted: the hairs are
//!   drawn, not folded in).

use crate::bcsdf;
use crate::gpu_data::YarnBuffers;
use crate::pack::PackedYarns;
use crate::passes::draw::{DEPTH, FrameTargets, SHADING_WGSL, color_format};
use crate::passes::shadow::{ShadowPass, ShadowPassRaw, ShadowViewsRaw, frame_views, views_raw};
use crate::renderer::{FiberImage, FiberStats};
use crate::view::{FiberCamera, FiberLight, ViewRaw, ViewSetup, lights_raw, to_cols};
use crate::{Error, Result};
use btf_render::Gpu;
use std::path::Path;
use wgpu::util::DeviceExt;

fn entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
}
use yarn::bcsdf::FiberBcsdf;
use yarn::{YarnParams, YarnSet};
use yarn_precompute::strip_bake::AMBIENT_ENTRIES;
use yarn_precompute::{FlyawayBake, StripBake, StripBakeSettings};

const WGSL: &str = include_str!("shaders/strip_regular.wgsl");

/// The pass's WGSL (generator, view and fiber shading in front).
pub fn source() -> String {
    format!("{}\n{}\n{SHADING_WGSL}\n{WGSL}", crate::FIBER_GEN_WGSL, crate::FIBER_VIEW_WGSL)
}

/// Accuracy/time knobs of a strip frame (DESIGN §3.5's sweep).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StripSettings {
    /// Subdivisions per yarn segment (strip vertices 2·(n_sub + 1)).
    pub n_sub: u32,
    /// MSAA samples (1 or 4; [H25 §6.2]: 4).
    pub msaa: u32,
    /// Use the baked textures (off: plain shaded strips of the yarn's width — the baseline).
    pub textures: bool,
    /// Multiply by ξ (the multiple-scattering correction).
    pub xi: bool,
    /// Multiply by Ψ^Fiber (fiber-level shadowing).
    pub psi: bool,
    /// Multiply by the yarn colour.
    pub tint: bool,
    /// Strip shadow maps for the first four point or directional lights and every SRBF.
    pub shadows: bool,
    /// PCSS light angular radius (degrees; 0: hard shadow map, one tap).
    pub light_angle_deg: f64,
    /// Side of the shadow maps (texels).
    pub shadow_map: u32,
    /// Constant ambient radiance (linear RGB).
    pub ambient: [f32; 3],
    /// Strips narrower than this (pixels) are widened to it with their coverage as a
    /// fraction of the samples (as the fiber renderer's `min_strip_px`).
    pub min_strip_px: f32,
    /// Draw the flyaway overlay when flyaway textures are set ([`StripRenderer::set_flyaways`]).
    pub flyaways: bool,
}

impl Default for StripSettings {
    fn default() -> Self {
        StripSettings {
            n_sub: 4,
            msaa: 4,
            textures: true,
            xi: true,
            psi: true,
            tint: true,
            shadows: true,
            light_angle_deg: 0.5,
            shadow_map: 1024,
            ambient: [0.0; 3],
            min_strip_px: 1.0,
            flyaways: true,
        }
    }
}

/// One header per yarn type (`strip_regular.wgsl`'s `StripHeader`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct StripHeaderRaw {
    dims: [u32; 4],
    offs: [u32; 4],
    f: [f32; 4],
    fly: [u32; 4],
}

/// The most SRBFs of an environment.
pub const MAX_SRBFS: usize = 32;
/// An SRBF environment as the strip and fiber shaders read it (`env`), uploaded: count, λ,
/// unused ×2; per SRBF its direction (xyz, 0) and weight (rgb, 0); then `I_M` on 16³
/// nodes, RGB — and the centres of the SRBFs kept, in that order (one shadow map each).
/// SRBFs whose weight is at most 1e-6 of the largest in every channel are left out: the
/// non-negative fit zeroes some of them, and each costs a shadow map and a term per
/// fragment for nothing. `who` names the renderer in errors: more than [`MAX_SRBFS`] or
/// no SRBFs, weights and centres of different counts, non-finite values, or a table for
/// another λ are refused.
pub fn env_buffer(
    gpu: &Gpu,
    who: &str,
    fit: &yarn_precompute::SrbfFit,
    table: &yarn_precompute::ImTable,
) -> Result<(wgpu::Buffer, Vec<[f64; 3]>)> {
    let n = fit.centres.len();
    if n == 0 || n > MAX_SRBFS || fit.weights.len() != n {
        return Err(Error::Invalid(format!("{who}: {n} SRBFs (1..={MAX_SRBFS})")));
    }
    if (table.lambda - fit.lambda).abs() > 1e-9 * fit.lambda {
        return Err(Error::Invalid(format!(
            "{who}: I_M table for λ = {} but the fit has λ = {}",
            table.lambda, fit.lambda
        )));
    }
    let mut values = fit.centres.iter().flatten().chain(fit.weights.iter().flatten());
    if !(values.all(|x| x.is_finite()) && fit.lambda.is_finite()) {
        return Err(Error::Invalid(format!("{who}: non-finite SRBF fit")));
    }
    let top = fit.weights.iter().flatten().fold(0.0f64, |m, &w| m.max(w));
    let kept: Vec<usize> =
        (0..n).filter(|&j| fit.weights[j].iter().any(|&w| w > 1e-6 * top)).collect();
    let mut data = vec![kept.len() as f32, fit.lambda as f32, 0.0, 0.0];
    for &j in &kept {
        let (c, w) = (fit.centres[j], fit.weights[j]);
        data.extend([c[0] as f32, c[1] as f32, c[2] as f32, 0.0]);
        data.extend([w[0] as f32, w[1] as f32, w[2] as f32, 0.0]);
    }
    table.values.iter().for_each(|v| data.extend(v));
    let buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("srbf env"),
        contents: bytemuck::cast_slice(&data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    Ok((buffer, kept.iter().map(|&j| fit.centres[j]).collect()))
}

/// An environment fitted by SRBFs, uploaded.
struct StripEnv {
    buffer: wgpu::Buffer,
    dirs: Vec<[f64; 3]>,
    /// PCSS angular radius of each SRBF (`1/√λ`, DESIGN §3.3 item 14), degrees.
    angle_deg: f64,
}

/// The strip bakes of `set`'s yarn types: one per entry of `params`, tinted with the colour
/// of the first curve using it (white if none does), read from or written to `cache_dir`.
pub fn bakes_for(
    set: &YarnSet,
    params: &[YarnParams],
    bcsdf: &FiberBcsdf,
    settings: &StripBakeSettings,
    cache_dir: Option<&Path>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<StripBake>> {
    params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let color = set
                .curves
                .iter()
                .find(|c| c.params_ids.first() == Some(&(i as u32)))
                .and_then(|c| c.colors.first().copied())
                .unwrap_or([1.0; 3]);
            StripBake::for_params(p, bcsdf, color, settings, cache_dir, progress)
                .map_err(|e| Error::Invalid(format!("yarn '{}': strip bake: {e}", p.name)))
        })
        .collect()
}

/// The flyaway textures of the yarn types `params` ([`yarn_precompute::FlyawayBake`], 64 × 32
/// texels, 3 textures, 8 rays per texel; a second or so, not cached).
pub fn flyaways_for(params: &[YarnParams], seed: u64) -> Result<Vec<FlyawayBake>> {
    params
        .iter()
        .map(|p| {
            FlyawayBake::bake(p, 64, 32, 3, 8, seed)
                .map_err(|e| Error::Invalid(format!("yarn '{}': flyaway bake: {e}", p.name)))
        })
        .collect()
}

/// The strip renderer of one packed yarn set.
pub struct StripRenderer {
    data: YarnBuffers,
    pipeline: wgpu::RenderPipeline,
    pipeline_fly: wgpu::RenderPipeline,
    headers_cpu: Vec<StripHeaderRaw>,
    fly: wgpu::Buffer,
    fly_count: u32,
    extent: f64,
    layout: wgpu::BindGroupLayout,
    shadow: ShadowPass,
    headers: wgpu::Buffer,
    texels: wgpu::Buffer,
    lobes: wgpu::Buffer,
    q_nodes: wgpu::Buffer,
    lobe_count: u32,
    sampler: wgpu::Sampler,
    settings: StripSettings,
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    texel_bytes: u64,
    env: Option<StripEnv>,
    no_env: wgpu::Buffer,
}

impl StripRenderer {
    /// Uploads `packed` and `bakes` (one per entry of `packed.yarn_params`, e.g. from
    /// [`bakes_for`]) and compiles the passes.
    pub fn new(
        gpu: &Gpu,
        packed: &PackedYarns,
        bakes: &[StripBake],
        bcsdf: &FiberBcsdf,
        settings: StripSettings,
    ) -> Result<Self> {
        if settings.msaa != 1 && settings.msaa != 4 {
            return Err(Error::Invalid(format!("strips: MSAA {} (1 or 4)", settings.msaa)));
        }
        if settings.n_sub == 0 || settings.n_sub > 64 {
            return Err(Error::Invalid(format!("strips: n_sub {} (1..=64)", settings.n_sub)));
        }
        if settings.shadow_map < 16 || settings.shadow_map > 8192 {
            return Err(Error::Invalid(format!(
                "strips: shadow_map {} (16..=8192)",
                settings.shadow_map
            )));
        }
        if !(settings.min_strip_px.is_finite() && settings.min_strip_px >= 0.0) {
            return Err(Error::Invalid(format!("strips: min_strip_px {}", settings.min_strip_px)));
        }
        if !(settings.light_angle_deg.is_finite()
            && (0.0..45.0).contains(&settings.light_angle_deg))
        {
            return Err(Error::Invalid(format!(
                "strips: light_angle_deg {} (0 ≤ angle < 45)",
                settings.light_angle_deg
            )));
        }
        if bakes.len() != packed.yarn_params.len() {
            return Err(Error::Invalid(format!(
                "strips: {} bakes for {} yarn types",
                bakes.len(),
                packed.yarn_params.len()
            )));
        }
        let dev = &gpu.device;
        let data = YarnBuffers::new(gpu, packed)?;
        let shadow = ShadowPass::new(gpu, &data)?;
        let mut headers = Vec::new();
        let mut texels: Vec<f32> = Vec::new();
        for b in bakes {
            let s = &b.settings;
            let base = texels.len() as u32;
            let t = b.gpu_texels();
            let n_tex = s.width * s.height * b.texel_stride();
            headers.push(StripHeaderRaw {
                dims: [s.width as u32, s.height as u32, s.directions as u32, s.tangents as u32],
                offs: [base, base + n_tex as u32, b.texel_stride() as u32, AMBIENT_ENTRIES as u32],
                f: [b.half_width as f32, b.half_width as f32, 0.0, 0.0],
                fly: [0; 4],
            });
            texels.extend(t);
        }
        let max = dev.limits().max_storage_buffer_binding_size;
        if texels.len() as u64 * 4 > max {
            return Err(Error::Limit(format!(
                "strip textures of {} bytes exceed the storage binding limit {max}",
                texels.len() * 4
            )));
        }
        let (lobes, q) = bcsdf::pack(bcsdf)?;
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
        let fs = wgpu::ShaderStages::FRAGMENT;
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("strip_regular"),
            entries: &[
                buf(0, vf, wgpu::BufferBindingType::Uniform),
                buf(1, vf, ro),
                buf(2, fs, ro),
                buf(3, fs, ro),
                buf(4, fs, ro),
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: fs,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 6,
                    visibility: fs,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                buf(7, fs, wgpu::BufferBindingType::Uniform),
                buf(8, fs, ro),
                buf(9, fs, ro),
            ],
        });
        let src = source();
        let samples = settings.msaa;
        let make = |fly: bool| {
            gpu.scoped("strip_regular pipeline", || {
                let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("strip_regular.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(src.as_str().into()),
                });
                let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("strip_regular"),
                    bind_group_layouts: &[Some(&data.layout), Some(&layout)],
                    immediate_size: 0,
                });
                dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("strip_regular"),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_strip"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleStrip,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: Some(true),
                        // The flyaway overlay lies in the regular strips' plane: it passes
                        // at equal depth and is pulled towards the eye by a few ulps.
                        depth_compare: Some(if fly {
                            wgpu::CompareFunction::LessEqual
                        } else {
                            wgpu::CompareFunction::Less
                        }),
                        stencil: Default::default(),
                        bias: if fly {
                            wgpu::DepthBiasState { constant: -4, slope_scale: -1.0, clamp: 0.0 }
                        } else {
                            Default::default()
                        },
                    }),
                    multisample: wgpu::MultisampleState {
                        count: samples,
                        mask: !0,
                        alpha_to_coverage_enabled: false,
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_strip"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: color_format(samples),
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
            .map_err(|e| Error::Gpu(e.to_string()))
        };
        let pipeline = make(false)?;
        let pipeline_fly = make(true)?;
        let (lo, hi) = packed.bounds;
        let reach = bakes.iter().map(|b| b.half_width).fold(packed.max_reach, f64::max);
        let (centre, extent) = if packed.segments.is_empty() {
            ([0.0; 3], 1.0)
        } else {
            let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - packed.origin[a]);
            let r = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt() * 0.5;
            (c, r)
        };
        let radius = extent + reach;
        let headers = if headers.is_empty() { vec![StripHeaderRaw::default()] } else { headers };
        if texels.is_empty() {
            texels.push(0.0);
        }
        Ok(StripRenderer {
            headers: dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("strip headers"),
                contents: bytemuck::cast_slice(&headers),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            }),
            headers_cpu: headers,
            fly: storage("strip flyaways (none)", bytemuck::cast_slice(&[0.0f32; 4])),
            fly_count: 0,
            extent,
            pipeline_fly,
            texel_bytes: texels.len() as u64 * 4,
            texels: storage("strip texels", bytemuck::cast_slice(&texels)),
            lobes: storage("strip lobes", bytemuck::cast_slice(&lobes)),
            q_nodes: storage("strip q nodes", bytemuck::cast_slice(&q)),
            lobe_count: lobes.len() as u32,
            sampler: dev.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("strip shadow"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
            data,
            pipeline,
            layout,
            shadow,
            settings,
            origin: packed.origin,
            centre,
            radius,
            env: None,
            no_env: storage("strip env (none)", bytemuck::cast_slice(&[0.0f32; 4])),
        })
    }

    /// Lights the next frames with an environment fitted by SRBFs and the `I_M` table of this
    /// renderer's BCSDF at the fit's λ ([H25 eq. 14–17]; `None`: no environment). Each SRBF
    /// gets a strip shadow map with PCSS of angular radius `1/√λ` when shadows are on.
    pub fn set_environment(
        &mut self,
        gpu: &Gpu,
        env: Option<(&yarn_precompute::SrbfFit, &yarn_precompute::ImTable)>,
    ) -> Result<()> {
        let Some((fit, table)) = env else {
            self.env = None;
            return Ok(());
        };
        let (buffer, dirs) = env_buffer(gpu, "strips", fit, table)?;
        let angle_deg = crate::passes::shadow::srbf_angle_deg(fit.lambda);
        self.env = Some(StripEnv { buffer, dirs, angle_deg });
        Ok(())
    }

    /// The settings in use.
    pub fn settings(&self) -> &StripSettings {
        &self.settings
    }

    /// Sets the flyaway textures, one per yarn type of the packed set (e.g. from
    /// [`flyaways_for`]; an empty slice removes them): the overlay pass draws them over the
    /// regular strips when [`StripSettings::flyaways`] is on.
    pub fn set_flyaways(&mut self, gpu: &Gpu, flyaways: &[FlyawayBake]) -> Result<()> {
        if !flyaways.is_empty() && flyaways.len() != self.headers_cpu.len() {
            return Err(Error::Invalid(format!(
                "strips: {} flyaway bakes for {} yarn types",
                flyaways.len(),
                self.headers_cpu.len()
            )));
        }
        let mut data: Vec<f32> = Vec::new();
        let mut reach: f64 = 0.0;
        for (k, h) in self.headers_cpu.iter_mut().enumerate() {
            match flyaways.get(k) {
                Some(f) => {
                    h.fly =
                        [(data.len() / 4) as u32, f.width as u32, f.height as u32, f.count as u32];
                    h.f[1] = f.half_width as f32;
                    reach = reach.max(f.half_width);
                    data.extend(f.gpu_texels());
                }
                None => {
                    h.fly = [0; 4];
                    h.f[1] = h.f[0];
                }
            }
        }
        let max = gpu.device.limits().max_storage_buffer_binding_size;
        if data.len() as u64 * 4 > max {
            return Err(Error::Limit(format!("flyaway textures of {} bytes", data.len() * 4)));
        }
        self.fly_count = flyaways.len() as u32;
        if data.is_empty() {
            data.extend([0.0; 4]);
        }
        self.fly = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("strip flyaways"),
            contents: bytemuck::cast_slice(&data),
            usage: wgpu::BufferUsages::STORAGE,
        });
        gpu.queue.write_buffer(&self.headers, 0, bytemuck::cast_slice(&self.headers_cpu));
        self.radius = self.radius.max(self.extent + reach);
        Ok(())
    }

    /// Sets the constant ambient radiance of the next frames (non-finite or negative
    /// channels count as zero).
    pub fn set_ambient(&mut self, radiance: [f32; 3]) {
        self.settings.ambient = radiance.map(|x| if x.is_finite() && x > 0.0 { x } else { 0.0 });
    }

    /// Bytes of the strip textures on the GPU.
    pub fn texture_bytes(&self) -> u64 {
        self.texel_bytes
    }

    fn view_raw(
        &self,
        cam: &FiberCamera,
        lights: &[FiberLight],
        size: (u32, u32),
    ) -> Result<ViewRaw> {
        let setup = ViewSetup::new(cam, self.origin, self.centre, self.radius, size)?;
        let s = &self.settings;
        let flags =
            s.xi as u32 | (s.psi as u32) << 1 | (s.tint as u32) << 2 | (s.textures as u32) << 3;
        let f3 = |v: nalgebra::Vector3<f64>, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        Ok(ViewRaw {
            view_proj: to_cols(&setup.view_proj),
            eye: f3(setup.eye, if setup.orthographic { 0.0 } else { 1.0 }),
            forward: f3(setup.forward, 0.0),
            viewport: [size.0 as f32, size.1 as f32, setup.px_per_metre as f32, 0.0],
            planes: setup.planes().map(|p| p.map(|x| x as f32)),
            lod: [0, s.n_sub, flags, 0],
            counts: [lights.len() as u32, self.lobe_count, self.data.segment_count, 0],
            strip: [s.min_strip_px, s.msaa as f32, 0.0, 0.0],
            lights: lights_raw(lights, self.origin)?,
            ambient: [s.ambient[0], s.ambient[1], s.ambient[2], 0.0],
        })
    }

    fn shadow_views(&self, lights: &[FiberLight]) -> Result<(Vec<ShadowPassRaw>, ShadowViewsRaw)> {
        let size = self.settings.shadow_map;
        if !self.settings.shadows {
            return Ok((Vec::new(), ShadowViewsRaw::empty(size)));
        }
        // PCSS: a directional light's angular radius, an SRBF's 1/√λ.
        let (srbfs, angle) = match &self.env {
            Some(e) => (&e.dirs[..], e.angle_deg),
            None => (&[][..], 0.0),
        };
        let angles = (self.settings.light_angle_deg, angle);
        let views =
            frame_views(lights, srbfs, angles, self.origin, self.centre, self.radius, size)?;
        Ok((views.iter().map(|v| v.pass).collect(), views_raw(&views, size)))
    }

    /// Records the shadow and strip passes of one frame into `enc`.
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
        let raw = self.view_raw(cam, lights, size)?;
        let (passes, sraw) = self.shadow_views(lights)?;
        let side = self.settings.shadow_map;
        let maps = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("strip shadow maps"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: passes.len().max(1) as u32,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let maps_view = maps.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sbuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("strip shadow views"),
            contents: bytemuck::bytes_of(&sraw),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        // Group 1 for a view uniform (the regular pass, and the flyaway overlay with flag 16).
        let group = |label, view: &ViewRaw| {
            let vbuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(view),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &self.layout,
                entries: &[
                    entry(0, &vbuf),
                    entry(1, &self.headers),
                    entry(2, &self.texels),
                    entry(3, &self.lobes),
                    entry(4, &self.q_nodes),
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&maps_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: wgpu::BindingResource::Sampler(&self.sampler),
                    },
                    entry(7, &sbuf),
                    entry(8, self.env.as_ref().map_or(&self.no_env, |e| &e.buffer)),
                    entry(9, &self.fly),
                ],
            })
        };
        let regular = group("strip_regular", &raw);
        let fly_group = (self.settings.flyaways && self.fly_count > 0).then(|| {
            let mut fraw = raw;
            fraw.lod[2] |= 16;
            group("strip_flyaway", &fraw)
        });
        self.shadow.encode(gpu, enc, &self.data, &maps, (0, &passes));
        let load = |c: Option<[f64; 4]>| match c {
            Some(c) => wgpu::LoadOp::Clear(wgpu::Color { r: c[0], g: c[1], b: c[2], a: c[3] }),
            None => wgpu::LoadOp::Load,
        };
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("strip_regular"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations { load: load(clear), store: wgpu::StoreOp::Store },
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
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.data.bind_group, &[]);
        pass.set_bind_group(1, &regular, &[]);
        pass.draw(0..2 * (self.settings.n_sub + 1), 0..self.data.segment_count);
        if let Some(g) = &fly_group {
            pass.set_pipeline(&self.pipeline_fly);
            pass.set_bind_group(1, g, &[]);
            pass.draw(0..2 * (self.settings.n_sub + 1), 0..self.data.segment_count);
        }
        Ok(())
    }

    /// Records one frame into another renderer's targets (loaded, depth-tested against
    /// what is there), as [`crate::FiberRenderer::encode_into`] does; nothing is submitted.
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
        crate::passes::draw::check_targets("strips", targets, size, self.settings.msaa)?;
        gpu.scoped("strip frame (into targets)", || {
            self.record(gpu, enc, cam, lights, size, targets, None)
        })??;
        Ok(())
    }

    /// Renders one `width × height` frame over a background of `clear` (linear RGBA).
    pub fn render(
        &self,
        gpu: &Gpu,
        cam: &FiberCamera,
        lights: &[FiberLight],
        (width, height): (u32, u32),
        clear: [f64; 4],
    ) -> Result<FiberImage> {
        let t = FrameTargets::new(gpu, "strip", (width, height), self.settings.msaa)?;
        let (cv, rv, dv) = t.views();
        gpu.scoped("strip frame", || -> Result<()> {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            let targets = (&cv, rv.as_ref(), &dv);
            self.record(gpu, &mut enc, cam, lights, (width, height), targets, Some(clear))?;
            gpu.queue.submit([enc.finish()]);
            Ok(())
        })??;
        let pixels = t.read(gpu)?;
        let n = self.data.segment_count;
        let stats = FiberStats {
            segments: n,
            culled: 0,
            instances: n,
            hairs: 0,
            shadow_instances: 0,
            overflow: 0,
            triangles: n as u64 * 2 * self.settings.n_sub as u64,
            yarn_bytes: self.data.bytes + self.texel_bytes,
        };
        Ok(FiberImage { width, height, pixels, stats })
    }
}
