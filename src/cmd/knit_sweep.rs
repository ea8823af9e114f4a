//! `btf knit sweep -o DIR`: what accuracy costs in time for the GPU fiber renderer (issue
//! #19, DESIGN §2.5 "What accuracy costs in time", with the per-cell metrics of §4.2's
//! headline study) and, with `--strips`, for the yarn strips of [H25] (issue #20, DESIGN
//! §3.5: bake directions, texture size, tangents, ξ and Ψ on/off, PCSS, MSAA, the plain
//! strips). One chart patch (hair flyaways off: DESIGN §2.5's R-approx; with `--hairs` on
//! in the reference and the GPU fibers, which draw the same hairs, and the strips get
//! [H25 §4.4]'s flyaway overlay, whose cost and error the `no-flyaways` strip variant
//! shows) is path traced by `yarn-ref` once per camera and shading model; then
//! `yarn-render` draws it over the grid ω^LoD ([W19 eq. 4]) × shading ([W19 eq. 5] simple,
//! [W19 eq. 6] Khungurn) × n_max, plus the plain-tube baseline, all cells interleaved frame
//! by frame in one run. Per cell: relative RMSE `√(Σ(g−r)²/Σr²)` over the interior mask
//! (reference coverage ≥ 0.99 and GPU alpha ≥ 0.99) and over the silhouette band (the other
//! pixels either covers by more than 0.01), median frame ms and its ratio to the tubes of
//! the same camera and shading, instances and triangles. Writes `sweep.csv`, `sweep.md`,
//! `sweep.png` (error against time ratio) and the references `ref-*.exr`, and prints the
//! LoD crossover (defined in [`super::knit_sweep_report::crossover`]); the tables and the
//! plot are `knit_sweep_report`. The defaults are set for speed; `--samples-per-turn 48
//! --n-sub 64 --min-strip-px 0 --supersample 16 --no-core --fiber-shadows --shadow-map
//! 8192` converge both renderers (#19's 5 % comparison, yarn-render README).

use super::knit::{ShadingChoice, chart_inputs_of, load_chart, load_yarn};
use super::knit_render::{bcsdf as fiber_bcsdf, fiber_light};
use super::knit_sweep_report::{csv, markdown, plot};
use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use btf_image::plot::render;
use btf_image::write::{write_exr_rgb, write_png, write_text};
use clap::Args;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use yarn::fiber::GenOptions;
use yarn::knit::SkeletonParams;
use yarn_ref::patch::{KnitPatch, PatchOptions};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

