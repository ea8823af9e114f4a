//! Environment lighting end to end through the `btf` binary (Sattler et al. 2003, §5):
//! a white furnace renders the albedo, rotating by 360° is the identity, environment light
//! adds to a directional light, `btf relight` resumes and writes its summary and
//! eigenweightset report, and bad environment files are refused naming the file. Tiny data:
//! a vertical 4×4-quad plane, an 8×8 Lambertian store, 64×32 environments.

use crate::common;
use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use common::*;
use std::path::Path;

const ALBEDO: f32 = 0.8;

/// An exactly Lambertian eigen store (`BTF = ρ/π · cos θ_l`, one component), ubo81.
fn lambert_store(path: &Path) {
    let s = Sampling::ubo81();
    let n = 8 * 8 * 3;
    let meta = EigenMeta {
        btf: BtfMeta::new(s.clone(), s.clone(), 8, 8),
        components: 1,
        quantization: Quantization::F16,
    };
    let w = EigenWriter::create(path, meta, false).unwrap();
    let rho_pi = ALBEDO / std::f32::consts::PI;
    let cos: Vec<f32> = (0..s.len()).map(|i| s.direction(i).cos_theta() as f32).collect();
    let mean_cos = cos.iter().sum::<f32>() / cos.len() as f32;
    let unit = 1.0 / (n as f32).sqrt();
    let (eigentextures, scale_offset) = quantize(&vec![unit; n], 1, Quantization::F16);
    let slot = QuantizedSlot {
        mean: vec![rho_pi * mean_cos; n],
        eigentextures,
        scale_offset,
        weights: cos.iter().map(|c| rho_pi * (c - mean_cos) / unit).collect(),
        eigenvalues: vec![1.0; s.len()],
    };
    for j in 0..s.len() {
        w.write_slot(j, &slot).unwrap();
    }
    w.finish().unwrap();
}

/// The plane `y = 0`, `x, z ∈ [0, 1]`, facing `−y`, UV = (x, z).
fn vertical_plane(n: usize) -> String {
    let mut s = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
            s += &format!("v {x} 0 {z}\nvt {x} {z}\nvn 0 -1 0\n");
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            s += &format!(
                "f {a}/{a}/{a} {c}/{c}/{c} {b}/{b}/{b}\nf {a}/{a}/{a} {d}/{d}/{d} {c}/{c}/{c}\n"
            );
        }
    }
    s
}

/// A UV sphere of radius 0.35 around `(0.5, 0, 0.5)` (many normals: a rich `U(δ)`).
pub(crate) fn sphere(seg: usize, rings: usize) -> String {
    let mut s = String::new();
    for j in 0..=rings {
        for i in 0..=seg {
            let (t, p) = (
                std::f32::consts::PI * j as f32 / rings as f32,
                std::f32::consts::TAU * i as f32 / seg as f32,
            );
            let n = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
            let (u, v) = (i as f32 / seg as f32, 1.0 - j as f32 / rings as f32);
            s += &format!(
                "v {} {} {}\nvt {u} {v}\nvn {} {} {}\n",
                0.5 + 0.35 * n[0],
                0.35 * n[1],
                0.5 + 0.35 * n[2],
                n[0],
                n[1],
                n[2]
            );
        }
    }
    let id = |i: usize, j: usize| j * (seg + 1) + i + 1;
    for j in 0..rings {
        for i in 0..seg {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if j + 1 < rings {
                s += &format!("f {a}/{a}/{a} {c}/{c}/{c} {b}/{b}/{b}\n");
            }
            if j > 0 {
                s += &format!("f {a}/{a}/{a} {d}/{d}/{d} {c}/{c}/{c}\n");
            }
        }
    }
    s
}

/// Writes an equirectangular 64×32 EXR of `radiance(θ, φ)`.
pub(crate) fn write_env(path: &Path, radiance: impl Fn(f32, f32) -> [f32; 3] + Sync) {
    let (w, h) = (64usize, 32usize);
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let theta = std::f32::consts::PI * (y as f32 + 0.5) / h as f32;
        let phi = std::f32::consts::TAU * (x as f32 + 0.5) / w as f32;
        let c = radiance(theta, phi);
        (c[0], c[1], c[2])
    })
    .unwrap();
}

