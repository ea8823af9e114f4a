//! UBO2014 readers against hand-built byte fixtures: every signature, header version,
//! scalar size, matrix layout and DFMF colour model decodes to the known values, mapped
//! onto our sampling order; malformed files fail with errors naming the file and field.

mod fixtures;

use btf_capture::bonn::bytes::Limits;
use btf_capture::bonn::svd::decode_fmf;
use btf_capture::bonn::ubo2014::{Ubo2014, import_to_store, open_bytes, parse_all};
use btf_core::store::BtfStore;
use btf_core::zarr::DType;
use fixtures::*;

/// Writes `bytes` as a file, imports it, returns the store (and keeps the folder alive).
fn import(bytes: &[u8]) -> (tempfile::TempDir, BtfStore) {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("m.btf");
    std::fs::write(&src, bytes).unwrap();
    let out = dir.path().join("m.zarr");
    import_to_store(&src, &out, DType::F32, 1 << 20).unwrap();
    let s = BtfStore::open(&out).unwrap();
    (dir, s)
}

/// Largest |store − expected| over all values; `expected(c, l, v, t)` in file indices.
fn max_err(
    s: &BtfStore,
    cosine: bool,
    expected: &dyn Fn(usize, usize, usize, usize) -> f32,
) -> f32 {
    let mut worst = 0f32;
    for v in 0..NV {
        for l in 0..NL {
            let img = s.read_image(VIEW_OURS[v], LIGHT_OURS[l]).unwrap();
            let cos = if cosine { 1.0 } else { LIGHTS_DEG[l].0.to_radians().cos() };
            for t in 0..W * H {
                for c in 0..NC {
                    worst = worst.max((img[t * 3 + c] - cos * expected(c, l, v, t)).abs());
                }
            }
        }
    }
    worst
}

/// Largest |decoded − f| over all textures of an FMF file, in file order (no store).
fn fmf_decode_err(bytes: &[u8]) -> f32 {
    let src = open_bytes(bytes, "fmf", Limits::default()).unwrap();
    let Ubo2014::Fmf(h, payload, lay) = &src else { panic!("not FMF") };
    let mut img = vec![0f32; W * H * NC];
    let mut worst = 0f32;
    for v in 0..NV {
        for l in 0..NL {
            decode_fmf(h, payload, *lay, v, l, &mut img);
            for (i, x) in img.iter().enumerate() {
                worst = worst.max((x - f(i % NC, l, v, i / NC)).abs());
            }
        }
    }
    worst
}

#[test]
fn fmf_every_signature_version_size_and_layout() {
    let mut cases = 0;
    for (sig, hvs) in [("!FMF06FC", &[0u8][..]), ("!FMF06FCR", &[0]), ("!FMF12FCER", &[0, 1, 2])] {
        for &hv in hvs {
            // Through the store: every signature and header version, both layouts.
            for transposed in [false, true] {
                let (_d, s) = import(&fmf(sig, meta(4, &["R", "G", "B"]), 4, transposed, hv));
                assert!(max_err(&s, true, &|c, l, v, t| f(c, l, v, t)) < 1e-6, "{sig} hv {hv}");
            }
            // Decoded in memory: every scalar size.
            for size in [2u8, 4, 8] {
                for transposed in [false, true] {
                    let e =
                        fmf_decode_err(&fmf(sig, meta(4, &["R", "G", "B"]), size, transposed, hv));
                    assert!(e < 1e-6, "{sig} hv {hv} size {size} transposed {transposed}: {e}");
                    cases += 1;
                }
            }
        }
    }
    assert_eq!(cases, 30);
    // Every metadata version through the store; version 1 has no cosine flag, so
    // cos θ_light is multiplied in.
    for version in 1..=4 {
        let (_d, s) = import(&fmf("!FMF06FCR", meta(version, &["R", "G", "B"]), 4, false, 0));
        let e = max_err(&s, version > 1, &|c, l, v, t| f(c, l, v, t));
        assert!(e < 1e-6, "meta version {version}: {e}");
    }
}

