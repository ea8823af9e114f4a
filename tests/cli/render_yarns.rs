//! `btf render` of a scene with `[[yarns]]`: the example scene `examples/scenes/knit-swatch.toml`
//! (a rib swatch of fiber-level yarns above a corduroy BTF floor) rendered by the binary,
//! measured against the standalone fiber renderer of the same yarns, camera and lights; and
//! bad `[[yarns]]` entries refused by the binary naming the key, before any GPU work and
//! without writing an image. GPU checks skip without an adapter unless `BTF_REQUIRE_GPU=1`.

use crate::common::{Dir, read_exr};
use btf_render::{Gpu, RenderOptions, Renderer, Scene};
use std::path::Path;
use yarn_render::FiberRenderer;
use yarn_render::scene::overlay::{scene_bcsdf, settings};
use yarn_render::scene::{bounds_f32, fiber_camera, fiber_lights};

const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/scenes");
const SIZE: u32 = 64;

/// The example scene, its meshes and a small corduroy store in a temporary folder.
fn example(d: &Dir) {
    for f in ["knit-swatch.toml", "plane.obj", "swatch.obj"] {
        std::fs::copy(Path::new(EXAMPLES).join(f), d.path(f)).unwrap();
    }
    d.ok(&["synth", "material", "--kind", "corduroy", "--size", "8", "-o", "corduroy.btf"]);
    d.ok(&["compress", "corduroy.btf", "-o", "corduroy.eigen", "--components", "8"]);
}

/// The scene at `path` (at SIZE²), the render options that frame its yarns, and its first
/// `[[yarns]]` entry drawn by `FiberRenderer` alone with the scene's camera and lights
/// over a clear of 0.
fn standalone(gpu: &Gpu, path: &Path) -> (Scene, RenderOptions, yarn_render::FiberImage) {
    let mut scene = Scene::load(path).unwrap();
    (scene.output.width, scene.output.height) = (SIZE, SIZE);
    let yarns = yarn_render::scene::build(&scene, path).unwrap();
    let options = RenderOptions { extra_bounds: bounds_f32(&yarns), ..Default::default() };
    let camera = *Renderer::new(gpu, &scene, options).unwrap().camera();
    let y = &scene.yarns[0];
    let bake = yarn_precompute::BakeSettings { seed: y.seed, ..Default::default() };
    let fibers = FiberRenderer::with_bake(
        gpu,
        &yarns[0].packed,
        &scene_bcsdf().unwrap(),
        settings(&scene, y),
        &bake,
        None,
    )
    .unwrap();
    let lights = fiber_lights(&scene.lights);
    let img = fibers.render(gpu, &fiber_camera(&camera), &lights, (SIZE, SIZE), [0.0; 4]).unwrap();
    (scene, options, img)
}

