//! `btf knit lumislice -o DIR`: what accuracy costs in time for the lumislice renderer of
//! [C03 §5] (issue #21, DESIGN §1.5 "What accuracy costs in time"). One flat chart patch
//! (its Chen skeleton, no periodic copies) is rendered by the CPU volumetric reference
//! (`yarn_ref::volume`: the union of all swept yarn volumes, the same fibers' density on a
//! 64² grid — finer than every table but `res64`'s —, Kajiya–Kay phase, light attenuated
//! through every yarn; single scattering, and with `ms` variants also multiple scattering)
//! once per camera, then by `yarn_render::LumisliceRenderer` over
//! the variants, and by the plain tubes of the fiber renderer as the time baseline — all
//! cells interleaved frame by frame in one run. Per cell: relative RMSE `√(Σ(g−r)²/Σr²)`
//! over the frame, the ratio of mean radiances, median frame ms and its ratio to the tubes,
//! table seconds and GPU bytes. Writes `lumislice.csv`, `lumislice.md`, `lumislice.png`
//! (error against time ratio), `ref-*.exr` and `gpu-*.exr`.

use super::knit::{chart_inputs_of, load_chart, load_yarn};
use super::knit_render::fiber_light;
use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use btf_image::plot::{Plot, Series, render};
use btf_image::write::{write_exr_rgb, write_png, write_text};
use clap::Args;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use yarn::density::{CrossSectionDensity, DensityOptions, Extinction};
use yarn::knit::{SkeletonParams, StitchMesh, chen_skeleton};
use yarn_precompute::lumislice::{LodRule, ShadowVariant};
use yarn_precompute::{Lumislice, LumisliceSettings};
use yarn_ref::volume::{ExtinctionLaw, Phase, SliceDensity, VolumeScene, VolumeSettings};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, LumisliceRenderSettings,
    LumisliceRenderer, PackOptions, PackedYarns,
};

/// `btf knit lumislice`.
#[derive(Args)]
pub struct LumisliceArgs {
    /// Output folder (lumislice.csv, lumislice.md, lumislice.png, ref-*.exr, gpu-*.exr).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Built-in chart name or chart file.
    #[arg(long, default_value = "stockinette")]
    pub chart: String,
    /// Yarn preset name or yarn TOML file.
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Stitches W,C of the patch.
    #[arg(long, default_value = "4,4")]
    pub stitches: String,
    /// Single-scattering albedo ϖ of the yarn (grey, so the reference's multiple
    /// scattering is comparable).
    #[arg(long, default_value_t = 0.8)]
    pub albedo: f64,
    /// Image size W,H.
    #[arg(long, default_value = "96,96")]
    pub size: String,
    /// Viewing direction THETA,PHI (degrees, towards the viewer).
    #[arg(long, default_value = "40,270")]
    pub view: String,
    /// Perspective cameras, one per value: the on-screen width of a stitch in pixels
    /// (30° field of view).
    #[arg(long, value_delimiter = ',', default_value = "24,6")]
    pub distances: Vec<f64>,
    /// Directional light dir:THETA,PHI[,E] or point light point:X,Y,Z,I (repeatable, ≤ 8;
    /// default dir:50,30).
    #[arg(long = "light")]
    pub lights: Vec<String>,
    /// Variants, one cell each: default (32² table, transmittance-preserving LoD, eq. 10
    /// physical, 1-cell steps, 4 pieces a segment, single scattering), res16, res64,
    /// steps0.5, steps2, bias-1 (one level finer), bias+1 (coarser), finest (LoD off),
    /// eq11 (the paper's LoD rule), no-shadow, empirical (eq. 10 as published), isotropic
    /// (the paper's extinction), nsub2, nsub8, ms (multiple scattering in the table, against
    /// the reference with multiple scattering), slices8 (the paper's instanced slices, 8 a
    /// piece, instead of the ray march).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "default,res16,res64,steps2,bias+1,finest,eq11,no-shadow,empirical,isotropic,ms"
    )]
    pub variants: Vec<String>,
    /// Reference samples per pixel.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// Paths per voxel of the multiple-scattering tables.
    #[arg(long, default_value_t = 32)]
    pub ms_paths: usize,
    /// Timed frames per cell (median reported), interleaved across cells.
    #[arg(long, default_value_t = 3)]
    pub repeat: u32,
    /// Seed of the fiber table the density comes from.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Remove this command's earlier outputs from the folder first.
    #[arg(long)]
    pub fresh: bool,
}

