//! `btf synth …`: command-line front end of the `datasets` crate — synthetic materials,
//! HDR environments, meshes and (later) raw captures. Arguments are parsed and validated
//! here; all the work happens in `datasets`.

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use datasets::material::preview::write_contact_sheet;
use datasets::{EnvKind, EnvParams, GenerateOptions, MaterialKind, MaterialSpec};
use std::io::IsTerminal;
use std::path::PathBuf;

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
    /// lambert, corduroy, knit, woven, wallpaper or stone.
    #[arg(long)]
    pub kind: String,
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
    /// Store values as f16 instead of f32.
    #[arg(long)]
    pub f16: bool,
    /// Keep the images of an interrupted run.
    #[arg(long)]
    pub resume: bool,
    /// Also write a PNG contact sheet `DIR/KIND.png`.
    #[arg(long, value_name = "DIR")]
    pub preview: Option<PathBuf>,
    /// Output BTF store.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `btf synth env`.
#[derive(Args)]
pub struct EnvArgs {
    /// sky, studio or interior.
    #[arg(long)]
    pub kind: String,
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
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `btf synth mesh`.
#[derive(Args)]
pub struct MeshArgs {
    /// plane, sphere, drape, curtain, shirt or trousers.
    #[arg(long)]
    pub kind: String,
    /// low (~900 vertices) or high (~9000 vertices).
    #[arg(long, default_value = "low")]
    pub resolution: String,
    /// Output OBJ file.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// `btf synth capture`.
#[derive(Args)]
pub struct CaptureArgs {
    /// Material kind on the plate (lambert, corduroy, knit, woven, wallpaper, stone).
    #[arg(long)]
    pub material: String,
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
    #[arg(long)]
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

fn show_progress() -> bool {
    std::env::var_os("BTF_NO_PROGRESS").is_none() && std::io::stderr().is_terminal()
}

fn parse_rgb(s: &str) -> Result<[f64; 3]> {
    let v = crate::args::numbers::<f64, 3>(s, "--albedo")?;
    if !v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)) {
        bail!("--albedo '{s}': expected three values in [0, 1]");
    }
    Ok(v)
}

fn material(a: MaterialArgs) -> Result<()> {
    let kind = MaterialKind::from_name(&a.kind)?;
    let mut spec = MaterialSpec::new(kind, a.size);
    spec.sampling = datasets::capture::parse_sampling(&a.sampling)?;
    spec.seed = a.seed;
    spec.albedo = a.albedo.as_deref().map(parse_rgb).transpose()?;
    let dtype = if a.f16 { btf_core::zarr::DType::F16 } else { btf_core::zarr::DType::F32 };
    let opts = GenerateOptions { resume: a.resume, progress: show_progress(), dtype };
    let r = datasets::generate(&spec, &a.output, &opts)
        .with_context(|| format!("synthesising {} into {}", a.kind, a.output.display()))?;
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
    let kind = EnvKind::from_name(&a.kind)?;
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
    let kind = datasets::MeshKind::from_name(&a.kind)?;
    let res = datasets::Resolution::from_name(&a.resolution)?;
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
    let kind = MaterialKind::from_name(&a.material)?;
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
    let r = datasets::capture::capture(&spec, &a.out, show_progress())
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
