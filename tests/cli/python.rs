//! The stores as Python users meet them (issue #25): zarr-python ≥ 3 opens every store
//! kind under `python3 -W error` (no warning), and docs/stores_example.py — included
//! verbatim in docs/stores.md — rebuilds a texture from an eigen store that matches
//! `btf reconstruct` of the same view and light.
//!
//! Needs `python3` with `zarr` (v3) and `numpy`: without them the test fails when `CI` or
//! `BTF_REQUIRE_PYTHON` is set and is skipped with a printed reason otherwise.

use crate::common::{Dir, read_exr};
use std::path::Path;
use std::process::Command;

const EXAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/stores_example.py");

/// Why Python cannot run the example, if it cannot.
fn python_missing() -> Option<String> {
    let probe = Command::new("python3")
        .args(["-c", "import zarr, numpy; assert int(zarr.__version__.split('.')[0]) >= 3"])
        .output();
    match probe {
        Err(e) => Some(format!("python3 does not run: {e}")),
        Ok(o) if !o.status.success() => Some(format!(
            "python3 lacks zarr>=3 or numpy (python3 -m pip install 'zarr>=3,<4' numpy): {}",
            String::from_utf8_lossy(&o.stderr).lines().last().unwrap_or("")
        )),
        Ok(_) => None,
    }
}

fn python_or_skip() -> bool {
    let Some(why) = python_missing() else { return true };
    let required = std::env::var_os("CI").is_some()
        || std::env::var("BTF_REQUIRE_PYTHON").is_ok_and(|v| v == "1");
    assert!(!required, "{why} (CI or BTF_REQUIRE_PYTHON=1 is set)");
    eprintln!("skipped: {why}");
    false
}

fn python(dir: &Path, args: &[&str]) -> String {
    let o = Command::new("python3").arg("-W").arg("error").args(args).current_dir(dir).output();
    let o = o.expect("python3 runs");
    assert!(
        o.status.success(),
        "python3 -W error {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// Reads a little-endian float32 `.npy` (what `np.save` writes for `<f4`).
fn read_npy_f32(path: &Path) -> Vec<f32> {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..6], b"\x93NUMPY");
    let header_len = u16::from_le_bytes([b[8], b[9]]) as usize;
    let header = String::from_utf8_lossy(&b[10..10 + header_len]);
    assert!(header.contains("'<f4'") && header.contains("False"), "{header}");
    b[10 + header_len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn stores_md_includes_the_example_verbatim() {
    let md =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/stores.md")).unwrap();
    let script = std::fs::read_to_string(EXAMPLE).unwrap();
    assert!(
        md.contains(&format!("```python\n{script}```")),
        "docs/stores.md must hold docs/stores_example.py verbatim in a ```python block"
    );
}

#[test]
fn zarr_python_opens_every_store_and_the_example_matches_btf_reconstruct() {
    if !python_or_skip() {
        return;
    }
    let d = Dir::new();
    d.ok(&["synth", "material", "--kind", "lambert", "--size", "16", "-o", "m.btf"]);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "m.eig"]);
    d.ok(&["compress", "m.btf", "-c", "3", "--quantize", "u8", "-o", "u8.eig"]);
    // Every node of every store kind, walked by zarr-python with warnings as errors.
    let walk = "import sys, zarr\n\
        for p in sys.argv[1:]:\n\
        \x20   g = zarr.open_group(p, mode='r')\n\
        \x20   n = sum(1 for _ in g.members(max_depth=None))\n\
        \x20   print(p, n, g['view_theta_deg'].attrs['units'], g['light_phi_deg'].shape[0])\n";
    let out = python(d.tmp.path(), &["-c", walk, "m.btf", "m.eig", "u8.eig"]);
    // ubo81: 81 view slots and 81 lights, angles in degrees.
    assert!(out.contains("m.btf 5 degree 81"), "{out}");
    assert!(out.contains("m.eig ") && out.contains("u8.eig "), "{out}");
    // View slot 5 = (15°, 240°), light 40 = (60°, 54°) in ubo81 (DESIGN.md §3): measured
    // directions, so `btf reconstruct`'s four-nearest weights are 1 on that slot and light.
    for (store, view, light) in [("m.eig", "15,240", "60,54"), ("u8.eig", "15,240", "60,54")] {
        let out = python(d.tmp.path(), &[EXAMPLE, store, "5", "40", "py.npy", "m.btf"]);
        assert!(out.contains("view slot 5: theta=15 deg, phi=240 deg"), "{out}");
        assert!(out.contains("light 40: theta=60 deg, phi=54 deg"), "{out}");
        d.ok(&["reconstruct", store, "--view", view, "--light", light, "-o", "rust.exr"]);
        let (w, h, rust) = read_exr(&d.path("rust.exr"));
        let py = read_npy_f32(&d.path("py.npy"));
        assert_eq!((w, h, py.len()), (16, 16, rust.len()));
        // Same dequantised inputs on both sides (f16 · power-of-two scale is exact in f32;
        // u8 · scale + offset rounds once in f32), so the difference is f32 rounding of a
        // sum of c + 1 terms each at most the peak: ≤ (c + 2)·2⁻²⁴ of the peak, c ≤ 4.
        let peak = rust.iter().fold(0f32, |a, v| a.max(v.abs()));
        let tol = 6.0 * f32::EPSILON / 2.0 * peak * 4.0;
        for (i, (a, b)) in py.iter().zip(&rust).enumerate() {
            assert!((a - b).abs() <= tol, "{store} texel value {i}: python {a}, btf {b}");
        }
    }
}

