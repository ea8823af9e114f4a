//! Pass selection and work measured by texture reads per pixel (nearest vs four, fewer
//! components, per-pixel vs per-vertex), and hard cases: zero-area triangles, missing and
//! zero normals, degenerate UVs, grazing cameras and lights at the horizon.

use crate::common::*;
use btf_core::InterpMode;
use btf_core::eigen::Quantization;
use btf_render::scene::{Effects, Evaluation, Light, Shadows};
use btf_render::{BtfPassKey, RenderOptions, Renderer, Scene, render_scene};

fn scene(
    dir: &std::path::Path,
    obj: &str,
    effects: impl FnOnce(&mut Effects),
    light: Light,
    eye: [f32; 3],
) -> Scene {
    SceneBuilder::new(dir, 48)
        .mesh(obj)
        .material("m.eigen")
        .perspective(eye, [0.5, 0.5, 0.0], [0.0, 0.0, 1.0], 50.0)
        .light(light)
        .effects(effects)
        .build()
}

const SUN: [f32; 3] = [0.3, 0.2, 1.0];

fn sun() -> Light {
    directional(SUN)
}

/// The pass compiles the group count in (and packs the weights as f16) only where it may:
/// one shared G ≤ 4; with G = 8 it keeps the run-time loop and f32 rows.
#[test]
fn constant_group_count_and_packed_weights_only_where_they_apply() {
    let Some(gpu) = gpu("constant_group_count_and_packed_weights_only_where_they_apply") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 16, 16, 32, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 2);
    let key = |c: usize, evaluation: Evaluation| {
        let fx = |e: &mut Effects| (e.components, e.evaluation) = (Some(c), evaluation);
        let s = scene(dir.path(), "plane.obj", fx, sun(), [0.5, -0.4, 1.0]);
        Renderer::new(&gpu, &s, RenderOptions::default()).unwrap().pass_key()
    };
    let gp = |c: usize| {
        let k = key(c, Evaluation::PerPixel);
        (k.groups, k.packed)
    };
    assert_eq!(gp(4), (1, true));
    assert_eq!(gp(16), (4, true));
    assert_eq!(gp(32), (0, false), "G = 8 keeps the run-time loop");
    // the separable per-vertex layout: per-vertex mode with a directional light only
    assert!(!key(4, Evaluation::PerPixel).separable());
    for c in [4, 32] {
        let k = key(c, Evaluation::PerVertex);
        assert!(k.separable(), "c = {c}: per-vertex under a sun is separable");
        assert!(!BtfPassKey { environment: true, ..k }.separable(), "an environment is not");
    }
}

#[test]
fn only_requested_work_is_done() {
    let Some(gpu) = gpu("only_requested_work_is_done") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 16, 16, 16, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 4);
    let eye = [0.5, -0.4, 1.0];
    let run = |effects: fn(&mut Effects)| {
        let f = render_scene(
            &gpu,
            &scene(dir.path(), "plane.obj", effects, sun(), eye),
            RenderOptions { count_reads: true, ..Default::default() },
        )
        .unwrap();
        let names: Vec<String> = f.stats.passes.iter().map(|p| p.name.clone()).collect();
        (f.stats.reads_per_pixel.unwrap(), names)
    };
    let (four, names) = run(|_| {});
    assert_eq!(names, ["btf (per-pixel)"], "no shadow, no per-vertex work: {names:?}");
    let unshadowed = Light::Directional { direction: SUN, irradiance: [1.0; 3], shadows: false };
    let f = render_scene(
        &gpu,
        &scene(dir.path(), "plane.obj", |e| e.shadows = Shadows::Volume, unshadowed, eye),
        RenderOptions::default(),
    )
    .unwrap();
    assert!(
        !f.stats.ran("shadow"),
        "no shadow pass without a shadowing light: {:?}",
        f.stats.passes
    );
    let (_, names) = run(|e| e.shadows = Shadows::Volume);
    assert!(names.iter().any(|n| n.starts_with("shadow volume")), "{names:?}");
    let (nearest, _) = run(|e| e.view_blend = InterpMode::Nearest);
    let (c8, _) = run(|e| e.components = Some(8));
    let (c4_nearest, _) = run(|e| (e.components, e.view_blend) = (Some(4), InterpMode::Nearest));
    let (per_vertex, names) = run(|e| e.evaluation = Evaluation::PerVertex);
    assert!(names.iter().any(|n| n.starts_with("per-vertex coefficients")));
    // One slot with c = 16 costs 1 mean + 3 · 4 packed reads = 13.
    eprintln!(
        "reads/pixel: four {four:.2}, nearest {nearest:.2}, c=8 {c8:.2}, c=4 nearest {c4_nearest:.2}, per-vertex {per_vertex:.2}"
    );
    assert_eq!(nearest, 13.0);
    assert_eq!(c4_nearest, 4.0);
    assert!(four > 13.0 && four <= 4.0 * 13.0);
    assert!((c8 / four - 7.0 / 13.0).abs() < 1e-9, "reads scale with ⌈c/4⌉");
    assert!(per_vertex >= four, "per-pixel reads no more than the paper's per-vertex blending");
}

