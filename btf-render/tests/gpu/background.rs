//! The environment background (`passes/background`) against the CPU reference it replaced
//! (the per-pixel loop of the former `env_background.rs`, kept here): the same camera ray
//! per pixel centre, the map turned by `δ` and scaled by `f`, bilinear in the map. Without
//! MSAA the target is `f32` and the two differ by the transcendental functions' rounding
//! (the ray's `θ`, `φ`); with MSAA the target is `f16` (≤ 2⁻¹¹ relative). And the background
//! behind a mesh with MSAA: what `show_environment` needed `msaa = 1` for before.

use crate::common::*;
use btf_core::eigen::Quantization;
use btf_image::EnvMap;
use btf_render::camera::CameraSetup;
use btf_render::scene::{EnvironmentLight, Light};
use btf_render::{RenderOptions, Renderer, Scene};
use nalgebra::Vector4;
use std::f32::consts::PI;
use std::path::Path;

/// World direction of the camera ray through the centre of pixel `(x, y)` (row 0 at the
/// top), from the inverse of the camera's world → clip matrix.
fn ray_dir(inv: &btf_render::math::Mat4, w: u32, h: u32, x: u32, y: u32) -> [f32; 3] {
    let nx = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ny = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
    let at = |z: f32| {
        let p = inv * Vector4::new(nx, ny, z, 1.0);
        nalgebra::Vector3::new(p.x / p.w, p.y / p.w, p.z / p.w)
    };
    let d = (at(0.75) - at(0.25)).try_normalize(0.0).unwrap_or(nalgebra::Vector3::z());
    [d.x, d.y, d.z]
}

/// Bilinear radiance of `map` in world direction `d` (unit), wrapping in `φ`, and the
/// spread (largest − smallest) of the four texels it blends, per channel.
fn radiance(map: &EnvMap, d: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let theta = d[2].clamp(-1.0, 1.0).acos();
    let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
    let (w, h) = (map.width, map.height);
    let u = phi / (2.0 * PI) * w as f32 - 0.5;
    let v = (theta / PI * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
    let (c0, r0) = (u.floor(), v.floor());
    let (fu, fv) = (u - c0, v - r0);
    let col = |c: f32| (c as i64).rem_euclid(w as i64) as usize;
    let row = |r: f32| (r as usize).min(h - 1);
    let px = |c: f32, r: f32| map.pixels[row(r) * w + col(c)];
    let mut out = [0f32; 3];
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for (dc, dr, wgt) in [
        (0.0, 0.0, (1.0 - fu) * (1.0 - fv)),
        (1.0, 0.0, fu * (1.0 - fv)),
        (0.0, 1.0, (1.0 - fu) * fv),
        (1.0, 1.0, fu * fv),
    ] {
        let p = px(c0 + dc, r0 + dr);
        for k in 0..3 {
            out[k] += wgt * p[k];
            (lo[k], hi[k]) = (lo[k].min(p[k]), hi[k].max(p[k]));
        }
    }
    (out, [0, 1, 2].map(|k| hi[k] - lo[k]))
}

/// The CPU background: linear RGB, row-major from the top row, and per value the spread of
/// the texels it blends (times `f`).
fn reference(
    map: &EnvMap,
    camera: &CameraSetup,
    (w, h): (u32, u32),
    rot: f64,
    f: f32,
) -> (Vec<f32>, Vec<f32>) {
    let inv = camera.view_proj.try_inverse().unwrap();
    let (sin, cos) = rot.to_radians().sin_cos();
    let (sin, cos) = (sin as f32, cos as f32);
    let (mut out, mut spread) = (Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let d = ray_dir(&inv, w, h, x, y);
            // the environment turned by δ: world direction ω sees the map at R_{−δ} ω
            let e = [cos * d[0] + sin * d[1], -sin * d[0] + cos * d[1], d[2]];
            let (l, s) = radiance(map, e);
            out.extend(l.map(|c| f * c));
            spread.extend(s.map(|c| f * c));
        }
    }
    (out, spread)
}

/// A sky with a horizon, a gradient in φ and a small sun 40× brighter than the sky.
fn sky(d: [f64; 3]) -> [f64; 3] {
    let sun = [0.6f64, 0.2, 0.775];
    let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    let s = if c > 0.995 { 40.0 } else { 0.0 };
    let base = 0.3 + 0.6 * d[2].max(0.0) + 0.1 * (d[0] + 1.0) + 0.05 * d[1];
    [base + s, 0.9 * base + s, 0.7 * base + 0.8 * s]
}

/// A camera: perspective `(eye, target, up, fov)` or, without a field of view, orthographic
/// (view height 3).
type Cam = ([f32; 3], [f32; 3], [f32; 3], Option<f32>);

/// The unit plane under the sky, shown behind it, seen by `cam` at `msaa` samples.
fn scene(dir: &Path, cam: Cam, msaa: u32, rotation_deg: f64, exposure: f32) -> Scene {
    let env = EnvironmentLight {
        rotation_deg,
        exposure,
        visibility_res: 4,
        ..environment(dir, "sky.exr")
    };
    let (eye, target, up, fov) = cam;
    let b = SceneBuilder::new(dir, 64).size(64, 48);
    let b = match fov {
        Some(fov) => b.perspective(eye, target, up, fov),
        None => b.ortho(Ortho { eye, target, height: 3.0 }),
    };
    b.output(|o| o.show_environment = true)
        .mesh("plane.obj")
        .material("m.eigen")
        .light(Light::Environment(env))
        .effects(|e| e.msaa = msaa)
        .build()
}

