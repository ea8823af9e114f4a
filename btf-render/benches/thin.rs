//! Frame-time cost of thin cloth's transmission on lavapipe (issue #9; BENCHMARKS.md "Thin
//! cloth (issue #9)"): the synthetic curtain (`datasets` curtain, low) at 256², c = 16,
//! per-pixel four/four, a point light circling it at 8 positions (the paper's demo).
//!
//! - group `thin-orbit`: the curtain in front of a wall; `opaque` (**baseline**, no
//!   `transmission`) and `transmission` (`tau = 2`, `tau_texture = "btf-mean"`,
//!   `albedo = 1`). An iteration renders the 8 positions (the light moved by
//!   `Renderer::set_lights` before each frame, untimed) and counts as their mean frame time.
//!   The orbit's frames are written once to `target/tmp/thin-orbit/`.
//! - group `thin-environment`: no wall, the synthetic sky lights the curtain and shows
//!   behind it (`show_environment`, `visibility_res = 16`); `opaque` (**baseline**) and
//!   `transmission` (scalar `tau = 0.6`, `albedo = 0.9`), the same orbit.
//! - group `thin-env-tables`: the one-off CPU cost of the thin-cloth environment tables
//!   (`Stats` pass `thin-cloth env tables`), 32² frames, visibility from a cache: `scalar tau`
//!   (**baseline**, one τ node) against `tau texture` (`tau_texture = "btf-mean"`, 8 τ
//!   nodes), each a new renderer per sample, and `rotation` (the scalar tables again after
//!   each 30° turn of the environment).
//!
//! Frames are timed by `Stats::frame_ms` (CPU work, encoding, GPU execution; no read-back).
//! After criterion, markdown tables give per orbit position and on average the median
//! frame times and the ratio transmission / opaque (with the CPU back-to-front sort), and the
//! table costs with their ratios to the scalar tables.
//!
//! `cargo bench -p btf-render --bench thin` (`-- --quick` for a short run, `-- thin-orbit`
//! for one group). Without a GPU adapter it prints why and exits 0.

mod common;

use btf_core::eigen::Quantization;
use btf_render::scene::Light;
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use common::*;
use criterion::{BenchmarkGroup, SamplingMode, measurement::WallTime};
use std::path::Path;
use std::time::Duration;

/// Light positions around the curtain.
const STEPS: usize = 8;

fn orbit(k: usize) -> [f32; 3] {
    let a = std::f32::consts::TAU * k as f32 / STEPS as f32;
    [0.9 * a.sin(), -0.9 * a.cos() + 0.1, 1.0]
}

/// Moves the first (point) light of `r` to orbit position `k`.
fn move_light(gpu: &Gpu, r: &mut Renderer, k: usize) {
    let mut lights = r.scene().lights.clone();
    if let Light::Point { position, .. } = &mut lights[0] {
        *position = orbit(k);
    }
    r.set_lights(gpu, &lights).unwrap();
}

/// The opaque (`opaque`) and thin (`transmission`) curtain of `scenes`: each iteration
/// renders the whole orbit (one frame per light position) and counts as the mean frame;
/// per position the frame times are recorded as `frame k` and the sort as `sort k`. The
/// renderers are made (and the orbit's frames written to `out`) before timing.
fn orbit_group(
    group: &mut BenchmarkGroup<WallTime>,
    gpu: &Gpu,
    samples: &Samples,
    scenes: [(&'static str, Scene); 2],
    out: Option<&Path>,
) {
    for (case, scene) in scenes {
        let samples = samples.clone();
        let mut r = Renderer::new(gpu, &scene, RenderOptions::default()).unwrap();
        for k in 0..STEPS {
            move_light(gpu, &mut r, k);
            let f = r.render(gpu).unwrap();
            if let Some(out) = out.filter(|_| case == "transmission") {
                f.write_png(&out.join(format!("orbit-{k:02}.png")), 3.0).unwrap();
            }
        }
        group.bench_function(case, move |b| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                for _ in 0..iters {
                    for k in 0..STEPS {
                        move_light(gpu, &mut r, k);
                        let f = r.render(gpu).unwrap();
                        total += f.stats.frame_ms / STEPS as f64;
                        samples.push(case, "frame", f.stats.frame_ms);
                        samples.push(case, &format!("frame {k}"), f.stats.frame_ms);
                        samples.push(case, &format!("sort {k}"), f.stats.ms_of("thin-cloth sort"));
                    }
                }
                Duration::from_secs_f64(total / 1e3)
            })
        });
    }
}

