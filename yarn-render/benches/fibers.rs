//! Scale of the GPU fiber renderer on lavapipe (issue #19, "Scale"; BENCHMARKS.md
//! "Fiber-level yarn on the GPU (issue #19)"): frame time against yarn control points, as a
//! ratio to the plain-tube baseline (DESIGN §2.5: "plain shaded yarn tubes", one strip of
//! the yarn diameter per segment, same vertex pulling and BCSDF) measured in the same run,
//! the fitted slope, GPU bytes per control point ([W19 §5]: fibers are generated every
//! frame, never stored, so memory must be `O(control points)`), instances per frame, and the
//! largest patch that renders at all on this machine.
//!
//! Scene: Crane's plain-knit patch (`CraneKnit::for_yarn_radius(r).yarn_set(s, c, 8)`,
//! not periodic), cotton-2ply, `s × s` stitches for control points `8·s²` from ~10³ to
//! ~10⁶; an orthographic camera looking down at 35° from the normal frames the whole patch
//! (so LoD engages as the patch grows: ω^LoD = 1 px, the default settings), one directional
//! light, 256² frames, MSAA 4.
//!
//! - group `fibers-scale`: per size `fibers/CP` and `tubes/CP`, each iteration one frame timed
//!   by wall clock around `FiberRenderer::render` (LoD + draw passes, the 256² read-back).
//!   Sizes above `FIBERS_CRITERION_MAX_CP` (70 000) take seconds per frame on lavapipe and
//!   are timed directly instead: `FIBERS_DIRECT_FRAMES` (3) frames per case, fibers and
//!   tubes interleaved frame by frame; the median is reported either way.
//! - then **largest**: sides growing by √2 past the series until
//!   `PackedYarns`/`FiberRenderer` refuse (a `Limit` error) or a frame fails, then bisection
//!   on the side between the last size that rendered and the first refused. A size is
//!   skipped (stopped) when its host memory (estimated high at 1 KiB per control point:
//!   ~390 B packed, as much again in lavapipe's buffers, which are host memory, plus the
//!   `YarnSet`) exceeds half of `MemAvailable`, or its frame, extrapolated linearly in
//!   control points, exceeds `FIBERS_LARGEST_BUDGET_S` (90 s). Each size renders one frame.
//!   Nothing here panics on a refusal.
//!
//! `cargo bench -p yarn-render --bench fibers --profile dev -- --quick` (the dev profile
//! builds every dependency at opt-level 3 and avoids a release build of the workspace; the
//! timed work is lavapipe's either way). `FIBERS_MAX_CP=100000` stops the series early,
//! `FIBERS_LARGEST=0` skips the largest-patch search. Without a GPU adapter it prints why
//! and exits 0.

use btf_render::Gpu;
use criterion::{Criterion, SamplingMode};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;
use std::time::{Duration, Instant};
use yarn::YarnParams;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::crane::CraneKnit;
use yarn_render::{
    Error, FiberCamera, FiberLight, FiberRenderer, FiberSettings, FiberStats, PackOptions,
    PackedYarns,
};

const SIZE: (u32, u32) = (256, 256);
const LIGHTS: [FiberLight; 1] =
    [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] }];

/// Stitches per side of the series: 8·s² control points ≈ 1e3, 4e3, 1.6e4, 6.4e4, 2.5e5, 1e6.
const SIDES: [usize; 6] = [11, 22, 45, 89, 177, 354];

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|s| s.trim().parse().ok()).unwrap_or(default)
}

/// The `s × s` Crane patch, packed (not periodic).
fn patch(p: &YarnParams, s: usize) -> Result<PackedYarns, Error> {
    let k = CraneKnit::for_yarn_radius(p.yarn_radius());
    let mut set = k.yarn_set(s, s, 8)?;
    set.period = None;
    PackedYarns::new(&set, std::slice::from_ref(p), &PackOptions::default())
}

