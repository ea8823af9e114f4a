//! `btf knit render`: the real-time fiber renderer of `yarn-render` ([W19]: fibers
//! generated on the GPU from yarn control points every frame, LoD [W19 eq. 4], fiber BCSDF)
//! on a chart patch or BCC yarn curves, with the cameras, lights and image outputs of
//! `btf knit ref`, so that the two render the same scene and `--compare` can score one
//! against the other.

use super::knit::{
    PatchArgs, ShadingChoice, chart_inputs, ext, light, load_chart, load_yarn, rgb, stitches,
};
use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::PathBuf;
use yarn::bcsdf::{FiberBcsdf, HuangParams, KhungurnParams, SimpleParams};
use yarn::knit::{SkeletonParams, StitchMesh, chen_skeleton};
use yarn_render::{
    AoMode, FiberCamera, FiberEffects, FiberLight, FiberRenderer, FiberSettings, PackOptions,
    PackedYarns,
};

/// `--min-strip-px` and `--supersample` of `knit render` and `knit sweep`, refused naming
/// the flag.
pub(crate) fn check_sampling(min_strip_px: f32, supersample: u32) -> Result<()> {
    if !(min_strip_px.is_finite() && min_strip_px >= 0.0) {
        bail!("--min-strip-px {min_strip_px}: a width ≥ 0 pixels");
    }
    if !(1..=yarn_render::MAX_SUPERSAMPLE).contains(&supersample) {
        bail!(
            "--supersample {supersample}: 1..={} frames a pixel side",
            yarn_render::MAX_SUPERSAMPLE
        );
    }
    Ok(())
}

/// `btf knit render`.
#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub patch: PatchArgs,
    /// Render these BCC yarn curves instead of a chart patch.
    #[arg(long)]
    pub bcc: Option<PathBuf>,
    /// Camera: btf:THETA,PHI (the BTF's oblique orthographic view of one period) or
    /// persp:EX,EY,EZ,TX,TY,TZ,FOV_DEG (metres).
    #[arg(long, default_value = "btf:0,0")]
    pub camera: String,
    /// Directional light dir:THETA,PHI[,E] or point light point:X,Y,Z,I (repeatable, ≤ 8).
    #[arg(long = "light")]
    pub lights: Vec<String>,
    /// Fiber scattering (the GPU has no Lambert mode).
    #[arg(long, default_value = "khungurn")]
    pub shading: ShadingChoice,
    /// Yarn colour R,G,B (linear).
    #[arg(long)]
    pub albedo: Option<String>,
    /// Image size W,H.
    #[arg(long, default_value = "256,256")]
    pub size: String,
    /// LoD threshold ω^LoD in pixels (0: LoD off, every fiber of every segment).
    #[arg(long, default_value_t = 1.0)]
    pub lod_px: f32,
    /// Fibers per ply at full detail (default: all of the yarn's).
    #[arg(long)]
    pub n_max: Option<u32>,
    /// Subdivisions per yarn segment at full detail (≤ 255).
    #[arg(long, default_value_t = 8)]
    pub n_sub: u32,
    /// MSAA samples (1 or 4).
    #[arg(long, default_value_t = 4)]
    pub msaa: u32,
    /// No frustum culling (for checking that culling changes nothing).
    #[arg(long)]
    pub no_cull: bool,
    /// No core strips: every fiber explicit (LoD then drops the innermost fibers).
    #[arg(long)]
    pub no_core: bool,
    /// No shadow hiding (the light = view hot spot) in the self-shadows.
    #[arg(long)]
    pub no_shadow_hiding: bool,
    /// Self-shadows marched through the twisted yarn instead of [W19]'s slices (slower).
    #[arg(long)]
    pub helix_shadows: bool,
    /// No self-shadows inside the yarns (the precomputed volume, [W19 §4.1]).
    #[arg(long)]
    pub no_self_shadow: bool,
    /// No shadows of other yarns (tube shadow maps of directional lights).
    #[arg(long)]
    pub no_yarn_shadows: bool,
    /// Shadows of every fiber: each delta light's map drawn from the fibers themselves,
    /// fitted to the seen part of the yarns, instead of tubes and the self-shadow volume
    /// (one more fiber pass per light; `--shadow-map` texels across what the camera sees).
    #[arg(long)]
    pub fiber_shadows: bool,
    /// Side of the shadow maps in texels (16..=8192).
    #[arg(long, default_value_t = 1024)]
    pub shadow_map: u32,
    /// Strips narrower than this many pixels are widened to it and keep their coverage as
    /// a hashed sample mask (0: every strip at its true width, sampled exactly).
    #[arg(long, default_value_t = 1.0)]
    pub min_strip_px: f32,
    /// Frames per pixel side (1..=16): the fibers drawn K × K times larger and
    /// box-filtered, K²·MSAA samples a pixel (--lod-px and --min-strip-px stay in output
    /// pixels).
    #[arg(long, default_value_t = 1)]
    pub supersample: u32,
    /// Ambient occlusion inside the yarns [W19 §4.2].
    #[arg(long, default_value = "cubic")]
    pub ao: AoChoice,
    /// Constant environment radiance R,G,B for the ambient term [W19 eq. 7] (default none).
    #[arg(long)]
    pub ambient: Option<String>,
    /// Environment map (equirectangular EXR/HDR), optionally ,SCALE, as `btf knit ref --env`
    /// takes it: fitted by --srbfs SRBF lobes, each with its tube shadow map ([H25 eq. 14–17]
    /// at every fiber's own tangent); replaces --ambient.
    #[arg(long)]
    pub env: Option<String>,
    /// SRBF lobes of the --env fit (1..=32).
    #[arg(long, default_value_t = 16)]
    pub srbfs: usize,
    /// Directory of the precomputation cache (core texture, self-shadow volume, AO).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// A chart patch alone instead of its 3 × 3 periodic neighbourhood.
    #[arg(long)]
    pub no_wrap: bool,
    /// Score the render against this image of the same size (e.g. from `btf knit ref`):
    /// relative RMSE over the frame and the ratio of mean radiances.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
    /// Renderer: GPU fibers [W19] or lumislices [C03 §5] (the scattering table computed
    /// once, cached in --cache; the fiber options do not apply).
    #[arg(long, default_value = "fibers")]
    pub method: RenderMethod,
}