#[test]
fn header_fields_xml_channels_rotations_and_height_map() {
    let bytes = fmf("!FMF12FCER", meta(4, &["R", "G", "B", "550nm", "650nm"]), 4, false, 2);
    let src = open_bytes(&bytes, "spectral.btf", Limits::default()).unwrap();
    let h = src.header();
    assert_eq!(h.meta.version, 4);
    assert_eq!(h.meta.channel_names, ["R", "G", "B", "550nm", "650nm"]);
    assert!(h.meta.xml.contains("<sample>wool</sample>"));
    assert_eq!(
        (h.meta.measurement_setup.as_str(), h.meta.ppmm, h.meta.rgb_scale),
        ("gonio", 12.5, [1.0, 0.9, 0.8])
    );
    assert_eq!(h.rotations.len(), 2);
    assert_eq!(h.rotations[1][8], 8.5);
    assert_eq!((h.width, h.height, h.views.len(), h.lights.len()), (3, 2, 4, 3));
    let Ubo2014::Fmf(_, payload, _) = &src else { panic!("not FMF") };
    assert_eq!(payload.header_version, 2);
    assert_eq!(payload.height_map.as_ref().map(|m| (m.0, m.1, m.2[5])), Some((2, 3, 2.5)));
    // Five channels decode, but our RGB stores refuse them with the channel names.
    assert_eq!(parse_all(&bytes).unwrap(), 3 * 2 * 5);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("spectral.btf");
    std::fs::write(&p, &bytes).unwrap();
    let e =
        import_to_store(&p, &dir.path().join("o"), DType::F32, 1 << 20).unwrap_err().to_string();
    assert!(e.contains("spectral.btf") && e.contains("550nm") && e.contains("5 channels"), "{e}");
    // Version-1 metadata: no cosine flag, XML or channel list.
    let v1_bytes = fmf("!FMF06FC", meta(1, &["R", "G", "B"]), 4, false, 0);
    let v1 = open_bytes(&v1_bytes, "v1", Limits::default()).unwrap();
    assert_eq!(
        (v1.header().meta.cosine_flag, v1.header().meta.xml.as_str(), v1.header().rotations.len()),
        (false, "", 0)
    );
}

#[test]
fn imported_sampling_is_recovered_and_ordered() {
    let (_d, s) = import(&fmf("!FMF06FCR", meta(4, &["R", "G", "B"]), 4, false, 0));
    let m = s.meta();
    assert_eq!(m.view_sampling.rings.len(), 2);
    assert_eq!((m.view_sampling.rings[1].theta_deg, m.view_sampling.rings[1].count), (40.0, 3));
    assert!((m.view_sampling.direction(2).phi_deg - 120.0).abs() < 1e-4);
    assert!((m.light_sampling.direction(2).phi_deg - 180.0).abs() < 1e-4);
    assert_eq!(m.provenance["format"], "!FMF06FCR");
}

/// Forward transforms (RGB → decorrelated) used to build the fixtures for each model.
fn forward(model: i32, rgb: [f32; 3], m: &[f32; 9], mean: [f32; 3]) -> [f32; 3] {
    let [r, g, b] = rgb;
    let yuv = |r: f32, g: f32, b: f32| {
        // Inverse of the reader's YUV→RGB matrix, solved in f64.
        let a = [[1.0f64, 0.0, 1.13983], [1.0, -0.39465, -0.5806], [1.0, 2.03211, 0.0]];
        solve3(a, [r as f64, g as f64, b as f64]).map(|x| x as f32)
    };
    let e = 1e-5f32;
    match model {
        0 => rgb,
        1 => yuv(r, g, b),
        3 => [0, 1, 2].map(|k| (0..3).map(|j| (rgb[j] - mean[j]) * m[k * 3 + j]).sum()),
        4 => [r / 4.0 + g / 2.0 + b / 4.0, r / 2.0 - b / 2.0, -r / 4.0 + g / 2.0 - b / 4.0],
        9 => {
            let [y, u, v] = yuv(r, g, b);
            [(y + e).ln(), u, v]
        }
        10 => {
            let [y, u, v] = yuv(r, g, b);
            let l = |x: f32| x.signum() * (x.abs().ln() - e.ln());
            [(y + e).ln(), l(u), l(v)]
        }
        11 => {
            let [y, u, v] = yuv(r, g, b);
            [(y + e).ln(), u / (y + e), v / (y + e)]
        }
        _ => [(r + e).ln(), (g + e).ln(), (b + e).ln()],
    }
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    [0, 1, 2].map(|k| {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        det(m) / d
    })
}

