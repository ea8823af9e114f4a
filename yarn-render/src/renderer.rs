//! `FiberRenderer`: the real-time fiber renderer of [W19] as wgpu passes — `fiber_lod`
//! (cull, λ of [W19 eq. 4], instance list, indirect arguments) then `fiber_draw` (vertex
//! pulling of the generator, fiber BCSDF, MSAA) — for a camera and delta lights, returning
//! the linear-RGB frame and what was drawn. Fibers are generated every frame from the
//! packed control points; nothing per fiber point is ever stored ([W19 §5]).
//!
//! The effects of [`FiberEffects`] ([W19 §4]): self-shadows from the precomputed volume,
//! AO, the environment — a constant ambient term ([W19 eq. 7–8]) or, with
//! [`FiberRenderer::set_environment`], the map's SRBF lobes through the `I_M` table of
//! [H25 eq. 16–17] read at each fiber's own tangent — and tube shadow maps of other yarns
//! (`crate::passes::shadow`) for the first four directional or point lights (a point light:
//! one perspective map, or six cube faces when it is near or among the yarns) and for
//! every SRBF lobe. [W19] lights its fibers by delta lights and a constant ambient only;
//! the lobes carry the map's directions, so rotating the environment moves the
//! highlights and the shadows.
//!
//! [`FiberSettings::n_max`] = all and `lod_px ≤ 0` draw every fiber (the full-detail mode
//! the CPU reference is compared with). Hair flyaways ([`FiberSettings::hairs`]) are the
//! CPU generator's: `fiber_lod` finds them by the slots' hashes and the generator draws
//! them along the curve (`crate::passes::lod`); they cast no shadow through the tube maps
//! and the self-shadow volume (those are of the regular fibers, DESIGN §2.3 item 14) —
//! beside a yarn they match the reference within 1 %, inside it they brighten the yarn 6 %
//! where the reference's brighten it 2 % (`tests/gpu/hairs.rs`).
//!
//! With [`FiberEffects::fiber_shadows`] each delta light's map is drawn from every fiber,
//! hair and core strip instead (`crate::passes::fiber_shadow`): per map a `fiber_lod` pass
//! with the light as the camera (LoD off) and `fiber_draw`'s `fs_shadow` into a depth and a
//! fiber-key layer, recorded before the frame's own passes; the instance list is shared,
//! used map by map, each map with its own indirect arguments.

use crate::bcsdf;
use crate::effects::{self, AoMode, FiberEffects};
use crate::gpu_data::YarnBuffers;
use crate::pack::PackedYarns;
use crate::passes::draw::{DEPTH, DrawPass, FrameTargets, SHADOW_IDS};
use crate::passes::fiber_shadow::{fitted_point_view, fitted_view};
use crate::passes::lod::{DrawArgsRaw, LodPass};
use crate::passes::shadow::{
    MAX_SHADOW_MAPS, MapView, ShadowPass, ShadowPassRaw, ShadowViewsRaw, frame_views,
    point_cameras, views_raw,
};
use crate::view::{FiberCamera, FiberLight, ViewRaw, ViewSetup, lights_raw, to_cols};
use crate::{Error, Result};
use btf_render::Gpu;
use std::path::Path;
use wgpu::util::DeviceExt;
use yarn::bcsdf::FiberBcsdf;
use yarn_precompute::BakeSettings;

/// Accuracy/time knobs of a fiber frame (DESIGN §2.5's sweep).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberSettings {
    /// Fibers per ply at λ = 1 (`u32::MAX`: all of the table).
    pub n_max: u32,
    /// Subdivisions per segment at λ = 1 (≤ 255).
    pub n_sub: u32,
    /// LoD threshold ω^LoD in pixels (≤ 0: LoD off, every segment at λ = 1).
    pub lod_px: f32,
    /// Conservative frustum culling.
    pub cull: bool,
    /// Loop flyaways.
    pub loops: bool,
    /// Hair flyaways (`fiber_lod` finds them by hashing the fibers' slots and thins them
    /// with LoD, `crate::passes::lod`; must match the CPU generator's `GenOptions::hairs`
    /// for the two to agree).
    pub hairs: bool,
    /// Multiply the BCSDF by the yarn colour.
    pub tint: bool,
    /// MSAA samples (1 or 4).
    pub msaa: u32,
    /// Strips narrower than this (pixels) are widened to it with their coverage as alpha.
    pub min_strip_px: f32,
    /// Most fiber instances one frame may list (8 bytes each).
    pub capacity: u32,
    /// Draw plain tubes of the yarn radius instead of fibers (the baseline every speed
    /// claim is a ratio to, DESIGN §2.5): one strip per segment, same vertex pulling,
    /// same BCSDF.
    pub tubes: bool,
    /// Self-shadows, AO, yarn shadows, ambient light.
    pub effects: FiberEffects,
    /// Side of the tube shadow maps (texels).
    pub shadow_map: u32,
    /// Soft shadows of the environment's SRBF lobes: the 3 × 3 PCF taps of each lobe's
    /// tube map spread over the penumbra of its angular radius `atan(1/√λ)` across a yarn
    /// diameter, instead of the delta light's one-texel taps. Hard lobes put each lobe's
    /// shadow exactly where its centre is, so turning the map about `+z` moves them: a
    /// constant sky turned 90° changed the patch by 18 % hard, 8.5 % soft, at no more error
    /// against the reference (0.530 soft, 0.538 hard) and the same frame time
    /// (`tests/gpu/lights.rs`, `benches/lights.rs`). (The strips' PCSS blocker search was
    /// tried here first: in this shader it made every lobe 3× dearer on llvmpipe.)
    pub soft_lobes: bool,
    /// Frames per pixel side (1..=16): [`FiberRenderer::render`] draws the frame `k × k`
    /// times larger and box-filters it down, `k²·msaa` samples a pixel on a regular grid.
    /// `lod_px` and `min_strip_px` stay in output pixels. MSAA 4 alone aliases fiber-scale
    /// geometry: on the converged stockinette comparison (`tests/gpu/fiber_shadows.rs`,
    /// its series) the interior rel. RMSE against the reference is 0.71 / 0.056 / 0.040 /
    /// 0.033 at k = 1 / 8 / 12 / 16, everything else converged.
    pub supersample: u32,
}