fn finite_render(gpu: &btf_render::Gpu, s: &Scene) -> btf_render::Frame {
    let f = render_scene(gpu, s, RenderOptions::default()).unwrap();
    assert!(f.all_finite(), "NaN or Inf in the image");
    f
}

#[test]
fn hard_cases_give_finite_images() {
    let Some(gpu) = gpu("hard_cases_give_finite_images") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 8, 8, 4, Quantization::U8);
    // Zero-area triangles (repeated and collinear vertices), no normals, degenerate UVs.
    let nasty = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.5\n\
                 f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 1/1 1/1 2/2\nf 1/1 2/2 5/2\nf 2/4 3/4 5/4\n";
    write(dir.path(), "nasty.obj", nasty);
    let zero_normals = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 0\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
    write(dir.path(), "zero.obj", zero_normals);
    let horizon = [1.0, 0.0, 0.0];
    let below = point([0.5, 0.5, -1.0], 1.0);
    let effects: [fn(&mut Effects); 3] = [
        |_| {},
        |e| (e.evaluation, e.shadows) = (Evaluation::PerVertex, Shadows::Volume),
        |e| (e.shadows, e.msaa) = (Shadows::Map, 4),
    ];
    for obj in ["nasty.obj", "zero.obj"] {
        for (light, at_horizon) in
            [(sun(), false), (directional(horizon), true), (below.clone(), false)]
        {
            for eye in [[0.5, -0.4, 1.0], [0.5, -3.0, 1e-3]] {
                for fx in effects {
                    let f = finite_render(&gpu, &scene(dir.path(), obj, fx, light.clone(), eye));
                    if at_horizon {
                        // A light exactly at the horizon of the plane contributes nothing.
                        assert!(
                            f.rgb.iter().all(|v| v.abs() < 1e-6),
                            "{obj}: horizon light lit the plane"
                        );
                    }
                }
            }
        }
    }
    // The back of the sheet seen from below under a light from below is lit (two-sided cloth).
    let f = finite_render(&gpu, &scene(dir.path(), "zero.obj", |_| {}, below, [0.5, 0.5, -1.5]));
    assert!(f.pixel(24, 24).iter().sum::<f32>() > 0.0);
}

#[test]
fn unusable_input_is_a_clear_error() {
    let Some(gpu) = gpu("unusable_input_is_a_clear_error") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 8, 8, 4, Quantization::F16);
    write(dir.path(), "nouv.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    let eye = [0.5, -0.4, 1.0];
    let e =
        render_scene(&gpu, &scene(dir.path(), "nouv.obj", |_| {}, sun(), eye), Default::default())
            .err()
            .unwrap()
            .to_string();
    assert!(e.contains("nouv.obj") && e.contains("planar_uv"), "{e}");
    let nine = |e: &mut Effects| e.components = Some(9);
    let e =
        render_scene(&gpu, &scene(dir.path(), "nouv.obj", nine, sun(), eye), Default::default());
    assert!(e.is_err());
    unit_plane(dir.path(), "plane.obj", 1);
    let e =
        render_scene(&gpu, &scene(dir.path(), "plane.obj", nine, sun(), eye), Default::default())
            .err()
            .unwrap()
            .to_string();
    assert!(e.contains("9 components") && e.contains("holds 4"), "{e}");
    write(dir.path(), "nan.obj", "v 0 0 0\nv 1 0 nan\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
    let e = render_scene(
        &gpu,
        &scene(dir.path(), "nan.obj", |_| {}, sun(), [0.5, -0.4, 1.0]),
        RenderOptions::default(),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("nan.obj") && e.contains("vertex 2"), "{e}");
}