/// `btf knit sweep`.
#[derive(Args)]
pub struct SweepArgs {
    /// Output folder (sweep.csv, sweep.md, sweep.png, ref-*.exr).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Built-in chart name or chart file.
    #[arg(long, default_value = "stockinette")]
    pub chart: String,
    /// Yarn preset name or yarn TOML file.
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Stitches W,C of one period (multiples of the chart's size; default the chart's
    /// repeat, grown when a perspective camera would need more than 9 × 9 periods).
    #[arg(long)]
    pub stitches: Option<String>,
    /// Seed of the fibers.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The reference's fiber polyline points per helix turn (the GPU evaluates the fibers
    /// at `--n-sub` points a segment instead; 48 for a converged comparison).
    #[arg(long, default_value_t = 12)]
    pub samples_per_turn: u32,
    /// Image size W,H.
    #[arg(long, default_value = "96,96")]
    pub size: String,
    /// Viewing direction THETA,PHI (degrees, towards the viewer) of the `btf:` camera and
    /// of every perspective camera.
    #[arg(long, default_value = "30,270")]
    pub view: String,
    /// Perspective cameras, one per value: the on-screen width of a stitch at the target,
    /// in pixels (30° field of view; "" for none).
    #[arg(long, value_delimiter = ',', default_value = "24,6")]
    pub distances: Vec<String>,
    /// Directional light dir:THETA,PHI[,E] or point light point:X,Y,Z,I (repeatable, ≤ 8;
    /// default dir:35,60).
    #[arg(long = "light")]
    pub lights: Vec<String>,
    /// Environment map (equirectangular EXR/HDR, e.g. from `btf synth env`), optionally
    /// ,SCALE: the reference samples it; the GPU fibers and the strips get its SRBF fit
    /// and I_M table ([H25 eq. 14–17]; the fibers at their own tangents), each lobe with
    /// its tube shadow map.
    #[arg(long)]
    pub env: Option<String>,
    /// SRBFs of the environment fit.
    #[arg(long, default_value_t = 16)]
    pub srbfs: usize,
    /// Under --env, light the GPU fibers (and tubes) by [W19]'s constant ambient term of the
    /// map's power (eq. 7–8, with AO) instead of the SRBF lobes: the comparison.
    #[arg(long)]
    pub ambient_fibers: bool,
    /// LoD thresholds ω^LoD in pixels (0: every fiber of every segment).
    #[arg(long, value_delimiter = ',', default_value = "0,0.5,1,2,4")]
    pub lod_px: Vec<f32>,
    /// Shading models (simple, khungurn, huang).
    #[arg(long, value_delimiter = ',', default_value = "simple,khungurn")]
    pub shading: Vec<ShadingChoice>,
    /// Fibers per ply at full detail, one sweep axis (default: all of the yarn's).
    #[arg(long, value_delimiter = ',')]
    pub n_max: Vec<u32>,
    /// Subdivisions per yarn segment at full detail (1..=255).
    #[arg(long, default_value_t = 8)]
    pub n_sub: u32,
    /// MSAA samples (1 or 4).
    #[arg(long, default_value_t = 4)]
    pub msaa: u32,
    /// Fiber strips narrower than this many pixels are widened to it and keep their
    /// coverage as a hashed sample mask (0: every strip at its true width, sampled
    /// exactly, as the reference's rays hit them).
    #[arg(long, default_value_t = 1.0)]
    pub min_strip_px: f32,
    /// Frames per pixel side of the fiber and tube cells (1..=16): drawn K × K times
    /// larger and box-filtered, K²·MSAA samples a pixel (--lod-px and --min-strip-px stay
    /// in output pixels). MSAA alone aliases fiber-scale detail; the converged comparison
    /// needs ~16 (yarn-render README).
    #[arg(long, default_value_t = 1)]
    pub supersample: u32,
    /// Reference samples per pixel.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// Reference lit vertices per path (1 = direct light only).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    /// Timed frames per cell (median reported), interleaved across cells.
    #[arg(long, default_value_t = 3)]
    pub repeat: u32,
    /// Yarn-strip cells [H25] to add, one per variant: full (8 × 8 bake directions,
    /// 64 × 32 texels, 4 tangents, ξ, Ψ, PCSS 0.5°), plain (no textures: the plain shaded
    /// strips), no-xi, no-psi, k1 (one tangent per texel, as [H25]), dirs4 (4 × 4
    /// directions), tex32 (32 × 16 texels), tex128 (128 × 64), hard (PCSS off), msaa1,
    /// no-flyaways (the full strips without the flyaway overlay; needs `--hairs`), srbfN
    /// (the full strips with N SRBFs instead of `--srbfs`, e.g. srbf4, srbf32; needs
    /// `--env`). Bakes are cached in DIR/bake-cache.
    #[arg(long, value_delimiter = ',')]
    pub strips: Vec<String>,
    /// Hair flyaways (the yarn as it is; default off: DESIGN §2.5's R-approx) in the
    /// reference patch and the GPU fibers, and the flyaway overlay on the strips.
    #[arg(long)]
    pub hairs: bool,
    /// No core strips in the fiber cells: every fiber explicit, as the reference draws
    /// them (LoD then drops the innermost fibers).
    #[arg(long)]
    pub no_core: bool,
    /// Shadows of every fiber in the fiber cells (each light's map drawn from the fibers,
    /// fitted to the seen part of the yarns) instead of tubes and the self-shadow volume.
    #[arg(long)]
    pub fiber_shadows: bool,
    /// Side of the fiber and tube shadow maps in texels (16..=8192).
    #[arg(long, default_value_t = 1024)]
    pub shadow_map: u32,
    /// Camera rays per texel of the strip bakes.
    #[arg(long, default_value_t = 16)]
    pub bake_spp: u32,
    /// Remove this command's earlier outputs from the folder first.
    #[arg(long)]
    pub fresh: bool,
}

/// The strip variants `--strips` knows.
pub const STRIP_VARIANTS: [&str; 11] = [
    "full",
    "plain",
    "no-xi",
    "no-psi",
    "k1",
    "dirs4",
    "tex32",
    "tex128",
    "hard",
    "msaa1",
    "no-flyaways",
];

/// The SRBF count of strip variant `srbfN` (N in 1..=MAX_SRBFS), else `None`.
fn srbf_count(name: &str) -> Option<usize> {
    let n: usize = name.strip_prefix("srbf")?.parse().ok()?;
    (1..=yarn_render::strips::MAX_SRBFS).contains(&n).then_some(n)
}

/// The renderer and bake settings of strip variant `name` (see `--strips`).
fn strip_variant(
    name: &str,
    msaa: u32,
    spp: u32,
    seed: u64,
) -> Result<(yarn_render::StripSettings, yarn_precompute::StripBakeSettings)> {
    let mut s = yarn_render::StripSettings { msaa, ..Default::default() };
    let mut b = yarn_precompute::StripBakeSettings { spp, seed, ..Default::default() };
    match name {
        "full" => {}
        "plain" => s.textures = false,
        "no-xi" => s.xi = false,
        "no-psi" => s.psi = false,
        "k1" => b.tangents = 1,
        "dirs4" => b.directions = 4,
        "tex32" => (b.width, b.height) = (32, 16),
        "tex128" => (b.width, b.height) = (128, 64),
        "hard" => s.light_angle_deg = 0.0,
        "msaa1" => s.msaa = 1,
        "no-flyaways" => s.flyaways = false,
        other if srbf_count(other).is_some() => {}
        other => bail!(
            "--strips {other}: one of {}, srbfN (N in 1..={})",
            STRIP_VARIANTS.join(", "),
            yarn_render::strips::MAX_SRBFS
        ),
    }
    Ok((s, b))
}

/// A renderer of one cell.
enum CellRenderer {
    Fibers(FiberRenderer),
    Strips(yarn_render::StripRenderer),
}

impl CellRenderer {
    fn render(
        &self,
        gpu: &btf_render::Gpu,
        cam: &FiberCamera,
        lights: &[FiberLight],
        size: (u32, u32),
    ) -> yarn_render::Result<yarn_render::FiberImage> {
        match self {
            CellRenderer::Fibers(r) => r.render(gpu, cam, lights, size, [0.0; 4]),
            CellRenderer::Strips(r) => r.render(gpu, cam, lights, size, [0.0; 4]),
        }
    }
}

/// One camera of the sweep, for both renderers.
pub(crate) struct Cam {
    /// `btf` or `persp-Npx` (no commas: a CSV cell).
    pub(crate) name: String,
    /// On-screen stitch width of a perspective camera (px).
    pub(crate) stitch_px: Option<f64>,
    reference: yarn_ref::Camera,
    gpu: FiberCamera,
    /// Periods drawn per side by the GPU (odd).
    pub(crate) tiles: u32,
}

/// One cell of the grid and what it measured.
#[derive(Debug, Clone)]
pub struct Cell {
    /// Camera name (`btf`, the oblique BTF camera, or `persp-Npx`; no commas, for the CSV).
    pub camera: String,
    /// Shading model.
    pub shading: String,
    /// Fibers per ply at full detail (`u32::MAX`: all).
    pub n_max: u32,
    /// `None`: the plain-tube baseline or a strip cell.
    pub lod_px: Option<f32>,
    /// A yarn-strip cell: its variant (`--strips`).
    pub strips: Option<String>,
    /// Seconds the strip bake took (0 when cached or not a strip cell).
    pub bake_s: f64,
    /// Mean radiance of the frame over the reference's (luminance).
    pub mean_ratio: f64,
    /// What the frame drew.
    pub stats: yarn_render::FiberStats,
    /// Relative RMSE on the interior mask, and its pixel count.
    pub interior: (f64, usize),
    /// Relative RMSE on the silhouette band, and its pixel count.
    pub band: (f64, usize),
    /// Relative RMSE over every pixel either image covers by more than 0.01 (interior and
    /// band together: what the LoD crossover is judged on), and its pixel count.
    pub all: (f64, usize),
    /// Relative RMSE over the frame against the finest threshold's GPU image of the same
    /// camera, shading and n_max: what the LoD alone changes (0 for that image itself).
    pub vs_full: f64,
    /// Median frame ms.
    pub ms: f64,
    /// Median frame ms of the tubes of the same camera and shading.
    pub tubes_ms: f64,
    /// Median frame ms of the finest fiber cell of the same camera and shading.
    pub fibers_ms: f64,
}

fn validate(a: &SweepArgs) -> Result<()> {
    if a.msaa != 1 && a.msaa != 4 {
        bail!("--msaa {}: 1 or 4", a.msaa);
    }
    if !(16..=8192).contains(&a.shadow_map) {
        bail!("--shadow-map {}: the maps' side must be 16..=8192 texels", a.shadow_map);
    }
    if a.n_sub == 0 || a.n_sub > 255 {
        bail!("--n-sub {}: 1..=255", a.n_sub);
    }
    super::knit_render::check_sampling(a.min_strip_px, a.supersample)?;
    if a.samples_per_turn == 0 {
        bail!("--samples-per-turn 0: at least one point a helix turn");
    }
    if a.supersample != 1 && !a.strips.is_empty() {
        bail!(
            "--supersample {}: the fiber and tube cells' option; the strips (--strips) draw \
             one frame a pixel",
            a.supersample
        );
    }
    if let Some(l) = a.lod_px.iter().find(|l| !(l.is_finite() && **l >= 0.0)) {
        bail!("--lod-px {l}: thresholds must be finite and ≥ 0");
    }
    if a.lod_px.is_empty() {
        bail!("--lod-px: give at least one threshold");
    }
    if a.shading.is_empty() {
        bail!("--shading: give at least one model");
    }
    if a.shading.contains(&ShadingChoice::Lambert) {
        bail!("--shading lambert: the GPU fiber renderer takes simple, khungurn or huang");
    }
    if a.n_max.contains(&0) {
        bail!("--n-max 0: at least one fiber per ply");
    }
    if a.spp == 0 || a.bounces == 0 || a.repeat == 0 || a.bake_spp == 0 {
        bail!("--spp, --bounces, --repeat and --bake-spp must be ≥ 1");
    }
    for v in &a.strips {
        strip_variant(v, a.msaa, a.bake_spp, a.seed)?;
        if v == "no-flyaways" && !a.hairs {
            bail!("--strips no-flyaways: the strips have no flyaway overlay without --hairs");
        }
        if srbf_count(v).is_some() && a.env.is_none() {
            bail!("--strips {v}: SRBFs fit an environment; give --env");
        }
    }
    Ok(())
}

/// The perspective stitch widths of `--distances` (pixels).
fn distances(a: &SweepArgs) -> Result<Vec<f64>> {
    a.distances
        .iter()
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            let v: f64 = s.trim().parse().with_context(|| format!("--distances '{s}'"))?;
            if !(v.is_finite() && v > 0.0) {
                bail!("--distances {s}: a stitch width in pixels, > 0");
            }
            Ok(v)
        })
        .collect()
}

