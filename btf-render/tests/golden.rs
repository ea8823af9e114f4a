//! Golden comparisons of the GPU renderer against the CPU reconstruction
//! (`btf_core::reconstruct`, eq. 2–5), and per-vertex vs per-pixel convergence.

mod common;

use btf_core::eigen::{EigenStore, Quantization};
use btf_core::reconstruct::{ReconstructParams, reconstruct};
use btf_core::{Direction, InterpMode};
use btf_render::{RenderOptions, Scene, render_scene};
use common::*;

fn plane_scene(
    dir: &std::path::Path,
    obj: &str,
    store: &str,
    extra: &str,
    light_dir: [f32; 3],
    size: u32,
) -> Scene {
    let text = format!(
        r#"
        [output]
        width = {size}
        height = {size}
        [[meshes]]
        path = "{obj}"
        [[materials]]
        store = "{store}"
        [camera]
        projection = "orthographic"
        eye = [0.5, 0.5, 4.0]
        target = [0.5, 0.5, 0.0]
        up = [0.0, 1.0, 0.0]
        ortho_height = 1.0
        [[lights]]
        kind = "directional"
        direction = [{}, {}, {}]
        irradiance = [1.0, 1.0, 1.0]
        {extra}
        "#,
        light_dir[0], light_dir[1], light_dir[2]
    );
    Scene::load(&write(dir, "scene.toml", &text)).unwrap()
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
    write(dir.path(), "plane.obj", &plane_obj(4, false));
    for (q, name) in [(Quantization::F16, "f16"), (Quantization::U8, "u8")] {
        let store =
            write_store(dir.path(), &format!("m-{name}.eigen"), Pattern::Checker, n, n, 6, q);
        let es = EigenStore::open(&store).unwrap();
        for light in [[0.3f32, 0.5, 1.0], [-0.7, 0.2, 0.4], [0.0, 0.0, 1.0], [0.9, -0.9, 0.2]] {
            for (fx, params) in [
                ("", ReconstructParams::default()),
                (
                    "[effects]\nlight_interp = \"nearest\"\ncomponents = 3",
                    ReconstructParams {
                        light_mode: InterpMode::Nearest,
                        components: Some(3),
                        ..Default::default()
                    },
                ),
            ] {
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
                eprintln!("{name} light {light:?} {fx:?}: relative RMSE {e:.2e}");
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
