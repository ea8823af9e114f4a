//! `btf knit compare [--btf YARN.btf] [--stretch 0,0.1,…] -o DIR`: the headline study of
//! DESIGN §4.2 (issue #19's first comparison table, issue #21's final one) — one knit
//! garment, three camera distances, every representation scored against the path-traced
//! fibers, at rest and stretched. Without `--btf` the study first makes the yarn BTF by
//! the reference itself (resumable), so the whole study is one command:
//!
//! - **R0** the reference: the explicit fibers of the whole garment path traced by
//!   `yarn-ref` (the same yarn, chart, seed, flyaways, Khungurn BCSDF and bounces that
//!   made the yarn BTF), and **R0-direct**, one bounce, which the real-time methods model
//!   (the gap between the two is the multiple-scattering gap, reported separately);
//! - **R1** [W19]'s fibers on the GPU (`yarn-render`) at full detail and at
//!   ω^LoD ∈ `--lod` ([W19 eq. 4]);
//! - **R2** [H25]'s yarn strips (`yarn_render::strips`, textures baked once from a
//!   straight yarn of the same parameters and cached in `DIR/bake-cache`; with the flyaway
//!   overlay when the BTF's yarn has hair flyaways);
//! - **R3** [C03]'s lumislices (`yarn_render::lumislice`, the scattering table computed
//!   once for the yarn's colour and cached in `DIR/bake-cache`): a Kajiya–Kay volume, not
//!   the fibers' BCSDF, so its error holds the model's difference as well as the method's;
//! - **R4** the BTF on the garment: the yarn BTF made by the reference
//!   (`btf synth material --kind yarn`), compressed per view ([S03]'s PCA) to each
//!   `--components`, rendered by `btf-render` per pixel with four-light/four-view blending
//!   and shadow maps; and **R4 from fibers**, the same patch, sampling and store rendered
//!   by R1's GPU fibers instead (`yarn_render::btf`, at `--btf-fibers-lod`), compressed to
//!   the largest c — the BTF a lab gets in minutes instead of the reference's hour;
//! - **R5** the baselines: the plain texture of the BTF mean (`btf-render`'s `plain`
//!   baseline) and plain tubes of the yarn radius (`yarn-render`).
//!
//! The garment is `datasets`' drape (a cloth dropped over a sphere) scaled so that its
//! `--wales` stitches have the yarn's natural spacing; the chart is laid out on it through
//! its UVs ([`yarn::knit::StitchMesh::on_surface`]), courses running *down* the texture
//! (towards increasing texture rows) so that the BTF's rows (`+y` = courses of the flat
//! patch, DESIGN §3) and the yarns on the garment are the same map. That map is a
//! reflection of the flat patch (`+u` × rows points into the cloth), applied to the yarns'
//! loops and to the BTF alike; only the plies' twist, which the fiber generator builds in
//! each curve's right-handed frame, keeps its chirality on the garment while the BTF shows
//! it mirrored — a highlight-orientation difference at close range that no choice of UV
//! direction avoids under DESIGN §3's tangent frame. To fill the cloth with whole courses
//! the stitch aspect changes by less than `chart.height / courses` (for yarns and BTF
//! alike). The cameras look at the UV centre along `--view` from where a stitch covers
//! `--distances` pixels. The reference BTF has `S` texels per period (the study asks for
//! `S = 64`; the one measured has 32): at 40 px per stitch it is magnified ~5×.
//!
//! Per cell ([`super::knit_compare_report`]): rel. RMSE `√(Σ(x−r)²/Σr²)` on the interior
//! mask (the garment's rasterised silhouette eroded by the yarn reach) and on the
//! silhouette band (dilated minus eroded), the mean-radiance ratio, mean HDR-ꟻLIP
//! (`[A21]`, `btf_image::flip`) on both masks with the exposure range taken from the
//! reference's interior pixels (the black background would make the frame's median 0 and
//! the range of `[A21]` undefined), at the default 67 pixels per degree; the median GPU frame
//! time as a ratio to the plain texture drawn in the same run, preprocessing seconds and
//! memory, and whether the representation follows deformation. Writes `compare.csv`,
//! `report.md`, `pareto.png`, per-distance contact sheets, every image as EXR and a ꟻLIP heat
//! map per cell (`images/flip-*.png`). With `--stretch` each strain's study goes into
//! `stretch-S/`, and the top folder gets the final table over every strain (`report.md`:
//! ꟻLIP and rel. RMSE per strain, frame-time ratio, preprocessing, memory, whether it
//! follows deformation), `pareto-*px.png` (ꟻLIP against frame time, one series per strain)
//! and the stretch summary (`stretch.md`, `stretch.csv`, `stretch-*px.png`).

use super::knit_compare_report::{self as report, Cell, Distance, Scores};
use super::knit_render::fiber_light;
use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use btf_core::compress::CompressParams;
use btf_core::eigen::Quantization;
use btf_core::store::BtfStore;
use btf_core::zarr::DType;
use btf_image::write::{write_exr_rgb, write_png, write_text};
use clap::Args;
use datasets::mesh::{Mesh, MeshKind, Resolution};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::fiber::{GenOptions, generate_fibers};
use yarn::knit::{
    Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh, SurfaceMesh, UvLayout, chen_skeleton,
};
use yarn::params::YarnParams;
use yarn_ref::btf::{YarnBtfOptions, YarnBtfSpec};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