const FOV_DEG: f64 = 30.0;

/// Eye of the perspective camera whose stitch (wale spacing `ws`) covers `px` pixels at
/// `target`, looking along `-view`.
fn persp_eye(target: [f64; 3], view: [f64; 3], ws: f64, px: f64, height: u32) -> [f64; 3] {
    let f_px = 0.5 * height as f64 / (0.5 * FOV_DEG.to_radians()).tan();
    let d = ws * f_px / px;
    [0, 1, 2].map(|k| target[k] + d * view[k])
}

/// Half-extents (x, y) of where the frame's corner rays meet the plane `z = target.z`,
/// about the target; `None` when a corner ray misses the plane.
fn footprint(eye: [f64; 3], target: [f64; 3], (w, h): (u32, u32)) -> Option<[f64; 2]> {
    use nalgebra::Vector3;
    let e = Vector3::from(eye);
    let t = Vector3::from(target);
    let f = (t - e).normalize();
    let side = f.cross(&Vector3::z());
    let s = if side.norm() < 1e-9 { Vector3::x() } else { side.normalize() };
    let u = s.cross(&f);
    let ty = (0.5 * FOV_DEG.to_radians()).tan();
    let tx = ty * w as f64 / h as f64;
    let mut half = [0.0f64; 2];
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let d = f + s * (x * tx) + u * (y * ty);
        if d.z >= -1e-6 {
            return None;
        }
        let p = e + d * ((t.z - e.z) / d.z);
        half[0] = half[0].max((p.x - t.x).abs());
        half[1] = half[1].max((p.y - t.y).abs());
    }
    Some(half)
}

