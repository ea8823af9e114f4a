//! Thin cloth under an environment light (`transmission/env.rs`): the per-vertex tables
//! against a direct quadrature over the visible sources, half-space furnaces on a flat
//! sheet against the slab's hemispherical transmission and reflection share (1-D
//! quadratures of `btf_core::thin_slab`), and the limits τ₁ → 0 / ∞ on the curtain, also
//! through τ textures (all 0, all 1, constant). The τ-node tables: `tests/thin_env_tau.rs`.

mod common;
#[path = "common/curtain_env.rs"]
mod curtain_env;

use btf_core::eigen::Quantization;
use btf_core::thin_slab::{Phase, Slab, direct_transmittance, reflection_share};
use btf_image::EnvMap;
use btf_light::thin_tables::{
    MU_NODES, ROWS_PER_SIDE, SlabParams, TAU_NODES, VEC4_PER_VERTEX, mu_node, tables,
};
use btf_render::{Frame, RenderOptions, Scene, render_scene};
use common::*;
use curtain_env::*;
use std::f64::consts::PI;
use std::path::Path;

#[test]
fn tables_equal_a_direct_quadrature_over_the_visible_sources() {
    let dir = tempfile::tempdir().unwrap();
    let c = curtain_env(dir.path());
    let n = c.mesh.positions.len();
    let slab = SlabParams { tau: 0.4, textured: false, albedo: [0.9, 0.8, 0.7] };
    let got = tables(&c.env, &vec![Some(slab); n]).unwrap();
    assert_eq!(got.len(), n * VEC4_PER_VERTEX);
    let mus: Vec<f64> = (0..MU_NODES).map(mu_node).collect();
    let mut occluded_somewhere = false;
    let mut worst = 0f64;
    for v in (0..n).step_by(n / 13) {
        for side in 0..2 {
            let (a, tk, seen) = reference(&c, side * n + v, 0.4, slab.albedo, &mus);
            occluded_somewhere |= seen < 0.97;
            // A scalar τ fills the last τ node.
            let base =
                v * VEC4_PER_VERTEX + side * ROWS_PER_SIDE + (TAU_NODES - 1) * (1 + MU_NODES);
            for ch in 0..3 {
                let mut check = |got: f32, want: f64| {
                    let e = (got as f64 - want).abs() / want.abs().max(1e-9);
                    assert!(e <= 1e-4, "vertex {v} side {side}: {got} vs {want}");
                    worst = worst.max(e);
                };
                check(got[base][ch], a[ch]);
                for k in 0..MU_NODES {
                    check(got[base + 1 + k][ch], tk[k][ch]);
                }
            }
        }
    }
    eprintln!("worst relative difference {worst:.2e}");
    assert!(occluded_somewhere, "the curtain's folds must hide part of some hemisphere");
}

/// An equirectangular 64×32 EXR: 1 on one half-space (`above`: z > 0), 0 on the other.
fn write_half_env(path: &Path, above: bool) {
    exr::prelude::write_rgb_file(path, 64, 32, |_, y| {
        let v = if (y < 16) == above { 1.0 } else { 0.0 };
        (v, v, v)
    })
    .unwrap();
}

/// `ϖ₀/(4π) ∫ F_t(τ, μ, μ₀) μ₀ dω₀` over a hemisphere of unit radiance (midpoint rule).
fn hemispherical_transmission(tau: f64, albedo: f64, mu: f64) -> f64 {
    let s = Slab { tau, albedo, phase: Phase::Isotropic };
    let n = 20000;
    let sum: f64 = (0..n)
        .map(|i| {
            let mu0 = (i as f64 + 0.5) / n as f64;
            s.f_t(mu, mu0, 0.0) * mu0
        })
        .sum();
    2.0 * PI * sum / n as f64
}

/// `2 ∫ e^{−τ/μ₀} μ₀ dμ₀`: the irradiance-weighted direct transmittance of a uniform sky.
fn uniform_a(tau: f64) -> f64 {
    let n = 20000;
    let sum: f64 = (0..n).map(|i| (i as f64 + 0.5) / n as f64).map(|m| (-tau / m).exp() * m).sum();
    2.0 * sum / n as f64
}

const BG: [f32; 3] = [0.2, 0.3, 0.4];

fn sheet_scene(dir: &Path, env: &str, transmission: &str, tilt_deg: f64, extra: &str) -> Scene {
    let (s, c) = tilt_deg.to_radians().sin_cos();
    let eye = [0.5 + 2.0 * s, 0.5, 2.0 * c];
    let t = if transmission.is_empty() {
        String::new()
    } else {
        format!("transmission = {transmission}\n")
    };
    let text = format!(
        "[output]\nwidth = 24\nheight = 24\nbackground = {BG:?}\n[[meshes]]\npath = \"sheet.obj\"\n\
         [[materials]]\nstore = \"m.eigen\"\n{t}[camera]\nprojection = \"orthographic\"\n\
         eye = {eye:?}\ntarget = [0.5, 0.5, 0.0]\nup = [0.0, 1.0, 0.0]\northo_height = 0.4\n\
         {extra}[[lights]]\nkind = \"environment\"\npath = \"{env}\"\nvisibility_res = 16\n"
    );
    Scene::load(&write(dir, "sheet.toml", &text)).unwrap()
}

