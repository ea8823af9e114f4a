//! `btf synth …`: command-line front end of the `datasets` crate — synthetic materials,
//! HDR environments, meshes and (later) raw captures. Arguments are parsed and validated
//! here; all the work happens in `datasets`.

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use datasets::material::preview::write_contact_sheet;
use datasets::{EnvKind, EnvParams, GenerateOptions, MaterialKind, MaterialSpec};
use std::path::{Path, PathBuf};
use yarn_ref::btf::{YarnBtfOptions, YarnBtfSpec, generate_yarn_btf};

use crate::args::{Dtype, Material, choices};
use crate::cmd::knit;
use crate::guard;

choices! {
    /// What `btf synth material --kind` makes.
    SynthKind {
        /// Flat Lambertian with a patterned albedo (the analytic validation case).
        Lambert = "lambert",
        /// Rounded wales with a sheen pile (anisotropic).
        Corduroy = "corduroy",
        /// Stockinette knit of yarn tubes (height field).
        Knit = "knit",
        /// Plain weave of two yarn colours.
        Woven = "woven",
        /// Embossed glossy paint.
        Wallpaper = "wallpaper",
        /// Fractal stone relief.
        Stone = "stone",
        /// A knit patch of explicit fibers, path traced (see `--chart`, `--yarn`).
        Yarn = "yarn",
    }
}

choices! {
    /// How a yarn BTF is rendered.
    YarnMethod {
        /// The fiber-level path-traced reference (`yarn-ref`).
        Reference = "reference",
        /// Fibers generated on the GPU [W19] (`yarn-render`): seconds, not hours.
        Fibers = "fibers",
        /// Fiber-textured yarn strips [H25] (`yarn-render`, textures baked once and cached).
        Strips = "strips",
        /// Lumislices [C03 §5] (`yarn-render`, the scattering table computed once and cached).
        Lumislice = "lumislice",
    }
}

choices! {
    /// `btf synth env --kind`.
    EnvChoice {
        /// Preetham daylight sky with the sun disc and a diffuse ground.
        Sky = "sky",
        /// Dark photo studio with four soft boxes.
        Studio = "studio",
        /// A room with a window, a ceiling lamp and walls.
        Interior = "interior",
    }
}

choices! {
    /// `btf synth mesh --kind`.
    MeshChoice {
        /// 1 × 1 m square in the xy plane, normal +z.
        Plane = "plane",
        /// UV sphere of radius 0.5 m.
        Sphere = "sphere",
        /// 1 × 1 m cloth dropped over a sphere.
        Drape = "drape",
        /// 1.2 × 1.5 m curtain with pleats.
        Curtain = "curtain",
        /// Torso and two sleeves with folds.
        Shirt = "shirt",
        /// Hip part and two legs with folds.
        Trousers = "trousers",
    }
}

choices! {
    /// `btf synth mesh --resolution`.
    MeshResolution {
        /// About 900 vertices.
        Low = "low",
        /// About 9000 vertices.
        High = "high",
    }
}

/// What to synthesise.
#[derive(Subcommand)]
pub enum SynthCmd {
    /// A mesostructure material rendered into a BTF store (known ground truth).
    Material(MaterialArgs),
    /// An equirectangular HDR environment map (EXR).
    Env(EnvArgs),
    /// A mesh with normals and UVs (OBJ).
    Mesh(MeshArgs),
    /// Raw images of the sample on its holder plate from a virtual gonioreflectometer.
    Capture(CaptureArgs),
    /// A garment sewn from pattern panels and draped on a mannequin (or the mannequin).
    Garment(super::garment::GarmentArgs),
}

