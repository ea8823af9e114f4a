//! Radiometry and determinism of the path tracer: the white furnace on a fiber bundle (both
//! shadings), identical bits for one and two threads, and the periodic wrap against an
//! explicitly tiled 3×3 patch.

use std::sync::Arc;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::fiber::Fibers;
use yarn::knit::Chart;
use yarn::params::YarnParams;
use yarn_ref::patch::{KnitPatch, PatchOptions, fibers_from_polylines};
use yarn_ref::rng::Rng;
use yarn_ref::{
    Background, Camera, EnvLight, FiberScene, Image, Light, PathSettings, Period, RenderSettings,
    Scene, SceneOptions, Shading, render,
};

/// 24 wavy fibers in a loose bundle along x (radius 0.05, spread ±0.3).
fn bundle() -> Fibers {
    let mut rng = Rng::new(&[5]);
    let lines: Vec<Vec<[f64; 3]>> = (0..24)
        .map(|_| {
            let [y, z, ph] = rng.uniform3();
            (0..=40)
                .map(|i| {
                    let x = -2.0 + 0.1 * i as f64;
                    let w = 0.08 * (3.0 * x + 6.0 * ph).sin();
                    [x, 0.6 * (y - 0.5) + w, 0.6 * (z - 0.5) - w]
                })
                .collect()
        })
        .collect();
    fibers_from_polylines(&lines, 0.05, [1.0; 3])
}

fn furnace(shading: Shading, name: &str) {
    let fibers = bundle();
    let scene = FiberScene::new(&fibers, &SceneOptions::default()).unwrap();
    let env = EnvLight::new(btf_image::EnvMap::constant(32, [1.0; 3]).unwrap(), 1.0);
    let lights = [Light::Environment(env)];
    let sc = Scene { fibers: &scene, lights: &lights, shading: &shading };
    let cam =
        Camera::perspective([0.0, -4.0, 0.5], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 14.0).unwrap();
    let mut s = RenderSettings::new(24, 16, 64);
    // Enough bounces that the energy left inside the bundle is negligible; no roulette
    // (β stays 1 without absorption, so it would never end a path anyway).
    s.path = PathSettings { max_bounces: 256, rr_start: 1000, background: Background::Environment };
    let (img, _) = render(&sc, &cam, &s).unwrap();
    let (mut seen, mut worst, mut sum, mut var) = (0, 0.0f64, 0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = y * img.width + x;
            if img.coverage[i] == 0.0 {
                continue;
            }
            seen += 1;
            for c in 0..3 {
                let v = img.pixel(x, y)[c] as f64;
                let se = img.std_error(x, y, c);
                worst = worst.max((v - 1.0).abs() / se.max(1e-6));
                assert!(
                    (v - 1.0).abs() <= 4.0 * se + 1e-4,
                    "{name}: pixel ({x}, {y}) channel {c} = {v} ± {se}"
                );
                sum += v;
                var += se * se;
            }
        }
    }
    let mean = sum / (3 * seen) as f64;
    let se_mean = var.sqrt() / (3 * seen) as f64;
    eprintln!(
        "furnace ({name}): {seen} pixels see fibers, mean {mean:.5} ± {se_mean:.5}, worst pixel {worst:.2} σ"
    );
    assert!(seen > 60, "{name}: only {seen} pixels see the bundle");
    assert!((mean - 1.0).abs() < 4.0 * se_mean + 1e-4, "{name}: mean {mean}");
}

#[test]
fn white_furnace_lambert_fibers_reflect_everything() {
    furnace(Shading::Lambert { albedo: Some([1.0; 3]) }, "Lambert albedo 1");
}

#[test]
fn white_furnace_fiber_bcsdf_scatters_everything() {
    // Khungurn R + TT + diffuse with A_R + A_TT + k_d = 1: no absorption.
    let p =
        KhungurnParams { a_r: [0.2; 3], a_tt: [0.5; 3], kd: [0.3; 3], ..KhungurnParams::default() };
    let bcsdf = Arc::new(FiberBcsdf::khungurn(&p).unwrap());
    furnace(Shading::Fiber { bcsdf, tint: false }, "Khungurn R+TT+D, no absorption");
}