#[test]
fn dfmf_every_colour_model_returns_the_rgb() {
    // An orthonormal colour transform (rotation about the grey axis) and a mean.
    let (cs, sn) = (0.6f32, 0.8f32);
    let m = [cs, -sn, 0.0, sn, cs, 0.0, 0.0, 0.0, 1.0];
    let mean = [0.1, 0.2, 0.3];
    for model in [0, 1, 3, 4, 9, 10, 11, 12] {
        let g = |c: usize, l: usize, v: usize, t: usize| {
            forward(model, [0, 1, 2].map(|k| f(k, l, v, t)), &m, mean)[c]
        };
        let (_d, s) = import(&dfmf(model, mean, m, &g));
        let e = max_err(&s, true, &|c, l, v, t| f(c, l, v, t));
        assert!(e < 2e-5, "model {model}: max error {e}");
    }
}

#[test]
fn pvf_both_layouts_sizes_and_the_legacy_header() {
    for sig in ["!PVF06FC", "!PVF06FCR"] {
        for size in [2u8, 4, 8] {
            for eig in [true, false] {
                let (_d, s) = import(&pvf(sig, size, eig, false));
                let e = max_err(&s, true, &|c, l, v, t| f(c, l, v, t));
                assert!(e < 1e-6, "{sig} size {size} eigentextures {eig}: {e}");
            }
        }
        // Legacy: no metadata, so no cosine flag: cos θ_light is multiplied in.
        let (_d, s) = import(&pvf(sig, 4, true, true));
        assert!(max_err(&s, false, &|c, l, v, t| f(c, l, v, t)) < 1e-6);
    }
}

#[test]
fn bdi_full_and_sparse() {
    let (_d, s) = import(&bdi(false));
    assert_eq!(max_err(&s, true, &|c, l, v, t| f(c, l, v, t)), 0.0);
    let (_d, s) = import(&bdi(true));
    let e = max_err(&s, true, &|c, l, v, t| if t == 1 { 0.0 } else { f(c, l, v, t) });
    assert_eq!(e, 0.0);
}

fn all_fixtures() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("fmf", fmf("!FMF12FCER", meta(4, &["R", "G", "B"]), 2, false, 2)),
        ("fmf-t", fmf("!FMF06FCR", meta(3, &["R", "G", "B"]), 4, true, 0)),
        ("dfmf", dfmf(11, [0.0; 3], [0.0; 9], &|c, l, v, t| f(c, l, v, t) - 0.5)),
        ("pvf", pvf("!PVF06FCR", 2, true, false)),
        ("pvf-rows", pvf("!PVF06FC", 4, false, false)),
        ("pvf-legacy", pvf("!PVF06FC", 4, true, true)),
        ("bdi", bdi(true)),
    ]
}

#[test]
fn every_truncation_is_an_error_naming_the_field() {
    for (name, bytes) in all_fixtures() {
        assert!(parse_all(&bytes).is_ok(), "{name} parses whole");
        for cut in 0..bytes.len() {
            let e = parse_all(&bytes[..cut]).expect_err(name).to_string();
            assert!(e.starts_with("input: field '"), "{name} cut at {cut}: {e}");
        }
    }
}

#[test]
fn mutated_bytes_never_panic() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut ok, mut err) = (0, 0);
    for (_, bytes) in all_fixtures() {
        for _ in 0..3000 {
            let mut b = bytes.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % b.len() as u64) as usize;
                b[i] = next() as u8;
            }
            match parse_all(&b) {
                Ok(_) => ok += 1,
                Err(_) => err += 1,
            }
        }
    }
    assert_eq!(ok + err, 21_000);
    assert!(err > 1000, "mutations should mostly be caught: {ok} ok, {err} errors");
}