const FOV_DEG: f64 = 30.0;

/// The variants `--variants` knows.
const VARIANTS: [&str; 16] = [
    "slices8",
    "default",
    "res16",
    "res64",
    "steps0.5",
    "steps2",
    "bias-1",
    "bias+1",
    "finest",
    "eq11",
    "no-shadow",
    "empirical",
    "isotropic",
    "nsub2",
    "nsub8",
    "ms",
];

/// Table and renderer settings of variant `name`.
fn variant(
    name: &str,
    seed: u64,
    ms_paths: usize,
) -> Result<(LumisliceSettings, LumisliceRenderSettings)> {
    let mut t = LumisliceSettings { multiple: false, paths: ms_paths, seed, ..Default::default() };
    let mut r = LumisliceRenderSettings::default();
    match name {
        "default" => {}
        "res16" => t.res = 16,
        "res64" => t.res = 64,
        "steps0.5" => r.step_cells = 0.5,
        "steps2" => r.step_cells = 2.0,
        "bias-1" => r.level_bias = -1,
        "bias+1" => r.level_bias = 1,
        "finest" => r.level_bias = -4,
        "eq11" => t.lod = LodRule::Eq11,
        "no-shadow" => r.shadows = false,
        "empirical" => r.shadow_variant = ShadowVariant::Empirical,
        "isotropic" => t.extinction = Extinction::Isotropic,
        "nsub2" => r.n_sub = 2,
        "nsub8" => r.n_sub = 8,
        "ms" => t.multiple = true,
        "slices8" => r.slices = 8,
        other => bail!("--variants {other}: one of {}", VARIANTS.join(", ")),
    }
    Ok((t, r))
}

struct Cam {
    name: String,
    reference: yarn_ref::Camera,
    gpu: FiberCamera,
}

/// One row of the table.
struct Cell {
    camera: String,
    variant: String,
    rel_rmse: f64,
    mean_ratio: f64,
    ms: f64,
    tubes_ms: f64,
    table_s: f64,
    bytes: u64,
    pieces: usize,
    rgb: Vec<f32>,
    ms_ref: bool,
}

