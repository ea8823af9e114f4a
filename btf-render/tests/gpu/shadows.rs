//! Shadows with known geometry: an occluder's shadow on a plane against its analytic
//! projection (IoU), darkness inside and agreement outside, and the smooth shadow boundary
//! (`[S03 eq. 6]`) on a coarse sphere against where eq. 6 puts it.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_render::scene::Shadows;
use btf_render::{Frame, RenderOptions, Scene, render_scene};

const GROUND_AND_OCCLUDER: &str = "\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
v 0.35 0.4 0.3\nv 0.55 0.4 0.3\nv 0.55 0.6 0.3\nv 0.35 0.6 0.3\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 5/1 6/2 7/3\nf 5/1 7/3 8/4\n";

const L: [f32; 3] = [0.3, 0.2, 1.0];
/// Oblique light for the sphere (not aligned with its rings and segments).
const LS: [f32; 3] = [1.0, 0.35, 0.25];

/// World x of the eq. 6 boundary on the unit sphere's visible side at height `y`.
fn predicted_x(y: f32, alpha_deg: f32) -> f32 {
    let l = nalgebra::Vector3::new(LS[0], LS[1], LS[2]).normalize();
    let target = (90.0 - alpha_deg).to_radians().cos();
    let f = |x: f32| l.x * x + l.y * y + l.z * (1.0 - x * x - y * y).max(0.0).sqrt() - target;
    // f grows with x on the lit side: bisect between the centre line and the limb.
    let (mut lo, mut hi) = (-0.2f32, (1.0 - y * y).sqrt());
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

fn occluder_scene(dir: &std::path::Path, shadows: Shadows, size: u32) -> Scene {
    SceneBuilder::new(dir, size)
        .mesh("scene.obj")
        .material("u.eigen")
        .light(directional(L))
        .effects(|e| (e.shadows, e.shadow_map_size) = (shadows, 2048))
        .build()
}

fn lum(f: &Frame, x: u32, y: u32) -> f32 {
    f.pixel(x, y).iter().sum()
}

#[test]
fn occluder_shadow_matches_its_projection() {
    let Some(gpu) = gpu("occluder_shadow_matches_its_projection") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "u.eigen", Pattern::Lambert, 4, 4, 2, Quantization::F16);
    write(dir.path(), "scene.obj", GROUND_AND_OCCLUDER);
    let size = 96u32;
    let reference =
        render_scene(&gpu, &occluder_scene(dir.path(), Shadows::None, size), Default::default())
            .unwrap();
    // Shadow of the square [0.35,0.55]×[0.4,0.6] at height 0.3 along −L onto z = 0.
    let (dx, dy) = (-L[0] / L[2] * 0.3, -L[1] / L[2] * 0.3);
    for shadows in [Shadows::Volume, Shadows::Map] {
        let f = render_scene(
            &gpu,
            &occluder_scene(dir.path(), shadows, size),
            RenderOptions::default(),
        )
        .unwrap();
        assert!(f.all_finite());
        let (mut inter, mut union, mut max_dark, mut lit_err, mut lit_n) = (0, 0, 0f32, 0f64, 0);
        for y in 0..size {
            for x in 0..size {
                let (wx, wy) =
                    ((x as f32 + 0.5) / size as f32, 1.0 - (y as f32 + 0.5) / size as f32);
                let on_occluder = (0.35..0.55).contains(&wx) && (0.4..0.6).contains(&wy);
                if on_occluder {
                    continue;
                }
                let expect =
                    (0.35 + dx..0.55 + dx).contains(&wx) && (0.4 + dy..0.6 + dy).contains(&wy);
                let got = lum(&f, x, y) < 0.5 * lum(&reference, x, y);
                inter += (expect && got) as u32;
                union += (expect || got) as u32;
                // Well inside: black; well outside: as without shadows.
                let margin = 2.5 / size as f32;
                let inside = (0.35 + dx + margin..0.55 + dx - margin).contains(&wx)
                    && (0.4 + dy + margin..0.6 + dy - margin).contains(&wy);
                let outside = !((0.35 + dx - margin..0.55 + dx + margin).contains(&wx)
                    && (0.4 + dy - margin..0.6 + dy + margin).contains(&wy));
                if inside {
                    max_dark = max_dark.max(lum(&f, x, y) / lum(&reference, x, y));
                }
                if outside {
                    lit_err += ((lum(&f, x, y) - lum(&reference, x, y)) / lum(&reference, x, y))
                        .abs() as f64;
                    lit_n += 1;
                }
            }
        }
        let iou = inter as f64 / union as f64;
        let lit_err = lit_err / lit_n as f64;
        eprintln!(
            "{shadows:?}: IoU {iou:.4}, darkest/lit inside {max_dark:.2e}, mean |rel. diff| outside {lit_err:.2e}"
        );
        if iou <= 0.95 {
            save_comparison(&format!("occluder-{shadows:?}"), size, size, &reference.rgb, &f.rgb);
        }
        assert!(iou > 0.95, "{shadows:?}: IoU {iou}");
        assert!(max_dark < 1e-3, "{shadows:?}: shadow core not black ({max_dark})");
        assert!(
            lit_err < 1e-3,
            "{shadows:?}: lit region differs from the unshadowed render ({lit_err})"
        );
    }
}