impl Default for FiberSettings {
    fn default() -> Self {
        FiberSettings {
            n_max: u32::MAX,
            n_sub: 8,
            lod_px: 1.0,
            cull: true,
            loops: true,
            hairs: true,
            tint: true,
            msaa: 4,
            min_strip_px: 1.0,
            capacity: 1 << 24,
            tubes: false,
            effects: FiberEffects::default(),
            shadow_map: 1024,
            soft_lobes: true,
            supersample: 1,
        }
    }
}

/// What one frame drew.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FiberStats {
    /// Yarn segments packed.
    pub segments: u32,
    /// Segments culled.
    pub culled: u32,
    /// Fiber instances drawn (hairs included).
    pub instances: u32,
    /// Hair flyaways listed.
    pub hairs: u32,
    /// Fiber instances drawn into the fiber shadow maps (all maps of the frame).
    pub shadow_instances: u32,
    /// Instances beyond the capacity (not drawn), the fiber shadow maps' included.
    pub overflow: u32,
    /// Triangles submitted (`instances · 2·n_sub`, degenerate ones included).
    pub triangles: u64,
    /// GPU bytes of the packed yarn data (per-control-point memory).
    pub yarn_bytes: u64,
}

/// A rendered frame: linear RGB + coverage, rows top to bottom.
#[derive(Debug, Clone)]
pub struct FiberImage {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// RGBA per pixel.
    pub pixels: Vec<[f32; 4]>,
    /// What was drawn.
    pub stats: FiberStats,
}

/// [`FiberRenderer::pulled_points`]: the instance records and, per instance, its
/// `n_sub + 1` fiber points as the vertex stage evaluates them (origin-relative, w = 1).
pub type PulledPoints = (Vec<[u32; 2]>, Vec<[f32; 4]>);

/// The per-frame bindings of [`FiberRenderer::bindings`].
struct FrameBindings {
    g_lod: wgpu::BindGroup,
    g_draw: wgpu::BindGroup,
    maps: wgpu::Texture,
    /// The fiber maps' keys, layer by layer.
    ids: wgpu::Texture,
    /// Tube maps, in the layers after the fiber maps.
    passes: Vec<ShadowPassRaw>,
    /// Fiber maps, layers `0..`.
    fiber_maps: Vec<FiberMapBindings>,
}

/// One fiber shadow map of a frame: its LoD and draw bind groups (the light as the camera)
/// and its own indirect arguments (the instance list is shared, used map by map).
struct FiberMapBindings {
    g_lod: wgpu::BindGroup,
    g_draw: wgpu::BindGroup,
    args: wgpu::Buffer,
}

/// The shadow maps of one frame: the tube passes, the fiber maps' light views, and the
/// uniform the fiber shader reads them with (fiber maps first).
struct FrameShadows {
    tubes: Vec<ShadowPassRaw>,
    fibers: Vec<ViewSetup>,
    raw: ShadowViewsRaw,
}

/// The renderer of one packed yarn set.
pub struct FiberRenderer {
    data: YarnBuffers,
    lod: LodPass,
    draw: DrawPass,
    shadow: ShadowPass,
    effect_headers: wgpu::Buffer,
    effect_data: wgpu::Buffer,
    shadow_sampler: wgpu::Sampler,
    settings: FiberSettings,
    origin: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    lobe_count: u32,
    lobes: wgpu::Buffer,
    q_nodes: wgpu::Buffer,
    instances: wgpu::Buffer,
    args: wgpu::Buffer,
    capacity: u32,
    /// The SRBF environment ([`FiberRenderer::set_environment`]): the shader's buffer, the
    /// lobe centres (one tube shadow map each) and their PCSS angular radius (degrees).
    env: Option<(wgpu::Buffer, Vec<[f64; 3]>, f64)>,
    no_env: wgpu::Buffer,
    /// The largest yarn radius of the packed set (soft lobe shadows).
    yarn_radius: f64,
    /// The packed yarns' bounding box, origin-relative, inflated by their reach (fiber
    /// shadow maps).
    bounds: ([f64; 3], [f64; 3]),
    /// 1-texel depth and key arrays bound in place of the maps and the fiber maps' keys
    /// while the fiber maps are drawn.
    no_maps: Box<(wgpu::TextureView, wgpu::TextureView)>,
}