/// `btf synth material`.
#[derive(Args)]
pub struct MaterialArgs {
    /// The material.
    #[arg(long)]
    pub kind: SynthKind,
    /// yarn: built-in chart name or chart file.
    #[arg(long)]
    pub chart: Option<String>,
    /// yarn: yarn preset name or yarn TOML file.
    #[arg(long)]
    pub yarn: Option<String>,
    /// yarn: how the BTF is rendered (reference: path traced; fibers: GPU [W19]; strips:
    /// GPU yarn strips [H25]; lumislice: GPU lumislices [C03 §5]).
    #[arg(long, default_value = "reference")]
    pub method: YarnMethod,
    /// yarn: jittered samples per texel (default 16); strips: camera rays per texel of the
    /// texture bake.
    #[arg(long)]
    pub spp: Option<u32>,
    /// yarn: stitches W,C of the periodic patch (default one chart repeat).
    #[arg(long)]
    pub stitches: Option<String>,
    /// yarn: lit vertices per path (default 8; 1 = direct lighting).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Texels per side.
    #[arg(long, default_value_t = 64)]
    pub size: usize,
    /// View and light sampling: ubo81, ubo81-h1, dome151 or rings:θxCOUNT,… (e.g. rings:0x1,45x4).
    #[arg(long, default_value = "ubo81")]
    pub sampling: String,
    /// Seed of all random choices.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Base albedo as linear R,G,B in [0, 1].
    #[arg(long)]
    pub albedo: Option<String>,
    /// Element type of the store.
    #[arg(long, default_value = "f32")]
    pub dtype: Dtype,
    /// Old spelling of `--dtype f16` (hidden).
    #[arg(long, hide = true, conflicts_with = "dtype")]
    pub f16: bool,
    /// Chunk codec of the normtextures: blosc (byte shuffle, zstd level 1; the default), or
    /// none (raw: about twice the disk, and `btf compress` maps the chunks in place instead
    /// of decoding them). A resumed run, and every shard after the first, keeps the codec
    /// the store was begun with. Not for --kind yarn yet.
    #[arg(long)]
    pub codec: Option<crate::args::Codec>,
    /// Keep the images of an interrupted run.
    #[arg(long)]
    pub resume: bool,
    /// Shard of the synthesis (its view slots) when several processes share it.
    #[command(flatten)]
    pub shard: crate::args::ShardArgs,
    /// Also write a PNG contact sheet `DIR/KIND.png`.
    #[arg(long, value_name = "DIR")]
    pub preview: Option<PathBuf>,
    /// Output BTF store.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
}

/// `btf synth env`.
#[derive(Args)]
pub struct EnvArgs {
    /// The environment.
    #[arg(long)]
    pub kind: EnvChoice,
    /// Sun elevation above the horizon, degrees.
    #[arg(long, default_value_t = 35.0)]
    pub sun_elevation: f64,
    /// Sun azimuth from +x towards +y, degrees.
    #[arg(long, default_value_t = 30.0)]
    pub sun_azimuth: f64,
    /// Atmospheric turbidity (1.7 … 10).
    #[arg(long, default_value_t = 3.0)]
    pub turbidity: f64,
    /// Width in pixels (height = width / 2).
    #[arg(long, default_value_t = 1024)]
    pub width: usize,
    /// Output EXR file.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
}

/// `btf synth mesh`.
#[derive(Args)]
pub struct MeshArgs {
    /// The mesh.
    #[arg(long)]
    pub kind: MeshChoice,
    /// Tessellation.
    #[arg(long, default_value = "low")]
    pub resolution: MeshResolution,
    /// Output OBJ file.
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
}

/// `btf synth capture`.
#[derive(Args)]
pub struct CaptureArgs {
    /// Material kind on the plate.
    #[arg(long)]
    pub material: Material,
    /// Texels per side of the material.
    #[arg(long, default_value_t = 64)]
    pub size: usize,
    /// View and light sampling: ubo81, ubo81-h1, dome151 or rings:θxCOUNT,… (e.g.
    /// rings:0x1,45x4,75x4 for a small test capture).
    #[arg(long, default_value = "ubo81")]
    pub sampling: String,
    /// Seed of the material.
    #[arg(long, default_value_t = 1)]
    pub material_seed: u64,
    /// Image size W,H in pixels.
    #[arg(long, default_value = "320,240")]
    pub resolution: String,
    /// Robot pose error: rotation DEG and shift MM (standard deviations).
    #[arg(long, default_value = "1,1")]
    pub pose_noise: String,
    /// Sensor noise: read noise (DN) and shot-noise variance per DN.
    #[arg(long, default_value = "2,0.5")]
    pub noise: String,
    /// Vignetting strength (0 = none, 1 = natural cos⁴).
    #[arg(long, default_value_t = 1.0)]
    pub vignetting: f64,
    /// Seed of poses and noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Rays per pixel side (K² rays average each pixel's area, as a real sensor does).
    #[arg(long, default_value_t = 1)]
    pub supersample: usize,
    /// Output folder of raw images, capture.toml and truth.toml.
    #[arg(short = 'o', long, alias = "output")]
    pub out: PathBuf,
}