#[test]
fn the_knit_swatch_example_renders_its_yarns_as_the_standalone_fiber_renderer_does() {
    let d = Dir::new();
    example(&d);
    let size = SIZE.to_string();
    let o = d.btf(&[
        "render",
        "knit-swatch.toml",
        "--width",
        &size,
        "--height",
        &size,
        "-o",
        "ks.png",
        "--exr",
        "ks.exr",
    ]);
    if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
        return;
    }
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(d.path("ks.png").is_file());
    let (w, h, cli) = read_exr(&d.path("ks.exr"));
    assert_eq!((w, h), (SIZE as usize, SIZE as usize));
    // The same yarns, camera and lights through FiberRenderer alone.
    let Some(gpu) = Gpu::for_tests("knit_swatch_example") else { return };
    let (scene, options, img) = standalone(&gpu, &d.path("knit-swatch.toml"));
    let floor = Renderer::new(&gpu, &scene, options).unwrap().render(&gpu).unwrap();
    // MSAA resolves the mean of a pixel's samples, and both passes shade once per pixel:
    // where the standalone yarns cover a fraction α of the samples (over a clear of 0), the
    // binary's pixel is their sum plus (1 − α) of the floor alone, to f16 rounding.
    let n = (SIZE * SIZE) as usize;
    let yarn: Vec<usize> = (0..n).filter(|&i| img.pixels[i][3] > 0.0).collect();
    let expected = |i: usize, c: usize| {
        img.pixels[i][c] as f64 + (1.0 - img.pixels[i][3] as f64) * floor.rgb[3 * i + c] as f64
    };
    let (mut got, mut want, mut worst) = (0.0, 0.0, 0.0f64);
    for &i in &yarn {
        for c in 0..3 {
            got += cli[3 * i + c] as f64;
            want += expected(i, c);
            worst = worst.max((cli[3 * i + c] as f64 - expected(i, c)).abs());
        }
    }
    let ratio = got / want;
    // Coverage: pixels the binary changed from the floor alone against the yarn's pixels.
    let changed = (0..n)
        .filter(|&i| (0..3).any(|c| (cli[3 * i + c] - floor.rgb[3 * i + c]).abs() > 1e-3))
        .count();
    let coverage: f64 = yarn.iter().map(|&i| img.pixels[i][3] as f64).sum::<f64>() / n as f64;
    eprintln!(
        "{} of {n} pixels with yarn (mean coverage {coverage:.4}), {changed} changed from the \
         floor alone; yarn-region mean radiance binary / (standalone + (1 − α) floor) = \
         {ratio:.6}, worst pixel difference {worst:.2e}",
        yarn.len()
    );
    assert!(yarn.len() > n / 10, "the swatch must cover part of the frame: {}", yarn.len());
    assert!((ratio - 1.0).abs() < 1e-3, "{ratio}");
    // f16: 2⁻¹¹ of values below 2, summed over two terms.
    assert!(worst < 2e-3, "{worst}");
    assert!(changed <= yarn.len() && changed * 10 >= yarn.len() * 9, "{changed}");
}

/// The swatch's fibers and the same swatch with `method = "strips"`: the yarns are drawn
/// (the yarn region differs from the floor alone), and an environment light reaches them
/// through its SRBF fit (adding a sky brightens the yarn region; rotating it changes it —
/// a constant ambient term would not).
#[test]
fn the_knit_swatch_yarns_are_lit_by_lights_and_an_environment_through_srbfs() {
    let d = Dir::new();
    example(&d);
    let text = std::fs::read_to_string(d.path("knit-swatch.toml")).unwrap();
    let strips = text.replacen("method = \"fibers\"", "method = \"strips\"", 1);
    assert_ne!(strips, text);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "64", "-o", "sky.exr"]);
    let no_yarns = text[..text.find("\n[[yarns]]").unwrap()].to_string()
        + "\n"
        + &text[text.find("\n[camera]").unwrap()..];
    std::fs::write(d.path("floor.toml"), no_yarns).unwrap();
    let size = "48";
    let render = |scene: &str, exr: &str| -> Option<Vec<f32>> {
        let o = d.btf(&[
            "render",
            scene,
            "--width",
            size,
            "--height",
            size,
            "-o",
            &format!("{exr}.png"),
            "--exr",
            exr,
        ]);
        if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
            assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
            return None;
        }
        assert!(o.status.success(), "{scene}: {}", String::from_utf8_lossy(&o.stderr));
        Some(read_exr(&d.path(exr)).2)
    };
    let Some(floor) = render("floor.toml", "floor.exr") else { return };
    for (method, scene) in [("fibers", &text), ("strips", &strips)] {
        let env = |rot: f64| {
            format!(
                "{scene}\n[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\nexposure = 2e-3\nrotation_deg = {rot}\nvisibility_res = 4\n"
            )
        };
        std::fs::write(d.path(&format!("{method}.toml")), scene).unwrap();
        std::fs::write(d.path(&format!("{method}-env.toml")), env(0.0)).unwrap();
        std::fs::write(d.path(&format!("{method}-env-rot.toml")), env(120.0)).unwrap();
        let lit = render(&format!("{method}.toml"), &format!("{method}.exr")).unwrap();
        let env0 = render(&format!("{method}-env.toml"), &format!("{method}-env0.exr")).unwrap();
        let env1 =
            render(&format!("{method}-env-rot.toml"), &format!("{method}-env1.exr")).unwrap();
        let n = 48 * 48;
        let yarn: Vec<usize> = (0..n)
            .filter(|&i| (0..3).any(|c| (lit[3 * i + c] - floor[3 * i + c]).abs() > 1e-3))
            .collect();
        assert!(yarn.len() > n / 10, "the {method} cover part of the frame: {}", yarn.len());
        let sum = |img: &[f32]| {
            yarn.iter().map(|&i| (0..3).map(|c| img[3 * i + c] as f64).sum::<f64>()).sum::<f64>()
        };
        // Per pixel: how far the rotation moves the frame against what the sky adds.
        let dist = |a: &[f32], b: &[f32]| {
            yarn.iter()
                .map(|&i| {
                    (0..3).map(|c| (a[3 * i + c] as f64 - b[3 * i + c] as f64).powi(2)).sum::<f64>()
                })
                .sum::<f64>()
                .sqrt()
        };
        let (s_lit, s0, s1) = (sum(&lit), sum(&env0), sum(&env1));
        let (added, turned) = (dist(&env0, &lit), dist(&env1, &env0));
        eprintln!(
            "{method}, yarn region: directional {s_lit:.3}, + sky {s0:.3}, + sky rotated 120° \
             {s1:.3}; per pixel the rotation moves {:.3} of what the sky adds",
            turned / added
        );
        assert!(s0 > 1.01 * s_lit, "the sky adds light to the {method}: {s0} vs {s_lit}");
        // A constant ambient term would not move at all.
        assert!(
            turned > 0.05 * added,
            "rotating the sky changes the {method}: {turned} vs {added}"
        );
    }
}

