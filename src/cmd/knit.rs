//! `btf knit …` (and the helpers `btf synth material --kind yarn` uses): command-line front end of the `yarn`
//! and `yarn-ref` crates — charts, stitch meshes, yarn skeletons, explicit fibers,
//! reference renders and the yarn BTF. Arguments are parsed and validated here; the work
//! happens in the libraries.

use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use yarn::bcsdf::{FiberBcsdf, HuangParams, KhungurnParams, SimpleParams};
use yarn::fiber::{Fibers, GenOptions, generate_fibers};
use yarn::knit::{Chart, SkeletonParams, StitchMesh, chen_skeleton};
use yarn::params::YarnParams;
use yarn_ref::patch::{KnitPatch, PatchOptions};

/// `btf knit` subcommands.
#[derive(Subcommand)]
pub enum KnitCmd {
    /// Print, validate or write a stitch chart (a built-in name or a chart file).
    Chart(ChartArgs),
    /// Write the flat periodic stitch mesh of a chart as OBJ quads.
    Mesh(PatchArgs),
    /// Write the yarn centre lines (Chen skeleton) as BCC, Mitsuba curve text or OBJ lines.
    Skeleton(PatchArgs),
    /// Write the explicit fibers of a patch as BCC, Mitsuba curve text or OBJ lines.
    Fibers(PatchArgs),
    /// Reference render (path traced explicit fibers) of a patch or of BCC yarn curves.
    Ref(Box<RefArgs>),
    /// Real-time GPU render (fibers generated on the GPU, [W19]) of a patch or BCC curves.
    Render(Box<super::knit_render::RenderArgs>),
    /// What accuracy costs in time: GPU fibers over LoD × shading and yarn strips over
    /// their settings, against the reference.
    Sweep(Box<super::knit_sweep::SweepArgs>),
    /// The headline study: a knit garment as reference fibers, GPU fibers, the yarn BTF
    /// and the baselines, scored against the reference at three camera distances.
    Compare(Box<super::knit_compare::CompareArgs>),
    /// Knot-based yarn deformation [H25] of a patch under stretch and shear, scored
    /// against the converged reference, with the clearance between yarns.
    Deform(Box<super::knit_deform::DeformArgs>),
    /// The texture bake of [H25]'s yarn strips over bake settings: time, residual of the
    /// factorised model against the reference, pictures.
    Strips(Box<super::knit_strips::StripsArgs>),
    /// What accuracy costs in time for the lumislice renderer [C03 §5]: table resolution,
    /// march steps, level of detail, eq. 10 shadows, extinction, multiple scattering,
    /// against the volumetric reference, with frame-time ratios to plain tubes.
    Lumislice(Box<super::knit_lumislice::LumisliceArgs>),
    /// Knitwear that moves: the knit animation [C03 §4] (a scarf dropped or stretched)
    /// drives the yarns through the knot solver [H25]; BCC frames, rendered frames, a
    /// contact sheet and per-frame costs; resumable.
    Animate(Box<super::knit_animate::AnimateArgs>),
}

/// `btf knit chart`.
#[derive(Args)]
pub struct ChartArgs {
    /// Built-in chart name or chart file.
    pub chart: String,
    /// Also write the chart text to this file.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: Option<PathBuf>,
}