fn rel_rmse(g: &[[f32; 4]], r: &[f32]) -> (f64, f64) {
    let (mut num, mut den, mut sg, mut sr) = (0.0, 0.0, 0.0, 0.0);
    for (p, q) in g.iter().zip(r.chunks_exact(3)) {
        for c in 0..3 {
            num += (p[c] as f64 - q[c] as f64).powi(2);
            den += (q[c] as f64).powi(2);
            sg += p[c] as f64;
            sr += q[c] as f64;
        }
    }
    (
        if den > 0.0 { (num / den).sqrt() } else { f64::NAN },
        if sr > 0.0 { sg / sr } else { f64::NAN },
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { f64::NAN } else { v[v.len() / 2] }
}

/// Runs `btf knit lumislice`.
pub fn run(a: LumisliceArgs) -> Result<()> {
    let inputs = chart_inputs_of(&a.chart, &a.yarn);
    guard::refuse_overlap(&[("-o", &a.output)], &inputs)?;
    let [w, h] = crate::args::numbers::<u32, 2>(&a.size, "--size")?;
    if w == 0 || h == 0 || w > 2048 || h > 2048 {
        bail!("--size {w},{h}: each side must be 1..=2048");
    }
    let [vt, vp] = crate::args::numbers::<f64, 2>(&a.view, "--view")?;
    if !(1.0..80.0).contains(&vt) || !vp.is_finite() {
        bail!("--view {}: THETA in [1, 80) degrees, PHI finite", a.view);
    }
    if !(a.albedo.is_finite() && (0.0..=1.0).contains(&a.albedo)) {
        bail!("--albedo {}: in [0, 1]", a.albedo);
    }
    if a.distances.is_empty() || a.distances.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
        bail!("--distances: one or more stitch widths in pixels, each > 0");
    }
    if a.spp == 0 || a.spp > 4096 || a.repeat == 0 || a.repeat > 100 {
        bail!("--spp 1..=4096 and --repeat 1..=100");
    }
    if a.ms_paths == 0 || a.ms_paths > 4096 {
        bail!("--ms-paths {}: 1..=4096", a.ms_paths);
    }
    let mut variants = Vec::new();
    for v in &a.variants {
        variants.push((v.clone(), variant(v, a.seed, a.ms_paths)?));
    }
    if variants.is_empty() {
        bail!("--variants: give at least one");
    }
    let [ws, cs] = crate::args::numbers::<usize, 2>(&a.stitches, "--stitches")?;
    if !(1..=64).contains(&ws) || !(1..=64).contains(&cs) {
        bail!("--stitches {ws},{cs}: each 1..=64 (the reference marches every yarn)");
    }
    let chart = load_chart(&a.chart)?;
    let params = load_yarn(&a.yarn)?;
    let lights: Vec<String> =
        if a.lights.is_empty() { vec!["dir:50,30".into()] } else { a.lights.clone() };
    if lights.len() > yarn_render::view::MAX_LIGHTS {
        bail!("--light given {} times: at most {}", lights.len(), yarn_render::view::MAX_LIGHTS);
    }
    let gpu_lights: Vec<FiberLight> =
        lights.iter().map(|s| fiber_light(s)).collect::<Result<_>>()?;
    let ref_lights: Vec<yarn_ref::Light> =
        lights.iter().map(|s| super::knit::light(s)).collect::<Result<_>>()?;
    let gpu = btf_render::Gpu::new().context("creating a headless GPU device")?;
    guard::output_folder(&a.output, "knit lumislice", a.fresh, &guard::report_output)?;

    // The patch: the Chen skeleton of a flat stitch mesh, no periodic copies (the
    // reference marches exactly the yarns the GPU draws).
    let sk = SkeletonParams::new(params.yarn_radius());
    let (wsp, csp) = sk.default_spacing();
    let mesh = StitchMesh::flat(&chart, ws, cs, wsp, csp)
        .with_context(|| format!("--stitches {ws},{cs} for chart {}", a.chart))?;
    let mut set = chen_skeleton(&mesh, &sk)?;
    set.period = None;
    let grey = a.albedo as f32;
    for c in &mut set.curves {
        c.colors = vec![[grey; 3]; c.points.len()];
    }
    let packed = PackedYarns::new(&set, std::slice::from_ref(&params), &PackOptions::default())?;
    let (lo, hi) = packed.bounds;
    let target = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let view = btf_core::Direction::new(vt, vp).to_vector();
    let cams: Vec<Cam> = a
        .distances
        .iter()
        .map(|&px| {
            let f_px = 0.5 * h as f64 / (0.5 * FOV_DEG.to_radians()).tan();
            let d = wsp * f_px / px;
            let eye = [0, 1, 2].map(|k| target[k] + d * view[k]);
            let up = [0.0, 0.0, 1.0];
            Ok(Cam {
                name: format!("persp-{px}px"),
                reference: yarn_ref::Camera::perspective(eye, target, up, FOV_DEG)?,
                gpu: FiberCamera::perspective(eye, target, up, FOV_DEG),
            })
        })
        .collect::<Result<_>>()?;

    // Tables, cached in DIR/cache (one per distinct table setting).
    let cache = a.output.join("cache");
    let mut tables: Vec<(LumisliceSettings, Lumislice)> = Vec::new();
    for (name, (t, _)) in &variants {
        if tables.iter().any(|(s, _)| s == t) {
            continue;
        }
        let bar =
            crate::progress::bar((t.res * t.res) as u64, &format!("lumislice table ({name})"));
        let l = Lumislice::for_params(&params, [grey; 3], t, Some(&cache), &|n| bar.inc(n))?;
        bar.finish_and_clear();
        eprintln!(
            "lumislice table {name}: {}² → {} levels, {:.1} s{}",
            t.res,
            l.levels.len(),
            l.seconds,
            if l.from_cache { " (cached)" } else { "" }
        );
        tables.push((*t, l));
    }

    // References: single scattering, and with multiple scattering when a variant wants it.
    let want_ms = variants.iter().any(|(_, (t, _))| t.multiple);
    let d0 = &tables[0].0;
    let density = CrossSectionDensity::from_params(
        &params,
        &DensityOptions { res: 64, samples: d0.density_samples, seed: d0.seed, loops: true },
    )?;
    let step = density.cell_size() / 2.0;
    let dens: Arc<dyn SliceDensity> = Arc::new(density);
    let vol = VolumeScene::new(
        &set,
        std::slice::from_ref(&params),
        &[dens],
        ExtinctionLaw::Anisotropic,
        16,
    )?;
    let (wu, hu) = (w as usize, h as usize);
    let mut refs: Vec<[Option<Vec<f32>>; 2]> = Vec::new();
    let bar = crate::progress::bar((cams.len() * (1 + want_ms as usize)) as u64, "references");
    let t_ref = Instant::now();
    for cam in &cams {
        let mut pair = [None, None];
        for (k, ms) in [false, true].into_iter().enumerate() {
            if ms && !want_ms {
                continue;
            }
            let mut vs = VolumeSettings::new(step);
            vs.albedo = a.albedo;
            vs.phase = Phase::KajiyaKay;
            vs.multiple = ms;
            let (img, _) = yarn_ref::volume::render_volume(
                &vol,
                &ref_lights,
                &cam.reference,
                &yarn_ref::RenderSettings::new(wu, hu, a.spp),
                &vs,
            )?;
            let file = format!("ref-{}{}.exr", cam.name, if ms { "-ms" } else { "" });
            write_exr_rgb(&a.output.join(file), wu, hu, &img.rgb)?;
            pair[k] = Some(img.rgb);
            bar.inc(1);
        }
        refs.push(pair);
    }
    bar.finish_and_clear();
    eprintln!("references: {:.1} s", t_ref.elapsed().as_secs_f64());

    // Renderers: per camera the tubes, then every variant.
    let bcsdf = yarn::bcsdf::FiberBcsdf::khungurn(&Default::default())?;
    let tubes = FiberRenderer::new(
        &gpu,
        &packed,
        &bcsdf,
        FiberSettings { tubes: true, lod_px: 0.0, ..FiberSettings::default() },
    )?;
    let mut rens = Vec::new();
    for (name, (t, r)) in &variants {
        let table = &tables.iter().find(|(s, _)| s == t).expect("computed above").1;
        rens.push((
            name.clone(),
            t.multiple,
            LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(table), *r)?,
            table.seconds,
            table.gpu_bytes(),
        ));
    }
    let mut cells = Vec::new();
    let bar = crate::progress::bar(
        (cams.len() * (rens.len() + 1) * (a.repeat as usize + 1)) as u64,
        "GPU cells",
    );
    for (ci, cam) in cams.iter().enumerate() {
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); rens.len() + 1];
        let mut first: Vec<Option<Vec<[f32; 4]>>> = vec![None; rens.len()];
        for rep in 0..=a.repeat {
            let t = Instant::now();
            tubes.render(&gpu, &cam.gpu, &gpu_lights, (w, h), [0.0; 4])?;
            if rep > 0 {
                times[0].push(t.elapsed().as_secs_f64() * 1e3);
            }
            bar.inc(1);
            for (k, (_, _, ren, _, _)) in rens.iter().enumerate() {
                let t = Instant::now();
                let img = ren.render(&gpu, &cam.gpu, &gpu_lights, (w, h), [0.0; 4])?;
                if rep > 0 {
                    times[k + 1].push(t.elapsed().as_secs_f64() * 1e3);
                }
                first[k].get_or_insert(img.pixels);
                bar.inc(1);
            }
        }
        let tubes_ms = median(times[0].clone());
        for (k, (name, ms, ren, table_s, bytes)) in rens.iter().enumerate() {
            let px = first[k].take().expect("rendered");
            let r = refs[ci][*ms as usize].as_ref().expect("reference rendered");
            let (e, ratio) = rel_rmse(&px, r);
            let rgb: Vec<f32> = px.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
            write_exr_rgb(&a.output.join(format!("gpu-{}-{name}.exr", cam.name)), wu, hu, &rgb)?;
            cells.push(Cell {
                camera: cam.name.clone(),
                variant: name.clone(),
                rel_rmse: e,
                mean_ratio: ratio,
                ms: median(times[k + 1].clone()),
                tubes_ms,
                table_s: *table_s,
                bytes: *bytes,
                pieces: ren.pieces(),
                rgb,
                ms_ref: *ms,
            });
        }
    }
    bar.finish_and_clear();

    let mut csv = String::from(
        "camera,variant,rel_rmse,mean_ratio,ms,tubes_ms,ratio_tubes,table_s,table_bytes,pieces\n",
    );
    for c in &cells {
        csv.push_str(&format!(
            "{},{},{:.5},{:.4},{:.2},{:.2},{:.3},{:.2},{},{}\n",
            c.camera,
            c.variant,
            c.rel_rmse,
            c.mean_ratio,
            c.ms,
            c.tubes_ms,
            c.ms / c.tubes_ms,
            c.table_s,
            c.bytes,
            c.pieces
        ));
    }
    write_text(&a.output.join("lumislice.csv"), &csv)?;
    let mut md = format!(
        "# Lumislice: what accuracy costs in time\n\n{} × {} stitches of {} in {}, ϖ = {}, \
         {w} × {h}, the volumetric reference at {} spp (`ms` cells: with multiple \
         scattering). Rel. RMSE over the frame; time as a ratio to the plain tubes of the \
         same camera in the same run (median of {} frames).\n\n\
         | camera | variant | rel. RMSE | mean / ref | × tubes | table s | table MB |\n\
         |---|---|---|---|---|---|---|\n",
        ws, cs, a.chart, params.name, a.albedo, a.spp, a.repeat
    );
    for c in &cells {
        md.push_str(&format!(
            "| {} | {} | {:.4} | {:.3} | {:.2} | {:.1} | {:.1} |\n",
            c.camera,
            c.variant,
            c.rel_rmse,
            c.mean_ratio,
            c.ms / c.tubes_ms,
            c.table_s,
            c.bytes as f64 / 1e6
        ));
    }
    let series = cams
        .iter()
        .map(|cam| Series {
            name: cam.name.clone(),
            points: cells
                .iter()
                .filter(|c| c.camera == cam.name)
                .map(|c| (c.ms / c.tubes_ms, c.rel_rmse))
                .collect(),
            labels: cells
                .iter()
                .filter(|c| c.camera == cam.name)
                .map(|c| c.variant.clone())
                .collect(),
            points_only: true,
        })
        .collect();
    let plot = Plot {
        title: "lumislice: error against time".into(),
        x_label: "frame time / plain tubes".into(),
        y_label: "rel. RMSE against the volumetric reference".into(),
        log_x: true,
        series,
        ..Default::default()
    };
    write_png(&a.output.join("lumislice.png"), &render(&plot))?;
    for (ci, cam) in cams.iter().enumerate() {
        let sheet = contact_sheet(&cells, &cam.name, &refs[ci], (w, h));
        write_png(&a.output.join(format!("sheet-{}.png", cam.name)), &sheet)?;
        md.push_str(&format!("\n![{0}](sheet-{0}.png)\n", cam.name));
    }
    write_text(&a.output.join("lumislice.md"), &md)?;
    outln!("{md}");
    outln!("written to {}", a.output.join("lumislice.md").display());
    Ok(())
}

