//! Golden comparisons of the GPU renderer against the CPU reconstruction
//! (`btf_core::reconstruct`, `[S03 eq. 2–5]`), and per-vertex (`[S03 §4.2]`) vs per-pixel
//! convergence.

use crate::common::*;
use btf_core::eigen::{EigenStore, Quantization};
use btf_core::reconstruct::{ReconstructParams, reconstruct};
use btf_core::{Direction, InterpMode};
use btf_render::scene::{Effects, Evaluation, Light};
use btf_render::{RenderOptions, Renderer, Scene, render_scene};

fn plane_scene(
    dir: &std::path::Path,
    obj: &str,
    store: &str,
    fx: impl FnOnce(&mut Effects),
    light_dir: [f32; 3],
    size: u32,
) -> Scene {
    let b = SceneBuilder::new(dir, size).mesh(obj).material(store);
    b.light(directional(light_dir)).effects(fx).build()
}

/// The plane of the convergence tests from a perspective camera (view directions vary
/// across the image).
fn perspective_plane(dir: &std::path::Path, size: u32) -> SceneBuilder {
    SceneBuilder::new(dir, size).mesh("plane.obj").material("m.eigen").perspective(
        [0.5, -0.6, 1.2],
        [0.5, 0.5, 0.0],
        [0.0, 0.0, 1.0],
        60.0,
    )
}

/// World light direction on the plane → tangent direction: T = +x, B = −y, N = +z.
fn tangent_light(d: [f32; 3]) -> Direction {
    Direction::from_vector([d[0] as f64, -d[1] as f64, d[2] as f64]).unwrap()
}

#[test]
fn flat_plane_per_pixel_matches_cpu_reconstruction() {
    let Some(gpu) = gpu("flat_plane_per_pixel_matches_cpu_reconstruction") else { return };
    let dir = tempfile::tempdir().unwrap();
    let n = 32;
    unit_plane(dir.path(), "plane.obj", 4);
    for (q, name) in [(Quantization::F16, "f16"), (Quantization::U8, "u8")] {
        let store =
            write_store(dir.path(), &format!("m-{name}.eigen"), Pattern::Checker, n, n, 6, q);
        let es = EigenStore::open(&store).unwrap();
        for light in [[0.3f32, 0.5, 1.0], [-0.7, 0.2, 0.4], [0.0, 0.0, 1.0], [0.9, -0.9, 0.2]] {
            for nearest in [false, true] {
                let (fx, params): (fn(&mut Effects), _) = if nearest {
                    let params = ReconstructParams {
                        light_mode: InterpMode::Nearest,
                        components: Some(3),
                        ..Default::default()
                    };
                    (|e| (e.light_interp, e.components) = (InterpMode::Nearest, Some(3)), params)
                } else {
                    (|_| {}, ReconstructParams::default())
                };
                let scene = plane_scene(
                    dir.path(),
                    "plane.obj",
                    store.file_name().unwrap().to_str().unwrap(),
                    fx,
                    light,
                    n as u32,
                );
                let frame = render_scene(&gpu, &scene, RenderOptions::default()).unwrap();
                let cpu = reconstruct(&es, Direction::new(0.0, 0.0), tangent_light(light), params)
                    .unwrap();
                let e = assert_close(
                    &format!("golden-{name}-{:?}", light),
                    n as u32,
                    n as u32,
                    &cpu,
                    &frame.rgb,
                    0.01,
                );
                eprintln!("{name} light {light:?} nearest {nearest}: relative RMSE {e:.2e}");
                // Negative control: the tangent frame's +y is the texture row direction (world
                // −y here); taking world +y instead must be visibly wrong.
                if light[1] != 0.0 {
                    let wrong = reconstruct(
                        &es,
                        Direction::new(0.0, 0.0),
                        tangent_light([light[0], -light[1], light[2]]),
                        params,
                    )
                    .unwrap();
                    assert!(
                        rel_rmse(&wrong, &frame.rgb) > 0.03,
                        "test cannot tell the y convention apart"
                    );
                }
            }
        }
    }
}