/// The smallest odd tile count covering `half + margin` about the period's centre.
fn tiles_for(half: [f64; 2], margin: f64, period: [f64; 2]) -> u32 {
    let n = (0..2).map(|k| (2.0 * (half[k] + margin) / period[k]).ceil() as u32).max().unwrap_or(1);
    (n.max(3)) | 1
}

/// The period: the chart repeat `base` grown (× m) until every perspective camera's
/// footprint fits 9 × 9 periods; returns the stitches and each camera's tile count.
fn grow_period(
    base: [usize; 2],
    params: &yarn::params::YarnParams,
    view: [f64; 3],
    dists: &[f64],
    (w, h): (u32, u32),
    view_arg: &str,
) -> Result<([usize; 2], Vec<u32>)> {
    let sk = SkeletonParams::new(params.yarn_radius());
    let (ws, cs) = sk.default_spacing();
    let margin = 4.0 * params.yarn_radius();
    for m in 1..=16 {
        let st = [base[0] * m, base[1] * m];
        let period = [st[0] as f64 * ws, st[1] as f64 * cs];
        let centre = [0.5 * period[0], 0.5 * period[1], 0.0];
        let mut tiles = Vec::new();
        for &px in dists {
            let eye = persp_eye(centre, view, ws, px, h);
            let half = footprint(eye, centre, (w, h)).ok_or_else(|| {
                anyhow::anyhow!("--view {view_arg}: the frame reaches the horizon")
            })?;
            tiles.push(tiles_for(half, margin, period));
        }
        if tiles.iter().all(|&n| n <= 9) {
            return Ok((st, tiles));
        }
    }
    bail!(
        "--distances {dists:?}: a stitch this small shows more stitches than 9 × 9 periods of 16 × the chart hold"
    )
}

/// The `btf` camera over one period and a perspective camera per stitch width in `dists`,
/// looking along `-view` at the patch centre.
fn cameras(
    patch: &KnitPatch,
    view: [f64; 3],
    ws: f64,
    dists: &[f64],
    tiles: &[u32],
    h: u32,
) -> Result<Vec<Cam>> {
    let (lo, hi) = yarn_ref::patch::centre_line_z(&patch.yarns);
    let target = [0.5 * patch.period.size[0], 0.5 * patch.period.size[1], 0.5 * (lo + hi)];
    let mut cams = vec![Cam {
        name: "btf".into(),
        stitch_px: None,
        reference: yarn_ref::Camera::oblique(view, patch.z_ref, [0.0, 0.0], patch.period.size)?,
        gpu: FiberCamera::oblique(view, patch.z_ref, [0.0, 0.0], patch.period.size),
        tiles: 3,
    }];
    for (&px, &tiles) in dists.iter().zip(tiles) {
        let eye = persp_eye(target, view, ws, px, h);
        let up = [0.0, 0.0, 1.0];
        cams.push(Cam {
            name: format!("persp-{px}px"),
            stitch_px: Some(px),
            reference: yarn_ref::Camera::perspective(eye, target, up, FOV_DEG)?,
            gpu: FiberCamera::perspective(eye, target, up, FOV_DEG),
            tiles,
        });
    }
    Ok(cams)
}