#[test]
fn lying_sizes_and_wrong_signatures_are_refused_before_allocating() {
    // 54 bytes whose XML length claims 4 GB.
    let mut b = b"!FMF06FC".to_vec();
    b.extend_from_slice(&300u32.to_le_bytes());
    b.extend_from_slice(&3u32.to_le_bytes());
    b.resize(54, 0);
    let mut m = meta(3, &["R", "G", "B"]);
    m.xml.clear();
    let mut good = Vec::new();
    btf_capture::bonn::header::write_meta(&mut good, &m).unwrap();
    let xml_at = 8 + good.len() - 4;
    let mut lying = b"!FMF06FC".to_vec();
    lying.extend_from_slice(&good);
    lying[xml_at..xml_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = parse_all(&lying).unwrap_err().to_string();
    assert!(e.contains("'meta.xml'") && e.contains("4294967295 bytes"), "{e}");
    let e = parse_all(&b).unwrap_err().to_string();
    assert!(
        e.contains("'meta.version'") && e.contains("not in 1..=4") || e.contains("meta."),
        "{e}"
    );
    // A view count of 2^32 − 1 in an otherwise valid header.
    let f0 = fmf("!FMF06FC", meta(4, &["R", "G", "B"]), 4, false, 0);
    let nv_at = 8 + u32::from_le_bytes(f0[8..12].try_into().unwrap()) as usize;
    let mut big = f0.clone();
    big[nv_at..nv_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = parse_all(&big).unwrap_err().to_string();
    assert!(e.contains("'num_views'"), "{e}");
    // A wrong declared metadata size.
    let mut ms = f0.clone();
    ms[9] ^= 2;
    let e = parse_all(&ms).unwrap_err().to_string();
    assert!(e.contains("'meta.size'"), "{e}");
    // Wrong signature, named with what was found.
    let e = parse_all(b"!XYZ06FC\0\0\0\0").unwrap_err().to_string();
    assert!(e.contains("'signature'") && e.contains("!XYZ06FC") && e.contains("!PVF06FC"), "{e}");
    // A file path appears in the error of a real file.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("carpet01.btf");
    std::fs::write(&p, &f0[..f0.len() - 3]).unwrap();
    let e =
        import_to_store(&p, &dir.path().join("o"), DType::F32, 1 << 20).unwrap_err().to_string();
    assert!(
        e.contains("carpet01.btf") && e.contains("'svd payload'") && e.contains("truncated"),
        "{e}"
    );
}

/// Writes the fixtures as seed corpora for the fuzz targets (`btf-capture/fuzz`): run with
/// `BTF_FUZZ_CORPUS=btf-capture/fuzz/corpus cargo test -p btf-capture --test ubo2014 --
/// --ignored write_fuzz_seeds`.
#[test]
#[ignore = "a tool, not a test: writes fuzz seed files when BTF_FUZZ_CORPUS is set"]
fn write_fuzz_seeds() {
    let root = std::path::PathBuf::from(std::env::var("BTF_FUZZ_CORPUS").expect("BTF_FUZZ_CORPUS"));
    let m = || meta(4, &["R", "G", "B"]);
    let seeds: Vec<(&str, u8, Vec<u8>)> = vec![
        ("fmf", 0, fmf("!FMF06FC", meta(1, &["R", "G", "B"]), 4, false, 0)),
        ("fmf", 1, fmf("!FMF06FCR", m(), 2, true, 0)),
        ("fmf", 2, fmf("!FMF12FCER", m(), 8, false, 2)),
        ("fmf", 2, fmf("!FMF12FCER", meta(4, &["R", "G", "B", "550nm"]), 4, true, 1)),
        ("dfmf", 0, dfmf(11, [0.0; 3], [0.0; 9], &|c, l, v, t| f(c, l, v, t) - 0.5)),
        (
            "dfmf",
            0,
            dfmf(3, [0.1; 3], [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &|c, l, v, t| {
                f(c, l, v, t)
            }),
        ),
        ("pvf", 0, pvf("!PVF06FC", 4, true, false)),
        ("pvf", 1, pvf("!PVF06FCR", 2, false, false)),
        ("pvf", 0, pvf("!PVF06FC", 4, true, true)),
        ("bdi", 0, bdi(true)),
        ("bdi", 0, bdi(false)),
    ];
    for (k, (target, pick, bytes)) in seeds.into_iter().enumerate() {
        let sig_len = [10usize, 9, 8].into_iter().find(|&n| {
            btf_capture::bonn::header::signature(std::str::from_utf8(&bytes[..n]).unwrap_or(""))
                .is_some()
        });
        let sig_len = sig_len.unwrap();
        let dir = root.join(target);
        std::fs::create_dir_all(&dir).unwrap();
        let mut seed = vec![pick];
        seed.extend_from_slice(&bytes[sig_len..]);
        std::fs::write(dir.join(format!("seed{k:02}")), seed).unwrap();
    }
    let names = root.join("ubo2003_name");
    std::fs::create_dir_all(&names).unwrap();
    std::fs::write(names.join("a"), "tv030_pv030/00008 tl000 pl000 tv030 pv030.jpg").unwrap();
    std::fs::write(names.join("b"), "WoolPKNT256_00084_tl015_pl000_tv015_pv120.jpg").unwrap();
}