/// Renders the plane with a perspective camera (so view directions vary across the image)
/// and a point light, in both modes, on meshes of increasing resolution.
#[test]
fn per_vertex_converges_to_per_pixel_as_the_mesh_is_refined() {
    let Some(gpu) = gpu("per_vertex_converges_to_per_pixel_as_the_mesh_is_refined") else { return };
    let dir = tempfile::tempdir().unwrap();
    // c = 4: constant G, f16 separable entries; c = 32: G = 8, the run-time group loop;
    // c = 4 with weights beyond f16 (×1e6): constant G with f32 weight rows and entries
    for (components, scale) in [(4, 1.0), (32, 1.0), (4, 1e6)] {
        per_vertex_convergence(&gpu, dir.path(), components, scale);
    }
}

/// The separable per-vertex layout renders what the full RGB layout renders, on a coarse
/// mesh under a near coloured point light (its irradiance differs a lot between the
/// vertices, so an entry read for the wrong vertex or light would show) plus a sun: within
/// the layouts' f16 rounding at c = 4 (both packed) and c = 32 (both f32: to f32 rounding).
#[test]
fn separable_and_full_per_vertex_layouts_render_the_same() {
    let Some(gpu) = gpu("separable_and_full_per_vertex_layouts_render_the_same") else { return };
    let dir = tempfile::tempdir().unwrap();
    unit_plane(dir.path(), "plane.obj", 2);
    for (components, tol) in [(4usize, 2e-3), (32, 1e-5)] {
        write_store(dir.path(), "m.eigen", Pattern::Checker, 16, 16, components, Quantization::F16);
        let scene = perspective_plane(dir.path(), 48)
            .light(Light::Point {
                position: [0.9, 0.1, 0.3],
                intensity: [0.3, 0.2, 0.1],
                shadows: true,
            })
            .light(Light::Directional {
                direction: [-0.3, 0.4, 0.8],
                irradiance: [0.2, 0.4, 0.6],
                shadows: true,
            })
            .effects(|e| e.evaluation = Evaluation::PerVertex)
            .build();
        let frame = |full_vertex_layout| {
            let options = RenderOptions { full_vertex_layout, ..Default::default() };
            let mut r = Renderer::new(&gpu, &scene, options).unwrap();
            assert_eq!(r.pass_key().separable(), !full_vertex_layout);
            r.render(&gpu).unwrap()
        };
        let (sep, full) = (frame(false), frame(true));
        let e = rel_rmse(&full.rgb, &sep.rgb);
        eprintln!("c = {components}: separable vs full layout relative RMSE {e:.2e}");
        assert!(e <= tol, "c = {components}: {e}");
        assert!(sep.rgb.iter().all(|v| v.is_finite()) && sep.rgb.iter().any(|&v| v > 0.0));
    }
}

fn per_vertex_convergence(
    gpu: &btf_render::Gpu,
    dir: &std::path::Path,
    components: usize,
    weight_scale: f32,
) {
    let (q, p) = (Quantization::F16, Pattern::Checker);
    write_store_scaled(dir, "m.eigen", p, 16, 16, components, q, weight_scale);
    let size = 64;
    let mut errors = Vec::new();
    for n in [1usize, 2, 4, 8, 16] {
        unit_plane(dir, "plane.obj", n);
        let mut frames = Vec::new();
        for eval in [Evaluation::PerPixel, Evaluation::PerVertex] {
            let scene = perspective_plane(dir, size)
                .light(point([0.9, 0.2, 0.6], 0.5))
                .effects(|e| e.evaluation = eval)
                .build();
            if eval == Evaluation::PerVertex && n == 1 {
                let key = Renderer::new(gpu, &scene, RenderOptions::default()).unwrap().pass_key();
                let groups = if components <= 16 { components.div_ceil(4) as u32 } else { 0 };
                assert_eq!((key.groups, key.packed), (groups, groups > 0 && weight_scale < 10.0));
                assert!(key.separable());
            }
            frames.push(render_scene(gpu, &scene, RenderOptions::default()).unwrap());
        }
        let e = rel_rmse(&frames[0].rgb, &frames[1].rgb);
        eprintln!(
            "c = {components} (weights ×{weight_scale}), {n:>2}×{n:<2} quads: per-vertex vs per-pixel relative RMSE {e:.4}"
        );
        errors.push(e);
        if n == 16 && components == 4 && weight_scale == 1.0 {
            save_comparison("per-vertex-16", size, size, &frames[0].rgb, &frames[1].rgb);
        }
    }
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "c = {components}: refining must reduce the error: {errors:?}");
    }
    assert!(errors[4] < 0.25 * errors[0], "c = {components}: {errors:?}");
    assert!(errors[4] < 0.02, "c = {components}: {errors:?}");
}