const SIDEWAYS: Cam = ([0.0, -3.0, 0.4], [0.3, 0.0, 0.9], [0.0, 0.0, 1.0], Some(100.0));
/// Orthographic and oblique: every ray one direction.
const ORTHO: Cam = ([0.2, -1.0, 3.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], None);
/// Straight down at the plane, `[0, 1]²` centred at `(0.2, 0.1)`: 16 pixels per unit.
const DOWN: Cam = ([0.2, 0.1, 3.0], [0.2, 0.1, 0.0], [0.0, 1.0, 0.0], None);

#[test]
fn background_pass_matches_the_cpu_background() {
    let Some(gpu) = gpu("background_pass_matches_the_cpu_background") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 2, 2, 2, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 1);
    let map = EnvMap::from_fn(64, sky).unwrap();
    map.write_exr(&dir.path().join("sky.exr")).unwrap();
    let map = EnvMap::load(&dir.path().join("sky.exr")).unwrap();
    // The bound per value: the look-up may move by `SHIFT` map pixels (lavapipe's acos and
    // atan2 and the unprojection round differently from the CPU's: measured up to 1.6e-3
    // px, 1.6e-4 rad, on this 64 × 32 map), which changes a bilinear value by at most
    // SHIFT × the spread of its four texels; plus the target's rounding, f32 (1e-6
    // relative) or, with MSAA, one f16 step (2⁻¹⁰ relative: lavapipe truncates to f16).
    const SHIFT: f32 = 4e-3;
    for (msaa, rounding) in [(1, 1e-6f32), (4, 2f32.powi(-10))] {
        for (camera, rot, f) in [(SIDEWAYS, 0.0, 1.0), (SIDEWAYS, 137.0, 0.6), (ORTHO, -40.0, 2.0)]
        {
            let s = scene(dir.path(), camera, msaa, rot, f);
            let mut r = Renderer::new(&gpu, &s, RenderOptions::default()).unwrap();
            let gpu_bg = r.environment_background(&gpu).unwrap().unwrap();
            let (cpu_bg, spread) = reference(&map, r.camera(), (64, 48), rot, f);
            let mut worst = 0f32;
            for ((a, b), s) in gpu_bg.iter().zip(&cpu_bg).zip(&spread) {
                let bound = SHIFT * s + rounding * b.abs() + 1e-7;
                worst = worst.max((a - b).abs() / bound);
            }
            eprintln!("msaa {msaa}, δ = {rot}°, f = {f}: worst difference / bound {worst:.3}");
            if worst > 1.0 {
                save_comparison(&format!("background-{msaa}-{rot}"), 64, 48, &cpu_bg, &gpu_bg);
            }
            assert!(worst <= 1.0, "msaa {msaa}, δ = {rot}: {worst} of the bound");
        }
    }
}

#[test]
fn background_shows_behind_the_mesh_with_msaa() {
    let Some(gpu) = gpu("background_shows_behind_the_mesh_with_msaa") else { return };
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Lambert, 2, 2, 2, Quantization::F16);
    unit_plane(dir.path(), "plane.obj", 1);
    EnvMap::from_fn(64, sky).unwrap().write_exr(&dir.path().join("sky.exr")).unwrap();
    for msaa in [1, 4] {
        let s = scene(dir.path(), DOWN, msaa, 20.0, 1.0);
        let mut r = Renderer::new(&gpu, &s, RenderOptions::default()).unwrap();
        let bg = r.environment_background(&gpu).unwrap().unwrap();
        let shown = r.render(&gpu).unwrap();
        assert!(shown.stats.ran("environment background"), "{:?}", shown.stats.passes);
        r.set_show_environment(false).unwrap();
        let plain = r.render(&gpu).unwrap();
        assert!(!plain.stats.ran("environment background"));
        // The plane covers [0, 1]² of the 4 × 3 view: pixels well outside it show the
        // background, pixels well inside the plane as drawn without a background.
        let (mut background, mut plane) = (0, 0);
        for y in 0..48u32 {
            for x in 0..64u32 {
                let wx = 0.2 + (x as f32 + 0.5 - 32.0) / 16.0;
                let wy = 0.1 + (24.0 - y as f32 - 0.5) / 16.0;
                let m = 2.0 / 16.0;
                let inside = (m..1.0 - m).contains(&wx) && (m..1.0 - m).contains(&wy);
                let outside = !(-m..1.0 + m).contains(&wx) || !(-m..1.0 + m).contains(&wy);
                let i = ((y * 64 + x) * 3) as usize;
                if outside {
                    assert_eq!(shown.rgb[i..i + 3], bg[i..i + 3], "msaa {msaa}: ({x}, {y})");
                    assert_eq!(plain.rgb[i..i + 3], [0.0; 3], "msaa {msaa}: ({x}, {y})");
                }
                if inside {
                    assert_eq!(shown.rgb[i..i + 3], plain.rgb[i..i + 3], "msaa {msaa}: ({x}, {y})");
                    assert!(plain.rgb[i] > 0.0, "msaa {msaa}: ({x}, {y}) the plane is drawn");
                }
                background += outside as u32;
                plane += inside as u32;
            }
        }
        assert!(background > 500 && plane > 100, "{background} background, {plane} plane pixels");
    }
}
