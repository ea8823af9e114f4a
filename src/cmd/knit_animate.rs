//! `btf knit animate -o DIR`: knitwear that moves, end to end — the knit animation of
//! [C03 §4] (`datasets::sim`: a scarf dropped onto a table, an arm or a ball, or stretched
//! and released, [C03 Fig. 13]) drives a stitch mesh whose corners are the simulated loop
//! corners; the yarns follow by the knot solver of [H25 §5.2] (`yarn::knit::knot`, three
//! Gauss–Newton iterations per face and frame) and every frame is written as BCC yarn
//! curves and, with `--render`, rendered by the GPU fibers ([W19]) or the lumislice renderer
//! ([C03 §5]) to numbered PNG frames and a contact sheet.
//!
//! Per frame (`animate.csv`, `animate.md`): simulation steps, halvings and milliseconds,
//! the knot solve in milliseconds (with `--relaxed-rest`: plus the contact-relaxed template
//! carried on top, [`yarn::knit::knot::detail`]), the render in seconds. **Resumable**:
//! the simulation is cached in `DIR/cache/sim-<key>.bin` (written atomically once it has
//! run), and frames whose files exist are not redone, so an interrupted run picks up where
//! it stopped when run again with the same arguments; `--fresh` starts over.

use super::knit::{chart_inputs_of, load_chart, load_yarn};
use crate::guard::{self, outln};
use anyhow::{Context, Result, bail};
use btf_image::plot::{Plot, Series, render};
use btf_image::write::{write_png, write_text};
use clap::Args;
use datasets::sim::knit::LoopGrid;
use datasets::sim::scenes::{DropTarget, ScarfDrop, ScarfSize, ScarfStretch, SceneRun};
use std::path::{Path, PathBuf};
use std::time::Instant;
use yarn::knit::knot::{ContactParams, RestDetail};
use yarn::knit::{KnotModel, KnotParams, SkeletonParams, StitchMesh};
use yarn::params::YarnParams;

crate::args::choices! {
    /// `btf knit animate --scene`.
    SceneChoice {
        /// A scarf dropped onto a table, a third over the edge.
        DropTable = "drop-table",
        /// A scarf dropped across a horizontal capsule (an arm).
        DropArm = "drop-arm",
        /// A scarf dropped onto a ball.
        DropBall = "drop-ball",
        /// Both ends pulled apart by 30 %, held, released ([C03 Fig. 13] bottom).
        Stretch = "stretch",
    }
}

crate::args::choices! {
    /// `btf knit animate --method`.
    MethodChoice {
        /// GPU fibers [W19], LoD at 1 px.
        Fibers = "fibers",
        /// Lumislice pieces [C03 §5] (the table cached in DIR/cache).
        Lumislice = "lumislice",
    }
}

/// `btf knit animate`.
#[derive(Args)]
pub struct AnimateArgs {
    /// Output folder (frames/, animate.csv, animate.md, sheet.png, cache/).
    #[arg(short = 'o', long = "out", alias = "output")]
    pub output: PathBuf,
    /// The scene.
    #[arg(long, default_value = "drop-arm")]
    pub scene: SceneChoice,
    /// Built-in chart name or chart file (its repeat must divide the loop grid).
    #[arg(long, default_value = "stockinette")]
    pub chart: String,
    /// Yarn preset name or yarn TOML file: its radius sets the loop size.
    #[arg(long, default_value = "cotton-2ply")]
    pub yarn: String,
    /// Loop grid COURSES,WALES of the scarf (the paper's falling scarf: 250,30, 15 000
    /// triangles).
    #[arg(long, default_value = "48,12")]
    pub loops: String,
    /// Simulated seconds (25 frames a second).
    #[arg(long, default_value_t = 1.0)]
    pub seconds: f64,
    /// Render every K-th frame (1: all).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Render frames W,H (default: BCC curves only).
    #[arg(long)]
    pub render: Option<String>,
    /// Renderer of the frames.
    #[arg(long, default_value = "fibers")]
    pub method: MethodChoice,
    /// Gauss–Newton iterations of the knot solver per frame.
    #[arg(long, default_value_t = 3)]
    pub iterations: usize,
    /// Carry the chart's contact-relaxed template on top of every knot solve (the rest
    /// detail of `yarn::knit::knot::detail`, DESIGN §3.3 item 1: yarns 0.88 → ~1.0 × 2r
    /// apart at rest).
    #[arg(long)]
    pub relaxed_rest: bool,
    /// Remove this command's earlier outputs from the folder first (no resume).
    #[arg(long)]
    pub fresh: bool,
}

