//! `btf thin demo`: the thin-cloth paper's flag scene on embedded defaults — the datasets
//! curtain in a synthetic woven material, in front of a synthetic sky that lights it
//! (environment light, Sattler et al. 2003 §5) and shows through it (alpha `e^{−τ₁/μ}`,
//! [TC eq. 9]), with a point light circling it so that the frames go from
//! front-lit (reflection, [TC eq. 7]) to back-lit (transmission, [TC eq. 8]) and back.
//!
//! Per frame the same scene is rendered with the curtain opaque and with `transmission`,
//! back to back (frame time ratio), and the thin one again without the background, which
//! separates what lies behind from the sheet's own light. Once per run, renders with the
//! point light off at `τ₁` and `2τ₁` measure the alpha per curtain pixel: the model says
//! `α(2τ₁) = α(τ₁)²` and `α ≤ e^{−τ₁}`. Inputs, frames (PNG) and per-frame numbers (JSON)
//! are kept, so an interrupted run resumes at the first missing frame.

use crate::progress::compress_with_progress;
use crate::report::thin::{AlphaReport, FrameReport};
use anyhow::{Context, Result, bail};
use btf_core::compress::CompressParams;
use btf_core::eigen::{EigenStore, Quantization};
use btf_core::store::BtfStore;
use btf_render::scene::Light;
use btf_render::{Frame, Gpu, RenderOptions, Renderer, Scene};
use std::path::{Path, PathBuf};

/// Arguments of `btf thin demo`.
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(short = 'o', long, alias = "output", default_value = "thin-demo")]
    out: PathBuf,
    /// Light positions on the orbit (frames).
    #[arg(long, default_value_t = 12)]
    frames: usize,
    /// Frame width and height in pixels.
    #[arg(long, default_value_t = 256)]
    size: u32,
    /// Texels per side of the synthetic material.
    #[arg(long, default_value_t = 32)]
    texels: usize,
    /// Components per view slot.
    #[arg(short = 'c', long, default_value_t = 8)]
    components: usize,
    /// Curtain material: `woven` (datasets mesostructure BTF, synthesised and compressed;
    /// the uncompressed store is removed afterwards) or `weave-lambert` (a Lambertian
    /// basket weave written straight into an eigen store, in milliseconds).
    #[arg(long, default_value = "woven", value_parser = ["woven", "weave-lambert"])]
    material: String,
    /// Optical thickness τ₁ of the curtain.
    #[arg(long, default_value_t = 0.6)]
    tau: f64,
    /// Start from scratch instead of reusing finished inputs and frames.
    #[arg(long)]
    fresh: bool,
}

/// Single-scattering albedo ϖ₀ of the curtain.
const ALBEDO: f64 = 0.9;
/// Point-light intensity (W/sr per channel) and orbit: radius, height, centre `y`.
const INTENSITY: f32 = 1.5;
const ORBIT: (f32, f32, f32) = (0.9, 1.0, 0.1);
/// PNG exposure of the frames.
const PNG_EXPOSURE: f32 = 2.0;