/// `btf knit compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// The yarn BTF made by the reference (`btf synth material --kind yarn`): its
    /// provenance gives the chart, yarn, seed, colour, flyaways and bounces of every
    /// representation. Without it the study makes one into `DIR/btf-reference.btf` from
    /// `--chart`, `--yarn`, `--btf-size`, `--btf-spp`, `--btf-bounces` and
    /// `--btf-sampling` (resumed when the folder has an unfinished one): the whole study
    /// is then one command.
    #[arg(long)]
    pub btf: Option<PathBuf>,
    /// Chart of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf")]
    pub chart: Option<String>,
    /// Yarn of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf")]
    pub yarn: Option<String>,
    /// Texels per period of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf", default_value_t = 32)]
    pub btf_size: usize,
    /// Samples per texel of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf", default_value_t = 16)]
    pub btf_spp: u32,
    /// Path vertices of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf", default_value_t = 8)]
    pub btf_bounces: u32,
    /// View and light sampling of the BTF the study makes (only without `--btf`).
    #[arg(long, conflicts_with = "btf", default_value = "ubo81")]
    pub btf_sampling: String,
    /// Leave out R4 from fibers: the same BTF (patch, sampling, size, seed) rendered by the
    /// GPU fibers instead of the path tracer (`DIR/btf-fibers.btf`, resumed like the
    /// reference's), compressed to the largest `--components` and drawn on the garment.
    #[arg(long)]
    pub no_btf_fibers: bool,
    /// LoD threshold ω^LoD (px) of the GPU fibers that render the BTF from fibers: 1 (the
    /// renderer's and `btf synth material --method fibers`' default) draws a 32² BTF's
    /// fibers as core strips at 0.17 s an image; 0 (full detail, every fiber) costs 2.8 s an
    /// image here, 5 h for `ubo81` (BENCHMARKS.md).
    #[arg(long, default_value_t = 1.0)]
    pub btf_fibers_lod: f32,
    /// Output folder (compare.csv, report.md, pareto.png, sheet-*.png, images/).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// Wales across the garment (a multiple of the chart's width); the courses follow
    /// from the yarn's spacing and the garment's shape.
    #[arg(long, default_value_t = 32)]
    pub wales: usize,
    /// Image size W,H.
    #[arg(long, default_value = "128,128")]
    pub size: String,
    /// Camera distances as the on-screen width of a stitch at the target, in pixels.
    #[arg(long, value_delimiter = ',', default_value = "40,8,2")]
    pub distances: Vec<f64>,
    /// Viewing direction THETA,PHI (degrees, from the target towards the camera).
    #[arg(long, default_value = "35,250")]
    pub view: String,
    /// The directional light dir:THETA,PHI[,E] (perpendicular irradiance E, default 1).
    #[arg(long, default_value = "dir:40,300")]
    pub light: String,
    /// Samples per pixel of the reference.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// LoD thresholds ω^LoD of the GPU fibers in pixels (0 = full detail, always drawn).
    #[arg(long, value_delimiter = ',', default_value = "0.5,1,2")]
    pub lod: Vec<f32>,
    /// PCA components of the BTF on the garment.
    #[arg(long, value_delimiter = ',', default_value = "4,8,16,32")]
    pub components: Vec<usize>,
    /// Timed frames per GPU cell (interleaved; the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeat: u32,
    /// The stretch study (DESIGN §4.2, issue #20): engineering strains along the wales
    /// (e.g. 0,0.1,0.2,0.3,0.5). Each strain stretches the garment, moves its yarns by the
    /// knot solver ([`yarn::knit::knot`], 3 Gauss–Newton iterations) and runs the whole
    /// study into `stretch-S/`; `stretch.csv`, `stretch.md` and `stretch-*.png` compare the
    /// errors against the strain. Without it: the rest garment with the Chen skeleton.
    #[arg(long, value_delimiter = ',')]
    pub stretch: Vec<f64>,
    /// Camera rays per texel of the yarn strips' bake (R2).
    #[arg(long, default_value_t = 16)]
    pub bake_spp: u32,
    /// Replace an output folder a previous compare wrote.
    #[arg(long)]
    pub fresh: bool,
}

/// Field of view of every camera (degrees, vertical).
const FOV_DEG: f64 = 30.0;

/// What the yarn BTF was made from, read back from its provenance.
struct BtfSource {
    chart: Chart,
    chart_source: String,
    params: YarnParams,
    stitches: [usize; 2],
    sampling: btf_core::Sampling,
    seed: u64,
    hairs: bool,
    bounces: u32,
    color: [f32; 3],
    bcsdf: FiberBcsdf,
    size: usize,
}

fn btf_source(path: &Path) -> Result<BtfSource> {
    let store =
        BtfStore::open(path).with_context(|| format!("opening --btf {}", path.display()))?;
    let p = &store.meta().provenance;
    let field = |k: &str| {
        p.get(k).ok_or_else(|| {
            anyhow::anyhow!("--btf {}: provenance has no '{k}' (not a yarn BTF?)", path.display())
        })
    };
    let text = |k: &str| -> Result<String> {
        field(k)?.as_str().map(str::to_owned).ok_or_else(|| {
            anyhow::anyhow!("--btf {}: provenance '{k}' is not text", path.display())
        })
    };
    if text("kind")? != "yarn" {
        bail!("--btf {}: provenance kind is not 'yarn'", path.display());
    }
    if text("method")? != "reference" {
        bail!(
            "--btf {}: made by '{}', but the study needs the reference's BTF (R4 is scored \
             against the reference that made it)",
            path.display(),
            text("method")?
        );
    }
    let chart_text = field("chart")?.get("text").and_then(|t| t.as_str()).ok_or_else(|| {
        anyhow::anyhow!("--btf {}: provenance 'chart.text' missing", path.display())
    })?;
    let chart = Chart::parse(chart_text, "the BTF's provenance")?;
    let chart_source =
        field("chart")?.get("source").and_then(|t| t.as_str()).unwrap_or(&chart.name).to_owned();
    let stitches: Vec<usize> = field("stitches")?
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_u64()).map(|v| v as usize).collect())
        .unwrap_or_default();
    let [sw, sc] = stitches[..] else {
        bail!("--btf {}: provenance 'stitches' is not two counts", path.display());
    };
    let meta = store.meta();
    if meta.view_sampling != meta.light_sampling {
        bail!("--btf {}: view and light samplings differ (a yarn BTF has one)", path.display());
    }
    let yarn_text = field("yarn")?.get("params").and_then(|t| t.as_str()).ok_or_else(|| {
        anyhow::anyhow!("--btf {}: provenance 'yarn.params' missing", path.display())
    })?;
    let params = YarnParams::from_toml(yarn_text, "the BTF's provenance")?;
    let num = |k: &str| -> Result<f64> {
        field(k)?.as_f64().ok_or_else(|| {
            anyhow::anyhow!("--btf {}: provenance '{k}' is not a number", path.display())
        })
    };
    let color: Vec<f64> = field("color")?
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
        .unwrap_or_default();
    if color.len() != 3 {
        bail!("--btf {}: provenance 'color' is not three numbers", path.display());
    }
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default())?;
    let expected = yarn_ref::Shading::Fiber { bcsdf: Arc::new(bcsdf.clone()), tint: true }.name();
    if text("shading")? != expected {
        bail!(
            "--btf {}: shading '{}', but the GPU fibers model '{expected}' only",
            path.display(),
            text("shading")?
        );
    }
    Ok(BtfSource {
        chart,
        chart_source,
        params,
        stitches: [sw, sc],
        sampling: meta.view_sampling.clone(),
        seed: num("seed")? as u64,
        hairs: field("hairs")?.as_bool().unwrap_or(true),
        bounces: num("bounces")? as u32,
        color: [color[0] as f32, color[1] as f32, color[2] as f32],
        bcsdf,
        size: num("size")? as usize,
    })
}