crate::args::choices! {
    /// `btf knit render --method`.
    RenderMethod {
        /// Fibers generated on the GPU every frame.
        Fibers = "fibers",
        /// Ray-marched lumislice pieces (4× MSAA, point and directional lights).
        Lumislice = "lumislice",
    }
}

crate::args::choices! {
    /// `btf knit render --ao`: how ambient occlusion is computed.
    AoChoice {
        /// None.
        Off = "off",
        /// [W19]'s distance cubic (its default).
        Cubic = "cubic",
        /// The stratified 2-D texture over the cross-section.
        Texture = "texture",
    }
}

pub(crate) fn bcsdf(name: &str) -> Result<FiberBcsdf> {
    Ok(match name {
        "khungurn" => FiberBcsdf::khungurn(&KhungurnParams::default())?,
        "simple" => FiberBcsdf::simple(&SimpleParams::default())?,
        "huang" => FiberBcsdf::huang(&HuangParams::default())?,
        other => bail!("--shading {other}: the GPU fiber renderer takes khungurn, simple or huang"),
    })
}

pub(crate) fn fiber_light(s: &str) -> Result<FiberLight> {
    Ok(match light(s)? {
        yarn_ref::Light::Directional { to_light, irradiance } => {
            FiberLight::Directional { to_light, irradiance }
        }
        yarn_ref::Light::Point { position, intensity } => FiberLight::Point { position, intensity },
        yarn_ref::Light::Environment(_) => bail!("--light '{s}': no environment light here"),
    })
}