/// An orthographic camera 35° off the normal that frames the whole patch.
fn camera(packed: &PackedYarns) -> FiberCamera {
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (s, co) = 35f64.to_radians().sin_cos();
    let d = 2.0 * span;
    FiberCamera::orthographic([c[0], c[1] - d * s, c[2] + d * co], c, [0.0, 1.0, 0.0], 1.1 * span)
}

/// Per-case samples of a quantity (median read after criterion).
#[derive(Clone, Default)]
struct Samples(Rc<RefCell<BTreeMap<String, Vec<f64>>>>);

impl Samples {
    fn push(&self, key: &str, v: f64) {
        self.0.borrow_mut().entry(key.to_string()).or_default().push(v);
    }
    fn median(&self, key: &str) -> Option<f64> {
        let mut v = self.0.borrow().get(key)?.clone();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        (n > 0).then(|| if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
    }
}

/// Least squares `y = a + b·x`: `(a, b, R²)`.
fn fit(pts: &[(f64, f64)]) -> (f64, f64, f64) {
    let n = pts.len() as f64;
    let (mx, my) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxy: f64 = pts.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = pts.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let syy: f64 = pts.iter().map(|(_, y)| (y - my).powi(2)).sum();
    let b = sxy / sxx;
    (my - b * mx, b, if syy > 0.0 { sxy * sxy / (sxx * syy) } else { 1.0 })
}

struct Row {
    cps: usize,
    /// Median fiber frame ms (filled after the measurements).
    fibers_ms: f64,
    fibers: FiberStats,
    tubes: FiberStats,
}

/// Renders one frame of `r`, wall-clock milliseconds and the stats.
fn frame(
    gpu: &Gpu,
    r: &FiberRenderer,
    cam: &FiberCamera,
) -> yarn_render::Result<(f64, FiberStats)> {
    let t = Instant::now();
    let img = r.render(gpu, cam, &LIGHTS, SIZE, [0.0; 4])?;
    std::hint::black_box(img.pixels.len());
    Ok((t.elapsed().as_secs_f64() * 1e3, img.stats))
}

fn scaling(c: &mut Criterion, gpu: &Gpu, p: &YarnParams, bcsdf: &FiberBcsdf) -> Vec<Row> {
    let max_cp: usize = env_or("FIBERS_MAX_CP", usize::MAX);
    let criterion_max: usize = env_or("FIBERS_CRITERION_MAX_CP", 70_000);
    let direct_frames: usize = env_or("FIBERS_DIRECT_FRAMES", 3);
    let samples = Samples::default();
    let mut rows = Vec::new();
    let mut g = c.benchmark_group("fibers-scale");
    g.sampling_mode(SamplingMode::Flat);
    for s in SIDES.into_iter().filter(|s| 8 * s * s <= max_cp) {
        let packed = match patch(p, s) {
            Ok(x) => x,
            Err(e) => {
                println!("{s}×{s} stitches: not packed ({e})");
                break;
            }
        };
        let cps = packed.control_points();
        let cam = camera(&packed);
        let mut stats = [FiberStats::default(); 2];
        let mut renderers = Vec::new();
        for (k, tubes) in [false, true].into_iter().enumerate() {
            let case = if tubes { "tubes" } else { "fibers" };
            let settings = FiberSettings { tubes, ..Default::default() };
            let made = FiberRenderer::new(gpu, &packed, bcsdf, settings)
                .and_then(|r| frame(gpu, &r, &cam).map(|(_, st)| (r, st)));
            match made {
                Ok((r, st)) => {
                    stats[k] = st;
                    renderers.push((case, r));
                }
                Err(e) => println!("{cps} control points, {case}: refused ({e})"),
            }
        }
        if renderers.is_empty() {
            break;
        }
        if cps <= criterion_max {
            for (case, r) in &renderers {
                let key = format!("{case}/{cps}");
                let smp = samples.clone();
                g.bench_function(key.clone(), |b| {
                    b.iter_custom(|iters| {
                        let mut total = 0.0;
                        for _ in 0..iters {
                            let (ms, _) = frame(gpu, r, &cam).unwrap();
                            smp.push(&key, ms);
                            total += ms;
                        }
                        Duration::from_secs_f64(total / 1e3)
                    })
                });
            }
        } else {
            // Seconds per frame: criterion's ≥ 11 frames per case would take minutes, so
            // `direct_frames` frames each, fibers and tubes interleaved frame by frame.
            println!("{cps} control points: {direct_frames} interleaved frames per case (direct)");
            for _ in 0..direct_frames {
                for (case, r) in &renderers {
                    if let Ok((ms, _)) = frame(gpu, r, &cam) {
                        samples.push(&format!("{case}/{cps}"), ms);
                    }
                }
            }
        }
        rows.push(Row { cps, fibers_ms: f64::NAN, fibers: stats[0], tubes: stats[1] });
    }
    g.finish();
    report(&rows, &samples);
    for r in &mut rows {
        r.fibers_ms = samples.median(&format!("fibers/{}", r.cps)).unwrap_or(f64::NAN);
    }
    rows
}

fn report(rows: &[Row], samples: &Samples) {
    println!(
        "\n## Fiber frame time against control points ({}², lod_px 1, MSAA 4; tubes = baseline)\n",
        SIZE.0
    );
    println!(
        "| control points | segments | fiber instances | triangles | tube instances | fibers ms | tubes ms | × tubes | yarn bytes | bytes/CP |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut fib = Vec::new();
    let mut tub = Vec::new();
    for r in rows {
        let f = samples.median(&format!("fibers/{}", r.cps));
        let t = samples.median(&format!("tubes/{}", r.cps));
        let cell = |v: Option<f64>| v.map_or("—".into(), |v| format!("{v:.1}"));
        let ratio = match (f, t) {
            (Some(f), Some(t)) if t > 0.0 => format!("{:.2}", f / t),
            _ => "—".into(),
        };
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |",
            r.cps,
            r.fibers.segments,
            r.fibers.instances,
            r.fibers.triangles,
            r.tubes.instances,
            cell(f),
            cell(t),
            ratio,
            r.fibers.yarn_bytes,
            r.fibers.yarn_bytes as f64 / r.cps as f64
        );
        if let Some(f) = f {
            fib.push((r.cps as f64, f));
        }
        if let Some(t) = t {
            tub.push((r.cps as f64, t));
        }
    }
    println!("\nFitted (least squares over the sizes above):\n");
    println!("| case | ms = a + b·CP: a (ms) | b (µs per CP) | R² | log-log exponent |");
    println!("|---|---:|---:|---:|---:|");
    for (name, pts) in [("fibers", &fib), ("tubes", &tub)] {
        if pts.len() < 2 {
            continue;
        }
        let (a, b, r2) = fit(pts);
        let logs: Vec<(f64, f64)> = pts.iter().map(|(x, y)| (x.ln(), y.ln())).collect();
        let (_, e, _) = fit(&logs);
        println!("| {name} | {a:.2} | {:.4} | {r2:.4} | {e:.3} |", b * 1e3);
    }
}

/// MemAvailable of /proc/meminfo in bytes (`None` when unreadable).
fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kb| kb * 1024)
}