/// Runs one `btf synth` subcommand.
pub fn run(cmd: SynthCmd) -> Result<()> {
    match cmd {
        SynthCmd::Material(a) => material(a),
        SynthCmd::Env(a) => env(a),
        SynthCmd::Mesh(a) => mesh(a),
        SynthCmd::Capture(a) => capture(a),
        SynthCmd::Garment(a) => super::garment::run(a),
    }
}

fn parse_rgb(s: &str) -> Result<[f64; 3]> {
    let v = crate::args::numbers::<f64, 3>(s, "--albedo")?;
    if !v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)) {
        bail!("--albedo '{s}': expected three values in [0, 1]");
    }
    Ok(v)
}

fn material(a: MaterialArgs) -> Result<()> {
    if a.kind == SynthKind::Yarn {
        if a.shard.shard.is_some() || a.shard.shard_count.is_some() {
            bail!("--shard is not available for --kind yarn yet (issue #23)");
        }
        if a.codec.is_some() {
            bail!("--codec is not available for --kind yarn yet (its stores are blosc)");
        }
        synth_yarn_material(&a, crate::progress::enabled())?;
        if let Some(dir) = a.preview {
            let store = btf_core::store::BtfStore::open(&a.output)?;
            eprintln!("preview -> {}", write_contact_sheet(&store, &dir, "yarn")?.display());
        }
        return Ok(());
    }
    if a.chart.is_some()
        || a.yarn.is_some()
        || a.spp.is_some()
        || a.stitches.is_some()
        || a.bounces.is_some()
    {
        bail!("--chart, --yarn, --spp, --stitches and --bounces are for --kind yarn");
    }
    let kind = MaterialKind::from_name(a.kind.as_str())?;
    let mut spec = MaterialSpec::new(kind, a.size);
    spec.sampling = datasets::capture::parse_sampling(&a.sampling)?;
    spec.seed = a.seed;
    spec.albedo = a.albedo.as_deref().map(parse_rgb).transpose()?;
    let dtype = if a.f16 { btf_core::zarr::DType::F16 } else { a.dtype.dtype() };
    let shard = a.shard.shard()?;
    if shard.is_some() && a.preview.is_some() {
        bail!("--preview needs the whole store: give it to a run without --shard");
    }
    let opts = GenerateOptions {
        resume: a.resume,
        progress: crate::progress::enabled(),
        dtype,
        shard,
        codec: a.codec.unwrap_or(crate::args::Codec::Blosc).btf(),
    };
    let r = datasets::generate(&spec, &a.output, &opts)
        .with_context(|| format!("synthesising {} into {}", a.kind, a.output.display()))?;
    if let Some(s) = shard {
        eprintln!(
            "shard {}: when every shard is done: btf finalize {}",
            s.label(),
            a.output.display()
        );
    }
    eprintln!(
        "{} {}² ({}): {} images written, {} kept, {:.1} s -> {}",
        a.kind,
        a.size,
        a.sampling,
        r.images_written,
        r.images_skipped,
        r.seconds,
        a.output.display()
    );
    if let Some(dir) = a.preview {
        let store = btf_core::store::BtfStore::open(&a.output)?;
        let png = write_contact_sheet(&store, &dir, kind.name())?;
        eprintln!("preview -> {}", png.display());
    }
    Ok(())
}