fn parse_loops(s: &str) -> Result<LoopGrid> {
    let [courses, wales] = crate::args::numbers::<usize, 2>(s, "--loops")?;
    if !(2..=2000).contains(&courses) || !(2..=500).contains(&wales) {
        bail!("--loops {s}: COURSES in 2..=2000, WALES in 2..=500");
    }
    Ok(LoopGrid { courses, wales })
}

/// The scene's simulation, from the cache when a valid one for exactly these inputs is
/// there.
fn simulate(a: &AnimateArgs, grid: LoopGrid, ws: f64, cs: f64) -> Result<(SceneRun, bool)> {
    let key = format!(
        "knit animate sim v1\n{:?}\n{:?}\n{ws:e}\n{cs:e}\n{:e}",
        a.scene.as_str(),
        grid,
        a.seconds
    );
    let hash = yarn::hash::hash_bytes(key.as_bytes());
    let path = a.output.join("cache").join(format!("sim-{hash:016x}.bin"));
    if let Ok(bytes) = std::fs::read(&path)
        && let Some(run) = decode_run(&bytes, &key, grid)
    {
        return Ok((run, true));
    }
    let size = ScarfSize(grid);
    let run = match a.scene {
        SceneChoice::Stretch => {
            let mut s = ScarfStretch::new(size);
            s.knit.wale_spacing_m = ws;
            s.knit.course_spacing_m = cs;
            s.recording.seconds = a.seconds;
            s.run()?
        }
        drop => {
            let target = match drop {
                SceneChoice::DropTable => DropTarget::Table,
                SceneChoice::DropBall => DropTarget::Ball,
                _ => DropTarget::Arm,
            };
            let mut s = ScarfDrop::new(size, target);
            s.knit.wale_spacing_m = ws;
            s.knit.course_spacing_m = cs;
            s.recording.seconds = a.seconds;
            s.run()?
        }
    };
    std::fs::create_dir_all(path.parent().expect("in cache/"))?;
    btf_core::fs::write_atomic(&path, &encode_run(&run, &key))?;
    Ok((run, false))
}

fn encode_run(run: &SceneRun, key: &str) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend((key.len() as u64).to_le_bytes());
    out.extend(key.as_bytes());
    out.extend((run.frames.len() as u64).to_le_bytes());
    for f in &run.frames {
        out.extend(f.time_s.to_le_bytes());
        let r = &f.report;
        for v in [r.steps, r.halvings, r.projected, r.force_evaluations] {
            out.extend((v as u64).to_le_bytes());
        }
        out.extend(r.wall_ms.to_le_bytes());
        out.extend((f.positions.len() as u64).to_le_bytes());
        for p in &f.positions {
            p.iter().for_each(|x| out.extend(x.to_le_bytes()));
        }
    }
    let sum = yarn::hash::hash_bytes(&out);
    out.extend(sum.to_le_bytes());
    out
}

