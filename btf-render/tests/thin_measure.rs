//! Frame-time cost of the transmission effect on lavapipe, and the paper's demo: a point
//! light circling a curtain in front of a wall (run with `cargo test -p btf-render --test
//! thin_measure -- --ignored --nocapture`). Per light position the same scene is rendered
//! with the curtain opaque and with `transmission`, back to back; the frames of the orbit
//! go to `CARGO_TARGET_TMPDIR/thin-orbit/`. Asserts nothing about speed.

mod common;

use btf_core::eigen::Quantization;
use btf_render::{RenderOptions, Renderer, Scene};
use common::*;

fn best_ms(r: &mut Renderer, gpu: &btf_render::Gpu, repeats: usize) -> (f64, btf_render::Frame) {
    let mut best = (f64::MAX, r.render(gpu).unwrap());
    for _ in 0..repeats {
        let f = r.render(gpu).unwrap();
        if f.stats.frame_ms < best.0 {
            best = (f.stats.frame_ms, f);
        }
    }
    best
}

#[test]
#[ignore = "a measurement on lavapipe: run for BENCHMARKS.md"]
fn transmission_cost_and_orbit() {
    let Some(gpu) = gpu("transmission_cost_and_orbit") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "voile.eigen", Pattern::Checker, 64, 64, 16, Quantization::F16);
    write_store(dir.path(), "wall.eigen", Pattern::Ribs, 64, 64, 16, Quantization::F16);
    let mesh =
        datasets::synth_mesh(datasets::MeshKind::Curtain, datasets::Resolution::Low).unwrap();
    datasets::write_obj(&mesh, &dir.path().join("curtain.obj"), "curtain").unwrap();
    let wall = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/wall.obj"
    ))
    .unwrap();
    write(dir.path(), "wall.obj", &wall);
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("thin-orbit");
    std::fs::create_dir_all(&out).unwrap();
    let steps = 8;
    let (mut sum_opaque, mut sum_thin, mut sum_sort) = (0.0, 0.0, 0.0);
    for k in 0..steps {
        let a = std::f32::consts::TAU * k as f32 / steps as f32;
        let pos = [0.9 * a.sin(), -0.9 * a.cos() + 0.1, 1.0];
        let scene = |t: &str| {
            let text = format!(
                "[output]\nwidth = 256\nheight = 256\n\
                 [[meshes]]\npath = \"curtain.obj\"\n[[meshes]]\npath = \"wall.obj\"\n\
                 [[materials]]\nname = \"wall\"\nstore = \"wall.eigen\"\nuv_scale = 2.0\n\
                 [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\n{t}\n\
                 [camera]\neye = [0.0, -2.6, 0.75]\ntarget = [0.0, 0.0, 0.75]\nup = [0.0, 0.0, 1.0]\n\
                 [[lights]]\nkind = \"point\"\nposition = {pos:?}\nintensity = [0.6, 0.6, 0.6]\n"
            );
            Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap()
        };
        let mut opaque = Renderer::new(&gpu, &scene(""), RenderOptions::default()).unwrap();
        let mut thin = Renderer::new(
            &gpu,
            &scene("transmission = { tau = 2.0, tau_texture = \"btf-mean\", albedo = 1.0 }"),
            RenderOptions::default(),
        )
        .unwrap();
        let (t_opaque, _) = best_ms(&mut opaque, &gpu, 3);
        let (t_thin, frame) = best_ms(&mut thin, &gpu, 3);
        let sort = frame.stats.ms_of("thin-cloth sort");
        frame.write_png(&out.join(format!("orbit-{k:02}.png")), 3.0).unwrap();
        eprintln!(
            "light {k}: opaque {t_opaque:.1} ms, transmission {t_thin:.1} ms (sort {sort:.3} ms), ratio {:.3}",
            t_thin / t_opaque
        );
        sum_opaque += t_opaque;
        sum_thin += t_thin;
        sum_sort += sort;
    }
    eprintln!(
        "mean over the orbit: opaque {:.1} ms, transmission {:.1} ms, ratio {:.3}, sort {:.3} ms; {} triangles of curtain; frames in {}",
        sum_opaque / steps as f64,
        sum_thin / steps as f64,
        sum_thin / sum_opaque,
        sum_sort / steps as f64,
        mesh.triangles.len(),
        out.display()
    );
}

