//! End-to-end tests of `btf inspect`, `compress`, `reconstruct` and `export` on tiny stores.

use crate::common;
use common::*;
use serde_json::Value;

#[test]
fn inspect_reports_the_contract_keys() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    let v: Value = serde_json::from_str(&d.ok(&["inspect", "m.btf", "--json"])).unwrap();
    assert_eq!(v["kind"], "btf");
    assert_eq!(v["sampling"], "custom");
    assert_eq!((v["n_views"].as_u64(), v["n_lights"].as_u64()), (Some(7), Some(7)));
    assert_eq!((v["width"].as_u64(), v["height"].as_u64()), (Some(4), Some(4)));
    assert_eq!(v["dtype"], "f32");
    // 49 chunks of 4·4·3 floats plus a 4-byte checksum each.
    assert_eq!(v["bytes"].as_u64(), Some(49 * (48 * 4 + 4)));
    d.ok(&["compress", "m.btf", "-c", "3", "-o", "m.eig"]);
    let e: Value = serde_json::from_str(&d.ok(&["inspect", "m.eig", "--json"])).unwrap();
    assert_eq!(e["kind"], "eigen");
    assert_eq!(e["components"].as_u64(), Some(3));
    assert_eq!(e["dtype"], "f16");
}

#[test]
fn compress_json_satisfies_eckart_young_per_slot() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 6);
    let v: Value =
        serde_json::from_str(&d.ok(&["compress", "m.btf", "-c", "2", "-o", "m.eig", "--json"]))
            .unwrap();
    for key in
        ["components", "rel_rmse", "psnr_db", "seconds", "input_bytes", "output_bytes", "slots"]
    {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["components"].as_u64(), Some(2));
    let slots = v["slots"].as_array().unwrap();
    assert_eq!(slots.len(), 7);
    for s in slots {
        let (sse, disc) = (s["sse"].as_f64().unwrap(), s["discarded_eigen_sum"].as_f64().unwrap());
        assert!(disc > 0.0);
        assert!((sse - disc).abs() <= 1e-6 * disc, "slot {}: sse {sse} vs {disc}", s["view"]);
    }
    let rel = v["rel_rmse"].as_f64().unwrap();
    assert!(rel > 0.0 && rel < 0.2, "{rel}");
}

#[test]
fn f16_stores_get_the_f32_gram_by_default_within_its_bound() {
    // 32² (3072 values a row: three blocks of columns); the same values in f16 and f32.
    let d = Dir::new();
    write_test_btf_as(&d.path("h.btf"), 32, btf_core::zarr::DType::F16);
    let run = |store: &str, out: &str, gram: &str| -> Value {
        let args = ["compress", store, "-c", "3", "-o", out, "--json", "--gram", gram];
        serde_json::from_str(&d.ok(&args)).unwrap()
    };
    let auto = run("h.btf", "a.eig", "auto");
    let f64_ = run("h.btf", "b.eig", "f64");
    assert_eq!((auto["gram"].as_str(), f64_["gram"].as_str()), (Some("f32"), Some("f64")));
    let (sa, sb) = (auto["slots"].as_array().unwrap(), f64_["slots"].as_array().unwrap());
    let mut differs = false;
    for (a, b) in sa.iter().zip(sb) {
        let f = |s: &Value, k: &str| s[k].as_f64().unwrap();
        // 4 discarded eigenvalues of 7 images, each within ε·tr(YYᵀ) ≤ ε·16·energy
        // (‖x_i − x₀‖² ≤ 2‖x_i‖² + 2‖x₀‖²).
        let slack = 4.0 * btf_core::pca::GRAM32_EPS * 16.0 * f(b, "energy");
        let (x, y) = (f(a, "discarded_eigen_sum"), f(b, "discarded_eigen_sum"));
        assert!((x - y).abs() <= slack, "slot {}: {x} vs {y} (slack {slack})", a["view"]);
        assert_eq!(f(a, "energy"), f(b, "energy"));
        differs |= x != y;
    }
    assert!(differs, "the f32 lanes rounded nowhere: the bound was not tested");
    let err = d.fails(&["compress", "h.btf", "-o", "x.eig", "--gram", "f128"]);
    assert!(err.contains("invalid value 'f128'") && err.contains("f64"), "{err}");
}