fn uptime() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// Runs `btf thin demo`.
pub fn run(a: DemoArgs) -> Result<()> {
    if !(2..=360).contains(&a.frames) {
        bail!("--frames must be in 2..=360, got {}", a.frames);
    }
    if !(16..=2048).contains(&a.size) {
        bail!("--size must be in 16..=2048, got {}", a.size);
    }
    if a.material != "woven" && a.material != "weave-lambert" {
        bail!("--material must be woven or weave-lambert, got '{}'", a.material);
    }
    if !(4..=512).contains(&a.texels) {
        bail!("--texels must be in 4..=512, got {}", a.texels);
    }
    if !(a.tau.is_finite() && a.tau > 0.0 && a.tau <= 10.0) {
        bail!("--tau must be in (0, 10], got {}", a.tau);
    }
    crate::guard::output_folder(&a.out, "thin demo", a.fresh, &crate::guard::report_output)?;
    std::fs::create_dir_all(a.out.join("frames"))
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let env_exposure = make_inputs(&a)?;
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => return Err(e).context("btf thin demo renders on the GPU (lavapipe will do)"),
    };
    let scene = |name: &str, t: Option<f64>| -> Result<Scene> {
        let path = a.out.join(name);
        btf_image::write::write_text(&path, &scene_toml(a.size, t, env_exposure))?;
        Scene::load(&path).with_context(|| format!("loading {}", path.display()))
    };
    let opts = RenderOptions::default;
    let mut opaque = Renderer::new(&gpu, &scene("scene-opaque.toml", None)?, opts())?;
    let mut thin = Renderer::new(&gpu, &scene("scene-thin.toml", Some(a.tau))?, opts())?;
    let mut thin2 =
        Renderer::new(&gpu, &scene(".scene-thin-2tau.toml", Some(2.0 * a.tau))?, opts())?;
    // Once: the point light off, with and without the background.
    for r in [&mut opaque, &mut thin, &mut thin2] {
        set_light(&gpu, r, [0.0, ORBIT.2 - ORBIT.0, ORBIT.1], 0.0)?;
    }
    let (alpha, mask) = alpha_map(&gpu, &mut thin)?;
    let (alpha2, _) = alpha_map(&gpu, &mut thin2)?;
    let alpha_report = check_alpha(&alpha, &alpha2, &mask, a.tau);
    thin.set_show_environment(false)?;
    let dark_thin = thin.render(&gpu)?;
    thin.set_show_environment(true)?;
    let dark_opaque = opaque.render(&gpu)?;
    anyhow::ensure!(mask.iter().any(|&m| m), "the curtain covers no pixel");

    let pb = crate::progress::bar(a.frames as u64, "orbit");
    let mut frames = Vec::new();
    for k in 0..a.frames {
        let json = a.out.join(format!("frames/frame-{k:03}.json"));
        let png = a.out.join(format!("frames/frame-{k:03}.png"));
        if let Some(r) = reuse(&json, &png) {
            frames.push(r);
            pb.inc(1);
            continue;
        }
        let ctx = OrbitCtx { mask: &mask, dark_thin: &dark_thin, dark_opaque: &dark_opaque };
        let (report, frame) = orbit_frame(&gpu, &mut opaque, &mut thin, k, a.frames, &ctx)?;
        let (w, h) = (frame.width as usize, frame.height as usize);
        btf_image::write::write_png_linear(&png, w, h, &frame.rgb, PNG_EXPOSURE)?;
        btf_image::write::write_text(&json, &serde_json::to_string_pretty(&report)?)?;
        frames.push(report);
        pb.inc(1);
    }
    pb.finish_and_clear();
    contact_sheet(&a.out, a.frames)?;
    crate::report::thin::write(&a.out, &frames, &alpha_report, a.tau, ALBEDO, &uptime())
}

/// Mesh, sky and material (each kept and reused); returns the environment exposure.
fn make_inputs(a: &DemoArgs) -> Result<f64> {
    let mesh_path = a.out.join("curtain.obj");
    if !mesh_path.exists() {
        let mesh = datasets::synth_mesh(datasets::MeshKind::Curtain, datasets::Resolution::Low)?;
        datasets::write_obj(&mesh, &mesh_path, "btf thin demo: curtain, low resolution")?;
    }
    let sky_path = a.out.join("sky.exr");
    if !sky_path.exists() {
        let sky = datasets::synth_env(datasets::EnvKind::Sky, &Default::default(), 256)?;
        sky.write_exr(&sky_path)?;
    }
    let (btf_path, eig_path) = (a.out.join("voile.btf"), a.out.join("voile.eig"));
    let done = EigenStore::open(&eig_path).is_ok();
    if !done && a.material == "weave-lambert" {
        datasets::material::weave_lambert::write_weave_lambert(&eig_path, a.texels, a.components)?;
    } else if !done {
        eprintln!("[thin demo] synthesising and compressing the woven material …");
        let spec = datasets::MaterialSpec::new(datasets::MaterialKind::Woven, a.texels);
        let opts = datasets::GenerateOptions {
            resume: true,
            progress: crate::progress::enabled(),
            ..Default::default()
        };
        datasets::generate(&spec, &btf_path, &opts)?;
        let params = CompressParams {
            components: a.components,
            quantization: Quantization::F16,
            resume: true,
            ..Default::default()
        };
        compress_with_progress(&BtfStore::open(&btf_path)?, &eig_path, params)?;
        // 81 × 81 chunk files, only needed to compress.
        std::fs::remove_dir_all(&btf_path)
            .with_context(|| format!("cannot remove {}", btf_path.display()))?;
    }
    // The sky's horizontal irradiance → 0.5, so the point light stands out.
    Ok(0.5 * btf_image::EnvMap::load(&sky_path)?.unit_irradiance_exposure())
}