fn render(gpu: &btf_render::Gpu, scene: &Scene) -> Frame {
    let f = render_scene(gpu, scene, RenderOptions::default()).unwrap();
    assert!(f.all_finite());
    f
}

fn worst_rel(f: &Frame, expected: impl Fn(usize) -> f64) -> f64 {
    f.rgb
        .iter()
        .enumerate()
        .map(|(i, &v)| (v as f64 - expected(i)).abs() / expected(i))
        .fold(0.0, f64::max)
}

#[test]
fn half_space_furnaces_give_the_slab_albedos() {
    let Some(gpu) = gpu("half_space_furnaces_give_the_slab_albedos") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 8, 8, 4, Quantization::F16);
    write(dir.path(), "sheet.obj", &plane_obj(2, false));
    write_half_env(&dir.path().join("below.exr"), false);
    write_half_env(&dir.path().join("above.exr"), true);
    let (tau, albedo) = (0.5, 0.9);
    let thin = format!("{{ tau = {tau}, albedo = {albedo} }}");
    // μ = 1 and 0.64 fall on table nodes, μ = 0.5 between two (interpolated in √μ).
    for tilt in [0.0f64, 0.64f64.acos().to_degrees(), 60.0] {
        let mu = tilt.to_radians().cos();
        let alpha = direct_transmittance(tau, mu);
        // Lit from behind only: what is behind, plus the hemispherical transmission.
        let t = hemispherical_transmission(tau, albedo, mu);
        let f = render(&gpu, &sheet_scene(dir.path(), "below.exr", &thin, tilt, ""));
        let e = worst_rel(&f, |i| BG[i % 3] as f64 * alpha + t);
        eprintln!("back-lit μ = {mu:.3}: t = {t:.5}, worst relative error {e:.2e}");
        assert!(e < 0.01, "back-lit at μ = {mu}: {e}");
        // Lit from the front only: the opaque environment render scaled by 1 − e^{−τ/μ}·A.
        let opaque = render(&gpu, &sheet_scene(dir.path(), "above.exr", "", tilt, ""));
        let furnace = opaque.rgb.iter().map(|&v| v as f64).sum::<f64>() / opaque.rgb.len() as f64;
        assert!((furnace - 0.8).abs() < 0.01 * 0.8, "white furnace {furnace}");
        let share = 1.0 - alpha * uniform_a(tau);
        let f = render(&gpu, &sheet_scene(dir.path(), "above.exr", &thin, tilt, ""));
        let e = worst_rel(&f, |i| BG[i % 3] as f64 * alpha + share * opaque.rgb[i] as f64);
        eprintln!("front-lit μ = {mu:.3}: share = {share:.4}, worst relative error {e:.2e}");
        assert!(e < 0.01, "front-lit at μ = {mu}: {e}");
    }
    // The environment drawn behind the sheet shows through with the same alpha: seen from
    // above, the rays behind the sheet go down into the unit half of below.exr.
    let mut scene = sheet_scene(dir.path(), "below.exr", &thin, 0.0, "");
    scene.output.show_environment = true;
    let f = render(&gpu, &scene);
    let (alpha, t) = (direct_transmittance(tau, 1.0), hemispherical_transmission(tau, albedo, 1.0));
    let e = worst_rel(&f, |_| alpha + t);
    assert!(e < 0.01, "environment background: {e}");
    // Per-vertex scenes keep the environment's own entry: a directional light first (its
    // per-vertex BTF term must not leak into the thin sheet), lit from above.
    let (mu0, e_dir) = (1.0 / 1.09f64.sqrt(), 2.0);
    let dir_light = format!(
        "[[lights]]\nkind = \"directional\"\ndirection = [0.3, 0.0, 1.0]\nirradiance = [{e_dir}, {e_dir}, {e_dir}]\nshadows = false\n"
    );
    let expected = |i: usize| {
        BG[i % 3] as f64 * direct_transmittance(tau, 1.0)
            + hemispherical_transmission(tau, albedo, 1.0)
            + reflection_share(tau, 1.0, mu0) * 0.8 / PI * mu0 * e_dir
    };
    for eval in ["per-pixel", "per-vertex"] {
        let extra = format!("{dir_light}[effects]\nevaluation = \"{eval}\"\n");
        let f = render(&gpu, &sheet_scene(dir.path(), "below.exr", &thin, 0.0, &extra));
        let e = worst_rel(&f, expected);
        assert!(e < 0.01, "{eval}: {e}");
    }
}

