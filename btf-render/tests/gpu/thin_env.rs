//! Thin cloth under an environment light (`[TC eq. 7–8]` over the environment's visible
//! sources, the tables of `btf_light::thin_tables`, whose own tests are in btf-light):
//! half-space furnaces on a flat sheet against the slab's hemispherical transmission and
//! reflection share (1-D quadratures of `btf_core::thin_slab`), and the limits τ₁ → 0 / ∞
//! on the curtain, also through τ textures (all 0, all 1, constant).

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_core::thin_slab::{Phase, Slab, direct_transmittance, reflection_share};
use btf_image::EnvMap;
use btf_render::scene::{
    Albedo, EnvironmentLight, Evaluation, Light, PhaseDesc, TauTexture, TransmissionDesc,
};
use btf_render::{Frame, RenderOptions, Scene, render_scene};
use std::f64::consts::PI;
use std::path::Path;

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

/// A sky with a small bright sun, not symmetric under the rotation.
fn sky(d: [f64; 3]) -> [f64; 3] {
    let sun = [0.6f64, 0.2, 0.775];
    let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    let s = if c > 0.995 { 40.0 } else { 0.0 };
    let base = 0.3 + 0.6 * d[2].max(0.0) + 0.1 * (d[0] + 1.0);
    [(base + s) as f32 as f64, (0.9 * base + s) as f32 as f64, (0.7 * base + 0.8 * s) as f32 as f64]
}

/// The sheet seen at `tilt_deg` under the environment `env` (after the lights `before`),
/// thin with `transmission` or opaque.
fn sheet_scene(
    dir: &Path,
    env: &str,
    transmission: Option<TransmissionDesc>,
    tilt_deg: f64,
    before: Option<Light>,
) -> SceneBuilder {
    let (s, c) = tilt_deg.to_radians().sin_cos();
    let eye = [(0.5 + 2.0 * s) as f32, 0.5, (2.0 * c) as f32];
    let mut b = SceneBuilder::new(dir, 24)
        .output(|o| o.background = BG)
        .mesh("sheet.obj")
        .material_with(None, "m.eigen", 1.0, transmission)
        .ortho(Ortho { eye, target: [0.5, 0.5, 0.0], height: 0.4 });
    if let Some(l) = before {
        b = b.light(l);
    }
    b.light(Light::Environment(environment(dir, env)))
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
    unit_plane(dir.path(), "sheet.obj", 2);
    write_half_env(&dir.path().join("below.exr"), false);
    write_half_env(&dir.path().join("above.exr"), true);
    let (tau, albedo) = (0.5, 0.9);
    let thin =
        || Some(TransmissionDesc { albedo: Albedo::Grey(albedo as f32), ..thin(tau as f32) });
    // μ = 1 and 0.64 fall on table nodes, μ = 0.5 between two (interpolated in √μ).
    for tilt in [0.0f64, 0.64f64.acos().to_degrees(), 60.0] {
        let mu = tilt.to_radians().cos();
        let alpha = direct_transmittance(tau, mu);
        // Lit from behind only: what is behind, plus the hemispherical transmission.
        let t = hemispherical_transmission(tau, albedo, mu);
        let f = render(&gpu, &sheet_scene(dir.path(), "below.exr", thin(), tilt, None).build());
        let e = worst_rel(&f, |i| BG[i % 3] as f64 * alpha + t);
        eprintln!("back-lit μ = {mu:.3}: t = {t:.5}, worst relative error {e:.2e}");
        assert!(e < 0.01, "back-lit at μ = {mu}: {e}");
        // Lit from the front only: the opaque environment render scaled by 1 − e^{−τ/μ}·A.
        let opaque = render(&gpu, &sheet_scene(dir.path(), "above.exr", None, tilt, None).build());
        let furnace = opaque.rgb.iter().map(|&v| v as f64).sum::<f64>() / opaque.rgb.len() as f64;
        assert!((furnace - 0.8).abs() < 0.01 * 0.8, "white furnace {furnace}");
        let share = 1.0 - alpha * uniform_a(tau);
        let f = render(&gpu, &sheet_scene(dir.path(), "above.exr", thin(), tilt, None).build());
        let e = worst_rel(&f, |i| BG[i % 3] as f64 * alpha + share * opaque.rgb[i] as f64);
        eprintln!("front-lit μ = {mu:.3}: share = {share:.4}, worst relative error {e:.2e}");
        assert!(e < 0.01, "front-lit at μ = {mu}: {e}");
    }
    // The environment drawn behind the sheet shows through with the same alpha: seen from
    // above, the rays behind the sheet go down into the unit half of below.exr.
    let scene = sheet_scene(dir.path(), "below.exr", thin(), 0.0, None);
    let f = render(&gpu, &scene.output(|o| o.show_environment = true).build());
    let (alpha, t) = (direct_transmittance(tau, 1.0), hemispherical_transmission(tau, albedo, 1.0));
    let e = worst_rel(&f, |_| alpha + t);
    assert!(e < 0.01, "environment background: {e}");
    // Per-vertex scenes keep the environment's own entry: a directional light first (its
    // per-vertex BTF term must not leak into the thin sheet), lit from above.
    let (mu0, e_dir) = (1.0 / 1.09f64.sqrt(), 2.0);
    let dir_light =
        Light::Directional { direction: [0.3, 0.0, 1.0], irradiance: [2.0; 3], shadows: false };
    let expected = |i: usize| {
        BG[i % 3] as f64 * direct_transmittance(tau, 1.0)
            + hemispherical_transmission(tau, albedo, 1.0)
            + reflection_share(tau, 1.0, mu0) * 0.8 / PI * mu0 * e_dir
    };
    for eval in [Evaluation::PerPixel, Evaluation::PerVertex] {
        let scene = sheet_scene(dir.path(), "below.exr", thin(), 0.0, Some(dir_light.clone()));
        let f = render(&gpu, &scene.effects(|e| e.evaluation = eval).build());
        let e = worst_rel(&f, expected);
        assert!(e < 0.01, "{eval:?}: {e}");
    }
}