/// A coarse sphere (16 segments) lit obliquely, seen from +z: eq. 6 puts the boundary where
/// the normal makes 90° − α with the light; on the visible hemisphere, row by row, that is
/// the x solving `L · (x, y, √(1 − x² − y²)) = cos(90° − α)`.
#[test]
fn smooth_boundary_sits_where_eq6_puts_it_without_zigzag() {
    let Some(gpu) = gpu("smooth_boundary_sits_where_eq6_puts_it_without_zigzag") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "u.eigen", Pattern::Lambert, 4, 4, 2, Quantization::F16);
    write(dir.path(), "sphere.obj", &sphere_obj(1.0, [0.0, 0.0, 0.0], 16));
    let size = 128u32;
    for (shadows, alpha) in
        [(Shadows::Volume, 15.0f32), (Shadows::Volume, 30.0), (Shadows::Map, 15.0)]
    {
        let scene = SceneBuilder::new(dir.path(), size)
            .mesh("sphere.obj")
            .material("u.eigen")
            .ortho(OVER_SPHERE.with_height(2.4))
            .light(directional(LS))
            .effects(|e| (e.shadows, e.terminator_deg) = (shadows, alpha))
            .build();
        let f = render_scene(&gpu, &scene, RenderOptions::default()).unwrap();
        assert!(f.all_finite());
        let px_per_unit = size as f32 / 2.4;
        let cx = size as f32 / 2.0;
        let mut devs = Vec::new();
        for y in (size / 2 - 30)..(size / 2 + 30) {
            let wy = (cx - (y as f32 + 0.5)) / px_per_unit;
            let x_pred = cx + predicted_x(wy, alpha) * px_per_unit - 0.5;
            let reference = lum(&f, x_pred as u32 + 5, y);
            let mut x = x_pred as u32 + 5;
            while x > 0 && lum(&f, x, y) >= 0.5 * reference {
                x -= 1;
            }
            devs.push(x as f32 + 1.0 - x_pred);
        }
        let n = devs.len() as f32;
        let mean = devs.iter().sum::<f32>() / n;
        let rms = (devs.iter().map(|d| d * d).sum::<f32>() / n).sqrt();
        // Zig-zag: deviation of the boundary from its own running mean over 9 rows.
        let rough = (4..devs.len() - 4)
            .map(|i| (devs[i] - devs[i - 4..=i + 4].iter().sum::<f32>() / 9.0).abs())
            .fold(0f32, f32::max);
        eprintln!(
            "{shadows:?} α={alpha}: boundary offset mean {mean:+.2} px, RMS {rms:.2} px, max zig-zag {rough:.2} px (sphere radius {px_per_unit:.0} px, 16 segments)"
        );
        assert!(rms < 2.0, "boundary is {rms} px away from eq. 6");
        assert!(rough < 1.5, "boundary zig-zags by {rough} px");
    }
}