/// The knit garment: the drape scaled to the stitches, its UVs in periods of the chart
/// (`uv_scale = 1` tiles the BTF once per period), and its yarn curves.
struct Garment {
    mesh: Mesh,
    yarns: yarn::curve::YarnSet,
    wales: usize,
    courses: usize,
    /// Wale spacing (metres), the unit of the camera distances.
    ws: f64,
    /// UV centre: point and normal.
    centre: ([f64; 3], [f64; 3]),
    /// Minimum distance between different courses' centre lines / 2r.
    clearance: f64,
}

fn garment(src: &BtfSource, wales: usize, stretch: Option<f64>) -> Result<Garment> {
    let chart = &src.chart;
    let r = src.params.yarn_radius();
    let mut sk = SkeletonParams::new(r);
    sk.color = src.color;
    let (ws, cs) = sk.default_spacing();
    let mut mesh = datasets::synth_mesh(MeshKind::Drape, Resolution::High)?;
    let (lo, hi) = uv_bounds(&mesh);
    // The drape is 1 m of cloth per unit of UV; scale it so `wales` stitches span u.
    let s = wales as f64 * ws / (hi[0] - lo[0]);
    for p in &mut mesh.positions {
        *p = p.map(|x| x * s);
    }
    let courses_f = s * (hi[1] - lo[1]) / cs;
    let courses = ((courses_f / chart.height as f64).floor() as usize).max(1) * chart.height;
    // Courses from the top of the texture down: +course = increasing texture row.
    let layout = UvLayout {
        origin: [lo[0], hi[1]],
        wale_du: (hi[0] - lo[0]) / wales as f64,
        // Whole courses over the whole cloth: the stitch aspect changes by < chart.height /
        // courses (under 12 % at 32 wales), the same for the yarns and the BTF.
        course_dv: -(hi[1] - lo[1]) / courses as f64,
        wales,
        courses,
    };
    let surface = surface_of(&mesh);
    let centre_uv = [
        lo[0] + 0.5 * wales as f64 * layout.wale_du,
        hi[1] + 0.5 * courses as f64 * layout.course_dv,
    ];
    let rest_stitches = StitchMesh::on_surface(&surface, chart, &layout)?;
    let (surface, yarns) = match stretch {
        None => {
            let yarns = chen_skeleton(&rest_stitches, &sk)?;
            (surface, yarns)
        }
        Some(eps) => {
            // The wale direction at the UV centre (towards the next course), made
            // horizontal: the drape is stretched about its centre along it by 1 + ε.
            let loc = yarn::knit::UvLocator::new(&surface)?;
            let dv = 0.5 * layout.course_dv;
            let at = |v: f64| loc.sample([centre_uv[0], centre_uv[1] + v]).map(|s| s.0);
            let (Some(p0), Some(p1), Some(c)) = (at(-dv), at(dv), at(0.0)) else {
                bail!("the drape has no points around its UV centre");
            };
            let axis = [p1[0] - p0[0], p1[1] - p0[1], 0.0];
            let n = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt();
            if n <= 0.0 {
                bail!("the drape's wale direction at its centre is vertical");
            }
            let axis = axis.map(|x| x / n);
            let stretch_p = |p: [f64; 3]| {
                let d = (0..3).map(|k| (p[k] - c[k]) * axis[k]).sum::<f64>();
                [0, 1, 2].map(|k| p[k] + eps * d * axis[k])
            };
            // Normals by the inverse transpose, I − ε/(1+ε) a aᵀ.
            let stretch_n = |m: [f64; 3]| {
                let d = (0..3).map(|k| m[k] * axis[k]).sum::<f64>();
                let q = [0, 1, 2].map(|k| m[k] - eps / (1.0 + eps) * d * axis[k]);
                let l = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                q.map(|x| x / l)
            };
            for p in &mut mesh.positions {
                *p = stretch_p(*p);
            }
            for m in &mut mesh.normals {
                *m = stretch_n(*m);
            }
            let surface = surface_of(&mesh);
            let stitches = StitchMesh::on_surface(&surface, chart, &layout)?;
            // The rest gauge is the garment's own (whole courses change the course spacing
            // by < chart.height / courses): at strain 0 the knots see only the drape.
            let model = KnotModel::new(&rest_stitches, &sk, (ws, layout.course_dv.abs() * s))?;
            let frame = model.solve(&stitches, &KnotParams::default())?;
            (surface, model.yarn_set(&frame, 1)?)
        }
    };
    let centre = yarn::knit::UvLocator::new(&surface)?
        .sample(centre_uv)
        .ok_or_else(|| anyhow::anyhow!("the drape has no point at its UV centre"))?;
    // UVs in chart periods: u grows with wales, v with courses upward (texture rows
    // grow downward, DESIGN §3), both starting at the corner (course 0, wale 0).
    for uv in &mut mesh.uvs {
        let w = (uv[0] - lo[0]) / layout.wale_du;
        let c = (uv[1] - hi[1]) / layout.course_dv;
        *uv = [w / chart.width as f64, -c / chart.height as f64];
    }
    let clearance = yarn::knit::knot::min_clearance(&yarns, None, r, 8).ratio;
    Ok(Garment { mesh, yarns, wales, courses, ws, centre, clearance })
}

/// A `datasets` mesh as the surface the stitch mesh is laid on through its UVs.
pub(crate) fn surface_of(mesh: &Mesh) -> SurfaceMesh {
    SurfaceMesh {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        uvs: mesh.uvs.clone(),
        triangles: mesh.triangles.clone(),
        triangle_uvs: mesh.triangle_uvs.clone(),
    }
}

fn uv_bounds(mesh: &Mesh) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for uv in &mesh.uvs {
        for k in 0..2 {
            lo[k] = lo[k].min(uv[k]);
            hi[k] = hi[k].max(uv[k]);
        }
    }
    (lo, hi)
}

/// One camera of the study.
struct Cam {
    stitch_px: f64,
    eye: [f64; 3],
    target: [f64; 3],
}

const UP: [f64; 3] = [0.0, 0.0, 1.0];