/// A scene of the plane seen head-on by an orthographic camera filling the frame.
pub(crate) fn scene(evaluation: &str, env: &str, extra: &str) -> String {
    format!(
        r#"
[output]
width = 16
height = 16
[[meshes]]
path = "plane.obj"
[[materials]]
store = "lambert.eig"
[camera]
projection = "orthographic"
eye = [0.5, -2.0, 0.5]
target = [0.5, 0.0, 0.5]
up = [0.0, 0.0, 1.0]
ortho_height = 0.8
{extra}
[[lights]]
kind = "environment"
path = "{env}"
visibility_res = 16
[effects]
evaluation = "{evaluation}"
msaa = 1   # exact sums within 1e-4: MSAA frames resolve into f16
"#
    )
}

pub(crate) fn setup() -> Dir {
    let d = Dir::new();
    lambert_store(&d.path("lambert.eig"));
    std::fs::write(d.path("plane.obj"), vertical_plane(4)).unwrap();
    write_env(&d.path("white.exr"), |_, _| [1.0; 3]);
    write_env(&d.path("sky.exr"), |t, p| {
        let l = 0.8 + 0.4 * p.cos() + 0.3 * t.cos();
        [l, 0.9 * l, 0.7 * l]
    });
    d
}

/// `btf ARGS`, or `None` when there is no GPU adapter and none is required.
pub(crate) fn run_gpu(d: &Dir, args: &[&str]) -> Option<String> {
    let o = d.btf(args);
    let err = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() && err.contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "{err}");
        eprintln!("skipped: {err}");
        return None;
    }
    assert!(o.status.success(), "btf {args:?} failed:\n{err}");
    Some(String::from_utf8(o.stdout).unwrap())
}

fn render_exr(d: &Dir, name: &str, text: &str) -> Option<Vec<f32>> {
    std::fs::write(d.path(&format!("{name}.toml")), text).unwrap();
    let (toml, png, exr) = (format!("{name}.toml"), format!("{name}.png"), format!("{name}.exr"));
    run_gpu(d, &["render", &toml, "-o", &png, "--exr", &exr])?;
    Some(read_exr(&d.path(&exr)).2)
}

#[test]
fn white_furnace_renders_the_albedo_per_vertex_and_per_pixel() {
    let d = setup();
    for eval in ["per-vertex", "per-pixel"] {
        let Some(px) = render_exr(&d, eval, &scene(eval, "white.exr", "")) else { return };
        let worst = px.iter().map(|v| (v / ALBEDO - 1.0).abs()).fold(0f32, f32::max);
        eprintln!("furnace {eval}: worst relative error {worst:.5}");
        assert!(worst < 0.01, "{eval}: furnace off by {worst}");
    }
}

#[test]
fn rotating_by_360_degrees_is_the_identity_and_90_is_not() {
    let d = setup();
    for eigen in ["", "eigenweightsets = { rotations = 12, components = 4 }"] {
        let at = |deg: f64| {
            let s = scene("per-vertex", "sky.exr", "").replace(
                "visibility_res = 16",
                &format!("visibility_res = 16\nrotation_deg = {deg}\n{eigen}"),
            );
            render_exr(&d, &format!("rot{deg}"), &s)
        };
        let (Some(a), Some(b), Some(c)) = (at(0.0), at(360.0), at(90.0)) else { return };
        let rel = |x: &[f32], y: &[f32]| {
            let num: f32 = x.iter().zip(y).map(|(p, q)| (p - q).powi(2)).sum();
            (num / x.iter().map(|p| p * p).sum::<f32>()).sqrt()
        };
        assert!(rel(&a, &b) < 1e-5, "{eigen}: 0° vs 360°: {}", rel(&a, &b));
        assert!(rel(&a, &c) > 0.05, "{eigen}: 90° changes nothing: {}", rel(&a, &c));
    }
}