/// The same swatch with `method = "lumislice"`: the yarn volumes are drawn over the floor
/// (the yarn region differs from the floor alone), turning the light changes them, and
/// `btf view` draws them too (its turntable's first frame is `btf render`'s).
#[test]
fn the_knit_swatch_renders_as_lumislices() {
    let d = Dir::new();
    example(&d);
    let text = std::fs::read_to_string(d.path("knit-swatch.toml")).unwrap();
    let ls = text.replacen("method = \"fibers\"", "method = \"lumislice\"", 1);
    assert_ne!(ls, text);
    std::fs::write(d.path("ls.toml"), &ls).unwrap();
    let turned = ls.replacen("direction = [0.4, 1.0, 0.5]", "direction = [-1.0, 0.2, 0.4]", 1);
    assert_ne!(turned, ls);
    std::fs::write(d.path("ls-turned.toml"), &turned).unwrap();
    let no_yarns = text[..text.find("\n[[yarns]]").unwrap()].to_string()
        + "\n"
        + &text[text.find("\n[camera]").unwrap()..];
    std::fs::write(d.path("floor.toml"), no_yarns).unwrap();
    let render = |scene: &str, exr: &str| -> Option<Vec<f32>> {
        let o = d.btf(&[
            "render",
            scene,
            "--width",
            "40",
            "--height",
            "40",
            "-o",
            &format!("{exr}.png"),
            "--exr",
            exr,
        ]);
        if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
            assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
            return None;
        }
        assert!(o.status.success(), "{scene}: {}", String::from_utf8_lossy(&o.stderr));
        Some(read_exr(&d.path(exr)).2)
    };
    let Some(floor) = render("floor.toml", "floor.exr") else { return };
    let lit = render("ls.toml", "ls.exr").unwrap();
    let turned = render("ls-turned.toml", "turned.exr").unwrap();
    let n = 40 * 40;
    let yarn: Vec<usize> = (0..n)
        .filter(|&i| (0..3).any(|c| (lit[3 * i + c] - floor[3 * i + c]).abs() > 1e-3))
        .collect();
    assert!(yarn.len() > n / 10, "the lumislices cover part of the frame: {}", yarn.len());
    assert!(lit.iter().all(|v| v.is_finite()));
    let diff = yarn
        .iter()
        .filter(|&&i| (0..3).any(|c| (lit[3 * i + c] - turned[3 * i + c]).abs() > 1e-3))
        .count();
    assert!(diff * 2 > yarn.len(), "the light moves over the yarns: {diff} of {}", yarn.len());
    // In `btf view` (a headless turntable: camera and lights orbit together) the first frame
    // is `btf render`'s, and the half turn shows the swatch from behind.
    let o = d.btf(&[
        "view",
        "ls.toml",
        "--turntable",
        "2",
        "--width",
        "40",
        "--height",
        "40",
        "-o",
        "tt",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = |f: &str| image::open(d.path(f)).unwrap().to_rgb8().into_raw();
    let (rendered, front, back) =
        (png("ls.exr.png"), png("tt/turntable-0000.png"), png("tt/turntable-0001.png"));
    let rel = |a: &[u8], b: &[u8]| {
        let d2: f64 = a.iter().zip(b).map(|(x, y)| (*x as f64 - *y as f64).powi(2)).sum();
        let a2: f64 = a.iter().map(|x| (*x as f64).powi(2)).sum();
        (d2 / a2.max(1.0)).sqrt()
    };
    let (same, turned) = (rel(&rendered, &front), rel(&rendered, &back));
    eprintln!("btf view turntable vs btf render: frame 0 {same:.2e}, half turn {turned:.3}");
    assert!(same <= 1e-3, "turntable frame 0 against btf render: rel. RMSE {same:.2e}");
    assert!(turned > 0.05, "the half turn shows another side: rel. RMSE {turned:.3}");
}

/// The knit swatch with its fiber-level yarns (`method = "fibers"`) in `btf view`: the
/// headless turntable's first frame is `btf render`'s (camera and lights orbit together,
/// so frame 0 is the scene itself), and the quarter turn shows the swatch and its yarns
/// from the side.
#[test]
fn the_knit_swatch_turns_in_btf_view() {
    let d = Dir::new();
    example(&d);
    let size = "48";
    let o =
        d.btf(&["render", "knit-swatch.toml", "--width", size, "--height", size, "-o", "r.png"]);
    if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
        return;
    }
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let args = ["view", "knit-swatch.toml", "--turntable", "4", "--width", size, "--height", size];
    let o = d.btf(&[&args[..], &["-o", "tt"]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = |f: &str| image::open(d.path(f)).unwrap().to_rgb8().into_raw();
    let rel = |a: &[u8], b: &[u8]| {
        let d2: f64 = a.iter().zip(b).map(|(x, y)| (*x as f64 - *y as f64).powi(2)).sum();
        let a2: f64 = a.iter().map(|x| (*x as f64).powi(2)).sum();
        (d2 / a2.max(1.0)).sqrt()
    };
    let rendered = png("r.png");
    let (same, quarter) = (
        rel(&rendered, &png("tt/turntable-0000.png")),
        rel(&rendered, &png("tt/turntable-0001.png")),
    );
    eprintln!(
        "knit swatch in btf view: frame 0 against btf render {same:.2e}, quarter turn {quarter:.3}"
    );
    assert!(same <= 1e-3, "turntable frame 0 against btf render: rel. RMSE {same:.2e}");
    assert!(quarter > 0.05, "the quarter turn shows another side: rel. RMSE {quarter:.3}");
}

#[test]
fn bad_yarns_entries_are_refused_by_the_binary_naming_the_key() {
    let d = Dir::new();
    for f in ["knit-swatch.toml", "plane.obj", "swatch.obj"] {
        std::fs::copy(Path::new(EXAMPLES).join(f), d.path(f)).unwrap();
    }
    let text = std::fs::read_to_string(d.path("knit-swatch.toml")).unwrap();
    let cases = [
        ("yarn = \"cotton-2ply\"", "yarn = \"silk-9ply\"", vec!["yarns[0].yarn", "silk-9ply"]),
        ("chart = \"rib2x2\"", "chart = \"argyle\"", vec!["yarns[0].chart", "argyle"]),
        ("method = \"fibers\"", "method = \"slices\"", vec!["slices"]),
        ("wales = 8", "wales = 0", vec!["yarns[0].wales"]),
        (
            "wales = 8\ncourses = 8",
            "wales = 4096\ncourses = 4096",
            vec!["yarns[0].wales", "stitches"],
        ),
        (
            "uv_origin = [0.05, 0.1]",
            "uv_origin = [0.5, 0.1]",
            vec!["yarns[0].uv_origin", "stitch cell (course 0, wale", "uv (", "no preimage"],
        ),
        ("mesh = \"swatch.obj\"", "mesh = \"gone.obj\"", vec!["yarns[0].mesh", "gone.obj"]),
    ];
    for (from, to, wanted) in cases {
        assert!(text.contains(from), "{from}");
        std::fs::write(d.path("bad.toml"), text.replace(from, to)).unwrap();
        let err = d.fails(&["render", "bad.toml", "-o", "bad.png"]);
        for w in wanted {
            assert!(err.contains(w), "{to}: '{w}' not in: {err}");
        }
        assert!(!d.path("bad.png").exists(), "{to}: an image was written");
    }
    // Lumislices blend into 4× MSAA targets: a scene without MSAA is refused by name.
    let ls = text.replacen("method = \"fibers\"", "method = \"lumislice\"", 1).replacen(
        "[effects]\n",
        "[effects]\nmsaa = 1\n",
        1,
    );
    std::fs::write(d.path("bad.toml"), ls).unwrap();
    let err = d.fails(&["render", "bad.toml", "-o", "bad.png"]);
    assert!(err.contains("yarns[0].method = \"lumislice\"") && err.contains("msaa = 1"), "{err}");
}

#[test]
fn btf_relight_draws_the_yarns_in_every_rotation() {
    let d = Dir::new();
    example(&d);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "32", "-o", "sky.exr"]);
    let text = std::fs::read_to_string(d.path("knit-swatch.toml")).unwrap();
    let start = text.find("\n[[yarns]]\n").unwrap();
    let end = text.find("\n[camera]\n").unwrap();
    let bare = format!("{}{}", &text[..start], &text[end..]);
    std::fs::write(d.path("bare.toml"), bare).unwrap();
    let mut frames = Vec::new();
    for (scene, out) in [("knit-swatch.toml", "with"), ("bare.toml", "without")] {
        let o = d.btf(&[
            "relight",
            scene,
            "--env",
            "sky.exr",
            "--rotations",
            "2",
            "--width",
            "32",
            "--height",
            "32",
            "--exr",
            "-o",
            out,
        ]);
        if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
            assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
            return;
        }
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for r in 0..2 {
            frames.push(read_exr(&d.path(&format!("{out}/sky_r00{r}.exr"))).2);
        }
    }
    let n = 32 * 32;
    for r in 0..2 {
        let (with, without) = (&frames[r], &frames[2 + r]);
        let yarn =
            (0..n).filter(|&i| (0..3).any(|c| with[3 * i + c] != without[3 * i + c])).count();
        let finite = with.iter().all(|v| v.is_finite());
        eprintln!("rotation {r}: {yarn} of {n} pixels differ from the scene without [[yarns]]");
        assert!(finite);
        // The swatch covers about a tenth of the frame at 64² (799 of 4096 pixels touched).
        assert!(yarn > n / 20 && yarn < n / 2, "{yarn}");
    }
    // The yarns turn with the environment (its SRBF lobes rotate; a constant ambient
    // term would not): their pixels change between the two rotations.
    let yarn: Vec<usize> =
        (0..n).filter(|&i| (0..3).any(|c| frames[0][3 * i + c] != frames[2][3 * i + c])).collect();
    let moved = |a: &[f32], b: &[f32]| {
        yarn.iter()
            .map(|&i| (0..3).map(|c| (a[3 * i + c] - b[3 * i + c]).abs() as f64).sum::<f64>())
            .sum::<f64>()
    };
    let total: f64 =
        yarn.iter().map(|&i| (0..3).map(|c| frames[0][3 * i + c].abs() as f64).sum::<f64>()).sum();
    let turned = moved(&frames[0], &frames[1]) / total;
    eprintln!("the yarn pixels change by {turned:.3} (mean relative) between the two rotations");
    assert!(turned > 0.01, "the yarns did not turn with the sky: {turned}");
}