#[test]
fn eigen_stores_written_raw_hold_the_same_values() {
    // `--codec none` changes how the means and eigentextures are chunked, nothing computed.
    let d = Dir::new();
    write_test_btf_as(&d.path("h.btf"), 32, btf_core::zarr::DType::F16);
    let run = |out: &str, codec: &[&str]| -> Value {
        let mut args = vec!["compress", "h.btf", "-c", "3", "-o", out, "--json"];
        args.extend_from_slice(codec);
        serde_json::from_str(&d.ok(&args)).unwrap()
    };
    let (packed, raw) = (run("a.eig", &[]), run("b.eig", &["--codec", "none"]));
    assert_eq!(packed["rel_rmse"], raw["rel_rmse"]);
    assert_eq!(packed["slots"].as_array().unwrap().len(), 7);
    for (x, y) in packed["slots"].as_array().unwrap().iter().zip(raw["slots"].as_array().unwrap()) {
        assert_eq!((&x["sse_stored"], &x["sse"]), (&y["sse_stored"], &y["sse"]));
    }
    for array in ["mean", "eigentextures", "weights"] {
        let codecs = |store: &str| {
            std::fs::read_to_string(d.path(store).join(array).join("zarr.json")).unwrap()
        };
        // The bulk arrays raw (bytes and the checksum only); the small ones as always.
        assert!(codecs("a.eig").contains("\"blosc\""), "{array}");
        assert_eq!(codecs("b.eig").contains("\"blosc\""), array == "weights", "{array}");
    }
    let (a, b) = (
        btf_core::eigen::EigenStore::open(&d.path("a.eig")).unwrap(),
        btf_core::eigen::EigenStore::open(&d.path("b.eig")).unwrap(),
    );
    for v in 0..7 {
        let (sa, sb) = (a.read_slot(v).unwrap(), b.read_slot(v).unwrap());
        assert_eq!((sa.mean, sa.basis, sa.weights), (sb.mean, sb.basis, sb.weights), "slot {v}");
    }
    // The binary reads it back like any other.
    for store in ["a.eig", "b.eig"] {
        let out = format!("{store}.exr");
        d.ok(&["reconstruct", store, "--view", "0,0", "--light", "30,0", "-o", &out]);
    }
    assert_eq!(
        std::fs::read(d.path("a.eig.exr")).unwrap(),
        std::fs::read(d.path("b.eig.exr")).unwrap()
    );
    let err = d.fails(&["compress", "h.btf", "-o", "x.eig", "--codec", "lz4"]);
    assert!(err.contains("invalid value 'lz4'") && err.contains("none"), "{err}");
    let err = d.fails(&["compress", "h.btf", "--sweep", "1,2", "--report", "r", "--codec", "none"]);
    assert!(err.contains("--codec") && err.contains("--sweep"), "{err}");
    assert!(!d.path("r").exists());
}

#[test]
fn too_many_components_are_clamped_with_a_warning() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    let o = d.btf(&["compress", "m.btf", "-c", "16", "-o", "m.eig", "--json"]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("at most 6"), "{err}");
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["components"].as_u64(), Some(6));
    // All 6 components of 7 images: lossless up to f16 storage.
    assert!(v["rel_rmse"].as_f64().unwrap() < 1e-3);
}

