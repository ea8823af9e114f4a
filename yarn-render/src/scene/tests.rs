//! `[[yarns]]` built on the CPU: the default stitch size is the yarn's gauge on the
//! carrier's UV scale, and every bad entry is refused naming its key.

use super::*;

/// A 10 mm carrier plane (UV = position / 10 mm) and a BTF plane, in a temporary folder.
fn folder() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    let plane = "v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nv 0 0.01 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                 f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    std::fs::write(d.path().join("carrier.obj"), plane).unwrap();
    std::fs::write(d.path().join("bare.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
    d
}

const SCENE: &str = "[[meshes]]\npath = \"carrier.obj\"\n[[materials]]\nstore = \"m.eigen\"\n\
                     [camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\n[[yarns]]\n\
                     chart = \"stockinette\"\nmesh = \"carrier.obj\"\nuv_origin = [0.05, 0.1]\n\
                     wales = 2\ncourses = 2\n";

fn build_with(dir: &Path, extra: &str, replace: (&str, &str)) -> Result<Vec<SceneYarn>> {
    let text = format!("{SCENE}{extra}").replace(replace.0, replace.1);
    let path = dir.join("scene.toml");
    let scene = Scene::from_toml(&text, &path)?;
    build(&scene, &path)
}

#[test]
fn the_default_stitch_is_the_yarns_gauge_on_the_carriers_uv_scale() {
    let d = folder();
    let y = build_with(d.path(), "", ("", "")).unwrap();
    let r = y[0].params.yarn_radius();
    // 10 mm of surface per UV unit: a 9r × 8r stitch (the OBJ is f32: 1e-7 relative).
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    assert!(rel(y[0].stitch_uv[0], 9.0 * r / 0.01) < 1e-6, "{:?}", y[0].stitch_uv);
    assert!(rel(y[0].stitch_uv[1], 8.0 * r / 0.01) < 1e-6, "{:?}", y[0].stitch_uv);
    assert_eq!(y[0].set.curves.len(), 2, "one yarn per course");
    let (lo, hi) = y[0].bounds();
    assert!(lo[0] >= -0.002 && hi[0] <= 0.012 && lo[2] < 0.0 && hi[2] > 0.0, "{lo:?} {hi:?}");
    // The carrier may be a [[meshes]] path or any OBJ; a given stitch size is used as is.
    let y = build_with(d.path(), "stitch_uv = [0.3, 0.35]\n", ("", "")).unwrap();
    assert_eq!(y[0].stitch_uv, [0.3, 0.35]);
}

#[test]
fn bad_entries_are_refused_naming_the_key() {
    let d = folder();
    let zero = YarnParams {
        ply_center_distance: 0.0,
        ply_ellipse_n: 0.0,
        ply_ellipse_b: 0.0,
        ..YarnParams::preset("cotton-2ply").unwrap()
    };
    std::fs::write(d.path().join("zero.toml"), zero.to_toml().unwrap()).unwrap();
    let cases: [(&str, (&str, &str), &[&str]); 8] = [
        ("yarn = \"silk-9ply\"\n", ("", ""), &["yarns[0].yarn", "silk-9ply"]),
        ("yarn = \"zero.toml\"\n", ("", ""), &["yarns[0].yarn"]),
        ("", ("\"stockinette\"", "\"argyle\""), &["yarns[0].chart", "argyle"]),
        ("", ("\"stockinette\"", "\"none.chart\""), &["yarns[0].chart", "none.chart"]),
        (
            "",
            ("uv_origin = [0.05, 0.1]", "uv_origin = [0.7, 0.1]"),
            &["yarns[0].uv_origin", "stitch cell (course 0, wale 0)", "uv (1.085200, 0.100000)"],
        ),
        ("", ("mesh = \"carrier.obj\"", "mesh = \"gone.obj\""), &["yarns[0].mesh", "gone.obj"]),
        ("", ("mesh = \"carrier.obj\"", "mesh = \"bare.obj\""), &["yarns[0].mesh", "texture"]),
        ("stitch_uv = [0.1, 0]\n", ("", ""), &["yarns[0].stitch_uv"]),
    ];
    for (extra, replace, wanted) in cases {
        let e = build_with(d.path(), extra, replace).unwrap_err().to_string();
        for w in wanted {
            assert!(e.contains(w), "{extra}{replace:?}: '{w}' not in: {e}");
        }
    }
}

/// `hairs` of a `[[yarns]]` entry (default on) reaches the fiber renderer's settings.
#[test]
fn the_hairs_key_turns_the_fibers_hairs_on_and_off() {
    let d = folder();
    let path = d.path().join("scene.toml");
    for (extra, want) in [("", true), ("hairs = false\n", false), ("hairs = true\n", true)] {
        let scene = Scene::from_toml(&format!("{SCENE}{extra}"), &path).unwrap();
        let s = crate::scene::overlay::settings(&scene, &scene.yarns[0]);
        assert_eq!(s.hairs, want, "{extra:?}");
    }
}

/// `fiber_shadows` of a `[[yarns]]` entry (default off) reaches the fiber renderer's
/// effects; with strips or without shadows it is refused naming the key.
#[test]
fn the_fiber_shadows_key_reaches_the_effects_or_is_refused() {
    let d = folder();
    let path = d.path().join("scene.toml");
    for (extra, want) in [("", false), ("fiber_shadows = true\n", true)] {
        let scene = Scene::from_toml(&format!("{SCENE}{extra}"), &path).unwrap();
        let s = crate::scene::overlay::settings(&scene, &scene.yarns[0]);
        assert_eq!(s.effects.fiber_shadows, want, "{extra:?}");
    }
    for extra in
        ["fiber_shadows = true\nmethod = \"strips\"\n", "fiber_shadows = true\nshadows = false\n"]
    {
        let e = Scene::from_toml(&format!("{SCENE}{extra}"), &path).unwrap_err().to_string();
        assert!(e.contains("yarns[0].fiber_shadows"), "{extra:?}: {e}");
    }
}