/// Distance at which a stitch of width `ws` covers `px` pixels of an `h`-pixel-high frame.
fn eye_for(target: [f64; 3], view: [f64; 3], ws: f64, px: f64, h: u32) -> [f64; 3] {
    let f_px = 0.5 * h as f64 / (0.5 * FOV_DEG.to_radians()).tan();
    let d = ws * f_px / px;
    [0, 1, 2].map(|k| target[k] + d * view[k])
}

pub fn run(a: CompareArgs) -> Result<()> {
    if let Some(b) = &a.btf {
        guard::refuse_overlap(&[("-o", &a.output)], &[("--btf", b)])?;
    }
    let [w, h] = crate::args::numbers::<u32, 2>(&a.size, "--size")?;
    if w == 0 || h == 0 || w > 2048 || h > 2048 {
        bail!("--size {w},{h}: each side must be 1..=2048");
    }
    let [vt, vp] = crate::args::numbers::<f64, 2>(&a.view, "--view")?;
    if !(1.0..80.0).contains(&vt) || !vp.is_finite() {
        bail!("--view {}: THETA in [1, 80) degrees, PHI finite", a.view);
    }
    if a.distances.is_empty() || a.distances.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
        bail!("--distances {:?}: stitch widths in pixels, > 0", a.distances);
    }
    if a.lod.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        bail!("--lod {:?}: thresholds in pixels, > 0 (full detail is always drawn)", a.lod);
    }
    if a.components.is_empty() || a.components.iter().any(|c| *c == 0 || *c > 256) {
        bail!("--components {:?}: each 1..=256", a.components);
    }
    if !(a.btf_fibers_lod.is_finite() && a.btf_fibers_lod >= 0.0) {
        bail!("--btf-fibers-lod {}: a threshold in pixels, ≥ 0", a.btf_fibers_lod);
    }
    if a.spp == 0 || a.repeat == 0 {
        bail!("--spp and --repeat must be ≥ 1");
    }
    let FiberLight::Directional { to_light, irradiance } = fiber_light(&a.light)? else {
        bail!("--light {}: the study uses one directional light (dir:THETA,PHI[,E])", a.light);
    };
    let view = btf_core::Direction::new(vt, vp).to_vector();
    // The yarn BTF: given, or made by the reference into the study's folder.
    let (btf_path, spec) = match &a.btf {
        Some(p) => (p.clone(), None),
        None => (a.output.join("btf-reference.btf"), Some(reference_spec(&a)?)),
    };
    let cw = match &spec {
        Some(spec) => spec.chart.width,
        None => btf_source(&btf_path)?.chart.width,
    };
    if a.wales == 0 || !a.wales.is_multiple_of(cw) || a.wales > 512 {
        bail!("--wales {}: a multiple of the chart's width {cw} up to 512", a.wales);
    }
    if a.stretch.iter().any(|s| !(s.is_finite() && (0.0..=1.0).contains(s))) {
        bail!("--stretch {:?}: engineering strains in [0, 1]", a.stretch);
    }
    let gpu = btf_render::Gpu::new().context("creating a headless GPU device")?;
    guard::output_folder(&a.output, "knit compare", a.fresh, &|n| {
        guard::report_output(n) || n.starts_with("stretch-")
    })?;
    if let Some(spec) = spec.as_ref().filter(|_| !btf_path.exists()) {
        // An unfinished store (`.partial`) is resumed; a finished one is reused below.
        let opts = YarnBtfOptions {
            resume: true,
            progress: crate::progress::enabled(),
            dtype: DType::F16,
        };
        eprintln!(
            "knit compare: the reference's yarn BTF ({}² on {}, {} spp, {} bounces) into {}{}",
            spec.size,
            a.btf_sampling,
            spec.spp,
            spec.bounces,
            btf_path.display(),
            if opts.resume { ", resumed" } else { "" }
        );
        let r = yarn_ref::btf::generate_yarn_btf(spec, &btf_path, &opts)
            .with_context(|| format!("making the reference's yarn BTF {}", btf_path.display()))?;
        eprintln!(
            "  {} images rendered, {} kept, {:.1} s",
            r.images_written, r.images_skipped, r.seconds
        );
    }
    let src = btf_source(&btf_path)?;
    if let Some(spec) = &spec {
        // A finished store of an earlier run: reused only if it is the one asked for.
        let same = src.chart.to_text() == spec.chart.to_text()
            && src.params == spec.params
            && src.size == spec.size
            && src.sampling == spec.sampling
            && src.bounces == spec.bounces;
        if !same {
            bail!(
                "{} was made with another chart, yarn, --btf-size, --btf-sampling or \
                 --btf-bounces; run with --fresh to make it again",
                btf_path.display()
            );
        }
    }

    // R4 and R5-plain: the BTF compressed to each c (once for every strain).
    let store = BtfStore::open(&btf_path)?;
    let mut eigs = Vec::new();
    let mut comps = a.components.clone();
    comps.sort_unstable();
    comps.dedup();
    for &c in &comps {
        let out = a.output.join(format!("btf-c{c}.eig"));
        let params = CompressParams {
            components: c,
            quantization: Quantization::F16,
            resume: false,
            ..Default::default()
        };
        let r = btf_core::compress::compress(&store, &out, params, &|| ())
            .with_context(|| format!("compressing --btf to {c} components"))?;
        eprintln!("  BTF c = {c}: rel. RMSE {:.3} in {:.2} s", r.rel_rmse, r.seconds);
        eigs.push((c, out, r.seconds, r.rel_rmse));
    }
    drop(store);
    // R4 from fibers: the same BTF by the GPU fibers, at the largest c.
    let from_fibers = if a.no_btf_fibers {
        None
    } else {
        let path = a.output.join("btf-fibers.btf");
        let made = fiber_btf(&gpu, &src, a.btf_fibers_lod, &path)?;
        let c = *comps.last().expect("--components is not empty");
        let out = a.output.join(format!("btf-fibers-c{c}.eig"));
        let params = CompressParams {
            components: c,
            quantization: Quantization::F16,
            resume: false,
            ..Default::default()
        };
        let store = BtfStore::open(&path)?;
        let r = btf_core::compress::compress(&store, &out, params, &|| ())
            .with_context(|| format!("compressing {} to {c} components", path.display()))?;
        eprintln!("  BTF from fibers c = {c}: rel. RMSE {:.3} in {:.2} s", r.rel_rmse, r.seconds);
        Some(FromFibers { c, eig: out, pca_s: r.seconds, rel_rmse: r.rel_rmse, made })
    };
    let setup = Setup { w, h, view, to_light, irradiance };
    let inputs = Inputs { btf: &btf_path, eigs: &eigs, from_fibers: from_fibers.as_ref() };
    if a.stretch.is_empty() {
        study(&a, &src, &gpu, &inputs, &a.output, None, &setup)?;
        return Ok(());
    }
    let mut runs = Vec::new();
    for &eps in &a.stretch {
        let out = a.output.join(format!("stretch-{eps}"));
        std::fs::create_dir_all(&out)?;
        eprintln!("knit compare: stretch {eps} along the wales");
        let (cells, dists, clearance) = study(&a, &src, &gpu, &inputs, &out, Some(eps), &setup)?;
        runs.push((eps, cells, dists, clearance));
    }
    let header = format!(
        "{} wales of `{}` in `{}` on the drape, {w} × {h} px, view {}, light {}; reference {} \
         spp and {} bounces (R0) and 1 (R0 direct); yarn BTF `{}` ({}² texels per period){}. \
         Reproduce: `{}`.",
        a.wales,
        src.chart.name,
        src.params.name,
        a.view,
        a.light,
        a.spp,
        src.bounces,
        btf_path.display(),
        src.size,
        from_fibers.as_ref().map_or(String::new(), |f| format!(
            "; BTF from fibers `{}` ({} images rendered in {:.1} s, {} kept from an earlier run)",
            a.output.join("btf-fibers.btf").display(),
            f.made.images_written,
            f.made.seconds,
            f.made.images_skipped
        )),
        std::iter::once("btf".to_owned())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" ")
    );
    super::knit_compare_report::write_stretch(&a.output, &runs, &header)?;
    Ok(())
}