/// The `blosc` codec both ways, bit for bit: chunks this toolkit writes (byte shuffle or
/// not, f16/f32/f64/u8, one block per chunk) read identically in zarr-python, and chunks
/// zarr-python writes through c-blosc (its automatic 32 KiB blocks, so a leftover block)
/// read identically here.
#[test]
fn zarr_python_and_the_toolkit_read_each_others_blosc_chunks_bit_identically() {
    use btf_core::zarr::{ArrayMeta, Compression, DType, Limits, ZarrArray};
    if !python_or_skip() {
        return;
    }
    let d = Dir::new();
    // Ours → zarr-python. Two chunks along the first axis; the bytes a smooth ramp with
    // noisy low bits, like the stores' data.
    let ours = [
        ("o16", DType::F16, Compression::DEFAULT),
        ("o32", DType::F32, Compression::Blosc { clevel: 5, shuffle: false }),
        ("o64", DType::F64, Compression::Blosc { clevel: 3, shuffle: true }),
        ("o8", DType::U8, Compression::Blosc { clevel: 1, shuffle: true }),
    ];
    let mut script = String::from("import sys, zarr\n");
    for (name, dtype, compression) in ours {
        let meta = ArrayMeta {
            compression,
            ..ArrayMeta::new(vec![2, 37, 41], vec![1, 37, 41], dtype, &["a", "b", "c"])
        };
        let a = ZarrArray::create(&d.path(name), meta).unwrap();
        let n = 37 * 41;
        let mut all = Vec::new();
        for k in 0..2u64 {
            let vals: Vec<f32> =
                (0..n).map(|i| (i as f32 * 0.01 + k as f32).sin() * 100.0 + 120.0).collect();
            let raw = btf_core::zarr::encode_f32(&vals, dtype);
            a.write_chunk(&[k, 0, 0], &raw).unwrap();
            all.extend_from_slice(&raw);
        }
        std::fs::write(d.path(&format!("{name}.bin")), &all).unwrap();
        script += &format!(
            "a = zarr.open_array('{name}', mode='r')\n\
             assert a.metadata.codecs[1].to_dict()['name'] == 'blosc', a.metadata.codecs\n\
             with open('{name}.bin', 'rb') as f:\n\
             \x20   assert a[...].tobytes() == f.read(), '{name}'\n\
             print('{name}', a.dtype, a.shape, 'identical')\n"
        );
    }
    // zarr-python → ours.
    script += "import numpy as np\n\
        from zarr.codecs import BloscCodec, BytesCodec, Crc32cCodec\n\
        for name, dtype, clevel, shuffle in [('p16', 'float16', 1, 'shuffle'),\n\
        \x20                                    ('p32', 'float32', 5, 'noshuffle')]:\n\
        \x20   a = zarr.create_array(name, shape=(3, 128, 129), chunks=(1, 128, 129), dtype=dtype,\n\
        \x20       serializer=BytesCodec(endian='little'), fill_value=0,\n\
        \x20       compressors=[BloscCodec(cname='zstd', clevel=clevel, shuffle=shuffle), Crc32cCodec()])\n\
        \x20   x = np.arange(3 * 128 * 129).reshape(3, 128, 129)\n\
        \x20   v = (np.sin(x / 50.0) * 3 + np.cos(x * 0.37) * 0.01).astype(dtype)\n\
        \x20   a[...] = v\n\
        \x20   with open(name + '.bin', 'wb') as f:\n\
        \x20       f.write(v.tobytes())\n";
    let out = python(d.tmp.path(), &["-c", &script]);
    for name in ["o16", "o32", "o64", "o8"] {
        assert!(out.contains(&format!("{name} ")) && out.contains("identical"), "{out}");
    }
    for (name, typesize) in [("p16", 2usize), ("p32", 4)] {
        let a = ZarrArray::open(&d.path(name), &Limits::default()).unwrap();
        assert!(matches!(a.meta().compression, Compression::Blosc { .. }), "{name}");
        let want = std::fs::read(d.path(&format!("{name}.bin"))).unwrap();
        let n = 128 * 129 * typesize;
        for k in 0..3u64 {
            let got = a.read_chunk(&[k, 0, 0]).unwrap();
            assert!(got == want[k as usize * n..][..n], "{name} chunk {k}");
            a.verify_chunk(&[k, 0, 0]).unwrap();
        }
        // c-blosc's automatic blocks at clevel 1: 32 KiB and a leftover.
        let f = std::fs::read(a.chunk_path(&[0, 0, 0])).unwrap();
        let blocksize = u32::from_le_bytes(f[8..12].try_into().unwrap()) as usize;
        if name == "p16" {
            assert_eq!((blocksize, n % blocksize), (32 << 10, n - (32 << 10)));
        }
    }
}