#[test]
fn reconstruct_at_a_sample_direction_gives_the_normtexture() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 5);
    d.ok(&["compress", "m.btf", "-c", "6", "-o", "m.eig"]);
    // View slot 3 = (40°, 120°); light 5 = (40°, 240°).
    let out = d.ok(&[
        "reconstruct",
        "m.eig",
        "--view",
        "40,120",
        "--light",
        "40,240",
        "-o",
        "t.exr",
        "--png",
        "t.png",
    ]);
    // One line says what was written where.
    assert_eq!(out.lines().count(), 1, "{out}");
    assert!(out.contains("5×5") && out.contains("t.exr") && out.contains("t.png"), "{out}");
    let (w, h, px) = read_exr(&d.path("t.exr"));
    assert_eq!((w, h), (5, 5));
    let expect: Vec<f32> = (0..75).map(|t| value(3, 5, t)).collect();
    let rel = btf_core::metrics::rel_rmse(&expect, &px);
    assert!(rel < 1e-3, "relative RMSE {rel}");
    assert!(d.path("t.png").exists());
    // Halfway between two lights of the ring: the mean of the two images.
    d.ok(&["reconstruct", "m.eig", "--view", "40,120", "--light", "40,270", "-o", "u.exr"]);
    let (_, _, mid) = read_exr(&d.path("u.exr"));
    let expect: Vec<f32> = (0..75).map(|t| 0.5 * (value(3, 5, t) + value(3, 6, t))).collect();
    assert!(btf_core::metrics::rel_rmse(&expect, &mid) < 1e-3);
}

#[test]
fn reconstruct_refuses_what_the_store_did_not_measure_unless_clamped() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 5);
    d.ok(&["compress", "m.btf", "-c", "6", "-o", "m.eig"]);
    // Below the horizon: refused, the angle named, nothing written.
    let err = d.fails(&["reconstruct", "m.eig", "--view", "0,0", "--light", "95,0", "-o", "z.exr"]);
    assert!(err.contains("--light θ = 95°") && err.contains("below the horizon"), "{err}");
    let err = d.fails(&["reconstruct", "m.eig", "--view", "91,0", "--light", "0,0", "-o", "z.exr"]);
    assert!(err.contains("--view θ = 91°"), "{err}");
    // Beyond the sampled range (the rings stop at 40°): refused, with the range and the way out.
    let err =
        d.fails(&["reconstruct", "m.eig", "--view", "40,120", "--light", "60,240", "-o", "z.exr"]);
    assert!(err.contains("θ = 60°") && err.contains("up to θ = 40°") && err.contains("--clamp"));
    assert!(!d.path("z.exr").exists());
    // --clamp: exactly the texture at the largest sampled θ (same φ), with a warning.
    let o = d.btf(&[
        "reconstruct",
        "m.eig",
        "--view",
        "40,120",
        "--light",
        "60,240",
        "--clamp",
        "-o",
        "c.exr",
    ]);
    assert!(o.status.success());
    let warning = String::from_utf8_lossy(&o.stderr);
    assert!(warning.contains("θ = 60°") && warning.contains("clamped to θ = 40°"), "{warning}");
    d.ok(&["reconstruct", "m.eig", "--view", "40,120", "--light", "40,240", "-o", "t.exr"]);
    assert_eq!(read_exr(&d.path("c.exr")).2, read_exr(&d.path("t.exr")).2);
}

#[test]
fn closed_choices_list_their_values_and_old_spellings_still_work() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    for (args, value) in [
        (&["compress", "m.btf", "-o", "x.eig", "--quantization", "f8"][..], "f8"),
        (&["export", "m.btf", "--format", "png", "-o", "x"][..], "png"),
        (&["synth", "material", "--kind", "velvet", "-o", "v.btf"][..], "velvet"),
        (
            &[
                "reconstruct",
                "m.eig",
                "--view",
                "0,0",
                "--light",
                "0,0",
                "--blend",
                "six",
                "-o",
                "x.exr",
            ][..],
            "six",
        ),
    ] {
        let err = d.fails(args);
        assert!(
            err.contains(&format!("invalid value '{value}'")) && err.contains("possible values"),
            "btf {args:?}: {err}"
        );
    }
    // Hidden aliases: --quantize and --output (the old spellings).
    d.ok(&["compress", "m.btf", "-c", "2", "--quantize", "u8", "--output", "m.eig"]);
    let e: Value = serde_json::from_str(&d.ok(&["inspect", "m.eig", "--json"])).unwrap();
    assert_eq!(e["dtype"], "u8");
}