#[test]
fn curtain_limits_under_an_environment() {
    let Some(gpu) = gpu("curtain_limits_under_an_environment") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "voile.eigen", Pattern::Checker, 16, 16, 4, Quantization::F16);
    synth_mesh(dir.path(), "curtain.obj", datasets::MeshKind::Curtain);
    let map = EnvMap::from_fn(64, sky).unwrap();
    exr::prelude::write_rgb_file(dir.path().join("sky.exr"), map.width, map.height, |x, y| {
        let p = map.pixels[y * map.width + x];
        (p[0], p[1], p[2])
    })
    .unwrap();
    let env = EnvironmentLight {
        rotation_deg: 40.0,
        visibility_res: 8,
        ..environment(dir.path(), "sky.exr")
    };
    let scene = |t: Option<TransmissionDesc>| {
        SceneBuilder::new(dir.path(), 40)
            .output(|o| o.background = BG)
            .mesh("curtain.obj")
            .material_with(None, "voile.eigen", 4.0, t)
            .perspective([0.0, -2.6, 0.75], [0.0, 0.0, 0.75], [0.0, 0.0, 1.0], 40.0)
            .light(Light::Environment(env.clone()))
            .build()
    };
    // tau, albedo, τ texture
    let slab = |tau: f32, albedo: f32, texture: Option<&str>| {
        Some(TransmissionDesc {
            albedo: Albedo::Grey(albedo),
            tau_texture: texture.map(|t| TauTexture::Image(t.into())),
            ..thin(tau)
        })
    };
    let opaque = render(&gpu, &scene(None));
    let thick = render(&gpu, &scene(slab(1e4, 1.0, None)));
    assert_close("env-thick", 40, 40, &opaque.rgb, &thick.rgb, 1e-5);
    let clear = render(&gpu, &scene(slab(1e-6, 1.0, None)));
    let background: Vec<f32> = (0..clear.rgb.len()).map(|i| BG[i % 3]).collect();
    assert_close("env-clear", 40, 40, &background, &clear.rgb, 1e-5);
    assert!(rel_rmse(&background, &opaque.rgb) > 0.05, "the opaque curtain must be visible");
    // What the tables cannot represent is refused, naming the material and the key.
    let err = render_scene(
        &gpu,
        &scene(Some(TransmissionDesc { phase: PhaseDesc::Hg { hg: 0.3 }, ..thin(0.5) })),
        RenderOptions::default(),
    )
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
    let zero = render(&gpu, &scene(slab(1.0, 1.0, Some("zero.png"))));
    // (1 − Σ bary · A₀ with A₀ = 1: f32 barycentrics sum to 1 within a few ulp)
    let e = assert_close("env-tex-zero", 40, 40, &background, &zero.rgb, 1e-5);
    eprintln!("τ texture 0 vs background: relative RMSE {e:.2e}");
    let one = render(&gpu, &scene(slab(1e4, 1.0, Some("one.png"))));
    let e = assert_close("env-tex-one", 40, 40, &opaque.rgb, &one.rgb, 1e-5);
    eprintln!("τ texture 1, tau 1e4 vs opaque: relative RMSE {e:.2e}");
    // 102/255 = 0.4, stored as f16 0.39990234375; τ = 0.4 lies between τ_4 = 0.327 and
    // τ_5 = 0.510.
    let tex = render(&gpu, &scene(slab(1.0, 0.9, Some("c.png"))));
    let flat = render(&gpu, &scene(slab(0.399_902_35, 0.9, None)));
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
