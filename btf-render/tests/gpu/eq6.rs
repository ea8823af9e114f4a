//! The smooth shadow boundary of `[S03 eq. 6]` switched on and off: on a coarse sphere (16
//! segments) under an oblique light, shadow volumes alone cut the shading along the
//! polygon terminator, a staircase across the segments; with eq. 6 the boundary follows the
//! interpolated normals. Measured per image row as the first pixel (from the lit side)
//! darker than half the unshadowed render, against a least-squares smooth curve.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::scene::Shadows;
use btf_render::{Frame, RenderOptions, Scene, render_scene};

const LS: [f32; 3] = [1.0, 0.35, 0.25];
const SIZE: u32 = 128;
const HALF_HEIGHT: f32 = 1.2;

fn sphere_scene(dir: &std::path::Path, shadows: Shadows, smooth: bool) -> Scene {
    SceneBuilder::new(dir, SIZE)
        .mesh("sphere.obj")
        .material("u.eigen")
        .ortho(OVER_SPHERE.with_height(2.0 * HALF_HEIGHT))
        .light(directional(LS))
        .effects(|e| (e.shadows, e.smooth_boundary) = (shadows, smooth))
        .build()
}

fn lum(f: &Frame, x: u32, y: u32) -> f32 {
    f.pixel(x, y).iter().sum()
}

/// Per row of the central band: x of the first pixel, scanning from the limb on the lit
/// side towards the dark side, that is darker than half the unshadowed render (or where the
/// unshadowed render itself has faded below 2 % of the row's maximum).
fn boundary(f: &Frame, lit: &Frame) -> Vec<(f32, f32)> {
    let mut out = Vec::new();
    for y in (SIZE / 2 - 30)..(SIZE / 2 + 30) {
        let row_max = (0..SIZE).map(|x| lum(lit, x, y)).fold(0f32, f32::max);
        let mut x = SIZE - 1;
        while x > 0 && lum(lit, x, y) < 0.02 * row_max {
            x -= 1; // background right of the limb
        }
        while x > 0 && lum(f, x, y) >= 0.5 * lum(lit, x, y) && lum(lit, x, y) >= 0.02 * row_max {
            x -= 1;
        }
        out.push((y as f32, x as f32));
    }
    out
}

/// RMS distance (pixels) of the boundary from its least-squares cubic in y.
fn deviation_from_smooth(b: &[(f32, f32)]) -> f64 {
    let n = b.len() as f64;
    let my = b.iter().map(|p| p.0 as f64).sum::<f64>() / n;
    // normal equations of a cubic in t = (y − ȳ)/30
    let mut a = [[0f64; 5]; 4];
    for &(y, x) in b {
        let t = (y as f64 - my) / 30.0;
        let pw = [1.0, t, t * t, t * t * t];
        for r in 0..4 {
            for c in 0..4 {
                a[r][c] += pw[r] * pw[c];
            }
            a[r][4] += pw[r] * x as f64;
        }
    }
    for i in 0..4 {
        let p = a[i][i];
        for c in i..5 {
            a[i][c] /= p;
        }
        for r in 0..4 {
            if r != i {
                let f = a[r][i];
                for c in i..5 {
                    a[r][c] -= f * a[i][c];
                }
            }
        }
    }
    let ss: f64 = b
        .iter()
        .map(|&(y, x)| {
            let t = (y as f64 - my) / 30.0;
            let fit = a[0][4] + a[1][4] * t + a[2][4] * t * t + a[3][4] * t * t * t;
            (x as f64 - fit).powi(2)
        })
        .sum();
    (ss / n).sqrt()
}

#[test]
fn smooth_boundary_removes_the_polygon_staircase() {
    let Some(gpu) = gpu("smooth_boundary_removes_the_polygon_staircase") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "u.eigen", Pattern::Lambert, 4, 4, 2, Quantization::F16);
    write(dir.path(), "sphere.obj", &sphere_obj(1.0, [0.0, 0.0, 0.0], 16));
    let render = |shadows, smooth| {
        let f = render_scene(
            &gpu,
            &sphere_scene(dir.path(), shadows, smooth),
            RenderOptions::default(),
        )
        .unwrap();
        assert!(f.all_finite());
        f
    };
    let lit = render(Shadows::None, true);
    for shadows in [Shadows::Volume, Shadows::Map] {
        let on = deviation_from_smooth(&boundary(&render(shadows, true), &lit));
        let off_frame = render(shadows, false);
        let off = deviation_from_smooth(&boundary(&off_frame, &lit));
        eprintln!(
            "{shadows:?}: boundary deviation from a smooth cubic, eq. 6 on {on:.2} px, off {off:.2} px (sphere radius {:.0} px, 16 segments)",
            SIZE as f32 / (2.0 * HALF_HEIGHT)
        );
        if off < 3.0 * on || on > 0.75 {
            save_comparison(&format!("eq6-{shadows:?}"), SIZE, SIZE, &lit.rgb, &off_frame.rgb);
        }
        assert!(on < 0.75, "{shadows:?}: eq. 6 boundary not smooth ({on} px)");
        assert!(
            off > 3.0 * on,
            "{shadows:?}: turning eq. 6 off should show the staircase ({off} vs {on} px)"
        );
    }
}