fn env(a: EnvArgs) -> Result<()> {
    let kind = EnvKind::from_name(a.kind.as_str())?;
    let params = EnvParams {
        sun_elevation_deg: a.sun_elevation,
        sun_azimuth_deg: a.sun_azimuth,
        turbidity: a.turbidity,
    };
    crate::guard::check_file(&a.output, btf_core::fs::EXR)?;
    let map = datasets::synth_env(kind, &params, a.width)?;
    map.write_exr(&a.output)?;
    let max = map.pixels.iter().flat_map(|p| p.iter()).fold(0f32, |m, &v| m.max(v));
    eprintln!(
        "{} {}x{} (max {:.3e}) -> {}",
        a.kind,
        map.width,
        map.height,
        max,
        a.output.display()
    );
    Ok(())
}

fn mesh(a: MeshArgs) -> Result<()> {
    let kind = datasets::MeshKind::from_name(a.kind.as_str())?;
    let res = datasets::Resolution::from_name(a.resolution.as_str())?;
    crate::guard::check_file(&a.output, btf_core::fs::TEXT)?;
    let t0 = std::time::Instant::now();
    let mesh = datasets::synth_mesh(kind, res)?;
    let comment = format!("btf synth mesh --kind {} --resolution {}", a.kind, a.resolution);
    datasets::write_obj(&mesh, &a.output, &comment)?;
    eprintln!(
        "{} ({}): {} vertices, {} triangles, {:.2} s -> {}",
        a.kind,
        a.resolution,
        mesh.positions.len(),
        mesh.triangles.len(),
        t0.elapsed().as_secs_f64(),
        a.output.display()
    );
    Ok(())
}

fn capture(a: CaptureArgs) -> Result<()> {
    let kind = MaterialKind::from_name(a.material.as_str())?;
    let mut material = MaterialSpec::new(kind, a.size);
    material.sampling = datasets::capture::parse_sampling(&a.sampling)?;
    material.seed = a.material_seed;
    let mut spec = datasets::capture::CaptureSpec::new(material);
    [spec.width, spec.height] = crate::args::numbers(&a.resolution, "--resolution")?;
    [spec.pose_noise_deg, spec.pose_noise_mm] =
        crate::args::numbers(&a.pose_noise, "--pose-noise")?;
    [spec.read_noise_dn, spec.shot_noise_per_dn] = crate::args::numbers(&a.noise, "--noise")?;
    spec.vignetting = a.vignetting;
    spec.seed = a.seed;
    spec.supersample = a.supersample;
    let r = datasets::capture::capture(&spec, &a.out, crate::progress::enabled())
        .with_context(|| format!("capturing {} into {}", a.material, a.out.display()))?;
    eprintln!(
        "capture {}: {} images written, {} kept, {:.1} s -> {}",
        a.material,
        r.images_written,
        r.images_skipped,
        r.seconds,
        a.out.display()
    );
    Ok(())
}