fn camera(
    s: &str,
    period: Option<[f64; 2]>,
    bounds: ([f64; 3], [f64; 3]),
    z_ref: f64,
) -> Result<FiberCamera> {
    let bad =
        || anyhow::anyhow!("--camera '{s}': expected btf:THETA,PHI or persp:EX,EY,EZ,TX,TY,TZ,FOV");
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
        ("btf", 2) => {
            let view = btf_core::Direction::new(v[0], v[1]).to_vector();
            let (origin, extent) = match period {
                Some(p) => ([0.0, 0.0], p),
                None => {
                    let (lo, hi) = bounds;
                    ([lo[0], lo[1]], [hi[0] - lo[0], hi[1] - lo[1]])
                }
            };
            Ok(FiberCamera::oblique(view, z_ref, origin, extent))
        }
        ("persp", 7) => Ok(FiberCamera::perspective(
            [v[0], v[1], v[2]],
            [v[3], v[4], v[5]],
            [0.0, 0.0, 1.0],
            v[6],
        )),
        _ => Err(bad()),
    }
}

/// Runs `btf knit render`.
pub fn run(a: RenderArgs) -> Result<()> {
    let Some(image) = a.patch.output.clone() else {
        bail!("give the image with -o OUT.exr|OUT.png")
    };
    let mut inputs = chart_inputs(&a.patch);
    if let Some(b) = &a.bcc {
        inputs.push(("bcc", b.as_path()));
    }
    if let Some(c) = &a.compare {
        inputs.push(("compare", c.as_path()));
    }
    let env_path = a.env.as_deref().map(|e| PathBuf::from(e.split(',').next().unwrap_or(e)));
    if let Some(e) = &env_path {
        inputs.push(("env", e.as_path()));
    }
    guard::refuse_overlap(&[("-o", &image)], &inputs)?;
    if a.env.is_some() && a.method == RenderMethod::Lumislice {
        bail!(
            "--env: the lumislices take point and directional lights only ([C03] has no environment)"
        );
    }
    if a.supersample != 1 && a.method == RenderMethod::Lumislice {
        bail!("--supersample {}: the fibers' option (--method fibers)", a.supersample);
    }
    if !(1..=yarn_render::strips::MAX_SRBFS).contains(&a.srbfs) {
        bail!("--srbfs {}: 1..={}", a.srbfs, yarn_render::strips::MAX_SRBFS);
    }
    let kind = match ext(&image).as_str() {
        "exr" => btf_core::fs::EXR,
        "png" => btf_core::fs::PNG,
        e => bail!("{}: unknown image extension '{e}' (exr or png)", image.display()),
    };
    guard::check_file(&image, kind)?;
    let [w, h] = crate::args::numbers::<u32, 2>(&a.size, "--size")?;
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        bail!("--size {w},{h}: each side must be 1..=8192");
    }
    if a.msaa != 1 && a.msaa != 4 {
        bail!("--msaa {}: 1 or 4", a.msaa);
    }
    let params = load_yarn(&a.patch.yarn)?;
    let color = rgb(&a.albedo, "--albedo")?;
    let t0 = std::time::Instant::now();
    let (mut set, z_ref) = if let Some(b) = &a.bcc {
        let set = yarn::io::read_bcc(b)?.set;
        let (_, hi) = yarn_ref::patch::centre_line_z(&set);
        (set, hi + params.yarn_radius())
    } else {
        let chart = load_chart(&a.patch.chart)?;
        let [wales, courses] = stitches(&a.patch.stitches)?.unwrap_or([chart.width, chart.height]);
        let sk = SkeletonParams::new(params.yarn_radius());
        let (ws, cs) = sk.default_spacing();
        let set = chen_skeleton(&StitchMesh::flat(&chart, wales, courses, ws, cs)?, &sk)?;
        let (_, hi) = yarn_ref::patch::centre_line_z(&set);
        (set, hi + params.yarn_radius())
    };
    if let Some(c) = color {
        let c = c.map(|x| x as f32);
        for curve in &mut set.curves {
            curve.colors = vec![c; curve.points.len()];
        }
    }
    let period = set.period;
    let tiles = if period.is_some() && !a.no_wrap { [3, 3] } else { [1, 1] };
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&params),
        &PackOptions { seed: a.patch.seed, frame_samples_per_segment: 16, tiles },
    )?;
    let pack_s = t0.elapsed().as_secs_f64();
    let lights: Vec<FiberLight> = a.lights.iter().map(|s| fiber_light(s)).collect::<Result<_>>()?;
    let env = a.env.as_deref().map(super::knit_sweep::env_map).transpose()?;
    if lights.is_empty() && env.is_none() {
        bail!("no light: give --light dir:THETA,PHI, --light point:X,Y,Z,I or --env FILE");
    }
    let cam = camera(&a.camera, period, packed.bounds, z_ref)?;
    let ambient = match &a.ambient {
        Some(s) => {
            let v = crate::args::numbers::<f32, 3>(s, "--ambient")?;
            if !v.iter().all(|x| x.is_finite() && *x >= 0.0) {
                bail!("--ambient '{s}': three finite values ≥ 0");
            }
            v
        }
        None => [0.0; 3],
    };
    let effects = FiberEffects {
        core: !a.no_core,
        shadow_hiding: !a.no_shadow_hiding,
        helix_shadows: a.helix_shadows,
        self_shadow: !a.no_self_shadow,
        yarn_shadows: !a.no_yarn_shadows,
        fiber_shadows: a.fiber_shadows,
        ao: match a.ao {
            AoChoice::Off => AoMode::Off,
            AoChoice::Cubic => AoMode::Cubic,
            AoChoice::Texture => AoMode::Texture,
        },
        ambient,
    };
    if !(16..=8192).contains(&a.shadow_map) {
        bail!("--shadow-map {}: the maps' side must be 16..=8192 texels", a.shadow_map);
    }
    if a.fiber_shadows && a.no_yarn_shadows {
        bail!(
            "--fiber-shadows draws the yarn shadows from every fiber; --no-yarn-shadows turns them off"
        );
    }
    check_sampling(a.min_strip_px, a.supersample)?;
    let settings = FiberSettings {
        effects,
        n_max: a.n_max.unwrap_or(u32::MAX),
        n_sub: a.n_sub,
        lod_px: a.lod_px,
        cull: !a.no_cull,
        msaa: a.msaa,
        hairs: !a.patch.no_hairs,
        shadow_map: a.shadow_map,
        min_strip_px: a.min_strip_px,
        supersample: a.supersample,
        ..FiberSettings::default()
    };
    let gpu = btf_render::Gpu::new()?;
    let (img, render_s) = match a.method {
        RenderMethod::Fibers => {
            let b = bcsdf(a.shading.as_str())?;
            let mut renderer = FiberRenderer::with_bake(
                &gpu,
                &packed,
                &b,
                settings,
                &yarn_precompute::BakeSettings { seed: a.patch.seed, ..Default::default() },
                a.cache.as_deref(),
            )?;
            if let Some(map) = &env {
                let fit = yarn_precompute::SrbfFit::fit(map, a.srbfs)?;
                let table = yarn_precompute::ImTable::build(&b, fit.lambda)?;
                renderer.set_environment(&gpu, Some((&fit, &table)))?;
                eprintln!(
                    "environment: {} SRBFs ({} of non-zero weight), λ {:.2}, fit error {:.3}, \
                     power ratio {:.3}",
                    fit.centres.len(),
                    renderer.srbf_lobes(),
                    fit.lambda,
                    fit.rel_error,
                    fit.power_ratio[1]
                );
            }
            let t1 = std::time::Instant::now();
            let img = renderer.render(&gpu, &cam, &lights, (w, h), [0.0, 0.0, 0.0, 0.0])?;
            (img, t1.elapsed().as_secs_f64())
        }
        RenderMethod::Lumislice => {
            // The table in the yarn's colour (ϖ), from the first curve.
            let albedo = yarn_render::lumislice::table_albedo(&set);
            let table = yarn_precompute::Lumislice::for_params(
                &params,
                albedo,
                &yarn_precompute::LumisliceSettings { seed: a.patch.seed, ..Default::default() },
                a.cache.as_deref(),
                &|_| {},
            )?;
            let rs = yarn_render::LumisliceRenderSettings {
                shadows: !a.no_yarn_shadows,
                ..Default::default()
            };
            let renderer = yarn_render::LumisliceRenderer::new(
                &gpu,
                &packed,
                std::slice::from_ref(&table),
                rs,
            )?;
            let t1 = std::time::Instant::now();
            let img = renderer.render(&gpu, &cam, &lights, (w, h), [0.0, 0.0, 0.0, 0.0])?;
            (img, t1.elapsed().as_secs_f64())
        }
    };
    let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let (wu, hu) = (w as usize, h as usize);
    match ext(&image).as_str() {
        "exr" => btf_image::write::write_exr_rgb(&image, wu, hu, &rgb)?,
        _ => btf_image::write::write_png_linear(&image, wu, hu, &rgb, 1.0)?,
    }
    let coverage: f64 = img.pixels.iter().map(|p| p[3] as f64).sum::<f64>() / (wu * hu) as f64;
    let rel_rmse = match &a.compare {
        Some(path) => {
            let (rw, rh, r) = btf_image::envmap::read_linear_rgb(path)
                .with_context(|| format!("reading --compare {}", path.display()))?;
            let r: Vec<f32> = r.into_iter().flatten().collect();
            if (rw, rh) != (wu, hu) {
                bail!("--compare {}: {rw} × {rh}, but the render is {w} × {h}", path.display());
            }
            let (mut num, mut den) = (0.0, 0.0);
            for (x, y) in rgb.iter().zip(&r) {
                num += (*x as f64 - *y as f64).powi(2);
                den += (*y as f64).powi(2);
            }
            let sum = |v: &[f32]| v.iter().map(|x| *x as f64).sum::<f64>();
            let ratio = sum(&rgb) / sum(&r);
            Some((if den > 0.0 { (num / den).sqrt() } else { f64::NAN }, ratio))
        }
        None => None,
    };
    let (rel_rmse, mean_ratio) = (rel_rmse.map(|r| r.0), rel_rmse.map(|r| r.1));
    let st = img.stats;
    if a.json {
        let j = serde_json::json!({
            "image": image, "method": a.method.as_str(), "width": w, "height": h,
            "lod_px": a.lod_px, "n_sub": a.n_sub, "supersample": a.supersample,
            "msaa": a.msaa, "segments": st.segments, "culled": st.culled,
            "instances": st.instances, "hairs": st.hairs, "overflow": st.overflow,
            "shadow_instances": st.shadow_instances, "fiber_shadows": a.fiber_shadows,
            "triangles": st.triangles,
            "yarn_bytes": st.yarn_bytes, "bytes_per_control_point":
                st.yarn_bytes as f64 / packed.control_points().max(1) as f64,
            "pack_seconds": pack_s, "render_seconds": render_s, "coverage": coverage,
            "mean_radiance": rgb.iter().map(|v| *v as f64).sum::<f64>() / rgb.len() as f64,
            "rel_rmse": rel_rmse, "mean_ratio": mean_ratio, "adapter": gpu.info.name,
        });
        outln!("{}", serde_json::to_string_pretty(&j)?);
    }
    eprintln!(
        "knit render: {} segments ({} culled), {} {}, {} triangles, {:.2} s{} -> {}",
        st.segments,
        st.culled,
        st.instances,
        if a.method == RenderMethod::Lumislice { "lumislice pieces" } else { "fiber instances" },
        st.triangles,
        render_s,
        rel_rmse.map(|r| format!(", rel. RMSE {r:.4} against --compare")).unwrap_or_default(),
        image.display()
    );
    if st.overflow > 0 {
        eprintln!(
            "warning: {} fiber instances did not fit the list and were not drawn",
            st.overflow
        );
    }
    Ok(())
}