/// `--env FILE[,SCALE]`: the map scaled.
pub(crate) fn env_map(spec: &str) -> Result<btf_image::EnvMap> {
    let (path, scale) = match spec.split_once(',') {
        Some((p, s)) => {
            (p, s.parse::<f64>().with_context(|| format!("--env '{spec}': bad scale"))?)
        }
        None => (spec, 1.0),
    };
    if !(scale.is_finite() && scale > 0.0) {
        bail!("--env '{spec}': the scale must be > 0");
    }
    let mut map = btf_image::EnvMap::load(std::path::Path::new(path))
        .with_context(|| format!("--env {path}"))?;
    map.pixels.iter_mut().for_each(|p| *p = p.map(|x| (x as f64 * scale) as f32));
    Ok(map)
}

/// `--light` for both renderers (default `dir:35,60` unless an environment is given).
fn lights(specs: &[String], env: bool) -> Result<(Vec<FiberLight>, Vec<yarn_ref::Light>)> {
    let specs = if specs.is_empty() && !env { vec!["dir:35,60".into()] } else { specs.to_vec() };
    let max = yarn_render::view::MAX_LIGHTS;
    if specs.len() > max {
        bail!("--light given {} times: at most {max}", specs.len());
    }
    let gpu = specs.iter().map(|s| fiber_light(s)).collect::<Result<_>>()?;
    let reference = specs.iter().map(|s| super::knit::light(s)).collect::<Result<_>>()?;
    Ok((gpu, reference))
}

/// Runs `btf knit sweep`.
pub fn run(a: SweepArgs) -> Result<()> {
    validate(&a)?;
    let mut inputs = chart_inputs_of(&a.chart, &a.yarn);
    let env_path = a.env.as_deref().map(|e| std::path::Path::new(e.split(',').next().unwrap_or(e)));
    if let Some(p) = env_path {
        inputs.push(("env", p));
    }
    guard::refuse_overlap(&[("-o", &a.output)], &inputs)?;
    let [w, h] = crate::args::numbers::<u32, 2>(&a.size, "--size")?;
    if w == 0 || h == 0 || w > 4096 || h > 4096 {
        bail!("--size {w},{h}: each side must be 1..=4096");
    }
    let [vt, vp] = crate::args::numbers::<f64, 2>(&a.view, "--view")?;
    if !(0.0..80.0).contains(&vt) || !vp.is_finite() {
        bail!("--view {}: THETA in [0, 80) degrees, PHI finite", a.view);
    }
    let dists = distances(&a)?;
    if vt < 1.0 && !dists.is_empty() {
        bail!("--view {}: THETA ≥ 1° with perspective cameras (their up vector is z)", a.view);
    }
    let view = btf_core::Direction::new(vt, vp).to_vector();
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let env = a.env.as_deref().map(env_map).transpose()?;
    let (gpu_lights, mut ref_lights) = lights(&a.lights, env.is_some())?;
    if let Some(map) = &env {
        ref_lights.push(yarn_ref::Light::Environment(yarn_ref::EnvLight::new(map.clone(), 1.0)));
    }
    if !(1..=yarn_render::strips::MAX_SRBFS).contains(&a.srbfs) {
        bail!("--srbfs {}: 1..={}", a.srbfs, yarn_render::strips::MAX_SRBFS);
    }
    if a.ambient_fibers && env.is_none() {
        bail!(
            "--ambient-fibers: the constant ambient term stands in for an environment; give --env"
        );
    }
    let srbf = env.as_ref().map(|m| yarn_precompute::SrbfFit::fit(m, a.srbfs)).transpose()?;
    if let Some(f) = &srbf {
        eprintln!(
            "environment: {} SRBFs, λ {:.2}, fit error {:.3}, power ratio {:.3}",
            f.centres.len(),
            f.lambda,
            f.rel_error,
            f.power_ratio[1]
        );
    }
    // The fibers' constant ambient term: the uniform radiance of the same power.
    let ambient = env
        .as_ref()
        .map_or([0.0; 3], |m| m.integral().map(|x| (x / (4.0 * std::f64::consts::PI)) as f32));
    // The fits of the srbfN strip variants.
    let mut per_count = Vec::new();
    if let Some(map) = &env {
        for v in &a.strips {
            if let Some(n) = srbf_count(v)
                && !per_count.iter().any(|(k, _)| *k == n)
            {
                let f = yarn_precompute::SrbfFit::fit(map, n)?;
                eprintln!(
                    "strips {v}: {n} SRBFs, λ {:.2}, fit error {:.3}, power ratio {:.3}",
                    f.lambda, f.rel_error, f.power_ratio[1]
                );
                per_count.push((n, f));
            }
        }
    }
    let light_env = LightEnv { ambient, srbf, per_count, ambient_fibers: a.ambient_fibers };
    let bcsdfs: Vec<(String, yarn::bcsdf::FiberBcsdf)> = a
        .shading
        .iter()
        .map(|s| Ok((s.as_str().to_string(), fiber_bcsdf(s.as_str())?)))
        .collect::<Result<_>>()?;
    // The device first: without one there is nothing to sweep.
    let gpu = btf_render::Gpu::new().context("creating a headless GPU device")?;
    guard::output_folder(&a.output, "knit sweep", a.fresh, &guard::report_output)?;

    let base = super::knit::stitches(&a.stitches)?.unwrap_or([chart.width, chart.height]);
    let (stitches, patch_tiles) = grow_period(base, &params, view, &dists, (w, h), &a.view)?;
    let popts = PatchOptions {
        stitches: Some(stitches),
        generation: GenOptions {
            seed: a.seed,
            hairs: a.hairs,
            samples_per_turn: a.samples_per_turn,
            ..GenOptions::default()
        },
        ..PatchOptions::default()
    };
    let t0 = Instant::now();
    let patch = KnitPatch::new(&chart, &params, &popts)?;
    let scene = yarn_ref::FiberScene::new(
        &patch.fibers,
        &yarn_ref::SceneOptions { period: Some(patch.period), backing_z: Some(patch.backing_z()) },
    )?;
    eprintln!(
        "knit sweep: {} × {} stitches, {} fibers ({}), scene built in {:.1} s",
        stitches[0],
        stitches[1],
        patch.fibers.fiber_count(),
        if a.hairs { "with hairs" } else { "no hairs" },
        t0.elapsed().as_secs_f64()
    );
    let ws = SkeletonParams::new(params.yarn_radius()).default_spacing().0;
    let cams = cameras(&patch, view, ws, &dists, &patch_tiles, h)?;

    // References: once per camera and shading model; then the GPU grid.
    let refs = references(&a, &cams, &bcsdfs, &scene, &ref_lights, (w, h))?;
    let cells = gpu_grid(
        &a,
        &gpu,
        &patch,
        &params,
        &cams,
        &bcsdfs,
        &gpu_lights,
        &light_env,
        &refs,
        (w, h),
    )?;

    write_text(&a.output.join("sweep.csv"), &csv(&cells, &cams))?;
    let md = markdown(&a, &cells, &cams, stitches, (w, h));
    write_text(&a.output.join("sweep.md"), &md)?;
    write_png(&a.output.join("sweep.png"), &render(&plot(&cells)))?;
    outln!("{md}");
    outln!("written to {}", a.output.join("sweep.md").display());
    Ok(())
}

