//! Frame-time ratios on lavapipe (run with `cargo test -p btf-render --test measure --
//! --ignored --nocapture`): evaluation mode, blending, components and shadow technique on
//! the example sphere-over-plane mesh. Absolute times are CPU-Vulkan times; the ratios are
//! what to read. Not a timed test: it asserts nothing about speed.

mod common;

use btf_core::eigen::Quantization;
use btf_render::{RenderOptions, Renderer, Scene};
use common::*;

#[test]
#[ignore = "a measurement on lavapipe: run for BENCHMARKS.md"]
fn frame_time_ratios() {
    let Some(gpu) = gpu("frame_time_ratios") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 64, 64, 16, Quantization::F16);
    let obj = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/sphere-on-plane.obj"
    ))
    .unwrap();
    write(dir.path(), "mesh.obj", &obj);
    let run = |effects: &str, shadows: bool| {
        let text = format!(
            r#"
            [output]
            width = 256
            height = 256
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
        let scene = Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap();
        let mut r = Renderer::new(&gpu, &scene, RenderOptions::default()).unwrap();
        r.render(&gpu).unwrap();
        let mut best = f64::MAX;
        let mut passes = Vec::new();
        for _ in 0..3 {
            let f = r.render(&gpu).unwrap();
            if f.stats.frame_ms < best {
                best = f.stats.frame_ms;
                passes = f.stats.passes.iter().map(|p| format!("{} {:.1}", p.name, p.ms)).collect();
            }
        }
        let counted =
            Renderer::new(&gpu, &scene, RenderOptions { count_reads: true, ..Default::default() })
                .unwrap()
                .render(&gpu)
                .unwrap();
        eprintln!(
            "{:<58} frame {best:>8.1} ms  reads/px {:>5.1}  [{}]",
            effects.replace('\n', "; "),
            counted.stats.reads_per_pixel.unwrap(),
            passes.join(", ")
        );
        best
    };
    let base = run("", false);
    for fx in [
        "components = 4",
        "components = 8",
        "components = 16\nview_blend = \"nearest\"",
        "components = 16\nview_blend = \"nearest\"\nlight_interp = \"nearest\"",
        "evaluation = \"per-vertex\"",
        "evaluation = \"per-vertex\"\nview_blend = \"nearest\"",
        "msaa = 4",
    ] {
        let t = run(fx, false);
        eprintln!("    ratio to per-pixel c=16 four/four: {:.2}", t / base);
    }
    for fx in ["shadows = \"volume\"", "shadows = \"map\""] {
        let t = run(fx, true);
        eprintln!("    ratio to unshadowed: {:.2}", t / base);
    }
}

/// The cost sweep of `btf render-sweep` on the sphere-over-plane mesh at 256², c = 4…32
/// (`BTF_SWEEP_SIZE` overrides the size, `BTF_SWEEP_COMPONENTS=4,32` the component counts,
/// `BTF_SWEEP_REPEATS` the timed frames per cell): prints the rows, the linear fits and the
/// checks.
#[test]
#[ignore = "a measurement on lavapipe: run for BENCHMARKS.md"]
fn cost_sweep_against_baselines() {
    use btf_render::cost_sweep::{SweepConfig, run};
    let Some(gpu) = gpu("cost_sweep_against_baselines") else { return };
    let size: u32 =
        std::env::var("BTF_SWEEP_SIZE").ok().and_then(|s| s.parse().ok()).unwrap_or(256);
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 64, 64, 32, Quantization::F16);
    let obj = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/sphere-on-plane.obj"
    ))
    .unwrap();
    write(dir.path(), "mesh.obj", &obj);
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
        "#
    );
    let scene = Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap();
    let components = std::env::var("BTF_SWEEP_COMPONENTS")
        .ok()
        .map(|s| s.split(',').map(|c| c.trim().parse().unwrap()).collect())
        .unwrap_or_else(|| vec![4, 8, 16, 32]);
    let repeats = std::env::var("BTF_SWEEP_REPEATS").ok().and_then(|s| s.parse().ok()).unwrap_or(5);
    let config = SweepConfig { components, repeats };
    let r = run(&gpu, &scene, &config, &mut |d, n| eprint!("\r{d}/{n}")).unwrap();
    eprintln!();
    eprintln!(
        "| c | evaluation | blending | rel. RMSE | reads/px | BTF ms | plain ms | bound ms | × plain | × bound |"
    );
    for x in &r.rows {
        eprintln!(
            "| {} | {} | {} | {:.2e} | {:.1} | {:.2} | {:.2} | {:.2} | {:.1} | {:.2} |",
            x.components,
            x.evaluation,
            x.blending,
            x.rel_rmse,
            x.reads_per_pixel,
            x.btf_ms,
            x.plain_ms,
            x.read_bound_ms,
            x.ratio_plain,
            x.ratio_read_bound
        );
    }
    for f in &r.fits {
        eprintln!("fit {}: {:.3} + {:.4}·c ms, R² {:.4}", f.mode, f.intercept, f.slope, f.r2);
    }
    eprintln!(
        "worst × read bound {:.2}; per-pixel reads ≤ per-vertex: {}",
        r.worst_read_bound_ratio, r.per_pixel_reads_le_per_vertex
    );
}