/// The same orbit with the curtain in front of a synthetic sky that lights it and shows
/// through it (environment light + `show_environment`, no wall): opaque and thin curtain
/// (scalar τ₁ = 0.6, as the environment terms need) rendered back to back per light
/// position, plus the one-off cost of the thin-cloth environment tables and of a rotation.
#[test]
#[ignore = "a measurement on lavapipe: run for BENCHMARKS.md"]
fn transmission_cost_under_an_environment() {
    let Some(gpu) = gpu("transmission_cost_under_an_environment") else { return };
    let (dir, mesh) = curtain_and_sky();
    let scene = |t: &str| {
        let text = format!(
            "[output]\nwidth = 256\nheight = 256\nshow_environment = true\n\
             [[meshes]]\npath = \"curtain.obj\"\n\
             [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\n{t}\n\
             [camera]\neye = [0.0, -2.6, 0.75]\ntarget = [0.0, 0.0, 0.75]\nup = [0.0, 0.0, 1.0]\n\
             [[lights]]\nkind = \"point\"\nposition = [0.0, -0.8, 1.0]\nintensity = [1.5, 1.5, 1.5]\nshadows = false\n\
             [[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nexposure = 0.05\nvisibility_res = 16\ncache_dir = \"cache\"\n"
        );
        Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap()
    };
    let mut opaque = Renderer::new(&gpu, &scene(""), RenderOptions::default()).unwrap();
    let mut thin = Renderer::new(
        &gpu,
        &scene("transmission = { tau = 0.6, albedo = 0.9 }"),
        RenderOptions::default(),
    )
    .unwrap();
    let first = thin.render(&gpu).unwrap();
    let tables_ms = first.stats.ms_of("thin-cloth env tables");
    thin.set_environment_rotation(30.0).unwrap();
    let rotated = thin.render(&gpu).unwrap();
    let rotation_ms = rotated.stats.ms_of("thin-cloth env tables");
    thin.set_environment_rotation(0.0).unwrap();
    thin.render(&gpu).unwrap();
    let steps = 8;
    let (mut sum_opaque, mut sum_thin) = (0.0, 0.0);
    for k in 0..steps {
        let a = std::f32::consts::TAU * k as f32 / steps as f32;
        let pos = [0.9 * a.sin(), -0.9 * a.cos() + 0.1, 1.0];
        for r in [&mut opaque, &mut thin] {
            let mut lights = r.scene().lights.clone();
            if let btf_render::scene::Light::Point { position, .. } = &mut lights[0] {
                *position = pos;
            }
            r.set_lights(&gpu, &lights).unwrap();
        }
        let (mut t_o, mut t_t) = (f64::MAX, f64::MAX);
        for _ in 0..3 {
            t_o = t_o.min(opaque.render(&gpu).unwrap().stats.frame_ms);
            t_t = t_t.min(thin.render(&gpu).unwrap().stats.frame_ms);
        }
        eprintln!(
            "light {k}: opaque {t_o:.1} ms, transmission {t_t:.1} ms, ratio {:.3}",
            t_t / t_o
        );
        sum_opaque += t_o;
        sum_thin += t_t;
    }
    eprintln!(
        "environment: mean over the orbit: opaque {:.1} ms, transmission {:.1} ms, ratio {:.3}; thin-cloth env tables {tables_ms:.1} ms once ({rotation_ms:.1} ms after a rotation), {} vertices",
        sum_opaque / steps as f64,
        sum_thin / steps as f64,
        sum_thin / sum_opaque,
        mesh.positions.len()
    );
}

/// The one-off cost of the thin-cloth environment tables: scalar τ₁ (one τ node) against
/// `tau_texture = "btf-mean"` (8 τ nodes), same curtain and sky as above, back to back.
#[test]
#[ignore = "a measurement: run for BENCHMARKS.md"]
fn environment_table_cost_scalar_vs_tau_texture() {
    let Some(gpu) = gpu("environment_table_cost_scalar_vs_tau_texture") else { return };
    let (dir, mesh) = curtain_and_sky();
    let scene = |t: &str| {
        let text = format!(
            "[output]\nwidth = 32\nheight = 32\n[[meshes]]\npath = \"curtain.obj\"\n\
             [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 6.0\ntransmission = {t}\n\
             [camera]\neye = [0.0, -2.6, 0.75]\ntarget = [0.0, 0.0, 0.75]\nup = [0.0, 0.0, 1.0]\n\
             [[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nexposure = 0.05\nvisibility_res = 16\ncache_dir = \"cache\"\n"
        );
        Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap()
    };
    let mut ms = [f64::MAX; 2];
    for _ in 0..3 {
        for (i, t) in [
            "{ tau = 0.6, albedo = 0.9 }",
            "{ tau = 0.6, tau_texture = \"btf-mean\", albedo = 0.9 }",
        ]
        .iter()
        .enumerate()
        {
            let mut r = Renderer::new(&gpu, &scene(t), RenderOptions::default()).unwrap();
            ms[i] = ms[i].min(r.render(&gpu).unwrap().stats.ms_of("thin-cloth env tables"));
            eprintln!("{t}: {:.1} ms", ms[i]);
        }
    }
    eprintln!(
        "thin-cloth env tables, {} vertices: scalar τ {:.1} ms, τ texture (8 nodes) {:.1} ms, ratio {:.2} (best of 3)",
        mesh.positions.len(),
        ms[0],
        ms[1],
        ms[1] / ms[0]
    );
}

/// A folder with the voile store, the low curtain (`curtain.obj`) and the synthetic sky
/// (`sky.exr`) that the environment measurements share.
fn curtain_and_sky() -> (tempfile::TempDir, datasets::Mesh) {
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "voile.eigen", Pattern::Checker, 64, 64, 16, Quantization::F16);
    let mesh =
        datasets::synth_mesh(datasets::MeshKind::Curtain, datasets::Resolution::Low).unwrap();
    datasets::write_obj(&mesh, &dir.path().join("curtain.obj"), "curtain").unwrap();
    let sky = datasets::synth_env(datasets::EnvKind::Sky, &Default::default(), 256).unwrap();
    sky.write_exr(&dir.path().join("sky.exr")).unwrap();
    (dir, mesh)
}