fn decode_run(bytes: &[u8], key: &str, grid: LoopGrid) -> Option<SceneRun> {
    let (body, sum) = bytes.split_at(bytes.len().checked_sub(8)?);
    if yarn::hash::hash_bytes(body) != u64::from_le_bytes(sum.try_into().ok()?) {
        return None;
    }
    let mut at = 0usize;
    let mut take = |n: usize| -> Option<&[u8]> {
        let s = body.get(at..at.checked_add(n)?)?;
        at += n;
        Some(s)
    };
    let u = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap()) as usize;
    let f = |b: &[u8]| f64::from_le_bytes(b.try_into().unwrap());
    let klen = u(take(8)?);
    if take(klen)? != key.as_bytes() {
        return None;
    }
    let nodes = (grid.courses + 1) * (grid.wales + 1);
    let n = u(take(8)?);
    let mut frames = Vec::with_capacity(n.min(1 << 16));
    for _ in 0..n {
        let time_s = f(take(8)?);
        let steps = u(take(8)?);
        let halvings = u(take(8)?);
        let projected = u(take(8)?);
        let force_evaluations = u(take(8)?);
        let wall_ms = f(take(8)?);
        if u(take(8)?) != nodes {
            return None;
        }
        let mut positions = Vec::with_capacity(nodes);
        for _ in 0..nodes {
            positions.push([f(take(8)?), f(take(8)?), f(take(8)?)]);
        }
        frames.push(datasets::sim::scenes::SceneFrame {
            time_s,
            positions,
            report: datasets::sim::step::AdvanceReport {
                steps,
                halvings,
                projected,
                force_evaluations,
                wall_ms,
            },
        });
    }
    Some(SceneRun { grid, triangles: Vec::new(), colliders: Vec::new(), frames })
}