/// The scene file: the curtain opaque (`tau = None`) or thin, the sky behind and around.
pub fn scene_toml(size: u32, tau: Option<f64>, env_exposure: f64) -> String {
    let t = tau.map_or(String::new(), |t| {
        format!("transmission = {{ tau = {t}, albedo = {ALBEDO}, phase = \"isotropic\" }}\n")
    });
    let (r, z, y0) = ORBIT;
    format!(
        r#"# Written by `btf thin demo`: the curtain in front of the sky it is lit by.
[output]
width = {size}
height = {size}
exposure = {PNG_EXPOSURE}
show_environment = true

[[meshes]]
path = "curtain.obj"

[[materials]]
store = "voile.eig"
uv_scale = 6.0
{t}
[camera]
eye = [0.0, -2.6, 0.75]
target = [0.0, 0.0, 0.75]
up = [0.0, 0.0, 1.0]
fov_y_deg = 40.0

[[lights]]
kind = "point"
position = [0.0, {:.3}, {z}]
intensity = [{INTENSITY}, {INTENSITY}, {INTENSITY}]
shadows = false

[[lights]]
kind = "environment"
path = "sky.exr"
exposure = {env_exposure:.6e}
visibility_res = 8
cache_dir = "cache"

[effects]
evaluation = "per-pixel"
shadows = "none"
msaa = 1
"#,
        y0 - r
    )
}

fn set_light(gpu: &Gpu, r: &mut Renderer, pos: [f32; 3], intensity: f32) -> Result<()> {
    let mut lights = r.scene().lights.clone();
    for l in &mut lights {
        if let Light::Point { position, intensity: i, .. } = l {
            *position = pos;
            *i = [intensity; 3];
        }
    }
    Ok(r.set_lights(gpu, &lights)?)
}

/// Alpha per value `(R_bg − R_dark) / B` and the curtain mask (`α < 0.99` where `B > 0`).
fn alpha_map(gpu: &Gpu, r: &mut Renderer) -> Result<(Vec<f64>, Vec<bool>)> {
    let with = r.render(gpu)?;
    r.set_show_environment(false)?;
    let dark = r.render(gpu)?;
    r.set_show_environment(true)?;
    let bg = r.environment_background(gpu)?.context("the demo scene shows its environment")?;
    let alpha: Vec<f64> = (0..bg.len())
        .map(|i| if bg[i] > 1e-4 { (with.rgb[i] - dark.rgb[i]) as f64 / bg[i] as f64 } else { 1.0 })
        .collect();
    let mask = alpha.iter().map(|&a| a < 0.99).collect();
    Ok((alpha, mask))
}

fn check_alpha(alpha: &[f64], alpha2: &[f64], mask: &[bool], tau: f64) -> AlphaReport {
    let idx: Vec<usize> = (0..alpha.len()).filter(|&i| mask[i]).collect();
    let n = idx.len().max(1) as f64;
    AlphaReport {
        values: idx.len(),
        mean_alpha: idx.iter().map(|&i| alpha[i]).sum::<f64>() / n,
        max_alpha: idx.iter().map(|&i| alpha[i]).fold(0.0, f64::max),
        bound: (-tau).exp(),
        max_square_error: idx
            .iter()
            .map(|&i| (alpha2[i] - alpha[i] * alpha[i]).abs())
            .fold(0.0, f64::max),
    }
}

