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
    // EXR: one single-part file with every image as named channels, read the way a
    // single-part reader does (the first and only part), and the weights beside it.
    d.ok(&["export", "m.eigen", "--format", "exr", "--slot", "4", "-o", "slot4.exr"]);
    let img = exr::prelude::read_all_flat_layers_from_file(d.path("slot4.exr")).unwrap();
    assert_eq!(img.layer_data.len(), 1, "single part");
    let part = &img.layer_data[0];
    let channel = |name: &str| -> Vec<f32> {
        let c = part.channel_data.list.iter().find(|c| c.name.to_string() == name);
        let c = c.unwrap_or_else(|| panic!("no channel {name}"));
        let exr::prelude::FlatSamples::F32(v) = &c.sample_data else { panic!("f32 samples") };
        v.clone()
    };
    let mut names: Vec<String> =
        part.channel_data.list.iter().map(|c| c.name.to_string()).collect();
    names.sort();
    assert_eq!(names.len(), 3 * 4);
    assert!(names.contains(&"mean.R".into()) && names.contains(&"eigen02.B".into()));
    // Texel 5 (y=1, x=1 of 4×4) red is texel value 15 of the slot; eigentexture 2 blue is 17.
    assert_eq!(channel("mean.R")[5], s.mean[15]);
    assert_eq!(channel("eigen02.B")[5], s.basis_row(2)[17]);
    let npy = std::fs::read(d.path("slot4.weights.npy")).unwrap();
    let header = u16::from_le_bytes([npy[8], npy[9]]) as usize;
    assert!(String::from_utf8_lossy(&npy[10..10 + header]).contains("'shape': (7, 3)"));
    let w: Vec<f32> = npy[10 + header..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(w, s.weights, "weights [light][component]");
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

#[test]
fn ubo2003_export_is_8_bit_unless_16_is_asked_for_and_says_so() {
    // Pillow reads 16-bit RGB PNGs as 8 bit without a warning (issue #25): the default is
    // 8-bit sRGB, `--image png16` writes 16 bits, and the sidecar records which.
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    for (args, bits, color) in [
        (&[][..], 8, image::ColorType::Rgb8),
        (&["--image", "png16"][..], 16, image::ColorType::Rgb16),
    ] {
        let mut a = vec!["export", "m.btf", "--format", "ubo2003", "-o", "ex"];
        a.extend_from_slice(args);
        d.ok(&a);
        let side: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.path("ex/btf-export.json")).unwrap())
                .unwrap();
        assert_eq!(side["bits_per_channel"], bits);
        let png = std::fs::read_dir(d.path("ex/tv040_pv060")).unwrap().next().unwrap().unwrap();
        let img = image::open(png.path()).unwrap();
        assert_eq!(img.color(), color, "{args:?}");
    }
    // The 8-bit default round-trips within half an 8-bit code through the sRGB curve's
    // steepest decoding slope, times the scale.
    d.ok(&["export", "m.btf", "--format", "ubo2003", "-o", "ex8"]);
    d.ok(&["import", "ubo2003", "ex8", "-o", "back.btf"]);
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path("ex8/btf-export.json")).unwrap())
            .unwrap();
    let scale = side["scale"].as_f64().unwrap() as f32;
    let (a, b) =
        (BtfStore::open(&d.path("m.btf")).unwrap(), BtfStore::open(&d.path("back.btf")).unwrap());
    let bound = 0.5 / 255.0 * 2.4 / 1.055 * scale;
    let e = max_abs_diff(&a, &b);
    assert!(e <= bound, "{e} > {bound} (scale {scale})");
}