fn knit_patch() -> KnitPatch {
    let chart = Chart::builtin("stockinette").unwrap();
    let params = YarnParams::preset("fine-2ply").unwrap();
    let mut opts = PatchOptions::default();
    opts.generation.samples_per_turn = 8;
    KnitPatch::new(&chart, &params, &opts).unwrap()
}

fn patch_render(
    fibers: &Fibers,
    period: Option<Period>,
    patch: &KnitPatch,
    threads: usize,
) -> Image {
    let scene =
        FiberScene::new(fibers, &SceneOptions { period, backing_z: Some(patch.backing_z()) })
            .unwrap();
    let lights = [Light::directional(btf_core::Direction::new(30.0, 60.0).to_vector(), [1.0; 3])];
    let bcsdf = Arc::new(FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap());
    let shading = Shading::Fiber { bcsdf, tint: true };
    let sc = Scene { fibers: &scene, lights: &lights, shading: &shading };
    let view = btf_core::Direction::new(45.0, 200.0).to_vector();
    let cam = Camera::oblique(view, patch.z_ref, patch.period.origin, patch.period.size).unwrap();
    let mut s = RenderSettings::new(16, 16, 4);
    s.path.max_bounces = 3;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| render(&sc, &cam, &s)).unwrap().0
}

#[test]
fn identical_bits_with_one_and_two_threads() {
    let patch = knit_patch();
    let a = patch_render(&patch.fibers, Some(patch.period), &patch, 1);
    let b = patch_render(&patch.fibers, Some(patch.period), &patch, 2);
    assert_eq!(a, b);
    assert!(a.rgb.iter().any(|v| *v > 0.0));
}

#[test]
fn periodic_wrap_equals_the_centre_tile_of_an_explicit_3x3_tiling() {
    let patch = knit_patch();
    let wrapped = patch_render(&patch.fibers, Some(patch.period), &patch, 2);
    // The same fibers copied into the 3×3 neighbourhood, no wrap.
    let f = &patch.fibers;
    let mut tiled = Fibers { offsets: vec![0], palette: f.palette.clone(), ..Fibers::default() };
    for i in -1..=1 {
        for j in -1..=1 {
            let (dx, dy) = (i as f64 * patch.period.size[0], j as f64 * patch.period.size[1]);
            for k in 0..f.fiber_count() {
                let (s, e) = (f.offsets[k] as usize, f.offsets[k + 1] as usize);
                for p in &f.points[s..e] {
                    tiled.points.push([(p[0] as f64 + dx) as f32, (p[1] as f64 + dy) as f32, p[2]]);
                }
                tiled.radii.extend_from_slice(&f.radii[s..e]);
                tiled.color_ids.extend_from_slice(&f.color_ids[s..e]);
                tiled.offsets.push(tiled.points.len() as u32);
                tiled.yarn.push(f.yarn[k]);
                tiled.ply.push(f.ply[k]);
                tiled.fiber.push(f.fiber[k]);
                tiled.kind.push(f.kind[k]);
                tiled.params_id.push(f.params_id[k]);
            }
        }
    }
    let explicit = patch_render(&tiled, None, &patch, 2);
    let (mut worst, mut same) = (0.0f64, 0);
    for y in 0..16 {
        for x in 0..16 {
            for c in 0..3 {
                let (a, b) = (wrapped.pixel(x, y)[c] as f64, explicit.pixel(x, y)[c] as f64);
                let se = (wrapped.std_error(x, y, c).powi(2) + explicit.std_error(x, y, c).powi(2))
                    .sqrt();
                if a == b {
                    same += 1;
                }
                worst = worst.max((a - b).abs() / se.max(1e-9));
                assert!(
                    (a - b).abs() <= 4.0 * se + 1e-5,
                    "pixel ({x}, {y}) channel {c}: {a} vs {b} ± {se}"
                );
            }
        }
    }
    eprintln!("wrap vs 3×3 tiling: {same}/768 values bit-identical, worst difference {worst:.2} σ");
    let cov_w: f32 = wrapped.coverage.iter().sum();
    let cov_e: f32 = explicit.coverage.iter().sum();
    assert!((cov_w - cov_e).abs() <= 2.0, "coverage {cov_w} vs {cov_e}");
}