/// `btf synth material --kind yarn`: the yarn BTF of DESIGN §4.2.
fn synth_yarn_material(a: &MaterialArgs, progress: bool) -> Result<()> {
    let chart_name = a.chart.as_deref().unwrap_or("stockinette");
    let yarn_name = a.yarn.as_deref().unwrap_or("cotton-2ply");
    let mut inputs: Vec<(&str, &Path)> = Vec::new();
    if Path::new(chart_name).is_file() {
        inputs.push(("chart", Path::new(chart_name)));
    }
    if Path::new(yarn_name).is_file() {
        inputs.push(("yarn", Path::new(yarn_name)));
    }
    guard::refuse_overlap(&[("output", &a.output)], &inputs)?;
    let chart = knit::load_chart(chart_name)?;
    let params = knit::load_yarn(yarn_name)?;
    let mut spec = YarnBtfSpec::new(chart, chart_name, params, a.size);
    spec.sampling = datasets::capture::parse_sampling(&a.sampling)?;
    spec.stitches = knit::stitches(&a.stitches)?;
    spec.seed = a.seed;
    spec.method = a.method.as_str().to_owned();
    if let Some(n) = a.spp {
        spec.spp = n;
    }
    if let Some(b) = a.bounces {
        spec.bounces = b;
    }
    if let Some(c) = knit::rgb(&a.albedo, "--albedo")? {
        spec.color = c.map(|x| x as f32);
    }
    let dtype = if a.f16 { btf_core::zarr::DType::F16 } else { a.dtype.dtype() };
    let opts = YarnBtfOptions { resume: a.resume, progress, dtype };
    if spec.method == "strips" {
        let gpu = btf_render::Gpu::new()?;
        let settings = yarn_render::StripSettings::default();
        // The bake of the strip textures takes --spp and --bounces.
        let mut bake = yarn_precompute::StripBakeSettings::default();
        if let Some(n) = a.spp {
            bake.spp = n;
        }
        if let Some(b) = a.bounces {
            bake.bounces = b;
        }
        let cache = a.output.parent().map(|p| p.join(".yarn-cache"));
        let r = yarn_render::btf::generate_strip_btf(
            &gpu,
            &spec,
            settings,
            &bake,
            cache.as_deref(),
            &a.output,
            &opts,
        )
        .with_context(|| format!("synthesising yarn {} into {}", chart_name, a.output.display()))?;
        eprintln!(
            "yarn {} in {} {}² ({}, GPU yarn strips): {} images written, {} kept, {:.1} s -> {}",
            spec.chart.name,
            spec.params.name,
            a.size,
            a.sampling,
            r.images_written,
            r.images_skipped,
            r.seconds,
            a.output.display()
        );
        return Ok(());
    }
    if spec.method == "lumislice" {
        let gpu = btf_render::Gpu::new()?;
        let cache = a.output.parent().map(|p| p.join(".yarn-cache"));
        let r = yarn_render::btf::generate_lumislice_btf(
            &gpu,
            &spec,
            yarn_render::LumisliceRenderSettings::default(),
            &yarn_precompute::LumisliceSettings::default(),
            cache.as_deref(),
            &a.output,
            &opts,
        )
        .with_context(|| format!("synthesising yarn {} into {}", chart_name, a.output.display()))?;
        eprintln!(
            "yarn {} in {} {}² ({}, GPU lumislices): {} images written, {} kept, {:.1} s -> {}",
            spec.chart.name,
            spec.params.name,
            a.size,
            a.sampling,
            r.images_written,
            r.images_skipped,
            r.seconds,
            a.output.display()
        );
        return Ok(());
    }
    if spec.method == "fibers" {
        let gpu = btf_render::Gpu::new()?;
        let settings = yarn_render::FiberSettings::default();
        let r = yarn_render::btf::generate_fiber_btf(&gpu, &spec, settings, &a.output, &opts)
            .with_context(|| {
                format!("synthesising yarn {} into {}", chart_name, a.output.display())
            })?;
        eprintln!(
            "yarn {} in {} {}² ({}, GPU fibers, {} instances per image): {} images written, {} \
             kept, {:.1} s -> {}",
            spec.chart.name,
            spec.params.name,
            a.size,
            a.sampling,
            r.instances,
            r.images_written,
            r.images_skipped,
            r.seconds,
            a.output.display()
        );
        return Ok(());
    }
    let r = generate_yarn_btf(&spec, &a.output, &opts)
        .with_context(|| format!("synthesising yarn {} into {}", chart_name, a.output.display()))?;
    eprintln!(
        "yarn {} in {} {}² ({}, {} spp): {} fibers, {} images written, {} kept, {:.1} s, {:.2} Mrays/s, τ₁ {} -> {}",
        spec.chart.name,
        spec.params.name,
        a.size,
        a.sampling,
        spec.spp,
        r.fibers,
        r.images_written,
        r.images_skipped,
        r.seconds,
        r.rays as f64 / r.seconds.max(1e-9) * 1e-6,
        r.tau1.map_or("n/a".into(), |t| format!("{t:.3}")),
        a.output.display()
    );
    Ok(())
}