/// The reference image of every (camera, shading), written as `ref-*.exr`.
fn references(
    a: &SweepArgs,
    cams: &[Cam],
    bcsdfs: &[(String, yarn::bcsdf::FiberBcsdf)],
    scene: &yarn_ref::FiberScene,
    lights: &[yarn_ref::Light],
    (w, h): (u32, u32),
) -> Result<Vec<Vec<yarn_ref::Image>>> {
    let (wu, hu) = (w as usize, h as usize);
    let bar = crate::progress::bar((cams.len() * bcsdfs.len() * hu) as u64, "references");
    let mut out = Vec::new();
    for cam in cams {
        let mut per = Vec::new();
        for (name, b) in bcsdfs {
            let shading = yarn_ref::Shading::Fiber { bcsdf: Arc::new(b.clone()), tint: true };
            let sc = yarn_ref::Scene { fibers: scene, lights, shading: &shading };
            let mut s = yarn_ref::RenderSettings::new(wu, hu, a.spp);
            s.path.max_bounces = a.bounces;
            let (img, _) = yarn_ref::render_with(&sc, &cam.reference, &s, &|| bar.inc(1))?;
            let file = format!("ref-{}-{name}.exr", file_safe(&cam.name));
            write_exr_rgb(&a.output.join(file), wu, hu, &img.rgb)?;
            per.push(img);
        }
        out.push(per);
    }
    bar.finish_and_clear();
    Ok(out)
}

fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' })
        .collect()
}

/// Relative RMSE and pixel count of `g` against `r` on the interior mask, the silhouette
/// band and both together.
pub fn errors(g: &[[f32; 4]], r: &yarn_ref::Image) -> [(f64, usize); 3] {
    let mut acc = [(0.0f64, 0.0f64, 0usize); 3];
    for (i, p) in g.iter().enumerate() {
        let (cov, alpha) = (r.coverage[i], p[3]);
        let k = if cov >= 0.99 && alpha >= 0.99 {
            0
        } else if cov > 0.01 || alpha > 0.01 {
            1
        } else {
            continue;
        };
        for kk in [k, 2] {
            for c in 0..3 {
                let (x, y) = (p[c] as f64, r.rgb[3 * i + c] as f64);
                acc[kk].0 += (x - y).powi(2);
                acc[kk].1 += y * y;
            }
            acc[kk].2 += 1;
        }
    }
    let rel = |(n, d, c): (f64, f64, usize)| (if d > 0.0 { (n / d).sqrt() } else { f64::NAN }, c);
    acc.map(rel)
}

/// Σ luminance of `g` over Σ luminance of the reference.
fn mean_ratio(g: &[[f32; 4]], r: &yarn_ref::Image) -> f64 {
    let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let a: f64 = g.iter().map(|p| lum([p[0], p[1], p[2]].map(f64::from))).sum();
    let b: f64 = r.rgb.chunks_exact(3).map(|p| lum([p[0], p[1], p[2]].map(f64::from))).sum();
    if b > 0.0 { a / b } else { f64::NAN }
}

/// `√(Σ(g−f)²/Σf²)` over the RGB of every pixel.
fn rel_rmse(g: &[[f32; 4]], f: &[[f32; 4]]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, q) in g.iter().zip(f) {
        for c in 0..3 {
            num += (p[c] as f64 - q[c] as f64).powi(2);
            den += (q[c] as f64).powi(2);
        }
    }
    if den > 0.0 { (num / den).sqrt() } else { f64::NAN }
}

