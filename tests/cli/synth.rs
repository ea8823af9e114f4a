//! End-to-end tests of `btf synth …` on tiny outputs: the binary writes what the library
//! promises and refuses bad arguments with a clear message.

use std::process::{Command, Output};

fn btf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .env("BTF_NO_PROGRESS", "1")
        .output()
        .expect("run btf")
}

fn ok(args: &[&str]) {
    let out = btf(args);
    assert!(out.status.success(), "btf {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn synth_material_writes_analytic_lambert_store_and_preview() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("l.btf");
    let preview = dir.path().join("gallery");
    let s = store.to_str().unwrap();
    ok(&[
        "synth",
        "material",
        "--kind",
        "lambert",
        "--size",
        "4",
        "--albedo",
        "0.8,0.4,0.2",
        "--preview",
        preview.to_str().unwrap(),
        "-o",
        s,
    ]);
    let st = btf_core::store::BtfStore::open(&store).unwrap();
    assert_eq!((st.meta().n_views(), st.meta().width), (81, 4));
    assert_eq!(st.meta().provenance["kind"], "lambert");
    // Light 7 is at θ = 30°: every value is ρ/π · cos 30° with ρ from the albedo pattern,
    // whose red/blue ratio is that of --albedo.
    let img = st.read_image(0, 7).unwrap();
    let cos = 30f64.to_radians().cos();
    for px in img.chunks_exact(3) {
        assert!((px[0] as f64 / px[2] as f64 - 4.0).abs() < 1e-4);
        assert!(px[0] as f64 <= 0.8 / std::f64::consts::PI * cos + 1e-6);
    }
    assert!(preview.join("lambert.png").is_file());
}

#[test]
fn synth_material_writes_raw_stores_that_compress_alike() {
    // `--codec none`: the same values in raw chunks (read in place by the compressor), so
    // both stores compress to the same eigen store.
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    for (out, codec) in [("b.btf", "blosc"), ("n.btf", "none")] {
        ok(&[
            "synth",
            "material",
            "--kind",
            "corduroy",
            "--size",
            "8",
            "--sampling",
            "rings:0x1,45x4",
            "--dtype",
            "f16",
            "--codec",
            codec,
            "-o",
            &p(out),
        ]);
    }
    let chain = |store: &str| {
        std::fs::read_to_string(dir.path().join(store).join("normtextures/zarr.json")).unwrap()
    };
    assert!(chain("b.btf").contains("\"blosc\"") && !chain("n.btf").contains("\"blosc\""));
    let (b, n) = (
        btf_core::store::BtfStore::open(&dir.path().join("b.btf")).unwrap(),
        btf_core::store::BtfStore::open(&dir.path().join("n.btf")).unwrap(),
    );
    assert!(b.map_slot(0).unwrap().is_none() && n.map_slot(0).unwrap().is_some());
    for v in 0..5 {
        assert_eq!(b.read_slot(v).unwrap().data, n.read_slot(v).unwrap().data, "slot {v}");
    }
    for s in ["b", "n"] {
        ok(&["compress", &p(&format!("{s}.btf")), "-c", "3", "-o", &p(&format!("{s}.eig"))]);
    }
    let (eb, en) = (
        btf_core::eigen::EigenStore::open(&dir.path().join("b.eig")).unwrap(),
        btf_core::eigen::EigenStore::open(&dir.path().join("n.eig")).unwrap(),
    );
    for v in 0..5 {
        let (x, y) = (eb.read_slot(v).unwrap(), en.read_slot(v).unwrap());
        assert_eq!((x.basis, x.weights), (y.basis, y.weights), "slot {v}");
    }
    let out = btf(&["synth", "material", "--kind", "yarn", "--codec", "none", "-o", &p("y.btf")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--codec") && err.contains("yarn"), "{err}");
}

#[test]
fn synth_env_and_mesh_write_loadable_files() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("sky.exr");
    ok(&[
        "synth",
        "env",
        "--kind",
        "sky",
        "--sun-elevation",
        "40",
        "--width",
        "128",
        "-o",
        exr.to_str().unwrap(),
    ]);
    let map = btf_image::EnvMap::load(&exr).unwrap();
    assert_eq!((map.width, map.height), (128, 64));
    let mut g: Vec<f32> = map.pixels.iter().map(|p| p[1]).collect();
    g.sort_by(f32::total_cmp);
    assert!(g[g.len() - 1] / g[g.len() / 2] > 1e3, "the sun stands out of the sky");
    let obj = dir.path().join("sphere.obj");
    ok(&["synth", "mesh", "--kind", "sphere", "-o", obj.to_str().unwrap()]);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.lines().filter(|l| l.starts_with("vt ")).count() > 800);
    // Written atomically: no temporary file is left beside the outputs.
    let names: Vec<_> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn synth_refuses_bad_arguments_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("x.btf");
    let out = btf(&["synth", "material", "--kind", "velvet", "-o", o.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("velvet") && err.contains("corduroy"), "{err}");
    let out = btf(&[
        "synth",
        "material",
        "--kind",
        "lambert",
        "--albedo",
        "2,0,0",
        "-o",
        o.to_str().unwrap(),
    ]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("[0, 1]"));
    let out = btf(&[
        "synth",
        "env",
        "--kind",
        "sky",
        "--turbidity",
        "40",
        "-o",
        dir.path().join("e.exr").to_str().unwrap(),
    ]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("turbidity"));
    assert!(!o.exists());
}