#[test]
fn environment_adds_to_a_directional_light() {
    let d = setup();
    let sun = "[[lights]]\nkind = \"directional\"\ndirection = [0.3, -1.0, 0.4]\nirradiance = [2.0, 2.0, 2.0]\n";
    for eval in ["per-pixel", "per-vertex"] {
        let both = scene(eval, "sky.exr", sun);
        let env_only = scene(eval, "sky.exr", "");
        let sun_only = both.replace(
            "[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nvisibility_res = 16\n",
            "",
        );
        let (Some(ab), Some(a), Some(b)) = (
            render_exr(&d, &format!("both-{eval}"), &both),
            render_exr(&d, &format!("env-{eval}"), &env_only),
            render_exr(&d, &format!("sun-{eval}"), &sun_only),
        ) else {
            return;
        };
        let worst = ab
            .iter()
            .zip(a.iter().zip(&b))
            .map(|(s, (x, y))| (s - x - y).abs() / s)
            .fold(0f32, f32::max);
        assert!(worst < 1e-4, "{eval}: env + sun differs from the sum by {worst}");
        assert!(b.iter().sum::<f32>() > 0.1 * a.iter().sum::<f32>(), "the sun adds light");
    }
}

#[test]
fn stats_list_environment_passes_only_with_an_environment() {
    let d = setup();
    std::fs::write(d.path("env.toml"), scene("per-pixel", "white.exr", "")).unwrap();
    let Some(out) = run_gpu(&d, &["render", "env.toml", "-o", "e.png", "--stats-json"]) else {
        return;
    };
    let s: serde_json::Value = serde_json::from_str(out.lines().last().unwrap()).unwrap();
    let names = |k: &str| -> Vec<String> {
        s[k].as_array()
            .map_or(vec![], |a| a.iter().map(|p| p["name"].as_str().unwrap().to_string()).collect())
    };
    assert!(names("setup").iter().any(|n| n.starts_with("env visibility maps")), "{s}");
    assert!(names("passes").iter().any(|n| n.starts_with("env coefficients")), "{s}");
    let plain = scene(
        "per-pixel",
        "white.exr",
        "[[lights]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\n",
    )
    .replace("[[lights]]\nkind = \"environment\"\npath = \"white.exr\"\nvisibility_res = 16\n", "");
    std::fs::write(d.path("plain.toml"), plain).unwrap();
    let out = run_gpu(&d, &["render", "plain.toml", "-o", "p.png", "--stats-json"]).unwrap();
    assert!(!out.contains("env "), "no environment work without an environment light: {out}");
}

#[test]
fn relight_renders_every_environment_and_rotation_and_resumes() {
    let d = setup();
    std::fs::write(d.path("s.toml"), scene("per-vertex", "white.exr", "")).unwrap();
    let args = [
        "relight",
        "s.toml",
        "--env",
        "white.exr",
        "--env",
        "sky.exr",
        "--rotations",
        "3",
        "-o",
        "out",
        "--exr",
    ];
    if run_gpu(&d, &args).is_none() {
        return;
    }
    let summary = |d: &Dir| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.path("out/summary.json")).unwrap()).unwrap()
    };
    let s = summary(&d);
    assert_eq!(s["frames_rendered"], 6, "{s}");
    for k in ["visibility_s", "weights_s_per_env", "frame_ms"] {
        assert!(s[k].as_f64().is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {s}");
    }
    assert_eq!(s["envs"].as_array().unwrap().len(), 2);
    // The camera shows one side of each vertex it sees: at most half the frames computed.
    let (computed, frames) =
        (s["visibility_frames_computed"].as_u64(), s["visibility_frames"].as_u64());
    assert!(computed.zip(frames).is_some_and(|(c, f)| c > 0 && 2 * c <= f), "{s}");
    let px = read_exr(&d.path("out/white_r002.exr")).2;
    assert!(px.iter().all(|v| (v / ALBEDO - 1.0).abs() < 0.01), "furnace through relight");
    // Interrupted job: one frame missing. Only it is rendered; visibility comes from the cache.
    let kept = d.path("out/sky_r000.png");
    let t0 = std::fs::metadata(&kept).unwrap().modified().unwrap();
    std::fs::remove_file(d.path("out/sky_r001.png")).unwrap();
    run_gpu(&d, &args).unwrap();
    let s = summary(&d);
    assert_eq!(
        (s["frames_rendered"].as_u64(), s["frames_skipped"].as_u64()),
        (Some(1), Some(5)),
        "{s}"
    );
    assert_eq!(s["visibility_cached"], true, "{s}");
    assert!(d.path("out/sky_r001.png").exists());
    assert_eq!(std::fs::metadata(&kept).unwrap().modified().unwrap(), t0);
    // A different job in the same folder is refused.
    let mut other = args.to_vec();
    other[7] = "4";
    let err = d.fails(&other);
    assert!(err.contains("different relight job"), "{err}");
}

