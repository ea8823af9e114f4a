//! Frame-time ratios of the BTF renderer on lavapipe (issue #5; BENCHMARKS.md "Rendering
//! (issue #5): what each effect costs"): evaluation mode, blending, components, MSAA and the
//! shadow technique on the example sphere-over-plane mesh, 256², synthetic 64² checker
//! store with 16 components (f16), one point light.
//!
//! One criterion benchmark per setting in the group `frame`, each timed per frame by
//! `Stats::frame_ms` (per-frame CPU work, encoding and GPU execution, not the read-back).
//! **Baseline**: `frame/baseline` — per-pixel evaluation, c = 16, four-slot view blending
//! and four-light interpolation, unshadowed — measured in the same run; the shadowed rows
//! are against the same unshadowed baseline. After criterion a markdown table gives, per
//! setting, the texture reads per pixel (counted in a separate frame), the median frame
//! time (over every frame criterion ran, warm-up included) and its ratio to the baseline's
//! median. Absolute times are CPU-Vulkan times; the
//! ratios are what to read.
//!
//! `cargo bench -p btf-render --bench frame` (`-- --quick` for a short run, `-- shadow` to
//! run only the shadow rows; `BTF_FRAME_SIZE=N` renders N² instead of 256²). Without a GPU
//! adapter it prints why and exits 0.

mod common;

use btf_core::eigen::Quantization;
use btf_render::{RenderOptions, Renderer, Scene};
use common::*;
use criterion::SamplingMode;

/// `(case, what the table calls it, [effects] body, point-light shadows)`.
const CASES: [(&str, &str, &str, bool); 10] = [
    ("baseline", "per-pixel, c = 16, four/four (baseline)", "", false),
    ("c=8", "c = 8", "components = 8", false),
    ("c=4", "c = 4", "components = 4", false),
    ("nearest view", "nearest view blending", "view_blend = \"nearest\"", false),
    (
        "nearest view+light",
        "nearest view blending and nearest light",
        "view_blend = \"nearest\"\nlight_interp = \"nearest\"",
        false,
    ),
    ("per-vertex", "per-vertex (paper), four/four", "evaluation = \"per-vertex\"", false),
    (
        "per-vertex nearest",
        "per-vertex, nearest view blending",
        "evaluation = \"per-vertex\"\nview_blend = \"nearest\"",
        false,
    ),
    ("msaa 4", "MSAA 4×", "msaa = 4", false),
    ("shadow volume", "+ shadow volumes (stencil)", "shadows = \"volume\"", true),
    ("shadow map", "+ shadow map", "shadows = \"map\"", true),
];

fn scene(dir: &std::path::Path, i: usize, size: u32, effects: &str, shadows: bool) -> Scene {
    let text = format!(
        r#"
        [output]
        width = {size}
        height = {size}
        [[meshes]]
        path = "mesh.obj"
        [[materials]]
        store = "m.eigen"
        uv_scale = 2.0
        [camera]
        eye = [0.0, 1.8, 2.6]
        target = [0.0, 0.4, 0.0]
        [[lights]]
        kind = "point"
        position = [1.2, 2.2, 0.8]
        intensity = [4.0, 4.0, 4.0]
        shadows = {shadows}
        [effects]
        {effects}
        "#
    );
    Scene::load(&write(dir, &format!("scene-{i}.toml"), &text)).unwrap()
}

fn main() {
    let Some(gpu) = gpu_or_skip("frame") else { return };
    let size: u32 = env_or("BTF_FRAME_SIZE", 256);
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 64, 64, 16, Quantization::F16);
    sphere_on_plane(dir.path());
    let samples = Samples::default();
    let mut c = criterion();
    let mut group = c.benchmark_group("frame");
    group.sampling_mode(SamplingMode::Flat);
    for (i, (case, _, effects, shadows)) in CASES.iter().enumerate() {
        let s = scene(dir.path(), i, size, effects, *shadows);
        let (gpu, samples) = (&gpu, samples.clone());
        let opts = RenderOptions { count_reads: true, ..Default::default() };
        let counted = Renderer::new(gpu, &s, opts).unwrap().render(gpu).unwrap();
        samples.push(case, "reads", counted.stats.reads_per_pixel.unwrap_or(f64::NAN));
        let mut r = Renderer::new(gpu, &s, RenderOptions::default()).unwrap();
        r.render(gpu).unwrap(); // warm: pipelines, per-vertex buffers
        group.bench_function(*case, move |b| {
            b.iter_custom(|iters| time_frames(iters, gpu, &mut r, &samples, case))
        });
    }
    group.finish();
    c.final_summary();

    println!("\n## frame: ratios to the baseline ({size}², median frame time per setting)\n");
    println!("| setting | texture reads / pixel | frame ms (median) | frames | × baseline |");
    println!("|---|---:|---:|---:|---:|");
    let base = samples.median("baseline", "frame");
    for (case, label, ..) in CASES {
        let Some(ms) = samples.median(case, "frame") else { continue };
        println!(
            "| {label} | {} | {ms:.1} | {} | {} |",
            num(samples.median(case, "reads"), 1),
            samples.count(case, "frame"),
            ratio(Some(ms), base, 2)
        );
    }
}