/// The reference's yarn BTF the study makes without `--btf`.
fn reference_spec(a: &CompareArgs) -> Result<YarnBtfSpec> {
    let chart_name = a.chart.as_deref().unwrap_or("stockinette");
    let yarn_name = a.yarn.as_deref().unwrap_or("cotton-2ply");
    let mut inputs: Vec<(&str, &Path)> = Vec::new();
    for (what, name) in [("--chart", chart_name), ("--yarn", yarn_name)] {
        if Path::new(name).is_file() {
            inputs.push((what, Path::new(name)));
        }
    }
    guard::refuse_overlap(&[("-o", &a.output)], &inputs)?;
    if !(1..=256).contains(&a.btf_size) || a.btf_spp == 0 || a.btf_bounces == 0 {
        bail!(
            "--btf-size {} (1..=256), --btf-spp {} and --btf-bounces {} (≥ 1)",
            a.btf_size,
            a.btf_spp,
            a.btf_bounces
        );
    }
    let chart = super::knit::load_chart(chart_name)?;
    let params = super::knit::load_yarn(yarn_name)?;
    let mut spec = YarnBtfSpec::new(chart, chart_name, params, a.btf_size);
    spec.sampling = datasets::capture::parse_sampling(&a.btf_sampling)
        .with_context(|| format!("--btf-sampling {}", a.btf_sampling))?;
    spec.spp = a.btf_spp;
    spec.bounces = a.btf_bounces;
    Ok(spec)
}

/// R4 from fibers: the BTF of `src`'s patch rendered by the GPU fibers into `out` (resumed
/// when `out` is an unfinished or finished run's).
fn fiber_btf(
    gpu: &btf_render::Gpu,
    src: &BtfSource,
    lod_px: f32,
    out: &Path,
) -> Result<yarn_render::btf::FiberBtfReport> {
    let mut spec =
        YarnBtfSpec::new(src.chart.clone(), &src.chart_source, src.params.clone(), src.size);
    spec.sampling = src.sampling.clone();
    spec.stitches = Some(src.stitches);
    spec.seed = src.seed;
    spec.color = src.color;
    spec.hairs = src.hairs;
    spec.method = "fibers".into();
    if out.exists() {
        // Finished by an earlier run: reused when it is this patch's.
        let store = BtfStore::open(out)?;
        let p = &store.meta().provenance;
        let same = p["method"] == "fibers"
            && p["size"].as_u64() == Some(src.size as u64)
            && p["seed"].as_u64() == Some(src.seed)
            // (f32 in the provenance: compared as f32, 0.1 is not 0.1f32 as f64)
            && p["settings"]["lod_px"].as_f64().map(|v| v as f32) == Some(lod_px)
            && p["stitches"] == serde_json::json!(src.stitches)
            // Made before the fibers drew hairs: no key, no hairs.
            && p["settings"]["hairs"].as_bool().unwrap_or(false) == src.hairs
            && p["chart"]["text"].as_str() == Some(src.chart.to_text().as_str())
            && store.meta().view_sampling == src.sampling;
        if !same {
            bail!(
                "{} is not the BTF from fibers of this study's BTF; run with --fresh",
                out.display()
            );
        }
        eprintln!("knit compare: BTF from fibers reused from {}", out.display());
        return Ok(yarn_render::btf::FiberBtfReport {
            images_written: 0,
            images_skipped: store.meta().view_sampling.len() * store.meta().light_sampling.len(),
            seconds: 0.0,
            instances: 0,
        });
    }
    let opts =
        YarnBtfOptions { resume: true, progress: crate::progress::enabled(), dtype: DType::F16 };
    let settings = FiberSettings { lod_px, ..FiberSettings::default() };
    let r = yarn_render::btf::generate_fiber_btf(gpu, &spec, settings, out, &opts)
        .with_context(|| format!("making the yarn BTF by the GPU fibers {}", out.display()))?;
    eprintln!(
        "knit compare: BTF from fibers: {} images rendered, {} kept, {:.1} s -> {}",
        r.images_written,
        r.images_skipped,
        r.seconds,
        out.display()
    );
    Ok(r)
}

/// The BTF by the GPU fibers, compressed (R4 from fibers).
struct FromFibers {
    c: usize,
    eig: PathBuf,
    pca_s: f64,
    rel_rmse: f64,
    made: yarn_render::btf::FiberBtfReport,
}

/// What every strain's study shares: the BTF, its compressed stores (c, path, PCA seconds,
/// PCA rel. RMSE) and the BTF from fibers.
struct Inputs<'a> {
    btf: &'a Path,
    eigs: &'a [(usize, PathBuf, f64, f64)],
    from_fibers: Option<&'a FromFibers>,
}

/// The fixed set-up of a study: frame size, view, light.
struct Setup {
    w: u32,
    h: u32,
    view: [f64; 3],
    to_light: [f64; 3],
    irradiance: [f64; 3],
}