/// One camera: the references and every variant (exposed so the reference's mean is 18 %
/// grey), each variant's error heat map below it (full scale = the reference's mean).
fn contact_sheet(
    cells: &[Cell],
    camera: &str,
    refs: &[Option<Vec<f32>>; 2],
    (w, h): (u32, u32),
) -> image::RgbImage {
    use btf_image::compose::{captioned_strip, stacked, upscale};
    let r0 = refs[0].as_deref().unwrap_or(&[]);
    let mean = r0.iter().map(|v| *v as f64).sum::<f64>() / r0.len().max(1) as f64;
    let exposure = if mean > 0.0 { (0.18 / mean) as f32 } else { 1.0 };
    let to = |rgb: &[f32]| {
        let img = image::RgbImage::from_raw(w, h, btf_image::write::to_srgb8(rgb, exposure))
            .expect("w × h RGB");
        upscale(&img, 160)
    };
    let mut top: Vec<(image::RgbImage, String)> = vec![(to(r0), "reference".into())];
    let mut bottom: Vec<(image::RgbImage, String)> = vec![(
        upscale(&image::RgbImage::from_pixel(w, h, image::Rgb([255; 3])), 160),
        String::new(),
    )];
    if let Some(r1) = &refs[1] {
        top.push((to(r1), "reference + MS".into()));
        bottom.push((bottom[0].0.clone(), String::new()));
    }
    for c in cells.iter().filter(|c| c.camera == camera) {
        let r = refs[c.ms_ref as usize].as_deref().unwrap_or(r0);
        top.push((to(&c.rgb), c.variant.clone()));
        let heat = btf_image::heatmap::error_heatmap_image(
            w as usize,
            h as usize,
            r,
            &c.rgb,
            mean.max(1e-9) as f32,
            None,
        );
        bottom.push((upscale(&heat, 160), format!("{:.3}", c.rel_rmse)));
    }
    let row = |v: &[(image::RgbImage, String)]| {
        let refs: Vec<(&image::RgbImage, &str)> = v.iter().map(|(i, s)| (i, s.as_str())).collect();
        captioned_strip(&refs, 4)
    };
    stacked(&[&row(&top), &row(&bottom)], 4)
}