fn orbit_table(title: &str, samples: &Samples, triangles: usize) {
    let (o, t) = (samples.median("opaque", "frame"), samples.median("transmission", "frame"));
    if o.is_none() && t.is_none() {
        return;
    }
    println!("\n## {title}: transmission against the opaque curtain (baseline)\n");
    println!("| light position | opaque ms | transmission ms | × opaque | sort ms |");
    println!("|---|---:|---:|---:|---:|");
    let (mut so, mut st, mut ss, mut n) = (0.0, 0.0, 0.0, 0);
    for k in 0..STEPS {
        let mo = samples.median("opaque", &format!("frame {k}"));
        let mt = samples.median("transmission", &format!("frame {k}"));
        let sort = samples.median("transmission", &format!("sort {k}"));
        println!(
            "| {k} | {} | {} | {} | {} |",
            num(mo, 1),
            num(mt, 1),
            ratio(mt, mo, 3),
            num(sort, 3)
        );
        if let (Some(mo), Some(mt)) = (mo, mt) {
            (so, st, ss, n) = (so + mo, st + mt, ss + sort.unwrap_or(0.0), n + 1);
        }
    }
    if n > 0 {
        let n = n as f64;
        println!(
            "| mean over the orbit | {:.1} | {:.1} | **{:.3}** | {:.3} |",
            so / n,
            st / n,
            st / so,
            ss / n
        );
    }
    println!("\n{triangles} triangles of curtain.");
}