/// The environment as each GPU method takes it.
struct LightEnv {
    /// The fibers' constant ambient radiance.
    ambient: [f32; 3],
    /// The SRBF fit (strips, and fibers unless `ambient_fibers`).
    srbf: Option<yarn_precompute::SrbfFit>,
    /// Fibers by the constant ambient term, not the SRBFs.
    ambient_fibers: bool,
    /// The fits of the `srbfN` strip variants: `(N, fit)`.
    per_count: Vec<(usize, yarn_precompute::SrbfFit)>,
}

/// Builds every cell's renderer, renders each once (stats, error), then times
/// `a.repeat` frames per cell, interleaved.
#[allow(clippy::too_many_arguments)]
fn gpu_grid(
    a: &SweepArgs,
    gpu: &btf_render::Gpu,
    patch: &KnitPatch,
    params: &yarn::params::YarnParams,
    cams: &[Cam],
    bcsdfs: &[(String, yarn::bcsdf::FiberBcsdf)],
    lights: &[FiberLight],
    env: &LightEnv,
    refs: &[Vec<yarn_ref::Image>],
    size: (u32, u32),
) -> Result<Vec<Cell>> {
    let n_maxes = if a.n_max.is_empty() { vec![u32::MAX] } else { a.n_max.clone() };
    // Fibers from the finest threshold up (the first is the full-detail image every other
    // threshold is also compared with), then the tubes.
    let mut fine: Vec<f32> = a.lod_px.clone();
    fine.sort_by(f32::total_cmp);
    fine.dedup();
    let mut lods: Vec<Option<f32>> = fine.iter().map(|&l| Some(l)).collect();
    lods.push(None);
    let total = cams.len() * bcsdfs.len() * (1 + n_maxes.len() * fine.len() + a.strips.len());
    let bar = crate::progress::bar((total * (1 + a.repeat as usize)) as u64, "GPU cells");
    let mut cells = Vec::new();
    let mut renderers = Vec::new();
    // The strips' flyaway textures ([H25 §4.4]) when the reference has hairs.
    let flyaways = if a.hairs && !a.strips.is_empty() {
        Some(yarn_render::strips::flyaways_for(std::slice::from_ref(params), a.seed)?)
    } else {
        None
    };
    for (ci, cam) in cams.iter().enumerate() {
        let packed = PackedYarns::new(
            &patch.yarns,
            std::slice::from_ref(params),
            &PackOptions {
                seed: a.seed,
                frame_samples_per_segment: GenOptions::default().frame_samples_per_segment,
                tiles: [cam.tiles; 2],
            },
        )?;
        for (si, (sname, b)) in bcsdfs.iter().enumerate() {
            // The fibers' SRBF environment: the I_M table of this BCSDF, once.
            let fiber_env = match &env.srbf {
                Some(fit) if !env.ambient_fibers => {
                    Some((fit, yarn_precompute::ImTable::build(b, fit.lambda)?))
                }
                _ => None,
            };
            for &n_max in &n_maxes {
                let mut full: Option<Vec<[f32; 4]>> = None;
                for &lod in &lods {
                    if lod.is_none() && n_max != n_maxes[0] {
                        continue; // one tube baseline per camera and shading
                    }
                    let settings = FiberSettings {
                        n_max,
                        n_sub: a.n_sub,
                        lod_px: lod.unwrap_or(0.0),
                        msaa: a.msaa,
                        min_strip_px: a.min_strip_px,
                        supersample: a.supersample,
                        tubes: lod.is_none(),
                        hairs: a.hairs,
                        shadow_map: a.shadow_map,
                        effects: yarn_render::FiberEffects {
                            core: !a.no_core,
                            fiber_shadows: a.fiber_shadows,
                            ..Default::default()
                        },
                        ..FiberSettings::default()
                    };
                    let mut r = FiberRenderer::new(gpu, &packed, b, settings)?;
                    r.set_ambient(env.ambient);
                    if let Some((fit, table)) = &fiber_env {
                        r.set_environment(gpu, Some((fit, table)))?;
                    }
                    let img = r.render(gpu, &cam.gpu, lights, size, [0.0; 4])?;
                    let [interior, band, all] = errors(&img.pixels, &refs[ci][si]);
                    let full = full.get_or_insert_with(|| img.pixels.clone());
                    let vs_full = rel_rmse(&img.pixels, full);
                    let lod_name = lod.map_or("tubes".into(), |l| format!("lod{l}"));
                    let n_name = if n_maxes.len() > 1 && lod.is_some() {
                        format!("-n{n_max}")
                    } else {
                        String::new()
                    };
                    let file =
                        format!("gpu-{}-{sname}-{lod_name}{n_name}.exr", file_safe(&cam.name));
                    let rgb: Vec<f32> =
                        img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
                    write_exr_rgb(&a.output.join(file), size.0 as usize, size.1 as usize, &rgb)?;
                    if img.stats.overflow > 0 {
                        eprintln!(
                            "warning: {} {sname} lod {lod:?}: {} instances overflowed",
                            cam.name, img.stats.overflow
                        );
                    }
                    bar.inc(1);
                    cells.push(Cell {
                        camera: cam.name.clone(),
                        shading: sname.clone(),
                        n_max,
                        lod_px: lod,
                        strips: None,
                        bake_s: 0.0,
                        mean_ratio: mean_ratio(&img.pixels, &refs[ci][si]),
                        stats: img.stats,
                        interior,
                        band,
                        all,
                        vs_full,
                        ms: f64::NAN,
                        tubes_ms: f64::NAN,
                        fibers_ms: f64::NAN,
                    });
                    renderers.push((CellRenderer::Fibers(r), ci));
                }
            }
            for v in &a.strips {
                let (ss, bs) = strip_variant(v, a.msaa, a.bake_spp, a.seed)?;
                let t = Instant::now();
                let bakes = yarn_render::strips::bakes_for(
                    &patch.yarns,
                    std::slice::from_ref(params),
                    b,
                    &bs,
                    Some(&a.output.join("bake-cache")),
                    &|_| {},
                )?;
                let bake_s = if bakes.iter().all(|k| k.from_cache) {
                    bakes.iter().map(|k| k.seconds).sum()
                } else {
                    t.elapsed().as_secs_f64()
                };
                eprintln!(
                    "strips {v}: bake {bake_s:.1} s, mean residual {:.3}",
                    bakes.iter().map(|k| k.mean_residual()).sum::<f64>() / bakes.len() as f64
                );
                let mut r = yarn_render::StripRenderer::new(gpu, &packed, &bakes, b, ss)?;
                if let Some(f) = &flyaways {
                    r.set_flyaways(gpu, f)?;
                }
                let fit = match srbf_count(v) {
                    Some(n) => env.per_count.iter().find(|(k, _)| *k == n).map(|(_, f)| f),
                    None => env.srbf.as_ref(),
                };
                if let Some(fit) = fit {
                    let table = yarn_precompute::ImTable::build(b, fit.lambda)?;
                    r.set_environment(gpu, Some((fit, &table)))?;
                }
                let img = r.render(gpu, &cam.gpu, lights, size, [0.0; 4])?;
                let [interior, band, all] = errors(&img.pixels, &refs[ci][si]);
                let file = format!("gpu-{}-{sname}-strips-{v}.exr", file_safe(&cam.name));
                let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
                write_exr_rgb(&a.output.join(file), size.0 as usize, size.1 as usize, &rgb)?;
                bar.inc(1);
                cells.push(Cell {
                    camera: cam.name.clone(),
                    shading: sname.clone(),
                    n_max: n_maxes[0],
                    lod_px: None,
                    strips: Some(v.clone()),
                    bake_s,
                    mean_ratio: mean_ratio(&img.pixels, &refs[ci][si]),
                    stats: img.stats,
                    interior,
                    band,
                    all,
                    vs_full: f64::NAN,
                    ms: f64::NAN,
                    tubes_ms: f64::NAN,
                    fibers_ms: f64::NAN,
                });
                renderers.push((CellRenderer::Strips(r), ci));
            }
        }
    }
    let mut times = vec![Vec::new(); cells.len()];
    for _ in 0..a.repeat {
        for (k, (r, ci)) in renderers.iter().enumerate() {
            let t = Instant::now();
            let img = r.render(gpu, &cams[*ci].gpu, lights, size)?;
            times[k].push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(img.pixels.len());
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    for (c, t) in cells.iter_mut().zip(times) {
        c.ms = median(t);
    }
    let tube_ms: Vec<(String, String, f64)> = cells
        .iter()
        .filter(|c| c.lod_px.is_none() && c.strips.is_none())
        .map(|c| (c.camera.clone(), c.shading.clone(), c.ms))
        .collect();
    // The finest fiber cell (the first of each camera and shading: thresholds ascend).
    let mut fiber_ms: Vec<(String, String, f64)> = Vec::new();
    for c in cells.iter().filter(|c| c.lod_px.is_some()) {
        if !fiber_ms.iter().any(|(cam, s, _)| *cam == c.camera && *s == c.shading) {
            fiber_ms.push((c.camera.clone(), c.shading.clone(), c.ms));
        }
    }
    let find = |v: &[(String, String, f64)], c: &Cell| {
        v.iter().find(|(cam, s, _)| *cam == c.camera && *s == c.shading).map_or(f64::NAN, |t| t.2)
    };
    for c in &mut cells {
        c.tubes_ms = find(&tube_ms, c);
        c.fibers_ms = find(&fiber_ms, c);
    }
    Ok(cells)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_footprint_with_an_odd_count() {
        assert_eq!(tiles_for([0.5, 0.5], 0.0, [1.0, 1.0]), 3);
        assert_eq!(tiles_for([2.1, 0.5], 0.0, [1.0, 1.0]), 5);
        let eye = persp_eye([0.0; 3], [0.0, 0.0, 1.0], 1.0, 10.0, 100);
        // Looking straight down: the frame's half-height at the plane is 5 stitches.
        let half = footprint(eye, [0.0; 3], (100, 100)).unwrap();
        assert!((half[1] - 5.0).abs() < 1e-9 && (half[0] - 5.0).abs() < 1e-9, "{half:?}");
    }
}