/// Centre-of-image contrast of the ribs along image x and image y.
fn rib_contrast(f: &btf_render::Frame) -> (f64, f64) {
    let lum = |x: u32, y: u32| f.pixel(x, y).iter().sum::<f32>() as f64;
    let (w, h) = (f.width, f.height);
    let mut along_x = 0.0;
    let mut along_y = 0.0;
    for k in 1..w - 1 {
        along_x += (lum(k, h / 2) - lum(k - 1, h / 2)).abs();
        along_y += (lum(w / 2, k) - lum(w / 2, k - 1)).abs();
    }
    (along_x, along_y)
}

#[test]
fn rotating_the_uvs_turns_the_ribs() {
    let Some(gpu) = gpu("rotating_the_uvs_turns_the_ribs") else { return };
    let dir = tempfile::tempdir().unwrap();
    let n = 32;
    let store = write_store(dir.path(), "ribs.eigen", Pattern::Ribs, n, n, 4, Quantization::F16);
    let es = EigenStore::open(&store).unwrap();
    let light = [0.4f32, 0.3, 1.0];
    unit_plane(dir.path(), "plane.obj", 2);
    write(dir.path(), "rot.obj", &plane_obj(2, true));
    let plain = render_scene(
        &gpu,
        &plane_scene(dir.path(), "plane.obj", "ribs.eigen", |_| {}, light, n as u32),
        RenderOptions::default(),
    )
    .unwrap();
    let rotated = render_scene(
        &gpu,
        &plane_scene(dir.path(), "rot.obj", "ribs.eigen", |_| {}, light, n as u32),
        RenderOptions::default(),
    )
    .unwrap();
    let (px, py) = rib_contrast(&plain);
    let (rx, ry) = rib_contrast(&rotated);
    eprintln!("ribs: plain contrast x {px:.3} y {py:.3}; rotated x {rx:.3} y {ry:.3}");
    assert!(px > 20.0 * py.max(1e-3) && ry > 20.0 * rx.max(1e-3), "ribs did not turn");
    // The rotated plane is the flat sample seen with its texture turned by 90°: u = y,
    // v = 1 − x, so texel (col, row) appears at image (x, y) = (n−1−row, … ): compare with the
    // CPU reconstruction for the light expressed in the rotated tangent frame
    // (T = world +y... here T = ∂P/∂u = +y, B = −∂P/∂v = +x).
    let cpu = reconstruct(
        &es,
        Direction::new(0.0, 0.0),
        Direction::from_vector([light[1] as f64, light[0] as f64, light[2] as f64]).unwrap(),
        Default::default(),
    )
    .unwrap();
    let mut expected = vec![0f32; cpu.len()];
    for y in 0..n {
        for x in 0..n {
            // image pixel (x, y): world (x, 1 − y) → u = world y = 1 − y/n, v = 1 − x/n
            // → texture column = (1 − y/n)·n, row = (1 − v)·n = x.
            let (col, row) = (n - 1 - y, x);
            for ch in 0..3 {
                expected[(y * n + x) * 3 + ch] = cpu[(row * n + col) * 3 + ch];
            }
        }
    }
    let e = assert_close("ribs-rotated", n as u32, n as u32, &expected, &rotated.rgb, 0.01);
    eprintln!("rotated ribs vs CPU: relative RMSE {e:.2e}");
}