#[test]
fn export_says_what_it_wrote_where() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    d.ok(&["compress", "m.btf", "-c", "3", "-o", "m.eig"]);
    let out = d.ok(&["export", "m.btf", "--format", "npy", "--slot", "2", "-o", "s.npy"]);
    assert!(out.contains("view slot 2") && out.contains("7 lights × 48 values"), "{out}");
    assert!(out.contains("s.npy"), "{out}");
    let out = d.ok(&["export", "m.eig", "--format", "exr", "--slot", "1", "-o", "s.exr"]);
    assert!(out.contains("mean + 3 eigentextures") && out.contains("s.exr"), "{out}");
    let out = d.ok(&["export", "m.eig", "--format", "pvf", "-o", "m.pvf"]);
    assert!(out.contains("7 view slots × 3 components") && out.contains("m.pvf"), "{out}");
    // exr without --slot: clap names the missing option.
    let err = d.fails(&["export", "m.eig", "--format", "exr", "-o", "t.exr"]);
    assert!(err.contains("--slot"), "{err}");
}

#[test]
fn export_npy_matches_the_store() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    d.ok(&["export", "m.btf", "--slot", "2", "--format", "npy", "-o", "s.npy"]);
    let bytes = std::fs::read(d.path("s.npy")).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(header.contains("'shape': (7, 48)") && header.contains("'<f4'"), "{header}");
    assert_eq!((10 + hlen) % 64, 0);
    let data: Vec<f32> = bytes[10 + hlen..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(data.len(), 7 * 48);
    assert_eq!(data[4 * 48 + 10], value(2, 4, 10));
    let err = d.fails(&["export", "m.btf", "--slot", "7", "-o", "x.npy"]);
    assert!(err.contains("out of range"), "{err}");
}

#[test]
fn corrupt_input_is_named_and_leaves_no_output() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    let chunk = d.path("m.btf/normtextures/c.4.2.0.0.0");
    let mut b = std::fs::read(&chunk).unwrap();
    b[17] ^= 0x40;
    std::fs::write(&chunk, &b).unwrap();
    let err = d.fails(&["compress", "m.btf", "-c", "2", "-o", "m.eig"]);
    assert!(
        err.contains("view slot 4, light 2")
            && err.contains("checksum")
            && err.contains("c.4.2.0.0.0"),
        "{err}"
    );
    assert!(!d.path("m.eig").exists());
    // A NaN with a valid checksum, in the store's codec (blosc, then crc32c over the
    // frame): refused, slot and light named.
    let mut raw = vec![0u8; 48 * 4];
    raw[..4].copy_from_slice(&f32::NAN.to_le_bytes());
    let settings =
        btf_core::blosc::Settings { clevel: 1, shuffle: true, blocksize: 0, split: false };
    let mut with_crc = btf_core::blosc::encode(&raw, 4, &settings).unwrap();
    with_crc.extend_from_slice(&crc32c::crc32c(&with_crc).to_le_bytes());
    std::fs::write(&chunk, &with_crc).unwrap();
    let err = d.fails(&["compress", "m.btf", "-c", "2", "-o", "m.eig"]);
    assert!(err.contains("view slot 4, light 2") && err.contains("non-finite"), "{err}");
    assert!(!d.path("m.eig").exists());
}

