//! End-to-end tests of `btf render`: a tiny eigen store and plane written into a temporary
//! folder, the real binary run on a scene, its PNG/EXR and `--stats-json` checked, and bad
//! input refused with messages that name the key or the file and line. GPU-dependent
//! checks are skipped without an adapter unless `BTF_REQUIRE_GPU=1`.

use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use std::path::Path;
use std::process::{Command, Output};

fn btf(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_btf")).args(args).current_dir(dir).output().expect("btf runs")
}

fn no_gpu(o: &Output) -> bool {
    let err = String::from_utf8_lossy(&o.stderr);
    if err.contains("no GPU adapter") {
        assert!(
            std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"),
            "BTF_REQUIRE_GPU=1 but: {err}"
        );
        eprintln!("skipped: {err}");
        return true;
    }
    false
}

/// An 8×8 store, 4 components: mean 0.25 everywhere, small texture-varying eigentextures.
fn tiny_store(dir: &Path) {
    let (w, h, c) = (8, 8, 4);
    let s = Sampling::ubo81();
    let meta = EigenMeta {
        btf: BtfMeta::new(s.clone(), s.clone(), w, h),
        components: c,
        quantization: Quantization::F16,
    };
    let writer = EigenWriter::create(&dir.join("m.eigen"), meta, false).unwrap();
    for j in 0..s.len() {
        let basis: Vec<f32> =
            (0..c * w * h * 3).map(|i| 0.01 * ((i * 7 + j) % 13) as f32).collect();
        let (eigentextures, scale_offset) = quantize(&basis, c, Quantization::F16);
        let slot = QuantizedSlot {
            mean: vec![0.25; w * h * 3],
            eigentextures,
            scale_offset,
            weights: (0..s.len() * c).map(|i| (i % 5) as f32 * 0.1).collect(),
            eigenvalues: vec![1.0; s.len()],
        };
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
}

const PLANE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";

fn scene(shadows: &str, light_shadows: bool) -> String {
    format!(
        r#"
[output]
width = 24
height = 16
[[meshes]]
path = "plane.obj"
[[materials]]
store = "m.eigen"
[camera]
eye = [0.5, 0.5, 2.0]
target = [0.5, 0.5, 0.0]
[[lights]]
kind = "directional"
direction = [0.2, 0.3, 1.0]
irradiance = [2.0, 2.0, 2.0]
shadows = {light_shadows}
[effects]
shadows = "{shadows}"
"#
    )
}

fn setup() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    tiny_store(d.path());
    std::fs::write(d.path().join("plane.obj"), PLANE).unwrap();
    d
}

#[test]
fn renders_png_exr_and_stats_json() {
    let d = setup();
    std::fs::write(d.path().join("s.toml"), scene("none", true)).unwrap();
    let o = btf(
        d.path(),
        &["render", "s.toml", "-o", "out.png", "--exr", "out.exr", "--width", "20", "--stats-json"],
    );
    if no_gpu(&o) {
        return;
    }
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = image::open(d.path().join("out.png")).unwrap();
    assert_eq!((png.width(), png.height()), (20, 16), "--width overrides the scene");
    // The plane fills the middle of the image: the centre pixel is lit, the corner is not.
    let centre = png.to_rgb8().get_pixel(10, 8).0;
    assert!(centre.iter().all(|&c| c > 20), "{centre:?}");
    assert_eq!(png.to_rgb8().get_pixel(0, 0).0, [0, 0, 0]);
    assert!(d.path().join("out.exr").is_file());
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let passes = json["passes"].as_array().unwrap();
    assert!(
        passes.iter().any(|p| p["name"] == "btf (per-pixel)" && p["ms"].as_f64().unwrap() >= 0.0),
        "{json}"
    );
    assert!(json["frame_ms"].as_f64().unwrap() > 0.0);
    assert!(
        !passes.iter().any(|p| p["name"].as_str().unwrap().contains("shadow")),
        "no shadow pass without shadows"
    );
}