#[test]
fn relight_writes_the_eigenweightset_report() {
    // A sphere under a sun-like lobe: U(δ) of many normals has rank ≥ 8 over 12 rotations.
    let d = setup();
    std::fs::write(d.path("sphere.obj"), sphere(16, 8)).unwrap();
    write_env(&d.path("sky.exr"), |t, p| {
        let c = (t.sin() * 0.6 * p.cos() + t.cos() * 0.8).max(0.0);
        [0.2 + 4.0 * c.powi(16); 3]
    });
    let s = scene("per-vertex", "sky.exr", "").replace("plane.obj", "sphere.obj").replace(
        "visibility_res = 16",
        "visibility_res = 16\neigenweightsets = { rotations = 12, components = 3 }",
    );
    std::fs::write(d.path("s.toml"), s).unwrap();
    if run_gpu(&d, &["relight", "s.toml", "--env", "sky.exr", "--rotations", "2", "-o", "out"])
        .is_none()
    {
        return;
    }
    let csv = std::fs::read_to_string(d.path("out/eigen/sky-error.csv")).unwrap();
    let rows: Vec<Vec<f64>> =
        csv.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 8, "{csv}");
    assert!(rows.iter().all(|r| r[1].is_finite() && r[1] >= 0.0 && r[2] >= r[1]), "{csv}");
    assert!(rows[7][1] < 0.5 * rows[0][1], "more eigenweightsets, smaller error: {csv}");
    assert!(rows[7][3] < rows[0][3], "and a smaller image error: {csv}");
    for f in [
        "sky-heat-e1.png",
        "sky-heat-e8.png",
        "sky-coefficients.png",
        "sky-error.md",
        "sky-error.png",
    ] {
        assert!(d.path("out/eigen").join(f).exists(), "missing {f}");
    }
    let img = image::open(d.path("out/eigen/sky-heat-e1.png")).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (16, 16));
}

#[test]
fn bad_environment_files_are_refused_naming_them() {
    let d = setup();
    write_env(&d.path("nan.exr"), |t, _| if t > 1.0 { [f32::NAN, 0.0, 0.0] } else { [1.0; 3] });
    std::fs::write(d.path("s.toml"), scene("per-vertex", "white.exr", "")).unwrap();
    let o = d.btf(&["relight", "s.toml", "--env", "white.exr", "--env", "nan.exr", "-o", "out"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    if !err.contains("no GPU adapter") {
        assert!(err.contains("nan.exr") && err.contains("non-finite"), "{err}");
    }
    let err = d.fails(&["relight", "s.toml", "--env", "missing.hdr", "-o", "out2"]);
    assert!(err.contains("missing.hdr") && err.contains("no such file"), "{err}");
    let err = d.fails(&["relight", "s.toml", "--env", "plane.obj", "-o", "out3"]);
    assert!(err.contains("plane.obj") && err.contains(".hdr or .exr"), "{err}");
}
