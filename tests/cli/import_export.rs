//! End-to-end tests of `btf import` and `btf export --format ubo2003|pvf|exr` on tiny
//! stores: the round trips keep the values within each format's precision.

use crate::common;

use btf_core::eigen::EigenStore;
use btf_core::store::BtfStore;
use common::{Dir, write_test_btf};

fn max_abs_diff(a: &BtfStore, b: &BtfStore) -> f32 {
    let mut worst = 0f32;
    for v in 0..a.meta().n_views() {
        for l in 0..a.meta().n_lights() {
            let (x, y) = (a.read_image(v, l).unwrap(), b.read_image(v, l).unwrap());
            worst = x.iter().zip(&y).fold(worst, |m, (p, q)| m.max((p - q).abs()));
        }
    }
    worst
}

#[test]
fn ubo2003_folder_round_trip_within_16_bit_srgb_precision() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    d.ok(&[
        "export", "m.btf", "--format", "ubo2003", "--image", "png16", "--name", "Wool", "-o",
        "wool",
    ]);
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path("wool/btf-export.json")).unwrap())
            .unwrap();
    let scale = side["scale"].as_f64().unwrap() as f32;
    assert!(std::fs::read_dir(d.path("wool/tv040_pv060")).unwrap().count() == 7);
    let out = d.ok(&["import", "ubo2003", "wool", "-o", "back.btf"]);
    assert!(out.contains("imported 49 images"), "{out}");
    let (a, b) =
        (BtfStore::open(&d.path("m.btf")).unwrap(), BtfStore::open(&d.path("back.btf")).unwrap());
    assert_eq!(b.meta().view_sampling.rings, a.meta().view_sampling.rings);
    // Half a 16-bit code times the largest slope of the sRGB decoding curve, times the scale.
    let bound = 0.5 / 65535.0 * 2.4 / 1.055 * scale;
    let e = max_abs_diff(&a, &b);
    assert!(e <= bound && scale > 1.0, "{e} > {bound} (scale {scale})");
}

#[test]
fn pvf_round_trip_and_exr_layers() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    d.ok(&["compress", "m.btf", "-c", "3", "-o", "m.eigen"]);
    d.ok(&["export", "m.eigen", "--format", "pvf", "-o", "m_W4xH4_L7xV7.btf"]);
    let head = std::fs::read(d.path("m_W4xH4_L7xV7.btf")).unwrap();
    assert!(head.starts_with(b"!PVF06FC"));
    d.ok(&["import", "ubo2014", "m_W4xH4_L7xV7.btf", "--eigen", "-o", "back.eigen"]);
    let (a, b) = (
        EigenStore::open(&d.path("m.eigen")).unwrap(),
        EigenStore::open(&d.path("back.eigen")).unwrap(),
    );
    for v in 0..7 {
        let (x, y) = (a.read_slot(v).unwrap(), b.read_slot(v).unwrap());
        assert_eq!((x.mean, x.basis, x.weights), (y.mean, y.basis, y.weights), "slot {v}");
    }
    // Decoded into a BTF store, the PVF gives the 3-component reconstruction.
    d.ok(&["import", "ubo2014", "m_W4xH4_L7xV7.btf", "-o", "rec.btf"]);
    let rec = BtfStore::open(&d.path("rec.btf")).unwrap();
    let s = a.read_slot(4).unwrap();
    let img = rec.read_image(4, 5).unwrap();
    for (i, x) in img.iter().enumerate() {
        let want = s.mean[i] + (0..3).map(|k| s.weights_of(5)[k] * s.basis_row(k)[i]).sum::<f32>();
        assert!((x - want).abs() < 1e-6, "texel value {i}: {x} vs {want}");
    }
    // EXR: mean and eigentextures of one slot as layers.
    d.ok(&["export", "m.eigen", "--format", "exr", "--slot", "4", "-o", "slot4.exr"]);
    let img = exr::prelude::read_all_flat_layers_from_file(d.path("slot4.exr")).unwrap();
    let names: Vec<String> = img
        .layer_data
        .iter()
        .map(|l| l.attributes.layer_name.as_ref().unwrap().to_string())
        .collect();
    assert_eq!(names, ["mean", "eigen00", "eigen01", "eigen02"]);
    let red =
        img.layer_data[0].channel_data.list.iter().find(|c| c.name.to_string() == "R").unwrap();
    let exr::prelude::FlatSamples::F32(r) = &red.sample_data else { panic!("f32 samples") };
    assert_eq!(r[5], s.mean[15]);
}

#[test]
fn import_errors_name_the_file_and_field() {
    let d = Dir::new();
    std::fs::write(d.path("bad.btf"), b"!NOPE0000000000000000").unwrap();
    let e = d.fails(&["import", "ubo2014", "bad.btf", "-o", "x.btf"]);
    assert!(e.contains("bad.btf") && e.contains("'signature'"), "{e}");
    std::fs::create_dir(d.path("empty")).unwrap();
    let e = d.fails(&["import", "ubo2003", "empty", "-o", "x.btf"]);
    assert!(e.contains("no image files"), "{e}");
    write_test_btf(&d.path("m.btf"), 2);
    let e = d.fails(&["export", "m.btf", "--format", "pvf", "-o", "m.pvf"]);
    assert!(e.contains("eigen store"), "{e}");
    let e = d.fails(&["export", "m.btf", "--format", "npy", "-o", "m.npy"]);
    assert!(e.contains("--slot"), "{e}");
}

/// `btf import ubo2003` and `btf export --format ubo2003` draw a progress bar on a terminal
/// (a pseudo-terminal from `script`), and none under `BTF_NO_PROGRESS=1` or when standard
/// error is a pipe.
#[test]
fn ubo2003_import_and_export_show_progress_only_on_a_terminal() {
    if std::process::Command::new("script").arg("--version").output().is_err() {
        eprintln!("skipped: no `script` (util-linux) to make a terminal");
        return;
    }
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    let bin = env!("CARGO_BIN_EXE_btf");
    let on_terminal = |cmd: &str, quiet: bool| {
        let mut c = std::process::Command::new("script");
        c.args(["-qec", &format!("{bin} {cmd}"), "/dev/null"]).current_dir(d.tmp.path());
        c.env_remove("BTF_NO_PROGRESS");
        if quiet {
            c.env("BTF_NO_PROGRESS", "1");
        }
        let o = c.output().expect("script runs");
        assert!(o.status.success(), "{cmd}: {}", String::from_utf8_lossy(&o.stdout));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    // 7 views × 7 lights = 49 images: the bar counts them.
    let tty = on_terminal("export m.btf --format ubo2003 -o ex", false);
    assert!(tty.contains("export [") && tty.contains("/49"), "{tty}");
    let tty = on_terminal("import ubo2003 ex -o back.btf", false);
    assert!(tty.contains("import [") && tty.contains("/49"), "{tty}");
    let quiet = on_terminal("export m.btf --format ubo2003 -o ex", true);
    assert!(!quiet.contains("/49") && quiet.contains("wrote 49 images"), "{quiet}");
    // Standard error a pipe: no bar even without BTF_NO_PROGRESS.
    let o = std::process::Command::new(bin)
        .args(["import", "ubo2003", "ex", "-o", "back2.btf"])
        .current_dir(d.tmp.path())
        .env_remove("BTF_NO_PROGRESS")
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
}