#[test]
fn shadow_passes_run_only_for_shadowing_lights() {
    let d = setup();
    for (shadows, casts, expect) in [
        ("volume", false, None),
        ("volume", true, Some("shadow volume")),
        ("map", true, Some("shadow map")),
    ] {
        std::fs::write(d.path().join("s.toml"), scene(shadows, casts)).unwrap();
        let o = btf(d.path(), &["render", "s.toml", "-o", "out.png", "--stats-json"]);
        if no_gpu(&o) {
            return;
        }
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let names: Vec<&str> = json["passes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["name"].as_str().unwrap())
            .collect();
        match expect {
            None => assert!(!names.iter().any(|n| n.contains("shadow")), "{names:?}"),
            Some(e) => assert!(names.iter().any(|n| n.starts_with(e)), "{shadows}: {names:?}"),
        }
    }
}

#[test]
fn bad_input_is_refused_with_its_location() {
    let d = setup();
    let bad_key = scene("sometimes", true);
    std::fs::write(d.path().join("s.toml"), bad_key).unwrap();
    let o = btf(d.path(), &["render", "s.toml", "-o", "out.png"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("shadows") && err.contains("sometimes"), "{err}");

    std::fs::write(d.path().join("plane.obj"), "v 0 0 0\nv 1 0 0\nvt 0 0\nf 1/1 2/1 7/1\n")
        .unwrap();
    std::fs::write(d.path().join("s.toml"), scene("none", true)).unwrap();
    let o = btf(d.path(), &["render", "s.toml", "-o", "out.png"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("plane.obj:4") && err.contains("vertex 7"),
        "{err}"
    );
}

/// A successful GPU command prints no line starting with "error" — in particular not
/// libwayland's `XDG_RUNTIME_DIR is invalid or not set`, which Mesa's device-select layer
/// provoked twice per command in containers and CI — and without any Vulkan driver the user
/// is told what to install instead of a pipeline validation error.
#[test]
fn quiet_on_success_and_an_install_hint_without_vulkan() {
    let d = setup();
    std::fs::write(d.path().join("s.toml"), scene("none", false)).unwrap();
    let run = |extra_env: &[(&str, &str)]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_btf"));
        c.args(["render", "s.toml", "-o", "out.png"]).current_dir(d.path());
        c.env_remove("XDG_RUNTIME_DIR").env_remove("NODEVICE_SELECT");
        for (k, v) in extra_env {
            c.env(k, v);
        }
        c.output().expect("btf runs")
    };
    let o = run(&[]);
    if no_gpu(&o) {
        return;
    }
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    let bad: Vec<&str> =
        err.lines().filter(|l| l.trim_start().to_lowercase().starts_with("error")).collect();
    assert!(bad.is_empty(), "a successful render printed {bad:?}");
    // No Vulkan driver (the loader finds no ICD): whatever else wgpu finds (an OpenGL
    // adapter that cannot render the f32 frame, or nothing), the message names the package.
    let none = "/nonexistent/icd.json";
    let o = run(&[("VK_ICD_FILENAMES", none), ("VK_DRIVER_FILES", none)]);
    assert!(!o.status.success(), "rendered without a Vulkan driver?");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no GPU adapter") && err.contains("mesa-vulkan-drivers"), "{err}");
    assert!(!err.contains("Validation"), "{err}");
}

#[test]
fn render_sweep_refuses_component_counts_the_store_does_not_hold() {
    // Checked before any GPU work: runs without an adapter.
    let d = setup();
    std::fs::write(d.path().join("s.toml"), scene("none", false)).unwrap();
    let o = btf(d.path(), &["render-sweep", "s.toml", "-o", "sweep", "-c", "4,8"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--components 8") && err.contains("holds only 4"), "{err}");
    assert!(err.contains("m.eigen"), "{err}");
    assert!(!d.path().join("sweep").exists());
}