enum Outcome {
    Rendered(f64),
    Refused,
    Stopped,
}

/// Packs, builds and renders the `side × side` patch once; prints its row.
fn try_side(
    gpu: &Gpu,
    p: &YarnParams,
    bcsdf: &FiberBcsdf,
    side: usize,
    predicted_s: f64,
) -> Outcome {
    let budget_s: f64 = env_or("FIBERS_LARGEST_BUDGET_S", 90.0);
    let cps = 8 * side * side;
    let row = |rest: String| println!("| {side}×{side} | {cps} | {rest} |");
    if predicted_s > budget_s {
        row(format!(
            "| | | | stopped: frame predicted ~{predicted_s:.0} s, above the {budget_s} s budget (FIBERS_LARGEST_BUDGET_S)"
        ));
        return Outcome::Stopped;
    }
    let need = cps as u64 * 1024;
    if let Some(avail) = mem_available().filter(|&a| need > a / 2) {
        row(format!(
            "| | | | stopped: ~{:.1} GB predicted, above half of the {:.1} GB available",
            need as f64 / 1e9,
            avail as f64 / 1e9
        ));
        return Outcome::Stopped;
    }
    let t = Instant::now();
    let packed = match patch(p, side) {
        Ok(x) => x,
        Err(e) => {
            row(format!("| | | | refused by PackedYarns: {e}"));
            return Outcome::Refused;
        }
    };
    let pack_s = t.elapsed().as_secs_f64();
    let r = match FiberRenderer::new(gpu, &packed, bcsdf, FiberSettings::default()) {
        Ok(r) => r,
        Err(e) => {
            row(format!("{pack_s:.1} | | | | refused by FiberRenderer: {e}"));
            return Outcome::Refused;
        }
    };
    match frame(gpu, &r, &camera(&packed)) {
        Ok((ms, st)) => {
            let over = if st.overflow > 0 {
                format!(", {} overflowed", st.overflow)
            } else {
                String::new()
            };
            row(format!(
                "{pack_s:.1} | {:.2} | {} | {} | rendered{over}",
                ms / 1e3,
                st.instances,
                st.yarn_bytes
            ));
            Outcome::Rendered(ms / 1e3)
        }
        Err(e) => {
            row(format!("{pack_s:.1} | | | | frame failed: {e}"));
            Outcome::Refused
        }
    }
}