/// Corner normals of a loop grid's positions: the cross product of the central
/// differences along the wales (`w`) and along the courses (`c`), one-sided at the borders.
fn grid_normals(grid: LoopGrid, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let (nc, nw) = (grid.courses + 1, grid.wales + 1);
    let at = |c: usize, w: usize| x[c * nw + w];
    let mut out = Vec::with_capacity(x.len());
    for c in 0..nc {
        for w in 0..nw {
            let (w0, w1) = (w.saturating_sub(1), (w + 1).min(nw - 1));
            let (c0, c1) = (c.saturating_sub(1), (c + 1).min(nc - 1));
            let du = [0, 1, 2].map(|k| at(c, w1)[k] - at(c, w0)[k]);
            let dv = [0, 1, 2].map(|k| at(c1, w)[k] - at(c0, w)[k]);
            let n = [
                du[1] * dv[2] - du[2] * dv[1],
                du[2] * dv[0] - du[0] * dv[2],
                du[0] * dv[1] - du[1] * dv[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            out.push(if l > 0.0 { n.map(|v| v / l) } else { [0.0, 0.0, 1.0] });
        }
    }
    out
}

struct Row {
    frame: usize,
    time_s: f64,
    steps: usize,
    halvings: usize,
    sim_ms: f64,
    solve_ms: f64,
    render_s: Option<f64>,
}

/// Runs `btf knit animate`.
pub fn run(a: AnimateArgs) -> Result<()> {
    let inputs = chart_inputs_of(&a.chart, &a.yarn);
    guard::refuse_overlap(&[("-o", &a.output)], &inputs)?;
    let grid = parse_loops(&a.loops)?;
    if !(a.seconds.is_finite() && a.seconds > 0.0 && a.seconds <= 120.0) {
        bail!("--seconds {}: in (0, 120]", a.seconds);
    }
    if a.every == 0 || !(1..=50).contains(&a.iterations) {
        bail!("--every ≥ 1 and --iterations in 1..=50");
    }
    let size =
        a.render.as_deref().map(|v| crate::args::numbers::<u32, 2>(v, "--render")).transpose()?;
    if let Some([w, h]) = size
        && (w == 0 || h == 0 || w > 2048 || h > 2048)
    {
        bail!("--render {w},{h}: each side 1..=2048");
    }
    let chart = load_chart(&a.chart)?;
    if !grid.wales.is_multiple_of(chart.width) || !grid.courses.is_multiple_of(chart.height) {
        bail!(
            "--loops {}: COURSES a multiple of chart '{}''s height {} and WALES of its width {}",
            a.loops,
            chart.name,
            chart.height,
            chart.width
        );
    }
    let params = load_yarn(&a.yarn)?;
    let gpu = match size {
        Some(_) => Some(btf_render::Gpu::new().context("creating a headless GPU device")?),
        None => None,
    };
    guard::output_folder(&a.output, "knit animate", a.fresh, &guard::report_output)?;
    let frames_dir = a.output.join("frames");
    std::fs::create_dir_all(&frames_dir)?;

    let sk = SkeletonParams::new(params.yarn_radius());
    let (ws, cs) = sk.default_spacing();
    let t0 = Instant::now();
    let (run, cached) = simulate(&a, grid, ws, cs)?;
    let sim_s = t0.elapsed().as_secs_f64();
    let steps: usize = run.frames.iter().map(|f| f.report.steps).sum();
    let sim_ms: f64 = run.frames.iter().map(|f| f.report.wall_ms).sum();
    eprintln!(
        "knit animate: {} × {} loops ({} triangles), {} frames, {steps} steps, {:.2} ms a step{}",
        grid.courses,
        grid.wales,
        2 * grid.courses * grid.wales,
        run.frames.len(),
        sim_ms / steps.max(1) as f64,
        if cached { " (simulation from the cache)".to_string() } else { format!(", {sim_s:.1} s") }
    );
    // The scarf has edges: its rest is the flat patch without the periodic lattice.
    let mut rest = StitchMesh::flat(&chart, grid.wales, grid.courses, ws, cs)?;
    rest.lattice = None;
    let model = KnotModel::new(&rest, &sk, (ws, cs))?;
    let kp = KnotParams { iterations: a.iterations, ..KnotParams::default() };
    let detail = if a.relaxed_rest {
        let d = RestDetail::relax(&model, &rest, &kp, &ContactParams::default())
            .context("relaxing the chart's template (--relaxed-rest)")?;
        outln!(
            "knit animate: rest detail relaxed on a {} × {} patch in {:.1} s, clearance {:.3} → \
             {:.3} × 2r",
            d.patch.0,
            d.patch.1,
            d.stats.seconds,
            d.stats.clearance_before,
            d.stats.clearance_after
        );
        Some(d)
    } else {
        None
    };
    let smoothed = run.smoothed()?;
    // The camera frames every position of every frame.
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in smoothed.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let mut renderer = FrameRenderer::new(&a, gpu.as_ref(), &params, size, (lo, hi))?;
    let bar = crate::progress::bar(run.frames.len() as u64, "frames");
    let mut rows = Vec::new();
    let mut shots = Vec::new();
    for (k, f) in run.frames.iter().enumerate() {
        let bcc = frames_dir.join(format!("frame-{k:04}.bcc"));
        let png = frames_dir.join(format!("frame-{k:04}.png"));
        let want_png = size.is_some() && k % a.every == 0;
        let mut row = Row {
            frame: k,
            time_s: f.time_s,
            steps: f.report.steps,
            halvings: f.report.halvings,
            sim_ms: f.report.wall_ms,
            solve_ms: f64::NAN,
            render_s: None,
        };
        if bcc.is_file() && (!want_png || png.is_file()) {
            if want_png {
                shots.push(png.clone());
            }
            rows.push(row);
            bar.inc(1);
            continue;
        }
        let mut mesh = rest.clone();
        mesh.corners = smoothed[k].clone();
        mesh.normals = grid_normals(grid, &smoothed[k]);
        mesh.lattice = None;
        let t = Instant::now();
        let mut frame =
            model.solve(&mesh, &kp).with_context(|| format!("frame {k}: the knot solve"))?;
        if let Some(d) = &detail {
            frame = d.apply(&model, &mesh, &frame).with_context(|| format!("frame {k}"))?;
        }
        row.solve_ms = t.elapsed().as_secs_f64() * 1e3;
        let set = model.yarn_set(&frame, 4)?;
        if want_png {
            let t = Instant::now();
            renderer.frame(&set, &png)?;
            row.render_s = Some(t.elapsed().as_secs_f64());
            shots.push(png.clone());
        }
        yarn::io::bcc::write_bcc(&bcc, &set, &format!("btf knit animate, frame {k}"))?;
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    report(&a, &rows, &shots, grid, steps, sim_ms)?;
    Ok(())
}

/// The renderer of the frames (fixed camera and light).
struct FrameRenderer<'a> {
    gpu: Option<&'a btf_render::Gpu>,
    params: YarnParams,
    size: (u32, u32),
    cam: yarn_render::FiberCamera,
    light: yarn_render::FiberLight,
    table: Option<yarn_precompute::Lumislice>,
}

impl<'a> FrameRenderer<'a> {
    fn new(
        a: &AnimateArgs,
        gpu: Option<&'a btf_render::Gpu>,
        params: &YarnParams,
        size: Option<[u32; 2]>,
        (lo, hi): ([f64; 3], [f64; 3]),
    ) -> Result<Self> {
        let [w, h] = size.unwrap_or([1, 1]);
        let target = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(hi[2] - lo[2]);
        let aspect = w as f64 / h as f64;
        let dist = 0.6 * extent / ((15f64).to_radians().tan() * aspect.min(1.0));
        let dir = btf_core::Direction::new(55.0, 250.0).to_vector();
        let eye = [0, 1, 2].map(|k| target[k] + dist * dir[k]);
        let table = match (a.method, gpu) {
            (MethodChoice::Lumislice, Some(_)) => {
                let s = yarn_precompute::LumisliceSettings::default();
                let bar = crate::progress::bar((s.res * s.res) as u64, "lumislice table");
                let t = yarn_precompute::Lumislice::for_params(
                    params,
                    [0.8, 0.55, 0.35],
                    &s,
                    Some(&a.output.join("cache")),
                    &|n| bar.inc(n),
                )?;
                bar.finish_and_clear();
                Some(t)
            }
            _ => None,
        };
        Ok(FrameRenderer {
            gpu,
            params: params.clone(),
            size: (w, h),
            cam: yarn_render::FiberCamera::perspective(eye, target, [0.0, 0.0, 1.0], 30.0),
            light: yarn_render::FiberLight::Directional {
                to_light: btf_core::Direction::new(35.0, 300.0).to_vector(),
                irradiance: [6.0; 3],
            },
            table,
        })
    }

    fn frame(&mut self, set: &yarn::YarnSet, png: &Path) -> Result<()> {
        use yarn_render::{
            FiberRenderer, FiberSettings, LumisliceRenderer, PackOptions, PackedYarns,
        };
        let Some(gpu) = self.gpu else { return Ok(()) };
        let packed = PackedYarns::new(
            set,
            std::slice::from_ref(&self.params),
            &PackOptions { seed: 1, frame_samples_per_segment: 4, tiles: [1, 1] },
        )?;
        let clear = [0.05, 0.05, 0.06, 1.0];
        let img = match &self.table {
            Some(t) => {
                LumisliceRenderer::new(gpu, &packed, std::slice::from_ref(t), Default::default())?
                    .render(gpu, &self.cam, &[self.light], self.size, clear)?
            }
            None => {
                let bcsdf = super::knit_render::bcsdf("khungurn")?;
                let settings = FiberSettings { lod_px: 1.0, msaa: 4, ..FiberSettings::default() };
                FiberRenderer::new(gpu, &packed, &bcsdf, settings)?.render(
                    gpu,
                    &self.cam,
                    &[self.light],
                    self.size,
                    clear,
                )?
            }
        };
        let rgb: Vec<f32> = img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        btf_image::write::write_png_linear(png, w, h, &rgb, 1.0)?;
        Ok(())
    }
}

fn report(
    a: &AnimateArgs,
    rows: &[Row],
    shots: &[PathBuf],
    grid: LoopGrid,
    steps: usize,
    sim_ms: f64,
) -> Result<()> {
    let mut csv = String::from("frame,time_s,steps,halvings,sim_ms,solve_ms,render_s\n");
    for r in rows {
        csv.push_str(&format!(
            "{},{:.4},{},{},{:.2},{},{}\n",
            r.frame,
            r.time_s,
            r.steps,
            r.halvings,
            r.sim_ms,
            if r.solve_ms.is_finite() { format!("{:.3}", r.solve_ms) } else { String::new() },
            r.render_s.map(|s| format!("{s:.3}")).unwrap_or_default()
        ));
    }
    write_text(&a.output.join("animate.csv"), &csv)?;
    let solved: Vec<f64> = rows.iter().map(|r| r.solve_ms).filter(|v| v.is_finite()).collect();
    let rendered: Vec<f64> = rows.iter().filter_map(|r| r.render_s).collect();
    let mean =
        |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    let frames = rows.len();
    let md = format!(
        "# Knit animation: {}\n\n{} × {} loops ({} triangles) of {} in {}, {} frames at 25 fps.\n\n\
         | | value |\n|---|---|\n\
         | simulation steps | {steps} ({:.0} a frame) |\n\
         | simulation ms a step | {:.3} |\n\
         | simulation ms a frame | {:.1} |\n\
         | knot solve ms a frame (this run) | {:.2} |\n\
         | render s a frame ({}) | {} |\n\n\
         The paper's falling scarf (15 000 triangles) took ≈ 1.8 s a frame to simulate and \
         render on an 864 MHz Pentium III [C03 §6]; a ratio, not a target.\n\n{}",
        a.scene.as_str(),
        grid.courses,
        grid.wales,
        2 * grid.courses * grid.wales,
        a.chart,
        a.yarn,
        frames,
        steps as f64 / frames.max(1) as f64,
        sim_ms / steps.max(1) as f64,
        sim_ms / frames.max(1) as f64,
        mean(&solved),
        a.method.as_str(),
        if rendered.is_empty() { "—".to_string() } else { format!("{:.3}", mean(&rendered)) },
        if shots.is_empty() { String::new() } else { "![frames](sheet.png)\n".to_string() }
    );
    write_text(&a.output.join("animate.md"), &md)?;
    if !shots.is_empty() {
        let pick: Vec<&PathBuf> = if shots.len() > 12 {
            (0..12).map(|i| &shots[i * (shots.len() - 1) / 11]).collect()
        } else {
            shots.iter().collect()
        };
        let imgs: Vec<(image::RgbImage, String)> = pick
            .iter()
            .map(|p| {
                let img = image::open(p).with_context(|| format!("reading {}", p.display()))?;
                let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("").to_string();
                Ok((img.to_rgb8(), name))
            })
            .collect::<Result<_>>()?;
        let refs: Vec<(&image::RgbImage, &str)> =
            imgs.iter().map(|(i, s)| (i, s.as_str())).collect();
        let rows: Vec<image::RgbImage> =
            refs.chunks(4).map(|c| btf_image::compose::captioned_strip(c, 4)).collect();
        let rr: Vec<&image::RgbImage> = rows.iter().collect();
        write_png(&a.output.join("sheet.png"), &btf_image::compose::stacked(&rr, 4))?;
    }
    let plot = Plot {
        title: "knit animation: cost per frame".into(),
        x_label: "frame".into(),
        y_label: "milliseconds".into(),
        log_y: true,
        series: vec![
            Series::new("simulation", rows.iter().map(|r| (r.frame as f64, r.sim_ms)).collect()),
            Series::new("knot solve", rows.iter().map(|r| (r.frame as f64, r.solve_ms)).collect()),
        ],
        ..Default::default()
    };
    write_png(&a.output.join("animate.png"), &render(&plot))?;
    outln!("{md}");
    outln!("written to {}", a.output.join("animate.md").display());
    Ok(())
}