fn main() {
    let Some(gpu) = gpu_or_skip("thin") else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_store(d, "voile.eigen", Pattern::Checker, 64, 64, 16, Quantization::F16);
    write_store(d, "wall.eigen", Pattern::Ribs, 64, 64, 16, Quantization::F16);
    let mesh =
        datasets::synth_mesh(datasets::MeshKind::Curtain, datasets::Resolution::Low).unwrap();
    datasets::write_obj(&mesh, &d.join("curtain.obj"), "curtain").unwrap();
    let wall = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/wall.obj"
    ))
    .unwrap();
    write(d, "wall.obj", &wall);
    let sky = datasets::synth_env(datasets::EnvKind::Sky, &Default::default(), 256).unwrap();
    sky.write_exr(&d.join("sky.exr")).unwrap();
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("thin-orbit");
    std::fs::create_dir_all(&out).unwrap();
    let camera =
        "[camera]\neye = [0.0, -2.6, 0.75]\ntarget = [0.0, 0.0, 0.75]\nup = [0.0, 0.0, 1.0]\n";
    let load = |name: &str, text: String| Scene::load(&write(d, name, &text)).unwrap();
    let wall_scene = |name: &str, t: &str| {
        load(
            name,
            format!(
                "[output]\nwidth = 256\nheight = 256\n\
                 [[meshes]]\npath = \"curtain.obj\"\n[[meshes]]\npath = \"wall.obj\"\n\
                 [[materials]]\nname = \"wall\"\nstore = \"wall.eigen\"\nuv_scale = 2.0\n\
                 [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\n{t}\n{camera}\
                 [[lights]]\nkind = \"point\"\nposition = {:?}\nintensity = [0.6, 0.6, 0.6]\n",
                orbit(0)
            ),
        )
    };
    let env_light = "[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nexposure = 0.05\n\
                     visibility_res = 16\ncache_dir = \"cache\"\n";
    let env_scene = |name: &str, t: &str| {
        load(
            name,
            format!(
                "[output]\nwidth = 256\nheight = 256\nshow_environment = true\n\
                 [[meshes]]\npath = \"curtain.obj\"\n\
                 [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\n{t}\n{camera}\
                 [[lights]]\nkind = \"point\"\nposition = {:?}\nintensity = [1.5, 1.5, 1.5]\n\
                 shadows = false\n{env_light}",
                orbit(0)
            ),
        )
    };
    let table_scene = |name: &str, t: &str| {
        load(
            name,
            format!(
                "[output]\nwidth = 32\nheight = 32\n[[meshes]]\npath = \"curtain.obj\"\n\
                 [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\ntransmission = {t}\n\
                 {camera}{env_light}"
            ),
        )
    };

    let samples = Samples::default();
    let mut c = criterion();
    let mut g = c.benchmark_group("thin-orbit");
    g.sampling_mode(SamplingMode::Flat);
    let thin = "transmission = { tau = 2.0, tau_texture = \"btf-mean\", albedo = 1.0 }";
    let scenes = [
        ("opaque", wall_scene("wall-o.toml", "")),
        ("transmission", wall_scene("wall-t.toml", thin)),
    ];
    orbit_group(&mut g, &gpu, &samples, scenes, Some(&out));
    g.finish();

    let env_samples = Samples::default();
    let mut g = c.benchmark_group("thin-environment");
    g.sampling_mode(SamplingMode::Flat);
    let thin = "transmission = { tau = 0.6, albedo = 0.9 }";
    let scenes =
        [("opaque", env_scene("env-o.toml", "")), ("transmission", env_scene("env-t.toml", thin))];
    orbit_group(&mut g, &gpu, &env_samples, scenes, None);
    g.finish();

    let tables = Samples::default();
    let mut g = c.benchmark_group("thin-env-tables");
    g.sampling_mode(SamplingMode::Flat);
    let cases = [
        ("scalar tau", "{ tau = 0.6, albedo = 0.9 }"),
        ("tau texture", "{ tau = 0.6, tau_texture = \"btf-mean\", albedo = 0.9 }"),
    ];
    for (i, (case, t)) in cases.into_iter().enumerate() {
        let scene = table_scene(&format!("tables-{i}.toml"), t);
        let (gpu, tables) = (&gpu, tables.clone());
        g.bench_function(case, move |b| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                for _ in 0..iters {
                    let mut r = Renderer::new(gpu, &scene, RenderOptions::default()).unwrap();
                    let ms = r.render(gpu).unwrap().stats.ms_of("thin-cloth env tables");
                    tables.push(case, "tables", ms);
                    total += ms;
                }
                Duration::from_secs_f64(total / 1e3)
            })
        });
    }
    let scene = table_scene("tables-r.toml", cases[0].1);
    let (gpu_ref, tables_ref) = (&gpu, tables.clone());
    let mut r = Renderer::new(gpu_ref, &scene, RenderOptions::default()).unwrap();
    r.render(gpu_ref).unwrap();
    let mut delta = 0.0;
    g.bench_function("rotation", move |b| {
        b.iter_custom(|iters| {
            let mut total = 0.0;
            for _ in 0..iters {
                delta = (delta + 30.0) % 360.0;
                r.set_environment_rotation(delta).unwrap();
                let ms = r.render(gpu_ref).unwrap().stats.ms_of("thin-cloth env tables");
                tables_ref.push("rotation", "tables", ms);
                total += ms;
            }
            Duration::from_secs_f64(total / 1e3)
        })
    });
    g.finish();
    c.final_summary();

    orbit_table("thin-orbit (curtain before a wall, 256²)", &samples, mesh.triangles.len());
    println!("Frames of the orbit: {}", out.display());
    orbit_table(
        "thin-environment (curtain under the sky, 256²)",
        &env_samples,
        mesh.triangles.len(),
    );
    let base = tables.median("scalar tau", "tables");
    if tables.count("scalar tau", "tables")
        + tables.count("tau texture", "tables")
        + tables.count("rotation", "tables")
        > 0
    {
        println!(
            "\n## thin-env-tables: thin-cloth environment tables, {} vertices (baseline: scalar τ)\n",
            mesh.positions.len()
        );
        println!("| tables | ms (median) | samples | × scalar τ |");
        println!("|---|---:|---:|---:|");
        for (case, label) in [
            ("scalar tau", "scalar τ₁ = 0.6 (one τ node)"),
            ("tau texture", "`tau_texture = \"btf-mean\"` (8 τ nodes)"),
            ("rotation", "scalar τ after a 30° rotation"),
        ] {
            let m = tables.median(case, "tables");
            if m.is_some() {
                println!(
                    "| {label} | {} | {} | {} |",
                    num(m, 1),
                    tables.count(case, "tables"),
                    ratio(m, base, 2)
                );
            }
        }
    }
}