#[test]
fn interrupted_compression_resumes_and_keeps_previous_output() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 4);
    d.ok(&["compress", "m.btf", "-c", "2", "-o", "m.eig"]);
    let before = std::fs::read(d.path("m.eig/eigentextures/c.0.0.0.0.0")).unwrap();
    // Simulate an interruption: a second run to the same output whose partial store has
    // only some slots (copy the finished store's arrays, drop slots 3..7). A partial
    // records the job that began it from the first instant, as a killed run leaves it.
    let partial = d.path("m.eig.partial");
    copy_dir(&d.path("m.eig"), &partial);
    // The record `compress -c 2` writes: the eigen store's metadata and the input's identity.
    let btf = btf_core::store::BtfStore::open(&d.path("m.btf")).unwrap().meta().clone();
    let meta = btf_core::eigen::EigenMeta {
        btf,
        components: 2,
        quantization: btf_core::eigen::Quantization::F16,
    };
    let input = btf_core::fs::input_identity(&d.path("m.btf"));
    let record = serde_json::json!({ "store": "eigen", "meta": meta, "job": { "input": input } });
    btf_core::zarr::write_group(&partial, &serde_json::json!({ "partial_job": record })).unwrap();
    for v in 3..7 {
        std::fs::remove_file(partial.join(format!("eigenvalues/c.{v}.0"))).unwrap();
    }
    assert!(!std::fs::read_to_string(d.path("m.eig/zarr.json")).unwrap().is_empty());
    let v: Value = serde_json::from_str(
        &d.ok(&["compress", "m.btf", "-c", "2", "-o", "m.eig", "--resume", "--json"]),
    )
    .unwrap();
    assert_eq!(v["resumed_slots"].as_u64(), Some(3));
    assert!(!partial.exists());
    assert_eq!(std::fs::read(d.path("m.eig/eigentextures/c.0.0.0.0.0")).unwrap(), before);
}

fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let t = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), t).unwrap();
        }
    }
}

#[test]
fn sweep_writes_tables_and_pictures_with_falling_error() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 6);
    d.ok(&["compress", "m.btf", "--sweep", "1,2,4,6", "--report", "rep"]);
    for f in [
        "report.md",
        "sweep.csv",
        "sweep.md",
        "error.png",
        "accuracy_vs_time.png",
        "size_time.png",
        "eigenvalues.png",
        "heatmaps.png",
        "reconstructions.png",
    ] {
        assert!(d.path("rep").join(f).exists(), "missing {f}");
    }
    let csv = std::fs::read_to_string(d.path("rep/sweep.csv")).unwrap();
    let errs: Vec<f64> =
        csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap().parse().unwrap()).collect();
    assert_eq!(errs.len(), 4);
    assert!(errs.windows(2).all(|w| w[1] < w[0]), "{errs:?}");
    assert!(errs[3] < 1e-3);
    let img = image::open(d.path("rep/heatmaps.png")).unwrap().to_rgb8();
    // The first panel compares the original with itself: pure green.
    assert_eq!(img.get_pixel(2, 2).0, [0, 255, 0]);
}

#[test]
fn missing_and_wrong_kind_inputs_give_clear_errors() {
    let d = Dir::new();
    let err = d.fails(&["inspect", "nope.btf"]);
    assert!(err.contains("nope.btf"), "{err}");
    write_test_btf(&d.path("m.btf"), 4);
    let err = d.fails(&["reconstruct", "m.btf", "--view", "0,0", "--light", "0,0", "-o", "x.exr"]);
    assert!(err.contains("not an eigen store"), "{err}");
    let err = d.fails(&["compress", "m.btf", "-o", "x.eig", "--quantization", "f8"]);
    assert!(err.contains("f8"), "{err}");
}

/// A `BTF_SIMD` that names no path, or one this CPU cannot run, is refused before any work
/// with the variable named — never a panic inside a kernel.
#[test]
fn a_bad_btf_simd_is_refused_up_front() {
    let d = Dir::new();
    write_test_btf(&d.path("m.btf"), 2);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(["compress", "m.btf", "-c", "2", "-o", "m.eig"])
        .current_dir(d.tmp.path())
        .env("BTF_SIMD", "sse9")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("BTF_SIMD") && err.contains("sse9") && !err.contains("panicked"), "{err}");
    assert!(!d.path("m.eig").exists());
}