struct OrbitCtx<'a> {
    mask: &'a [bool],
    dark_thin: &'a Frame,
    dark_opaque: &'a Frame,
}

fn mean_over(mask: &[bool], v: impl Fn(usize) -> f64) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        s += v(i);
        n += 1;
    }
    s / n.max(1) as f64
}

/// Renders frame `k` of `n`: opaque and thin interleaved twice (best time of each), then
/// the thin curtain without its background.
fn orbit_frame(
    gpu: &Gpu,
    opaque: &mut Renderer,
    thin: &mut Renderer,
    k: usize,
    n: usize,
    ctx: &OrbitCtx,
) -> Result<(FrameReport, Frame)> {
    let a = std::f32::consts::TAU * k as f32 / n as f32;
    let (r, z, y0) = ORBIT;
    let pos = [r * a.sin(), y0 - r * a.cos(), z];
    set_light(gpu, opaque, pos, INTENSITY)?;
    set_light(gpu, thin, pos, INTENSITY)?;
    let (mut t_o, mut t_t) = (f64::MAX, f64::MAX);
    let (mut f_o, mut f_t) = (None, None);
    for _ in 0..2 {
        let fo = opaque.render(gpu)?;
        let ft = thin.render(gpu)?;
        anyhow::ensure!(fo.all_finite() && ft.all_finite(), "frame {k} has non-finite pixels");
        t_o = t_o.min(fo.stats.frame_ms);
        t_t = t_t.min(ft.stats.frame_ms);
        (f_o, f_t) = (Some(fo), Some(ft));
    }
    let (f_o, f_t) = (f_o.expect("rendered"), f_t.expect("rendered"));
    thin.set_show_environment(false)?;
    let sheet = thin.render(gpu)?;
    thin.set_show_environment(true)?;
    let m = ctx.mask;
    let report = FrameReport {
        index: k,
        light_deg: (a as f64).to_degrees(),
        light_position: pos,
        side: match pos[1] {
            y if y < -0.25 => "front",
            y if y > 0.25 => "back",
            _ => "edge",
        }
        .into(),
        opaque_ms: t_o,
        thin_ms: t_t,
        curtain_mean: mean_over(m, |i| sheet.rgb[i] as f64),
        curtain_point_thin: mean_over(m, |i| (sheet.rgb[i] - ctx.dark_thin.rgb[i]) as f64),
        curtain_point_opaque: mean_over(m, |i| (f_o.rgb[i] - ctx.dark_opaque.rgb[i]) as f64),
    };
    Ok((report, f_t))
}

fn reuse(json: &Path, png: &Path) -> Option<FrameReport> {
    if !png.exists() {
        return None;
    }
    serde_json::from_str(&std::fs::read_to_string(json).ok()?).ok()
}

/// All frames in a grid of ⌈√n⌉ columns, scaled to at most 160 px each.
fn contact_sheet(out: &Path, n: usize) -> Result<()> {
    let cols = (n as f64).sqrt().ceil() as u32;
    let rows = (n as u32).div_ceil(cols);
    let mut tiles = Vec::new();
    for k in 0..n {
        let p = out.join(format!("frames/frame-{k:03}.png"));
        let img = image::open(&p).with_context(|| format!("reading {}", p.display()))?.to_rgb8();
        let s = img.width().min(160);
        tiles.push(image::imageops::resize(&img, s, s, image::imageops::FilterType::Triangle));
    }
    let s = tiles[0].width();
    let gap = 4;
    let mut sheet = image::RgbImage::from_pixel(
        cols * (s + gap) - gap,
        rows * (s + gap) - gap,
        image::Rgb([255, 255, 255]),
    );
    for (k, t) in tiles.iter().enumerate() {
        let (c, r) = (k as u32 % cols, k as u32 / cols);
        image::imageops::replace(&mut sheet, t, (c * (s + gap)) as i64, (r * (s + gap)) as i64);
    }
    Ok(btf_image::write::write_png(&out.join("contact.png"), &sheet)?)
}