#[test]
fn curtain_limits_under_an_environment() {
    let Some(gpu) = gpu("curtain_limits_under_an_environment") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "voile.eigen", Pattern::Checker, 16, 16, 4, Quantization::F16);
    curtain_mesh(dir.path());
    let map = EnvMap::from_fn(64, |d| sky(d).map(f64::from)).unwrap();
    exr::prelude::write_rgb_file(dir.path().join("sky.exr"), map.width, map.height, |x, y| {
        let p = map.pixels[y * map.width + x];
        (p[0], p[1], p[2])
    })
    .unwrap();
    let scene = |t: &str| {
        let t = if t.is_empty() { String::new() } else { format!("transmission = {t}\n") };
        let text = format!(
            "[output]\nwidth = 40\nheight = 40\nbackground = {BG:?}\n[[meshes]]\npath = \"curtain.obj\"\n\
             [[materials]]\nstore = \"voile.eigen\"\nuv_scale = 4.0\n{t}[camera]\neye = [0.0, -2.6, 0.75]\n\
             target = [0.0, 0.0, 0.75]\nup = [0.0, 0.0, 1.0]\nfov_y_deg = 40.0\n\
             [[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nrotation_deg = 40.0\nvisibility_res = 8\n"
        );
        Scene::load(&write(dir.path(), "c.toml", &text)).unwrap()
    };
    let opaque = render(&gpu, &scene(""));
    let thick = render(&gpu, &scene("{ tau = 1e4, albedo = 1.0 }"));
    assert_close("env-thick", 40, 40, &opaque.rgb, &thick.rgb, 1e-5);
    let clear = render(&gpu, &scene("{ tau = 1e-6, albedo = 1.0 }"));
    let background: Vec<f32> = (0..clear.rgb.len()).map(|i| BG[i % 3]).collect();
    assert_close("env-clear", 40, 40, &background, &clear.rgb, 1e-5);
    assert!(rel_rmse(&background, &opaque.rgb) > 0.05, "the opaque curtain must be visible");
    // What the tables cannot represent is refused, naming the material and the key.
    let err =
        render_scene(&gpu, &scene("{ tau = 0.5, phase = { hg = 0.3 } }"), RenderOptions::default())
            .err()
            .unwrap()
            .to_string();
    assert!(err.contains("hg") && err.contains("voile.eigen"), "{err}");
    // τ textures: all 0 is the bare background exactly (node τ_0 = 0), all 1 with
    // tau = 10⁴ the opaque curtain (the last node), and a constant c the scalar τ = tau·c
    // (between nodes: within the τ interpolation).
    let grey = |name: &str, v: u8| {
        image::GrayImage::from_pixel(8, 8, image::Luma([v])).save(dir.path().join(name)).unwrap();
    };
    grey("zero.png", 0);
    grey("one.png", 255);
    grey("c.png", 102);
    let zero = render(&gpu, &scene("{ tau = 1.0, tau_texture = \"zero.png\", albedo = 1.0 }"));
    // (1 − Σ bary · A₀ with A₀ = 1: f32 barycentrics sum to 1 within a few ulp)
    let e = assert_close("env-tex-zero", 40, 40, &background, &zero.rgb, 1e-5);
    eprintln!("τ texture 0 vs background: relative RMSE {e:.2e}");
    let one = render(&gpu, &scene("{ tau = 1e4, tau_texture = \"one.png\", albedo = 1.0 }"));
    let e = assert_close("env-tex-one", 40, 40, &opaque.rgb, &one.rgb, 1e-5);
    eprintln!("τ texture 1, tau 1e4 vs opaque: relative RMSE {e:.2e}");
    // 102/255 = 0.4, stored as f16 0.39990234375; τ = 0.4 lies between τ_4 = 0.327 and
    // τ_5 = 0.510.
    let tex = render(&gpu, &scene("{ tau = 1.0, tau_texture = \"c.png\", albedo = 0.9 }"));
    let flat = render(&gpu, &scene("{ tau = 0.39990234375, albedo = 0.9 }"));
    let e = assert_close("env-tex-const", 40, 40, &flat.rgb, &tex.rgb, 5e-3);
    eprintln!("constant τ texture vs scalar τ: relative RMSE {e:.2e}");
    assert!(rel_rmse(&background, &flat.rgb) > 0.05, "the τ = 0.4 curtain must be visible");
}

#[test]
fn show_environment_needs_an_environment_light_and_takes_msaa() {
    let dir = tempfile::tempdir().unwrap();
    let load = |lights: &str, msaa: u32| {
        let text = format!(
            "[output]\nshow_environment = true\n[[meshes]]\npath = \"a.obj\"\n[[materials]]\nstore = \"m.eigen\"\n\
             [camera]\neye = [0.0, -2.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n{lights}\
             [effects]\nmsaa = {msaa}\n"
        );
        Scene::load(&write(dir.path(), "s.toml", &text)).map(|_| ()).map_err(|e| e.to_string())
    };
    let env = "[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\n";
    assert!(load(env, 1).is_ok());
    let e = load("", 1).unwrap_err();
    assert!(e.contains("output.show_environment") && e.contains("environment light"), "{e}");
    // the background is a GPU pass that draws into the multisampled target too
    assert!(load(env, 4).is_ok());
}
