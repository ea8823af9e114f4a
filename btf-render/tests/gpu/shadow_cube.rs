//! Cube shadow maps (`passes/shadow/cube.rs`, `[S03 §4.3]`) for a point light inside the scene: a low light over a
//! ground plane with two small occluders whose shadows fall on different cube faces (one
//! straddles the −z face and the side faces, one lies in the +x face), against the
//! analytic central projection from the light (IoU), black inside and unchanged outside.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::scene::Shadows;
use btf_render::{Frame, RenderOptions, Scene, render_scene};

const LIGHT: [f32; 3] = [0.5, 0.5, 0.2];
const HEIGHT: f32 = 0.1;
/// Occluder squares at z = HEIGHT: (x0, x1, y0, y1).
const OCCLUDERS: [[f32; 4]; 2] = [[0.6, 0.7, 0.45, 0.55], [0.35, 0.45, 0.3, 0.4]];

fn mesh() -> String {
    let mut s = plane_obj(16, false);
    let mut next = 17 * 17 + 1;
    for [x0, x1, y0, y1] in OCCLUDERS {
        for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
            s += &format!("v {x} {y} {HEIGHT}\nvt {x} {y}\nvn 0 0 1\n");
        }
        let id = |k: usize| next + k;
        s += &format!(
            "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\nf {a}/{a}/{a} {c}/{c}/{c} {d}/{d}/{d}\n",
            a = id(0),
            b = id(1),
            c = id(2),
            d = id(3)
        );
        next += 4;
    }
    s
}

fn scene(dir: &std::path::Path, shadows: Shadows, size: u32) -> Scene {
    SceneBuilder::new(dir, size)
        .mesh("scene.obj")
        .material("u.eigen")
        .light(point(LIGHT, 0.05))
        .effects(|e| (e.shadows, e.shadow_map_size, e.terminator_deg) = (shadows, 1024, 5.0))
        .build()
}

/// Where the ray from ground point (x, y) to the light crosses the occluders' height.
fn at_occluder_height(x: f32, y: f32) -> (f32, f32) {
    let t = HEIGHT / LIGHT[2];
    (x + t * (LIGHT[0] - x), y + t * (LIGHT[1] - y))
}

/// Whether (x, y) lies in some occluder square grown by `grow` (negative: shrunk).
fn in_occluder(x: f32, y: f32, grow: f32) -> bool {
    OCCLUDERS.iter().any(|[x0, x1, y0, y1]| {
        (x0 - grow..x1 + grow).contains(&x) && (y0 - grow..y1 + grow).contains(&y)
    })
}

fn lum(f: &Frame, x: u32, y: u32) -> f32 {
    f.pixel(x, y).iter().sum()
}

#[test]
fn cube_map_shadows_of_an_inside_point_light_match_their_projection() {
    let Some(gpu) = gpu("cube_map_shadows_of_an_inside_point_light_match_their_projection") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "u.eigen", Pattern::Lambert, 4, 4, 2, Quantization::F16);
    write(dir.path(), "scene.obj", &mesh());
    let size = 96u32;
    let reference =
        render_scene(&gpu, &scene(dir.path(), Shadows::None, size), RenderOptions::default())
            .unwrap();
    let f = render_scene(&gpu, &scene(dir.path(), Shadows::Map, size), RenderOptions::default())
        .unwrap();
    assert!(f.all_finite());
    let (mut inter, mut union, mut max_dark, mut lit_err, mut lit_n) = (0, 0, 0f32, 0f64, 0);
    let (mut faces_hit, margin) = ([false; 6], 0.012);
    for y in 0..size {
        for x in 0..size {
            let (wx, wy) = ((x as f32 + 0.5) / size as f32, 1.0 - (y as f32 + 0.5) / size as f32);
            if in_occluder(wx, wy, 0.01) {
                continue; // the occluders themselves (and their rims) are not ground
            }
            let (ox, oy) = at_occluder_height(wx, wy);
            let expect = in_occluder(ox, oy, 0.0);
            let got = lum(&f, x, y) < 0.5 * lum(&reference, x, y);
            inter += (expect && got) as u32;
            union += (expect || got) as u32;
            if expect {
                let d = [wx - LIGHT[0], wy - LIGHT[1], -LIGHT[2]];
                let a = d.map(f32::abs);
                let face = if a[0] >= a[1] && a[0] >= a[2] {
                    (d[0] < 0.0) as usize
                } else if a[1] >= a[2] {
                    2 + (d[1] < 0.0) as usize
                } else {
                    5
                };
                faces_hit[face] = true;
            }
            let ratio = lum(&f, x, y) / lum(&reference, x, y);
            if in_occluder(ox, oy, -margin) {
                max_dark = max_dark.max(ratio);
            }
            if !in_occluder(ox, oy, margin) {
                lit_err += (ratio as f64 - 1.0).abs();
                lit_n += 1;
            }
        }
    }
    let iou = inter as f64 / union as f64;
    let lit_err = lit_err / lit_n as f64;
    let n_faces = faces_hit.iter().filter(|h| **h).count();
    eprintln!(
        "cube map: IoU {iou:.4}, darkest/lit inside {max_dark:.2e}, mean |rel. diff| outside {lit_err:.2e}, shadows on {n_faces} faces"
    );
    if iou <= 0.9 {
        save_comparison("cube-shadow", size, size, &reference.rgb, &f.rgb);
    }
    assert!(n_faces >= 3, "the shadows should span several cube faces ({faces_hit:?})");
    assert!(iou > 0.9, "IoU {iou}");
    assert!(max_dark < 1e-3, "shadow core not black ({max_dark})");
    assert!(lit_err < 2e-3, "lit ground differs from the unshadowed render ({lit_err})");
}
