//! Environment-light preparation through the renderer on the synthetic shirt (BENCHMARKS.md
//! "Session 5: only the vertex sides the camera shows"): what `Renderer::new` spends on a
//! scene's environment light before its first frame when it computes only the vertex sides
//! the camera shows (corner-id pass, then visibility and the gather for those sides) against
//! every side of the two-sided cloth (**baseline**, `RenderOptions::all_env_sides`, what the
//! orbiting viewer computes), same scene, same run.
//!
//! Scenes: the low shirt (925 vertices; `BTF_MEASURE_HIGH=1`: the 9160-vertex one), ubo81
//! store with c = 16, the synthetic sky 512×256, hemicube 32², no visibility cache; cameras
//! `front 256² msaa 1`, `front 512² msaa 4` and `below 512² msaa 4` (below the hem looking
//! up into the shirt: much of the inside in view). Group `camera-sides`, benchmarks
//! `CAMERA/camera sides` and `CAMERA/all sides`, each sample a new renderer, timed by its
//! `EnvTimings` (corner-id pass + visibility + gather; pipelines and the store's upload are
//! not counted). Before criterion, the frames of both are compared bit for bit (0 differing
//! values expected). After criterion a markdown table gives per camera the frames computed,
//! the corner-id pass, visibility, their sum per mesh vertex, the gather, and the ratios
//! camera sides / all sides.
//!
//! `cargo bench -p btf-render --bench envlight` (`-- --quick` for a short run,
//! `-- front` for the front cameras only). The CPU parts alone (visibility against the ray
//! cast, the gather, rotations) are btf-light's benches `visibility` and `envlight`. Without
//! a GPU adapter it prints why and exits 0.

mod common;

use btf_core::eigen::Quantization;
use btf_render::{RenderOptions, Renderer, Scene};
use common::*;
use criterion::SamplingMode;
use datasets::mesh::{MeshKind, Resolution};
use std::time::Duration;

fn main() {
    let Some(gpu) = gpu_or_skip("envlight") else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let high = env_flag("BTF_MEASURE_HIGH");
    let (name, res) =
        if high { ("shirt high", Resolution::High) } else { ("shirt low", Resolution::Low) };
    let synth = datasets::mesh::synth_mesh(MeshKind::Shirt, res).unwrap();
    datasets::mesh::write_obj(&synth, &d.join("shirt.obj"), "shirt").unwrap();
    let mesh = btf_light::mesh::Mesh::load_obj(&d.join("shirt.obj"), None).unwrap();
    let n = mesh.positions.len();
    write_store(d, "m.eigen", Pattern::Checker, 4, 4, 16, Quantization::F16);
    let env = datasets::env::synth_env(
        datasets::env::EnvKind::Sky,
        &datasets::env::EnvParams::default(),
        512,
    )
    .unwrap();
    env.write_exr(&d.join("sky.exr")).unwrap();
    let (lo, hi) = mesh.bounds();
    let target: [f32; 3] = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let cameras = [
        ("front 256² msaa 1", [0.0f32, -3.0, 0.5], 256, 1),
        ("front 512² msaa 4", [0.0, -3.0, 0.5], 512, 4),
        ("below 512² msaa 4", [0.3, -1.6, -2.2], 512, 4),
    ];
    let scenes: Vec<Scene> = cameras
        .iter()
        .enumerate()
        .map(|(i, (_, eye, size, msaa))| {
            let text = format!(
                "[output]\nwidth = {size}\nheight = {size}\n[[meshes]]\npath = \"shirt.obj\"\n\
                 [[materials]]\nstore = \"m.eigen\"\n[camera]\neye = {eye:?}\n\
                 target = {target:?}\nfov_y_deg = 35.0\n[[lights]]\nkind = \"environment\"\n\
                 path = \"sky.exr\"\nvisibility_res = 32\n[effects]\nmsaa = {msaa}\n"
            );
            Scene::load(&write(d, &format!("scene-{i}.toml"), &text)).unwrap()
        })
        .collect();
    println!("{name}: {n} vertices, {} triangles, hemicube 32², two-sided", mesh.triangles.len());
    let options = |all| RenderOptions { all_env_sides: all, ..Default::default() };
    for ((cam, ..), scene) in cameras.iter().zip(&scenes) {
        let frame = |all| Renderer::new(&gpu, scene, options(all)).unwrap().render(&gpu).unwrap();
        let (a, b) = (frame(false), frame(true));
        let differ = a.rgb.iter().zip(&b.rgb).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
        println!("{name}, {cam}: {differ} differing values between camera sides and all sides");
    }

    let samples = Samples::default();
    let mut c = criterion();
    let mut g = c.benchmark_group("camera-sides");
    g.sampling_mode(SamplingMode::Flat);
    for ((cam, ..), scene) in cameras.iter().zip(&scenes) {
        for (sides, all) in [("camera sides", false), ("all sides", true)] {
            let case = format!("{cam}/{sides}");
            let (gpu, samples) = (&gpu, samples.clone());
            g.bench_function(case.as_str(), |b| {
                b.iter_custom(|iters| {
                    let mut total = 0.0;
                    for _ in 0..iters {
                        let r = Renderer::new(gpu, scene, options(all)).unwrap();
                        let e = r.environment().unwrap();
                        let t = &e.timings;
                        samples.push(&case, "sides", t.sides_ms);
                        samples.push(&case, "visibility", t.visibility_ms);
                        samples.push(&case, "gather", t.weights_ms);
                        samples.push(&case, "computed", e.computed_frames() as f64);
                        samples.push(&case, "frames", e.frames() as f64);
                        total += t.sides_ms + t.visibility_ms + t.weights_ms;
                    }
                    Duration::from_secs_f64(total / 1e3)
                })
            });
        }
    }
    g.finish();
    c.final_summary();

    println!("\n## camera-sides: {name} ({n} vertices), medians; baseline: all sides\n");
    println!(
        "| camera | sides | frames computed | corner-id ms | visibility ms | per mesh vertex ms | gather ms | prep. × all sides | gather × all sides |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (cam, ..) in cameras {
        let prep =
            |case: &str| Some(samples.median(case, "sides")? + samples.median(case, "visibility")?);
        let all = format!("{cam}/all sides");
        for sides in ["camera sides", "all sides"] {
            let case = format!("{cam}/{sides}");
            let Some(p) = prep(&case) else { continue };
            println!(
                "| {cam} | {sides} | {:.0} of {:.0} | {} | {} | {:.3} | {} | {} | {} |",
                samples.median(&case, "computed").unwrap_or(f64::NAN),
                samples.median(&case, "frames").unwrap_or(f64::NAN),
                num(samples.median(&case, "sides"), 1),
                num(samples.median(&case, "visibility"), 1),
                p / n as f64,
                num(samples.median(&case, "gather"), 1),
                ratio(Some(p), prep(&all), 3),
                ratio(samples.median(&case, "gather"), samples.median(&all, "gather"), 3),
            );
        }
    }
}