/// A patch: chart, yarn, stitches (shared by mesh, skeleton, fibers).
#[derive(Args, Clone)]
pub struct PatchArgs {
    /// Built-in chart name or chart file.
    #[arg(long, default_value = "stockinette")]
    pub chart: String,
    /// Yarn preset name or yarn TOML file.
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Stitches W,C (wales, courses; multiples of the chart's size).
    #[arg(long)]
    pub stitches: Option<String>,
    /// Seed of the fibers.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// No hair flyaways.
    #[arg(long)]
    pub no_hairs: bool,
    /// Fiber polyline points per helix turn.
    #[arg(long, default_value_t = 12)]
    pub samples_per_turn: u32,
    /// Output file: .obj (mesh, lines), .bcc or .txt (Mitsuba curve text); for `knit ref`
    /// the image (.exr linear, or .png sRGB; `-i/--image` is its old spelling).
    #[arg(short = 'o', long = "out", aliases = ["output", "image"], short_alias = 'i')]
    pub output: Option<PathBuf>,
}

crate::args::choices! {
    /// `btf knit ref --shading`: how a fiber scatters light.
    ShadingChoice {
        /// Khungurn R + TT lobes and a diffuse term [W19 eq. 6–10].
        Khungurn = "khungurn",
        /// The simple fiber model [W19 eq. 5] plus a diffuse term.
        Simple = "simple",
        /// R + TT + D as in [H25 eq. 7].
        Huang = "huang",
        /// Lambertian fibers (albedo from `--albedo`).
        Lambert = "lambert",
    }
}

/// `btf knit ref`.
#[derive(Args)]
pub struct RefArgs {
    #[command(flatten)]
    pub patch: PatchArgs,
    /// Render these BCC yarn curves (fibers from --yarn) instead of a chart patch.
    #[arg(long)]
    pub bcc: Option<PathBuf>,
    /// Camera: btf:THETA,PHI (the BTF's oblique orthographic view of one period) or
    /// persp:EX,EY,EZ,TX,TY,TZ,FOV_DEG (metres).
    #[arg(long, default_value = "btf:0,0")]
    pub camera: String,
    /// Directional light dir:THETA,PHI[,E] or point light point:X,Y,Z,I (repeatable).
    #[arg(long = "light")]
    pub lights: Vec<String>,
    /// Environment map (equirectangular EXR/HDR), optionally ,SCALE.
    #[arg(long)]
    pub env: Option<String>,
    /// Fiber scattering.
    #[arg(long, default_value = "khungurn")]
    pub shading: ShadingChoice,
    /// Lambert albedo or yarn colour R,G,B (linear).
    #[arg(long)]
    pub albedo: Option<String>,
    /// Image size W,H.
    #[arg(long, default_value = "128,128")]
    pub size: String,
    /// Samples per pixel.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// Lit vertices per path (1 = direct lighting).
    #[arg(long, default_value_t = 8)]
    pub bounces: u32,
    /// No periodic wrap for a chart patch (a single patch, nothing around it).
    #[arg(long)]
    pub no_wrap: bool,
    /// No black backing plane under a chart patch.
    #[arg(long)]
    pub no_backing: bool,
    /// Seed of the pixel samples (the fibers use --seed).
    #[arg(long, default_value_t = 1)]
    pub render_seed: u64,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs one `btf knit` subcommand.
pub fn run(cmd: KnitCmd) -> Result<()> {
    match cmd {
        KnitCmd::Chart(a) => chart_cmd(a),
        KnitCmd::Mesh(a) => mesh_cmd(a),
        KnitCmd::Skeleton(a) => skeleton_cmd(a),
        KnitCmd::Fibers(a) => fibers_cmd(a),
        KnitCmd::Ref(a) => ref_cmd(*a),
        KnitCmd::Render(a) => super::knit_render::run(*a),
        KnitCmd::Sweep(a) => super::knit_sweep::run(*a),
        KnitCmd::Compare(a) => super::knit_compare::run(*a),
        KnitCmd::Deform(a) => super::knit_deform::run(*a),
        KnitCmd::Strips(a) => super::knit_strips::run(*a),
        KnitCmd::Lumislice(a) => super::knit_lumislice::run(*a),
        KnitCmd::Animate(a) => super::knit_animate::run(*a),
    }
}

/// A chart by built-in name or from a file.
pub fn load_chart(s: &str) -> Result<Chart> {
    let p = Path::new(s);
    if p.is_file() {
        let text = std::fs::read_to_string(p).with_context(|| format!("reading chart {s}"))?;
        return Ok(Chart::parse(&text, s)?);
    }
    Chart::builtin(s).map_err(|e| anyhow::anyhow!("{e} (and no chart file '{s}' exists)"))
}

/// A yarn by preset name or from a TOML file.
pub fn load_yarn(s: &str) -> Result<YarnParams> {
    let p = Path::new(s);
    if p.is_file() {
        let text = std::fs::read_to_string(p).with_context(|| format!("reading yarn {s}"))?;
        return Ok(YarnParams::from_toml(&text, s)?);
    }
    YarnParams::preset(s).map_err(|e| anyhow::anyhow!("{e} (and no yarn file '{s}' exists)"))
}

pub(crate) fn stitches(s: &Option<String>) -> Result<Option<[usize; 2]>> {
    s.as_deref().map(|s| crate::args::numbers::<usize, 2>(s, "--stitches")).transpose()
}

fn patch_opts(a: &PatchArgs) -> Result<PatchOptions> {
    let mut o = PatchOptions { stitches: stitches(&a.stitches)?, ..PatchOptions::default() };
    o.generation = GenOptions {
        seed: a.seed,
        hairs: !a.no_hairs,
        samples_per_turn: a.samples_per_turn,
        ..GenOptions::default()
    };
    Ok(o)
}

fn output(a: &PatchArgs, inputs: &[(&str, &Path)]) -> Result<PathBuf> {
    let Some(out) = a.output.clone() else { bail!("-o/--out is required") };
    guard::refuse_overlap(&[("output", &out)], inputs)?;
    let kind = if ext(&out) == "bcc" {
        btf_core::fs::OutputKind::File { magic: b"BCC", format: "BCC" }
    } else {
        btf_core::fs::TEXT
    };
    guard::check_file(&out, kind)?;
    Ok(out)
}

pub(crate) fn ext(p: &Path) -> String {
    p.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

pub(crate) fn chart_inputs(a: &PatchArgs) -> Vec<(&'static str, &Path)> {
    chart_inputs_of(&a.chart, &a.yarn)
}

/// The chart and yarn arguments that name files (inputs no output may overwrite).
pub(crate) fn chart_inputs_of<'a>(chart: &'a str, yarn: &'a str) -> Vec<(&'static str, &'a Path)> {
    let mut v: Vec<(&'static str, &Path)> = Vec::new();
    if Path::new(chart).is_file() {
        v.push(("chart", Path::new(chart)));
    }
    if Path::new(yarn).is_file() {
        v.push(("yarn", Path::new(yarn)));
    }
    v
}

fn chart_cmd(a: ChartArgs) -> Result<()> {
    let chart = load_chart(&a.chart)?;
    outln!("{} ({} wales × {} courses)", chart.name, chart.width, chart.height);
    outln!("{}", chart.to_text().trim_end());
    if let Some(out) = a.output {
        if Path::new(&a.chart).is_file() {
            guard::refuse_overlap(&[("output", &out)], &[("chart", Path::new(&a.chart))])?;
        }
        guard::check_file(&out, btf_core::fs::TEXT)?;
        btf_image::write::write_text(&out, &chart.to_text())?;
        eprintln!("chart -> {}", out.display());
    }
    Ok(())
}

fn mesh_cmd(a: PatchArgs) -> Result<()> {
    let out = output(&a, &chart_inputs(&a))?;
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let [w, c] = stitches(&a.stitches)?.unwrap_or([chart.width, chart.height]);
    let sk = SkeletonParams::new(params.yarn_radius());
    let (ws, cs) = sk.default_spacing();
    let mesh = StitchMesh::flat(&chart, w, c, ws, cs)?;
    let mut text = format!("# btf knit mesh --chart {} ({w} × {c} stitches, metres)\n", chart.name);
    for p in &mesh.corners {
        text.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for uv in &mesh.corner_uvs {
        text.push_str(&format!("vt {} {}\n", uv[0], uv[1]));
    }
    for cell in &mesh.cells {
        let i = |cc: usize, ww: usize| cc * (mesh.wales + 1) + ww + 1;
        let (cc, ww) = (cell.course, cell.wale);
        let q = [i(cc, ww), i(cc, ww + 1), i(cc + 1, ww + 1), i(cc + 1, ww)];
        text.push_str(&format!("# {:?}\n", cell.stitch));
        text.push_str(&format!("f {0}/{0} {1}/{1} {2}/{2} {3}/{3}\n", q[0], q[1], q[2], q[3]));
    }
    btf_image::write::write_text(&out, &text)?;
    eprintln!("stitch mesh {w} × {c} ({} cells) -> {}", mesh.cells.len(), out.display());
    Ok(())
}

fn skeleton_cmd(a: PatchArgs) -> Result<()> {
    let out = output(&a, &chart_inputs(&a))?;
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let [w, c] = stitches(&a.stitches)?.unwrap_or([chart.width, chart.height]);
    let sk = SkeletonParams::new(params.yarn_radius());
    let (ws, cs) = sk.default_spacing();
    let set = chen_skeleton(&StitchMesh::flat(&chart, w, c, ws, cs)?, &sk)?;
    match ext(&out).as_str() {
        "bcc" => yarn::io::write_bcc(&out, &set, &format!("btf knit {}", chart.name))?,
        "obj" => yarn::io::write_obj_yarns(&out, &set, 8)?,
        "txt" => yarn::io::write_mitsuba_yarns(&out, &set, params.yarn_radius(), 8)?,
        e => bail!("{}: unknown extension '{e}' (bcc, obj or txt)", out.display()),
    }
    eprintln!("skeleton: {} curves -> {}", set.curves.len(), out.display());
    Ok(())
}

fn fibers_to_set(f: &Fibers) -> Result<yarn::curve::YarnSet> {
    let curves = (0..f.fiber_count())
        .filter(|&k| f.fiber_points(k).len() >= 2)
        .map(|k| {
            yarn::curve::YarnCurve::open(
                f.fiber_points(k).iter().map(|p| p.map(f64::from)).collect(),
            )
        })
        .collect::<yarn::Result<Vec<_>>>()?;
    Ok(yarn::curve::YarnSet::new(curves, f.period)?)
}

fn fibers_cmd(a: PatchArgs) -> Result<()> {
    let out = output(&a, &chart_inputs(&a))?;
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let patch = KnitPatch::new(&chart, &params, &patch_opts(&a)?)?;
    let f = &patch.fibers;
    match ext(&out).as_str() {
        "bcc" => yarn::io::write_bcc(&out, &fibers_to_set(f)?, "btf knit fibers")?,
        "obj" => yarn::io::write_obj_fibers(&out, f)?,
        "txt" => yarn::io::write_mitsuba_fibers(&out, f)?,
        e => bail!("{}: unknown extension '{e}' (bcc, obj or txt)", out.display()),
    }
    eprintln!("fibers: {} fibers, {} points -> {}", f.fiber_count(), f.points.len(), out.display());
    Ok(())
}

fn shading(name: &str, color: Option<[f64; 3]>) -> Result<yarn_ref::Shading> {
    let bcsdf = match name {
        "lambert" => return Ok(yarn_ref::Shading::Lambert { albedo: color }),
        "khungurn" => FiberBcsdf::khungurn(&KhungurnParams::default())?,
        "simple" => FiberBcsdf::simple(&SimpleParams::default())?,
        "huang" => FiberBcsdf::huang(&HuangParams::default())?,
        other => bail!("--shading '{other}': expected khungurn, simple, huang or lambert"),
    };
    Ok(yarn_ref::Shading::Fiber { bcsdf: Arc::new(bcsdf), tint: true })
}

pub(crate) fn rgb(s: &Option<String>, what: &str) -> Result<Option<[f64; 3]>> {
    let Some(s) = s else { return Ok(None) };
    let v = crate::args::numbers::<f64, 3>(s, what)?;
    if !v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)) {
        bail!("{what} '{s}': expected three values in [0, 1]");
    }
    Ok(Some(v))
}

pub(crate) fn light(s: &str) -> Result<yarn_ref::Light> {
    let bad = || anyhow::anyhow!("--light '{s}': expected dir:THETA,PHI[,E] or point:X,Y,Z,I");
    let (kind, rest) = s.split_once(':').ok_or_else(bad)?;
    let v: Vec<f64> = rest
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    if !v.iter().all(|x| x.is_finite()) {
        return Err(bad());
    }
    match (kind, v.len()) {
        ("dir", 2 | 3) => {
            let e = v.get(2).copied().unwrap_or(1.0);
            Ok(yarn_ref::Light::directional(
                btf_core::Direction::new(v[0], v[1]).to_vector(),
                [e; 3],
            ))
        }
        ("point", 4) => {
            Ok(yarn_ref::Light::Point { position: [v[0], v[1], v[2]], intensity: [v[3]; 3] })
        }
        _ => Err(bad()),
    }
}

fn ref_cmd(a: RefArgs) -> Result<()> {
    let Some(image) = a.patch.output.clone() else {
        bail!("give the image with -o OUT.exr|OUT.png")
    };
    let mut inputs = chart_inputs(&a.patch);
    if let Some(b) = &a.bcc {
        inputs.push(("bcc", b.as_path()));
    }
    let env_path = a.env.as_deref().map(|e| PathBuf::from(e.split(',').next().unwrap_or(e)));
    if let Some(e) = &env_path {
        inputs.push(("env", e.as_path()));
    }
    guard::refuse_overlap(&[("-o", &image)], &inputs)?;
    let kind = match ext(&image).as_str() {
        "exr" => btf_core::fs::EXR,
        "png" => btf_core::fs::PNG,
        e => bail!("{}: unknown image extension '{e}' (exr or png)", image.display()),
    };
    guard::check_file(&image, kind)?;
    let [w, h] = crate::args::numbers::<usize, 2>(&a.size, "--size")?;
    let color = rgb(&a.albedo, "--albedo")?;
    let params = load_yarn(&a.patch.yarn)?;
    let t0 = std::time::Instant::now();
    let mut popts = patch_opts(&a.patch)?;
    if let Some(c) = color {
        popts.color = c.map(|x| x as f32);
    }
    let (fibers, period, z_ref, backing) = if let Some(b) = &a.bcc {
        let set = yarn::io::read_bcc(b)?.set;
        let f = generate_fibers(&set, std::slice::from_ref(&params), &popts.generation)?;
        let (lo, hi) = yarn_ref::patch::centre_line_z(&set);
        (f, None, hi + params.yarn_radius(), lo - 1.5 * params.yarn_radius())
    } else {
        let chart = load_chart(&a.patch.chart)?;
        let p = KnitPatch::new(&chart, &params, &popts)?;
        let back = p.backing_z();
        (p.fibers, Some(p.period), p.z_ref, back)
    };
    let opts = yarn_ref::SceneOptions {
        period: if a.no_wrap { None } else { period },
        backing_z: (!a.no_backing && a.bcc.is_none()).then_some(backing),
    };
    let scene = yarn_ref::FiberScene::new(&fibers, &opts)?;
    let build_s = t0.elapsed().as_secs_f64();
    let camera = camera(&a.camera, &scene, period, z_ref)?;
    let mut lights: Vec<yarn_ref::Light> =
        a.lights.iter().map(|s| light(s)).collect::<Result<_>>()?;
    if let (Some(spec), Some(path)) = (&a.env, &env_path) {
        let scale = match spec.split_once(',') {
            Some((_, s)) => {
                s.parse::<f64>().with_context(|| format!("--env '{spec}': bad scale"))?
            }
            None => 1.0,
        };
        let map = btf_image::EnvMap::load(path)?;
        lights.push(yarn_ref::Light::Environment(yarn_ref::EnvLight::new(map, scale)));
    }
    if lights.is_empty() {
        bail!("no light: give --light dir:THETA,PHI, --light point:X,Y,Z,I or --env FILE");
    }
    let shading = shading(a.shading.as_str(), color)?;
    let sc = yarn_ref::Scene { fibers: &scene, lights: &lights, shading: &shading };
    let mut s = yarn_ref::RenderSettings::new(w, h, a.spp);
    s.seed = a.render_seed;
    s.path.max_bounces = a.bounces;
    let bar = crate::progress::bar(h as u64, "rows");
    let (img, stats) = yarn_ref::render_with(&sc, &camera, &s, &|| bar.inc(1))?;
    bar.finish_and_clear();
    match ext(&image).as_str() {
        "exr" => btf_image::write::write_exr_rgb(&image, w, h, &img.rgb)?,
        _ => btf_image::write::write_png_linear(&image, w, h, &img.rgb, 1.0)?,
    }
    let mean: f64 = img.rgb.iter().map(|v| *v as f64).sum::<f64>() / img.rgb.len() as f64;
    let coverage: f64 = img.coverage.iter().map(|v| *v as f64).sum::<f64>() / (w * h) as f64;
    if a.json {
        let j = serde_json::json!({
            "image": image, "width": w, "height": h, "spp": a.spp, "bounces": a.bounces,
            "fibers": fibers.fiber_count(), "segments": scene.segment_count(),
            "scene_bytes": scene.bytes(), "build_seconds": build_s,
            "render_seconds": stats.seconds, "rays": stats.rays, "camera_rays": stats.camera_rays,
            "rays_per_second": stats.rays_per_second(), "mean_radiance": mean,
            "coverage": coverage, "backing_fraction": img.mean_backing(),
            "threads": rayon::current_num_threads(),
        });
        outln!("{}", serde_json::to_string_pretty(&j)?);
    }
    eprintln!(
        "ref: {} fibers, {}×{} at {} spp, {:.2} Mrays/s ({:.1} s) -> {}",
        fibers.fiber_count(),
        w,
        h,
        a.spp,
        stats.rays_per_second() * 1e-6,
        stats.seconds,
        image.display()
    );
    Ok(())
}

fn camera(
    s: &str,
    scene: &yarn_ref::FiberScene,
    period: Option<yarn_ref::Period>,
    z_ref: f64,
) -> Result<yarn_ref::Camera> {
    let bad =
        || anyhow::anyhow!("--camera '{s}': expected btf:THETA,PHI or persp:EX,EY,EZ,TX,TY,TZ,FOV");
    let (kind, rest) = s.split_once(':').ok_or_else(bad)?;
    let v: Vec<f64> = rest
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match (kind, v.len()) {
        ("btf", 2) => {
            let view = btf_core::Direction::new(v[0], v[1]).to_vector();
            let (origin, extent) = match period {
                Some(p) => (p.origin, p.size),
                None => {
                    let b = scene.bounds();
                    (
                        [b.min[0] as f64, b.min[1] as f64],
                        [(b.max[0] - b.min[0]) as f64, (b.max[1] - b.min[1]) as f64],
                    )
                }
            };
            Ok(yarn_ref::Camera::oblique(view, z_ref, origin, extent)?)
        }
        ("persp", 7) => Ok(yarn_ref::Camera::perspective(
            [v[0], v[1], v[2]],
            [v[3], v[4], v[5]],
            [0.0, 0.0, 1.0],
            v[6],
        )?),
        _ => Err(bad()),
    }
}