/// A scene of `[[yarns]]` alone (no BTF meshes or materials): the binary draws the yarns
/// over the background as the standalone fiber renderer does; an environment light there
/// is refused naming the light (its visibility lives on BTF meshes).
#[test]
fn a_scene_of_yarns_alone_renders_its_yarns_over_the_background() {
    let d = Dir::new();
    std::fs::copy(Path::new(EXAMPLES).join("swatch.obj"), d.path("swatch.obj")).unwrap();
    let text = std::fs::read_to_string(Path::new(EXAMPLES).join("knit-swatch.toml")).unwrap();
    let alone = text[..text.find("\n[[meshes]]").unwrap()].to_string()
        + "\n"
        + &text[text.find("\n[[yarns]]").unwrap()..];
    std::fs::write(d.path("alone.toml"), &alone).unwrap();
    let size = SIZE.to_string();
    let o = d.btf(&[
        "render",
        "alone.toml",
        "--width",
        &size,
        "--height",
        &size,
        "-o",
        "a.png",
        "--exr",
        "a.exr",
    ]);
    if String::from_utf8_lossy(&o.stderr).contains("no GPU adapter") {
        assert!(std::env::var("BTF_REQUIRE_GPU").as_deref() != Ok("1"), "no GPU adapter");
        return;
    }
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, cli) = read_exr(&d.path("a.exr"));
    let Some(gpu) = Gpu::for_tests("a_scene_of_yarns_alone") else { return };
    let (scene, _, img) = standalone(&gpu, &d.path("alone.toml"));
    // Every pixel: the yarn's premultiplied radiance plus (1 − α) of the background, to the
    // f16 rounding of the frame (2⁻¹¹ of values below 2, two terms).
    let bg = scene.output.background;
    let n = (SIZE * SIZE) as usize;
    let mut worst = 0.0f64;
    for i in 0..n {
        for c in 0..3 {
            let want = img.pixels[i][c] as f64 + (1.0 - img.pixels[i][3] as f64) * bg[c] as f64;
            worst = worst.max((cli[3 * i + c] as f64 - want).abs());
        }
    }
    let covered = (0..n).filter(|&i| img.pixels[i][3] > 0.0).count();
    eprintln!("yarns alone: {covered} of {n} pixels with yarn, worst difference {worst:.2e}");
    assert!(covered > n / 10, "{covered}");
    assert!(worst < 2e-3, "{worst}");
    // An environment light needs BTF meshes: refused naming the light.
    d.ok(&["synth", "env", "--kind", "sky", "--width", "16", "-o", "sky.exr"]);
    let env = format!("{alone}\n[[lights]]\nkind = \"environment\"\npath = \"sky.exr\"\n");
    std::fs::write(d.path("alone-env.toml"), env).unwrap();
    let e = d.fails(&["render", "alone-env.toml", "-o", "e.png"]);
    assert!(e.contains("lights[1]") && e.contains("[[meshes]]"), "{e}");
    assert!(!d.path("e.png").exists());
    // So is relighting it by environment maps, before any output folder is made.
    let e = d.fails(&["relight", "alone.toml", "--env", "sky.exr", "--out", "rl"]);
    assert!(e.contains("[[yarns]] alone"), "{e}");
    assert!(!d.path("rl").exists());
    // Neither meshes nor yarns: the error names meshes.
    let empty = text[..text.find("\n[[meshes]]").unwrap()].to_string()
        + "\n"
        + &text[text.find("\n[camera]").unwrap()..];
    std::fs::write(d.path("empty.toml"), empty).unwrap();
    let e = d.fails(&["render", "empty.toml", "-o", "x.png"]);
    assert!(e.contains("meshes"), "{e}");
}