/// An indirect-draw argument buffer `fiber_lod` writes ([`DrawArgsRaw`]).
fn args_buffer(dev: &wgpu::Device, label: &str) -> wgpu::Buffer {
    dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size_of::<DrawArgsRaw>() as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// A 2-D array of `layers` square `side²` textures of `format`.
fn texture_array(
    dev: &wgpu::Device,
    label: &str,
    (side, layers): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    dev.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: side, height: side, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The whole of `t` as a 2-D array view.
fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// A 1 × 1 × 1 texture array of `format`, bound where a pass must not read what it writes.
fn placeholder(dev: &wgpu::Device, label: &str, format: wgpu::TextureFormat) -> wgpu::TextureView {
    array_view(&texture_array(dev, label, (1, 1), format, wgpu::TextureUsages::TEXTURE_BINDING))
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

impl FiberRenderer {
    /// Uploads `packed` and compiles the passes; effects that need precomputed data bake
    /// it with the default [`BakeSettings`] (once per process and yarn).
    pub fn new(
        gpu: &Gpu,
        packed: &PackedYarns,
        bcsdf: &FiberBcsdf,
        settings: FiberSettings,
    ) -> Result<Self> {
        Self::with_bake(gpu, packed, bcsdf, settings, &BakeSettings::default(), None)
    }

    /// [`Self::new`] with explicit bake settings and an on-disk cache directory.
    pub fn with_bake(
        gpu: &Gpu,
        packed: &PackedYarns,
        bcsdf: &FiberBcsdf,
        settings: FiberSettings,
        bake: &BakeSettings,
        cache_dir: Option<&Path>,
    ) -> Result<Self> {
        if settings.n_sub == 0 || settings.n_sub > 255 {
            return Err(Error::Invalid(format!("n_sub {} (must be 1..=255)", settings.n_sub)));
        }
        if settings.n_max == 0 {
            return Err(Error::Invalid("n_max 0 (at least one fiber per ply)".into()));
        }
        if !settings.min_strip_px.is_finite() || settings.min_strip_px < 0.0 {
            return Err(Error::Invalid(format!("min_strip_px {}", settings.min_strip_px)));
        }
        if settings.shadow_map < 16 || settings.shadow_map > 8192 {
            return Err(Error::Invalid(format!("shadow_map {} (16..=8192)", settings.shadow_map)));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&settings.supersample) {
            return Err(Error::Invalid(format!(
                "supersample {} (1..={MAX_SUPERSAMPLE} frames a pixel side)",
                settings.supersample
            )));
        }
        let hairy = packed.yarn_params.iter().any(|p| p.hair_chance() > 0.0);
        if settings.hairs && hairy && packed.segments.len() >= 1 << 25 {
            return Err(Error::Limit(format!(
                "{} yarn segments with hair flyaways: a hair instance addresses at most 2^25 \
                 segments; render fewer segments at once or turn hairs off",
                packed.segments.len()
            )));
        }
        let dev = &gpu.device;
        let data = YarnBuffers::new(gpu, packed)?;
        let lod = LodPass::new(gpu, &data)?;
        let draw = DrawPass::new(gpu, &data, settings.msaa, fiber_maps(&settings))?;
        let shadow = ShadowPass::new(gpu, &data)?;
        let (lobes, q) = bcsdf::pack(bcsdf)?;
        let pre = packed
            .yarn_params
            .iter()
            .map(|p| {
                settings
                    .effects
                    .needs_bake()
                    .then(|| effects::precomputed(p, bake, cache_dir))
                    .transpose()
            })
            .collect::<Result<Vec<_>>>()?;
        let sigma = packed
            .yarn_params
            .iter()
            .map(|p| {
                if !(settings.effects.self_shadow && settings.effects.helix_shadows) {
                    return Ok(None);
                }
                let f = yarn_precompute::sigma::field_for(p, bake)
                    .map_err(|e| Error::Invalid(format!("yarn '{}': extinction: {e}", p.name)))?;
                Ok(Some((f, p.ply_pitch)))
            })
            .collect::<Result<Vec<_>>>()?;
        let pitches: Vec<f64> = packed.yarn_params.iter().map(|p| p.ply_pitch).collect();
        let fx = effects::pack(&pre, &sigma, &pitches, bcsdf, 256)?;
        let max_binding = dev.limits().max_storage_buffer_binding_size;
        let capacity = (settings.capacity.max(1) as u64).min(max_binding / 8) as u32;
        let (lo, hi) = packed.bounds;
        let bounds = (
            [0, 1, 2].map(|a| lo[a] - packed.origin[a] - packed.max_reach),
            [0, 1, 2].map(|a| hi[a] - packed.origin[a] + packed.max_reach),
        );
        let (centre, radius) = if packed.segments.is_empty() {
            ([0.0; 3], 1.0)
        } else {
            let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - packed.origin[a]);
            let r = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt() * 0.5;
            (c, r + packed.max_reach)
        };
        let storage = |label, contents: &[u8]| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let headers = if fx.headers.is_empty() { vec![Default::default()] } else { fx.headers };
        Ok(FiberRenderer {
            effect_headers: storage("fiber effects", bytemuck::cast_slice(&headers)),
            effect_data: storage("fiber effect data", bytemuck::cast_slice(&fx.data)),
            shadow_sampler: dev.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("yarn shadow"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
            shadow,
            lobes: storage("fiber lobes", bytemuck::cast_slice(&lobes)),
            q_nodes: storage("fiber q nodes", bytemuck::cast_slice(&q)),
            instances: dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("fiber instances"),
                size: capacity as u64 * 8,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            args: args_buffer(dev, "fiber draw args"),
            lobe_count: lobes.len() as u32,
            data,
            lod,
            draw,
            settings,
            origin: packed.origin,
            centre,
            radius,
            capacity,
            env: None,
            no_env: storage("fiber env (none)", bytemuck::cast_slice(&[0.0f32; 4])),
            yarn_radius: packed.yarn_params.iter().map(|p| p.yarn_radius()).fold(0.0, f64::max),
            bounds,
            no_maps: Box::new((
                placeholder(dev, "no shadow maps", DEPTH),
                placeholder(dev, "no shadow keys", SHADOW_IDS),
            )),
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &FiberSettings {
        &self.settings
    }

    /// Sets the constant ambient radiance (linear RGB, [W19 eq. 7–8]) of the next frames;
    /// negative or non-finite channels count as zero.
    pub fn set_ambient(&mut self, radiance: [f32; 3]) {
        self.settings.effects.ambient =
            radiance.map(|x| if x.is_finite() && x > 0.0 { x } else { 0.0 });
    }

    /// Lights the next frames with an environment fitted by SRBFs ([H25 eq. 14]) through the
    /// `I_M` table of this renderer's BCSDF at the fit's λ ([H25 eq. 16]), in place of the
    /// constant ambient term: per fiber fragment and lobe `j`, `W_j · I_M(θ_j, θ_o, Δφ)` in
    /// the frame of the fiber's own tangent, times the self-shadow towards `ω_j` and the
    /// lobe's tube shadow map (when yarn shadows are on). `None` removes it. The table must
    /// have been built from the same BCSDF as the renderer ([`yarn_precompute::ImTable::build`]).
    pub fn set_environment(
        &mut self,
        gpu: &Gpu,
        env: Option<(&yarn_precompute::SrbfFit, &yarn_precompute::ImTable)>,
    ) -> Result<()> {
        let Some((fit, table)) = env else {
            self.env = None;
            return Ok(());
        };
        let (buffer, dirs) = crate::strips::env_buffer(gpu, "fibers", fit, table)?;
        self.env = Some((buffer, dirs, crate::passes::shadow::srbf_angle_deg(fit.lambda)));
        Ok(())
    }

    /// SRBF lobes of the environment in use (those of non-zero weight; 0 without one).
    pub fn srbf_lobes(&self) -> usize {
        self.env.as_ref().map_or(0, |e| e.1.len())
    }

    /// The frame uniform for `cam` and `lights` at `size`, the frame as drawn (`supersample`
    /// times the output's side; the thresholds are scaled to it).
    pub fn view_raw(
        &self,
        cam: &FiberCamera,
        lights: &[FiberLight],
        size: (u32, u32),
    ) -> Result<ViewRaw> {
        let setup = ViewSetup::new(cam, self.origin, self.centre, self.radius, size)?;
        self.raw_of(&setup, lights, size)
    }

    /// The frame uniform of a fiber shadow map's light view `setup` (`size²` texels): no
    /// lights, no widened strips, and every fiber (LoD off): a fiber the frame's LoD drops
    /// still shadows the ones it keeps. (The map thinned like the frame — the camera's
    /// ω^LoD moved to the map's texels, commit 776328b — lost those shadows: the sweep's
    /// 64² stockinette at ω^LoD = 1 px came out 1.65× the reference's radiance, against
    /// 0.92 at full detail; BENCHMARKS.md, "Fiber shadow maps".)
    fn map_raw(&self, setup: &ViewSetup, size: u32) -> Result<ViewRaw> {
        let mut raw = self.raw_of(setup, &[], (size, size))?;
        // A fiber map's view: the vertex stage computes the far-side depth (fs_shadow).
        raw.lod[2] |= MAP_VIEW;
        raw.viewport[3] = 0.0;
        raw.strip[0] = 0.0;
        raw.strip[1] = 1.0;
        Ok(raw)
    }

    fn raw_of(
        &self,
        setup: &ViewSetup,
        lights: &[FiberLight],
        size: (u32, u32),
    ) -> Result<ViewRaw> {
        let s = &self.settings;
        // `size` is the drawn frame, `supersample` times the output's side: thresholds in
        // output pixels.
        let k = s.supersample as f32;
        let ao = match s.effects.ao {
            AoMode::Off => 0,
            AoMode::Cubic => 1,
            AoMode::Texture => 2,
        };
        let flags = s.cull as u32
            | (s.loops as u32) << 1
            | (s.tint as u32) << 2
            | (s.tubes as u32) << 3
            | (s.effects.self_shadow as u32) << 4
            | ao << 5
            | (s.effects.core as u32) << 7
            | (s.effects.shadow_hiding as u32) << 8
            | (s.effects.helix_shadows as u32) << 9
            | (s.hairs as u32) << 10
            | (fiber_maps(s) as u32) << 11;
        let f3 = |v: nalgebra::Vector3<f64>, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        Ok(ViewRaw {
            view_proj: to_cols(&setup.view_proj),
            eye: f3(setup.eye, if setup.orthographic { 0.0 } else { 1.0 }),
            forward: f3(setup.forward, 0.0),
            viewport: [size.0 as f32, size.1 as f32, setup.px_per_metre as f32, s.lod_px * k],
            planes: setup.planes().map(|p| p.map(|x| x as f32)),
            lod: [s.n_max, s.n_sub, flags, self.capacity],
            counts: [lights.len() as u32, self.lobe_count, self.data.segment_count, 0],
            strip: [s.min_strip_px * k, s.msaa as f32, 0.0, 0.0],
            lights: lights_raw(lights, self.origin)?,
            ambient: {
                let a = s.effects.ambient;
                [a[0], a[1], a[2], 0.0]
            },
        })
    }

    /// The shadow maps of a frame seen by `cam`, when yarn shadows are on: per the first
    /// four directional or point lights a fiber map ([`FiberEffects::fiber_shadows`]) or
    /// tube maps, and per SRBF of the environment a tube map; and the uniform the fiber
    /// shader reads them with (fiber maps first).
    fn shadow_views(&self, cam: &ViewSetup, lights: &[FiberLight]) -> Result<FrameShadows> {
        let size = self.settings.shadow_map;
        if !self.settings.effects.yarn_shadows || self.settings.tubes {
            return Ok(FrameShadows {
                tubes: Vec::new(),
                fibers: Vec::new(),
                raw: ShadowViewsRaw::empty(size),
            });
        }
        let (srbfs, angle) = match &self.env {
            Some(e) => (&e.1[..], e.2),
            None => (&[][..], 0.0),
        };
        let mut fibers = Vec::new();
        let mut views = Vec::new();
        // (An empty set casts nothing: no fiber maps.)
        let delta = if fiber_maps(&self.settings) && self.data.segment_count > 0 {
            for (i, l) in lights.iter().take(MAX_SHADOW_MAPS).enumerate() {
                let maps: Vec<ViewSetup> = match *l {
                    FiberLight::Directional { to_light, .. } => {
                        let (lo, hi) = self.bounds;
                        vec![fitted_view(to_light, cam, lo, hi, size)?.0]
                    }
                    FiberLight::Point { position, .. } => {
                        let p = [0, 1, 2].map(|a| position[a] - self.origin[a]);
                        let (lo, hi) = self.bounds;
                        match fitted_point_view(p, cam, lo, hi, size)? {
                            Some(v) => vec![v],
                            // Among the yarns: the whole sphere's map or cube faces.
                            None => point_cameras(p, self.origin, self.centre, self.radius)?
                                .iter()
                                .map(|c| {
                                    ViewSetup::new(
                                        c,
                                        self.origin,
                                        self.centre,
                                        self.radius,
                                        (size, size),
                                    )
                                })
                                .collect::<Result<_>>()?,
                        }
                    }
                };
                for v in maps {
                    views.push(MapView {
                        pass: ShadowPassRaw {
                            view_proj: to_cols(&v.view_proj),
                            to_light: [0.0; 4],
                            n: [0; 4],
                        },
                        light: i as u32,
                        depth_per_metre: f64::NAN,
                        bias: [0.0, 0.0],
                        pcss: 0.0,
                        spread: FIBER_MAP_TAPS,
                    });
                    fibers.push(v);
                }
            }
            &[][..]
        } else {
            lights
        };
        let mut v =
            frame_views(delta, srbfs, (0.0, 0.0), self.origin, self.centre, self.radius, size)?;
        // Each SRBF lobe soft (`soft_lobes`): its 3 × 3 PCF taps spread over the penumbra
        // its angular radius `atan(1/√λ)` casts across a yarn diameter (the gap between a
        // yarn and one resting on it), at most 32 texels.
        if self.settings.soft_lobes {
            let metres_per_texel = 2.0 * self.radius / size as f64;
            let penumbra = angle.to_radians().tan() * 2.0 * self.yarn_radius / metres_per_texel;
            for m in v.iter_mut().filter(|m| m.light >= crate::view::MAX_LIGHTS as u32) {
                m.spread = penumbra.clamp(1.0, 32.0) as f32;
            }
        }
        let tubes = v.iter().map(|m| m.pass).collect();
        views.extend(v);
        if views.len() > crate::passes::shadow::MAX_FIBER_MAPS {
            return Err(Error::Limit(format!(
                "{} shadow maps in one frame (at most {})",
                views.len(),
                crate::passes::shadow::MAX_FIBER_MAPS
            )));
        }
        Ok(FrameShadows { tubes, fibers, raw: views_raw(&views, size) })
    }

    /// The view uniform `raw` in a buffer, and the LoD pass's bind group listing into the
    /// instance list with the indirect arguments `args`.
    fn lod_group(
        &self,
        dev: &wgpu::Device,
        label: &str,
        raw: &ViewRaw,
        args: &wgpu::Buffer,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let ubuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(raw),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fiber_lod"),
            layout: &self.lod.layout,
            entries: &[entry(0, &ubuf), entry(1, &self.instances), entry(2, args)],
        });
        (ubuf, group)
    }

    /// The frame uniform, shadow maps and bind groups of one frame.
    fn bindings(
        &self,
        gpu: &Gpu,
        cam: &FiberCamera,
        lights: &[FiberLight],
        size: (u32, u32),
    ) -> Result<FrameBindings> {
        let dev = &gpu.device;
        let setup = ViewSetup::new(cam, self.origin, self.centre, self.radius, size)?;
        let raw = self.raw_of(&setup, lights, size)?;
        let (ubuf, g_lod) = self.lod_group(dev, "fiber view", &raw, &self.args);
        let shadows = self.shadow_views(&setup, lights)?;
        let side = self.settings.shadow_map;
        let layers = shadows.fibers.len() + shadows.tubes.len();
        let targets = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let maps =
            texture_array(dev, "yarn shadow maps", (side, layers.max(1) as u32), DEPTH, targets);
        let maps_view = array_view(&maps);
        // The fiber maps' keys (one layer per fiber map; a texel when there is none).
        let keys = match shadows.fibers.len() as u32 {
            0 => (1, 1),
            n => (side, n),
        };
        let ids = texture_array(dev, "fiber shadow keys", keys, SHADOW_IDS, targets);
        let ids_view = array_view(&ids);
        let draw_group = |view: &wgpu::Buffer,
                          (maps, ids): (&wgpu::TextureView, &wgpu::TextureView),
                          views: &wgpu::Buffer,
                          env: &wgpu::Buffer| {
            dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("fiber_draw"),
                layout: &self.draw.layout,
                entries: &[
                    entry(0, view),
                    entry(1, &self.instances),
                    entry(2, &self.lobes),
                    entry(3, &self.q_nodes),
                    entry(4, &self.effect_headers),
                    entry(5, &self.effect_data),
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: wgpu::BindingResource::TextureView(maps),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: wgpu::BindingResource::Sampler(&self.shadow_sampler),
                    },
                    entry(8, views),
                    entry(9, env),
                    wgpu::BindGroupEntry {
                        binding: 10,
                        resource: wgpu::BindingResource::TextureView(ids),
                    },
                ],
            })
        };
        let vbuf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("yarn shadow views"),
            contents: bytemuck::bytes_of(&shadows.raw),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let env = self.env.as_ref().map_or(&self.no_env, |e| &e.0);
        let g_draw = draw_group(&ubuf, (&maps_view, &ids_view), &vbuf, env);
        let none = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("no shadow views"),
            contents: bytemuck::bytes_of(&ShadowViewsRaw::empty(side)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let fiber_maps = shadows
            .fibers
            .iter()
            .map(|light| {
                let raw = self.map_raw(light, side)?;
                let args = args_buffer(dev, "fiber shadow args");
                let (ubuf, g_lod) = self.lod_group(dev, "fiber shadow view", &raw, &args);
                let g_draw =
                    draw_group(&ubuf, (&self.no_maps.0, &self.no_maps.1), &none, &self.no_env);
                Ok(FiberMapBindings { g_lod, g_draw, args })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(FrameBindings { g_lod, g_draw, maps, ids, passes: shadows.tubes, fiber_maps })
    }

    /// Records the shadow, LoD and draw passes of one frame into `enc`: each fiber map's
    /// LoD and depth draw (they share the instance list, one after another), the tube
    /// maps, then the frame's LoD and draw.
    fn record(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        b: &FrameBindings,
        targets: (&wgpu::TextureView, Option<&wgpu::TextureView>, &wgpu::TextureView),
        clear: Option<[f64; 4]>,
    ) {
        let n_sub = self.settings.n_sub;
        for (layer, m) in b.fiber_maps.iter().enumerate() {
            self.lod.encode(gpu, enc, &self.data, &m.g_lod, &m.args, n_sub);
            let layer_of = |t: &wgpu::Texture| {
                t.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer as u32,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            };
            let (map, ids) = (layer_of(&b.maps), layer_of(&b.ids));
            self.draw.encode_shadow(enc, &self.data, &m.g_draw, &m.args, (&map, &ids));
        }
        if !b.passes.is_empty() || b.fiber_maps.is_empty() {
            let first = b.fiber_maps.len() as u32;
            self.shadow.encode(gpu, enc, &self.data, &b.maps, (first, &b.passes));
        }
        self.lod.encode(gpu, enc, &self.data, &b.g_lod, &self.args, n_sub);
        self.draw.encode(enc, &self.data, &b.g_draw, &self.args, targets, clear);
    }

    /// Records one frame into another renderer's targets — `color` (multisampled under
    /// MSAA, resolved into `resolve`) and `depth`, both *loaded*, so that fibers behind
    /// what is already drawn stay hidden and fibers in front hide it — with that renderer's
    /// camera ([`FiberCamera::Matrix`]). The targets must have [`color_format`] and
    /// [`DEPTH`] at [`FiberSettings::msaa`] samples and be `size` pixels. Nothing is
    /// submitted: the LoD pass resets its arguments with `queue.write_buffer`, so submit
    /// `enc` before recording the next frame of this renderer.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_into(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        (color, resolve, depth): (
            &wgpu::TextureView,
            Option<&wgpu::TextureView>,
            &wgpu::TextureView,
        ),
        size: (u32, u32),
        cam: &FiberCamera,
        lights: &[FiberLight],
    ) -> Result<()> {
        crate::passes::draw::check_targets(
            "fibers",
            (color, resolve, depth),
            size,
            self.settings.msaa,
        )?;
        if self.settings.supersample != 1 {
            return Err(Error::Invalid(format!(
                "supersample {}: drawing into another renderer's targets takes their samples \
                 (supersample 1)",
                self.settings.supersample
            )));
        }
        let b = self.bindings(gpu, cam, lights, size)?;
        gpu.scoped("fiber frame (into targets)", || {
            self.record(gpu, enc, &b, (color, resolve, depth), None)
        })?;
        Ok(())
    }

    /// The pull = expand probe (DESIGN §2.5): the instance list `fiber_lod` makes for
    /// `cam`, and every strip vertex's fiber point as the *vertex stage* of `fiber_draw`
    /// evaluates it (`vs_probe`: `vs_main`'s decoding and generator call), one `vec4` per
    /// (instance, k ≤ n_sub), origin-relative — for comparing bit for bit with
    /// `fiber_expand` on the same list. Needs one subdivision count for every instance
    /// (`lod_px ≤ 0`) and no core strips (their vertices are not fiber points).
    pub fn pulled_points(
        &self,
        gpu: &Gpu,
        cam: &FiberCamera,
        lights: &[FiberLight],
    ) -> Result<PulledPoints> {
        let s = &self.settings;
        if s.lod_px > 0.0 || s.effects.core || s.tubes {
            return Err(Error::Invalid(
                "pulled_points: needs lod_px ≤ 0, no core strips and no tubes".into(),
            ));
        }
        let dev = &gpu.device;
        let per = s.n_sub as u64 + 1;
        let b = self.bindings(gpu, cam, lights, (256, 1))?;
        let args_read = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe args"),
            size: size_of::<DrawArgsRaw>() as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = dev.create_command_encoder(&Default::default());
        self.lod.encode(gpu, &mut enc, &self.data, &b.g_lod, &self.args, s.n_sub);
        enc.copy_buffer_to_buffer(&self.args, 0, &args_read, 0, args_read.size());
        gpu.queue.submit([enc.finish()]);
        let args: DrawArgsRaw = *bytemuck::from_bytes(&gpu.read_buffer(&args_read)?);
        let n = args.instance_count as u64;
        if n == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let inst_read = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe instances"),
            size: n * 8,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let height = (n * per).div_ceil(256) as u32;
        gpu.check_frame(256, height, 1)?;
        // The same list again (LoD with the probe's viewport; LoD is off, so only culling
        // depends on the view, and the camera is the same).
        let b = self.bindings(gpu, cam, lights, (256, height))?;
        let target = gpu.target(
            "pull probe",
            (256, height),
            1,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let view = target.create_view(&Default::default());
        let pipeline = self.draw.probe_pipeline(gpu, &self.data)?;
        gpu.scoped("pull probe", || {
            let mut enc = dev.create_command_encoder(&Default::default());
            self.lod.encode(gpu, &mut enc, &self.data, &b.g_lod, &self.args, s.n_sub);
            enc.copy_buffer_to_buffer(&self.instances, 0, &inst_read, 0, n * 8);
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("pull probe"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &self.data.bind_group, &[]);
                pass.set_bind_group(1, &b.g_draw, &[]);
                pass.draw_indirect(&self.args, 0);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        let inst: Vec<[u32; 2]> = bytemuck::cast_slice(&gpu.read_buffer(&inst_read)?).to_vec();
        let texels = gpu.read_texture(&target, 16)?;
        let pts: Vec<[f32; 4]> =
            bytemuck::cast_slice::<u8, [f32; 4]>(&texels)[..(n * per) as usize].to_vec();
        Ok((inst, pts))
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
        let k = self.settings.supersample;
        let drawn = (width.saturating_mul(k), height.saturating_mul(k));
        // The adapter's and the renderer's frame limits, on the frame as drawn.
        if let Err(e) = gpu.check_frame(drawn.0, drawn.1, self.settings.msaa) {
            return Err(match k {
                1 => e.into(),
                _ => Error::Limit(format!(
                    "a {width} × {height} frame at supersample {k} is drawn {} × {}: {e}",
                    drawn.0, drawn.1
                )),
            });
        }
        let t = FrameTargets::new(gpu, "fiber", drawn, self.settings.msaa)?;
        let dev = &gpu.device;
        let b = self.bindings(gpu, cam, lights, drawn)?;
        let (cv, rv, dv) = t.views();
        let one = size_of::<DrawArgsRaw>() as u64;
        let readback = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fiber args read-back"),
            size: one * (1 + b.fiber_maps.len() as u64),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        gpu.scoped("fiber frame", || {
            let mut enc = dev.create_command_encoder(&Default::default());
            self.record(gpu, &mut enc, &b, (&cv, rv.as_ref(), &dv), Some(clear));
            enc.copy_buffer_to_buffer(&self.args, 0, &readback, 0, one);
            for (k, m) in b.fiber_maps.iter().enumerate() {
                enc.copy_buffer_to_buffer(&m.args, 0, &readback, one * (1 + k as u64), one);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        let all: Vec<DrawArgsRaw> = bytemuck::pod_collect_to_vec(&gpu.read_buffer(&readback)?);
        let args = all[0];
        let pixels = box_filter(&t.read(gpu)?, drawn.0 as usize, k as usize);
        let stats = FiberStats {
            segments: self.data.segment_count,
            culled: args.culled,
            instances: args.instance_count,
            hairs: args.hairs,
            shadow_instances: all[1..].iter().map(|a| a.instance_count).sum(),
            overflow: all.iter().map(|a| a.overflow).sum(),
            triangles: args.instance_count as u64 * 2 * self.settings.n_sub as u64,
            yarn_bytes: self.data.bytes,
        };
        Ok(FiberImage { width, height, pixels, stats })
    }
}

/// The most frames a pixel side of [`FiberSettings::supersample`].
pub const MAX_SUPERSAMPLE: u32 = 16;

/// `pixels` (`width` wide) box-filtered over `k × k` blocks (`width` and the height
/// multiples of `k`): the mean of each block, RGB and coverage alike.
fn box_filter(pixels: &[[f32; 4]], width: usize, k: usize) -> Vec<[f32; 4]> {
    if k == 1 {
        return pixels.to_vec();
    }
    let (w, h) = (width / k, pixels.len() / width / k);
    let mut out = vec![[0.0f32; 4]; w * h];
    let weight = 1.0 / (k * k) as f32;
    for (y, row) in pixels.chunks_exact(width).enumerate() {
        let dst = &mut out[(y / k) * w..(y / k + 1) * w];
        for (x, p) in row.iter().enumerate() {
            let o = &mut dst[x / k];
            for c in 0..4 {
                o[c] += weight * p[c];
            }
        }
    }
    out
}

/// The fiber maps' 3 × 3 taps, texels apart: a box of 0.6 texel about the point. The
/// reference's shadow rays are points, so a narrow filter that still antialiases the texel
/// grid wins: tried once each against the converged reference of
/// `tests/gpu/fiber_shadows.rs` (variants not kept), one texel apart, a single tap and
/// 2 × 2 bilinear weights all scored worse than 0.3.
const FIBER_MAP_TAPS: f32 = 0.3;

/// The view flag (`lod.z` bit 12) of a fiber shadow map's light view.
const MAP_VIEW: u32 = 1 << 12;

/// Whether `s` draws fiber shadow maps (fiber shadows of yarn shadows, fibers drawn).
fn fiber_maps(s: &FiberSettings) -> bool {
    s.effects.fiber_shadows && s.effects.yarn_shadows && !s.tubes
}

#[cfg(test)]
mod tests {
    use super::box_filter;

    #[test]
    fn the_box_filter_averages_each_block() {
        // 4 × 2 pixels, k = 2: two blocks, each the mean of its four pixels.
        let px: Vec<[f32; 4]> =
            (0..8).map(|i| [i as f32, 2.0 * i as f32, 1.0, (i % 2) as f32]).collect();
        let out = box_filter(&px, 4, 2);
        // Block 0 holds pixels 0, 1, 4, 5; block 1 holds 2, 3, 6, 7.
        assert_eq!(out, vec![[2.5, 5.0, 1.0, 0.5], [4.5, 9.0, 1.0, 0.5]]);
        assert_eq!(box_filter(&px, 4, 1), px);
    }
}