/// One study on the garment (stretched by `stretch` along the wales, yarns by the knot
/// solver; `None`: at rest with the Chen skeleton) into `out`.
fn study(
    a: &CompareArgs,
    src: &BtfSource,
    gpu: &btf_render::Gpu,
    inputs: &Inputs,
    out: &Path,
    stretch: Option<f64>,
    setup: &Setup,
) -> Result<(Vec<Cell>, Vec<Distance>, f64)> {
    let Setup { w, h, view, to_light, irradiance } = *setup;
    let eigs = inputs.eigs;
    let images = out.join("images");
    std::fs::create_dir_all(&images)?;
    let t0 = Instant::now();
    let g = garment(src, a.wales, stretch)?;
    let garment_s = t0.elapsed().as_secs_f64();
    let obj = out.join("garment.obj");
    datasets::write_obj(&g.mesh, &obj, "btf knit compare: the drape, UVs in chart periods")?;
    eprintln!(
        "knit compare: {} × {} stitches on the drape ({:.3} m wide), {} yarn curves ({} yarns, \
         clearance {:.3} × 2r), {:.1} s",
        g.wales,
        g.courses,
        g.wales as f64 * g.ws,
        g.yarns.curves.len(),
        if stretch.is_some() { "knot" } else { "Chen skeleton" },
        g.clearance,
        garment_s
    );
    let lift = 2.0 * src.params.yarn_radius();
    let target = [0, 1, 2].map(|k| g.centre.0[k] + 0.5 * lift * g.centre.1[k]);
    let cams: Vec<Cam> = a
        .distances
        .iter()
        .map(|&px| Cam { stitch_px: px, eye: eye_for(target, view, g.ws, px, h), target })
        .collect();
    let reach = 2.0 * src.params.yarn_radius() + yarn_render::pack::flyaway_reach(&src.params);

    // R0: the reference, once with every bounce of the BTF and once direct only.
    let t1 = Instant::now();
    let gen_opts = GenOptions { seed: src.seed, hairs: src.hairs, ..GenOptions::default() };
    let fibers = generate_fibers(&g.yarns, std::slice::from_ref(&src.params), &gen_opts)?;
    let scene = yarn_ref::FiberScene::new(&fibers, &yarn_ref::SceneOptions::default())?;
    let r0_prep = t1.elapsed().as_secs_f64();
    eprintln!(
        "  reference: {} fibers, {} segments, {:.0} MiB, built in {:.1} s",
        fibers.fiber_count(),
        scene.segment_count(),
        scene.bytes() as f64 / 1048576.0,
        r0_prep
    );
    let r0_bytes = scene.bytes() as u64;
    drop(fibers);
    let shading = yarn_ref::Shading::Fiber { bcsdf: Arc::new(src.bcsdf.clone()), tint: true };
    let ref_light = [yarn_ref::Light::directional(to_light, irradiance)];
    let sc = yarn_ref::Scene { fibers: &scene, lights: &ref_light, shading: &shading };
    let (wu, hu) = (w as usize, h as usize);
    let bar = crate::progress::bar((2 * cams.len() * hu) as u64, "reference rows");
    let mut refs = Vec::new();
    for (k, cam) in cams.iter().enumerate() {
        let camera = yarn_ref::Camera::perspective(cam.eye, cam.target, UP, FOV_DEG)?;
        let mut pair = Vec::new();
        for bounces in [src.bounces, 1] {
            let mut s = yarn_ref::RenderSettings::new(wu, hu, a.spp);
            s.seed = src.seed + k as u64;
            s.path.max_bounces = bounces;
            let t = Instant::now();
            let (img, _) = yarn_ref::render_with(&sc, &camera, &s, &|| bar.inc(1))?;
            pair.push((img.rgb, t.elapsed().as_secs_f64()));
        }
        refs.push(pair);
    }
    bar.finish_and_clear();
    drop(scene);

    // The GPU cells: every representation at every distance, then interleaved timing.
    let packed = PackedYarns::new(
        &g.yarns,
        std::slice::from_ref(&src.params),
        &PackOptions { seed: src.seed, frame_samples_per_segment: 16, tiles: [1, 1] },
    )?;
    let fiber_lights = [FiberLight::Directional { to_light, irradiance }];
    let mut lods = vec![0.0f32];
    lods.extend(a.lod.iter().copied());
    lods.dedup();
    let mut cells: Vec<Cell> = Vec::new();
    let mut jobs: Vec<Job> = Vec::new();
    let n_cells =
        cams.len() * (lods.len() + 3 + eigs.len() + usize::from(inputs.from_fibers.is_some()) + 1);
    // R2: the strip textures, baked once (cached across strains and runs).
    let t = Instant::now();
    let bakes = yarn_render::strips::bakes_for(
        &g.yarns,
        std::slice::from_ref(&src.params),
        &src.bcsdf,
        &yarn_precompute::StripBakeSettings {
            seed: src.seed,
            spp: a.bake_spp,
            ..Default::default()
        },
        Some(&a.output.join("bake-cache")),
        &|_| {},
    )?;
    let flyaways = if src.hairs {
        yarn_render::strips::flyaways_for(std::slice::from_ref(&src.params), src.seed)?
    } else {
        Vec::new()
    };
    let strip_prep = if bakes[0].from_cache { bakes[0].seconds } else { t.elapsed().as_secs_f64() };
    // R3: the lumislice table, computed once (cached like the strip bakes).
    let t = Instant::now();
    let slice = yarn_precompute::Lumislice::for_params(
        &src.params,
        src.color.map(|c| c.clamp(0.0, 1.0)),
        &yarn_precompute::LumisliceSettings { seed: src.seed, ..Default::default() },
        Some(&a.output.join("bake-cache")),
        &|_| {},
    )?;
    let slice_prep = if slice.from_cache { slice.seconds } else { t.elapsed().as_secs_f64() };
    let bar = crate::progress::bar((n_cells * (1 + a.repeat as usize)) as u64, "GPU cells");
    for (ci, cam) in cams.iter().enumerate() {
        let fcam = FiberCamera::perspective(cam.eye, cam.target, UP, FOV_DEG);
        for (k, &lod) in lods.iter().chain([-1.0f32].iter()).enumerate() {
            let tubes = lod < 0.0;
            let t = Instant::now();
            let settings = FiberSettings {
                lod_px: lod.max(0.0),
                tubes,
                msaa: 4,
                hairs: src.hairs,
                ..FiberSettings::default()
            };
            let r = FiberRenderer::new(gpu, &packed, &src.bcsdf, settings)?;
            let prep = t.elapsed().as_secs_f64();
            let img = r.render(gpu, &fcam, &fiber_lights, (w, h), [0.0; 4])?;
            if img.stats.overflow > 0 {
                eprintln!("warning: {} fiber instances overflowed", img.stats.overflow);
            }
            let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
            let (repr, name) = if tubes {
                ("R5", "plain tubes".to_string())
            } else if k == 0 {
                ("R1", "fibers full detail".to_string())
            } else {
                ("R1", format!("fibers LoD {lod} px"))
            };
            cells.push(Cell::new(repr, &name, ci, rgb, prep, img.stats.yarn_bytes, true));
            jobs.push(Job::Fibers(Box::new((r, fcam))));
            bar.inc(1);
        }
        {
            let t = Instant::now();
            let mut r = yarn_render::StripRenderer::new(
                gpu,
                &packed,
                &bakes,
                &src.bcsdf,
                yarn_render::StripSettings::default(),
            )?;
            // The flyaway overlay when the reference has hair flyaways.
            if src.hairs {
                r.set_flyaways(gpu, &flyaways)?;
            }
            let prep = t.elapsed().as_secs_f64() + strip_prep;
            let img = r.render(gpu, &fcam, &fiber_lights, (w, h), [0.0; 4])?;
            let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
            cells.push(Cell::new("R2", "yarn strips", ci, rgb, prep, img.stats.yarn_bytes, true));
            jobs.push(Job::Strips(Box::new((r, fcam))));
            bar.inc(1);
        }
        {
            let t = Instant::now();
            let r = yarn_render::LumisliceRenderer::new(
                gpu,
                &packed,
                std::slice::from_ref(&slice),
                yarn_render::LumisliceRenderSettings::default(),
            )?;
            let prep = t.elapsed().as_secs_f64() + slice_prep;
            let img = r.render(gpu, &fcam, &fiber_lights, (w, h), [0.0; 4])?;
            let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
            cells.push(Cell::new("R3", "lumislices", ci, rgb, prep, img.stats.yarn_bytes, true));
            jobs.push(Job::Lumislice(Box::new((r, fcam))));
            bar.inc(1);
        }
        for (c, eig, pca_s, _) in eigs {
            let scene = btf_scene(out, &obj, eig, cam, (w, h), to_light, irradiance)?;
            let t = Instant::now();
            let mut r = btf_render::Renderer::new(gpu, &scene, Default::default())?;
            let prep = t.elapsed().as_secs_f64() + pca_s;
            let frame = r.render(gpu)?;
            let bytes = r.material_bytes();
            cells.push(Cell::new("R4", &format!("BTF c = {c}"), ci, frame.rgb, prep, bytes, false));
            jobs.push(Job::Btf(Box::new(r)));
            bar.inc(1);
        }
        if let Some(f) = inputs.from_fibers {
            let scene = btf_scene(out, &obj, &f.eig, cam, (w, h), to_light, irradiance)?;
            let t = Instant::now();
            let mut r = btf_render::Renderer::new(gpu, &scene, Default::default())?;
            let prep = t.elapsed().as_secs_f64() + f.pca_s;
            let frame = r.render(gpu)?;
            let bytes = r.material_bytes();
            let name = format!("BTF from fibers c = {}", f.c);
            cells.push(Cell::new("R4", &name, ci, frame.rgb, prep, bytes, false));
            jobs.push(Job::Btf(Box::new(r)));
            bar.inc(1);
        }
        // R5: the plain texture of the BTF mean, from the smallest store.
        let (_, eig, pca_s, _) = &eigs[0];
        let scene = btf_scene(out, &obj, eig, cam, (w, h), to_light, irradiance)?;
        let t = Instant::now();
        let opts = btf_render::RenderOptions {
            baseline: Some(btf_render::Baseline::Plain),
            ..Default::default()
        };
        let mut r = btf_render::Renderer::new(gpu, &scene, opts)?;
        let prep = t.elapsed().as_secs_f64() + pca_s;
        let frame = r.render(gpu)?;
        let bytes = r.material_bytes();
        cells.push(Cell::new("R5", "plain texture (BTF mean)", ci, frame.rgb, prep, bytes, false));
        jobs.push(Job::Btf(Box::new(r)));
        bar.inc(1);
    }
    let mut times = vec![Vec::new(); jobs.len()];
    for _ in 0..a.repeat {
        for (k, job) in jobs.iter_mut().enumerate() {
            let t = Instant::now();
            match job {
                Job::Fibers(rc) => {
                    let (r, cam) = &mut **rc;
                    let img = r.render(gpu, cam, &fiber_lights, (w, h), [0.0; 4])?;
                    std::hint::black_box(img.pixels.len());
                }
                Job::Strips(rc) => {
                    let (r, cam) = &**rc;
                    let img = r.render(gpu, cam, &fiber_lights, (w, h), [0.0; 4])?;
                    std::hint::black_box(img.pixels.len());
                }
                Job::Lumislice(rc) => {
                    let (r, cam) = &**rc;
                    let img = r.render(gpu, cam, &fiber_lights, (w, h), [0.0; 4])?;
                    std::hint::black_box(img.pixels.len());
                }
                Job::Btf(r) => {
                    let f = r.render(gpu)?;
                    std::hint::black_box(f.rgb.len());
                }
            }
            times[k].push(t.elapsed().as_secs_f64() * 1e3);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    for (c, t) in cells.iter_mut().zip(times) {
        c.ms = report::median(t);
    }

    // Masks, errors, images.
    let mut dists = Vec::new();
    for (ci, cam) in cams.iter().enumerate() {
        let mask = report::raster_mask(&g.mesh, cam.eye, cam.target, UP, FOV_DEG, (w, h));
        let px_m = 2.0 * dist(cam.eye, cam.target) * (0.5 * FOV_DEG.to_radians()).tan() / h as f64;
        let band_px = ((reach / px_m).ceil() as usize).max(2) + 1;
        let (interior, band) = report::interior_and_band(&mask, (wu, hu), band_px);
        let (full, direct) = (&refs[ci][0], &refs[ci][1]);
        let tag = format!("{}px", cam.stitch_px);
        write_exr_rgb(&images.join(format!("R0-{tag}.exr")), wu, hu, &full.0)?;
        write_exr_rgb(&images.join(format!("R0-direct-{tag}.exr")), wu, hu, &direct.0)?;
        let support: Vec<bool> = interior.iter().zip(&band).map(|(i, b)| *i || *b).collect();
        let k = (0.5 * cam.stitch_px).round() as usize;
        let score =
            |x: &[f32], r: &[f32]| report::scores(x, r, &interior, &band, &support, (wu, hu), k);
        // Exposures from the reference's interior; where its median is black (a stretched
        // knit at few samples shows mostly the background between yarns), from the interior
        // and band together; else no ꟻLIP at this distance (the scores stay unmeasured).
        let exposures = btf_image::flip::hdr_exposures_over(&full.0, &interior)
            .or_else(|_| btf_image::flip::hdr_exposures_over(&full.0, &support))
            .map_err(|e| eprintln!("warning: no HDR-ꟻLIP at {tag}: {e}"))
            .ok();
        let flip = |x: &[f32], s: &mut Scores| -> Result<Option<btf_image::flip::FlipMap>> {
            let Some(exposures) = exposures else { return Ok(None) };
            // A PCA reconstruction can dip below 0; HDR-ꟻLIP takes non-negative radiance.
            let x: Vec<f32> = x.iter().map(|v| v.max(0.0)).collect();
            let m = btf_image::flip::flip_hdr(
                &full.0,
                &x,
                wu,
                hu,
                btf_image::flip::DEFAULT_PPD,
                Some(exposures),
            )?;
            s.flip_interior = m.mean_over(&interior)?;
            s.flip_band = m.mean_over(&band)?;
            Ok(Some(m))
        };
        let mut gap = score(&direct.0, &full.0);
        flip(&direct.0, &mut gap)?;
        let ms_plain = cells
            .iter()
            .find(|c| c.distance == ci && c.name.starts_with("plain texture"))
            .map_or(f64::NAN, |c| c.ms);
        for c in cells.iter_mut().filter(|c| c.distance == ci) {
            c.vs_full = score(&c.rgb, &full.0);
            c.vs_direct = score(&c.rgb, &direct.0);
            if let Some(m) = flip(&c.rgb, &mut c.vs_full)? {
                m.write_heatmap(
                    &images.join(format!("flip-{}-{tag}.png", c.file_name())),
                    Some(&support),
                )?;
            }
            c.ms_plain = ms_plain;
            write_exr_rgb(&images.join(format!("{}-{tag}.exr", c.file_name())), wu, hu, &c.rgb)?;
        }
        dists.push(Distance {
            stitch_px: cam.stitch_px,
            band_px,
            interior_px: interior.iter().filter(|m| **m).count(),
            band_count: band.iter().filter(|m| **m).count(),
            ref_s: full.1,
            direct_s: direct.1,
            ms_gap: gap,
        });
        let sheet = report::contact_sheet(&cells, ci, &full.0, &direct.0, (w, h), &mask);
        write_png(&out.join(format!("sheet-{tag}.png")), &sheet)?;
    }
    let info = report::Info {
        btf: inputs.btf.display().to_string(),
        btf_size: src.size,
        wales: g.wales,
        courses: g.courses,
        width_m: g.wales as f64 * g.ws,
        size: (w, h),
        spp: a.spp,
        bounces: src.bounces,
        view: a.view.clone(),
        light: a.light.clone(),
        r0_prep_s: r0_prep,
        r0_bytes,
        adapter: gpu.info.name.clone(),
        eig_errors: eigs.iter().map(|(c, _, s, e)| (*c, *s, *e)).collect(),
        from_fibers: inputs.from_fibers.map(|f| (f.c, f.pca_s, f.rel_rmse, f.made.seconds)),
    };
    write_text(&out.join("compare.csv"), &report::csv(&cells, &dists))?;
    let md = report::markdown(&info, &cells, &dists);
    write_text(&out.join("report.md"), &md)?;
    write_png(&out.join("pareto.png"), &btf_image::plot::render(&report::pareto(&cells, &dists)))?;
    outln!("{md}");
    outln!("written to {}", out.join("report.md").display());
    for c in &mut cells {
        c.rgb = Vec::new(); // written above; the stretch summary needs the scores only
    }
    Ok((cells, dists, g.clearance))
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// A GPU cell kept for the timed repeats.
enum Job {
    Fibers(Box<(FiberRenderer, FiberCamera)>),
    Strips(Box<(yarn_render::StripRenderer, FiberCamera)>),
    Lumislice(Box<(yarn_render::LumisliceRenderer, FiberCamera)>),
    Btf(Box<btf_render::Renderer>),
}

/// The `btf-render` scene of the BTF on the garment for one camera, written beside the
/// study so that `btf render SCENE` reproduces the cell.
fn btf_scene(
    dir: &Path,
    obj: &Path,
    eig: &Path,
    cam: &Cam,
    (w, h): (u32, u32),
    to_light: [f64; 3],
    e: [f64; 3],
) -> Result<btf_render::Scene> {
    let name = eig.file_stem().and_then(|s| s.to_str()).unwrap_or("btf");
    let path = dir.join(format!("scene-{name}-{}px.toml", cam.stitch_px));
    let f = |v: [f64; 3]| format!("[{:.6}, {:.6}, {:.6}]", v[0], v[1], v[2]);
    let text = format!(
        r#"# Written by `btf knit compare`: R4, the yarn BTF on the garment.
[output]
width = {w}
height = {h}
exposure = 1.0
background = [0.0, 0.0, 0.0]

[[meshes]]
path = "{obj}"

[[materials]]
store = "{eig}"
uv_scale = 1.0

[camera]
eye = {eye}
target = {target}
up = [0.0, 0.0, 1.0]
fov_y_deg = {FOV_DEG}

[[lights]]
kind = "directional"
direction = {dir}
irradiance = {irr}

[effects]
evaluation = "per-pixel"
light_interp = "four"
view_blend = "four"
shadows = "map"
"#,
        obj = obj.file_name().and_then(|s| s.to_str()).unwrap_or("garment.obj"),
        eig = {
            // The stores sit in the study's top folder, a stretch run's scene one below.
            let name = eig.file_name().and_then(|s| s.to_str()).unwrap_or("btf.eig");
            if eig.parent() == Some(dir) { name.to_string() } else { format!("../{name}") }
        },
        eye = f(cam.eye),
        target = f(cam.target),
        dir = f(to_light),
        irr = f(e),
    );
    write_text(&path, &text)?;
    Ok(btf_render::Scene::from_toml(&text, &path)?)
}