/// Sizes growing by √2 per side past the last size of the series until one is refused (or
/// stopped by the time or memory budget), then bisection on the side between the last
/// size that rendered and the first refused.
fn largest(gpu: &Gpu, p: &YarnParams, bcsdf: &FiberBcsdf, start: (usize, f64)) {
    println!("\n## Largest patch that renders ({}², lod_px 1)\n", SIZE.0);
    let binding = gpu.device.limits().max_storage_buffer_binding_size;
    println!(
        "Storage-buffer binding limit {binding} B: the segment buffer (192 B a segment) is refused \
         above {} segments (= control points of closed curves).\n",
        binding / 192
    );
    println!("| stitches | control points | pack s | frame s | instances | yarn bytes | outcome |");
    println!("|---|---:|---:|---:|---:|---:|---|");
    let (mut ok, mut ok_s) = start;
    let per_cp = |side: usize, ok: usize, ok_s: f64| ok_s * (side * side) as f64 / (ok * ok) as f64;
    let mut refused = None;
    for _ in 0..8 {
        let side = (ok as f64 * std::f64::consts::SQRT_2).round() as usize;
        match try_side(gpu, p, bcsdf, side, per_cp(side, ok, ok_s)) {
            Outcome::Rendered(s) => (ok, ok_s) = (side, s),
            Outcome::Refused => {
                refused = Some(side);
                break;
            }
            Outcome::Stopped => break,
        }
    }
    if let Some(mut bad) = refused {
        while bad - ok > 1 {
            let mid = (ok + bad) / 2;
            match try_side(gpu, p, bcsdf, mid, per_cp(mid, ok, ok_s)) {
                Outcome::Rendered(s) => (ok, ok_s) = (mid, s),
                Outcome::Refused => bad = mid,
                Outcome::Stopped => break,
            }
        }
    }
    println!(
        "\nLargest patch rendered: {ok}×{ok} stitches, {} control points ({ok_s:.1} s a frame).",
        8 * ok * ok
    );
}

fn main() {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            println!("fibers: skipped, no GPU adapter ({e})");
            return;
        }
    };
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "fibers: adapter {} ({:?}); load average {}",
        gpu.info.name,
        gpu.info.backend,
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    let p = YarnParams::preset("cotton-2ply").expect("cotton-2ply preset");
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).expect("Khungurn BCSDF");
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .without_plots()
        .configure_from_args();
    let rows = scaling(&mut c, &gpu, &p, &bcsdf);
    if let Some(r) = rows.last().filter(|_| env_or("FIBERS_LARGEST", 1u32) == 1) {
        let side = ((r.cps / 8) as f64).sqrt().round() as usize;
        largest(&gpu, &p, &bcsdf, (side, r.fibers_ms / 1e3));
    }
    c.final_summary();
}
