//! Class 3: a size that a header or store metadata claims is checked before anything is
//! allocated. Each case runs the `btf` binary on a file that claims far more than it holds
//! (a store whose metadata consistently says 8192² texels; EXR and Radiance headers saying
//! 100 000 × 100 000 pixels, a PNG header the same) and asserts three things: the refusal names the file and the
//! field, nothing panics or aborts, and the process's peak resident memory (`ru_maxrss` of
//! that one child, from `wait4`) stays under 1 GiB. What the claims would have cost: 8192²
//! texels × 25 images × 3 channels × 4 bytes is 20 GiB; 10¹⁰ RGB pixels of `f32` are 112 GiB.

use crate::common::Dir;
use crate::hostile::{assert_no_panic, fixture, scene_toml};
use serde_json::{Value, json};
use std::io::Read;
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};

/// The ceiling the issue sets for any refusal.
const MAX_RSS_BYTES: u64 = 1 << 30;

/// Runs `btf ARGS` in `d`, and returns its exit status, stderr and peak resident memory in
/// bytes (that child's own `ru_maxrss`, which Linux reports in KiB). The one `unsafe` of
/// the suite: `std` has no way to read a child's resource usage.
#[allow(unsafe_code)]
#[allow(clippy::zombie_processes)] // reaped by `wait4` below, not by `Child::wait`
fn run_measured(d: &Dir, args: &[&str]) -> (ExitStatus, String, u64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .current_dir(d.tmp.path())
        .env("BTF_NO_PROGRESS", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("btf runs");
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        pipe.read_to_string(&mut s).unwrap();
        s
    });
    let mut status = 0;
    // SAFETY: `rusage` is plain old data; `wait4` fills it and the status for this one pid,
    // which `child` has not reaped (it is never waited on through `std` after this).
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    let got = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(got, pid, "wait4: {}", std::io::Error::last_os_error());
    let stderr = reader.join().unwrap();
    (ExitStatus::from_raw(status), stderr, usage.ru_maxrss as u64 * 1024)
}

/// Runs and expects a refusal naming every string of `names`, within the memory ceiling.
fn refused_within_budget(d: &Dir, args: &[&str], names: &[&str]) {
    let (status, err, rss) = run_measured(d, args);
    assert!(!status.success(), "btf {args:?} should have failed");
    assert!(status.code().is_some(), "btf {args:?} died by a signal ({status}): {err}");
    assert_no_panic(&err);
    for n in names {
        assert!(err.contains(n), "btf {args:?}: the message does not name {n:?}: {err}");
    }
    eprintln!("btf {}: refused, peak memory {:.1} MiB", args.join(" "), rss as f64 / 1048576.0);
    assert!(
        rss < MAX_RSS_BYTES,
        "btf {args:?}: peak memory {} MiB, over the 1 GiB ceiling",
        rss >> 20
    );
}

/// Rewrites a store's metadata so that it claims `w × h` texels everywhere, consistently
/// (the group's attributes, every array's shape and chunk shape); the chunks stay small.
fn claim_texels(store: &Path, w: u64, h: u64) {
    let group = store.join("zarr.json");
    let mut g: Value = serde_json::from_slice(&std::fs::read(&group).unwrap()).unwrap();
    g["attributes"]["btf"]["width"] = json!(w);
    g["attributes"]["btf"]["height"] = json!(h);
    std::fs::write(&group, serde_json::to_vec(&g).unwrap()).unwrap();
    for e in std::fs::read_dir(store).unwrap().flatten() {
        let meta = e.path().join("zarr.json");
        let Ok(bytes) = std::fs::read(&meta) else { continue };
        let mut a: Value = serde_json::from_slice(&bytes).unwrap();
        // Groups (stats/, registration/) have no dimensions.
        let Ok(names) = serde_json::from_value::<Vec<String>>(a["dimension_names"].clone()) else {
            continue;
        };
        for (i, n) in names.iter().enumerate() {
            let v = match n.as_str() {
                "y" => h,
                "x" => w,
                _ => continue,
            };
            a["shape"][i] = json!(v);
            a["chunk_grid"]["configuration"]["chunk_shape"][i] = json!(v);
        }
        std::fs::write(&meta, serde_json::to_vec(&a).unwrap()).unwrap();
    }
}

/// A valid 2 × 2 RGB EXR whose `dataWindow` is patched to claim `w × h` pixels.
fn exr_claiming(w: i32, h: i32) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.exr");
    exr::prelude::write_rgb_file(&p, 2, 2, |_, _| (1f32, 1f32, 1f32)).unwrap();
    let mut b = std::fs::read(&p).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = b.windows(key.len()).position(|s| s == key).unwrap() + key.len() + 4;
    b[at + 8..at + 12].copy_from_slice(&(w - 1).to_le_bytes());
    b[at + 12..at + 16].copy_from_slice(&(h - 1).to_le_bytes());
    b
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

/// A PNG (8-bit RGB) whose IHDR claims `w × h` pixels, with an empty IDAT.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
    b.extend_from_slice(&13u32.to_be_bytes());
    b.extend_from_slice(&ihdr);
    b.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    for tag in [b"IDAT", b"IEND"] {
        b.extend_from_slice(&0u32.to_be_bytes());
        b.extend_from_slice(tag);
        b.extend_from_slice(&crc32(tag).to_be_bytes());
    }
    b
}

/// Every file below `dir` whose name ends in `ext`, sorted.
fn files_with(dir: &Path, ext: &str) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(ext) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn stores_claiming_8192_squared_texels_are_refused_within_1_gib() {
    let d = fixture();
    crate::hostile::copy_dir(&d.path("A.btf"), &d.path("big.btf"));
    crate::hostile::copy_dir(&d.path("B.eig"), &d.path("big.eig"));
    claim_texels(&d.path("big.btf"), 8192, 8192);
    claim_texels(&d.path("big.eig"), 8192, 8192);
    for args in [
        &["compress", "big.btf", "-c", "2", "-o", "c.eig"][..],
        &["export", "big.btf", "--format", "ubo2003", "-o", "ex"],
        &["export", "big.btf", "--format", "npy", "--slot", "0", "-o", "s.npy"],
        &["export", "big.eig", "--format", "pvf", "-o", "b.pvf"],
        &["export", "big.eig", "--format", "exr", "--slot", "0", "-o", "b.exr"],
        &["reconstruct", "big.eig", "--view", "0,0", "--light", "45,0", "-o", "r.exr"],
    ] {
        refused_within_budget(&d, args, &["big."]);
    }
    if crate::hostile::gpu_available() {
        std::fs::write(d.path("big.toml"), scene_toml("").replace("B.eig", "big.eig")).unwrap();
        refused_within_budget(&d, &["render", "big.toml", "-o", "o.png"], &["big.eig"]);
    }
    assert_eq!(crate::hostile::leftovers(d.tmp.path()), Vec::<String>::new());
}

#[test]
fn images_claiming_100000_squared_pixels_are_refused_within_1_gib() {
    let d = fixture();
    let huge = exr_claiming(100_000, 100_000);
    // An import of an exported UBO2003 folder, one image of which claims 10¹⁰ pixels.
    d.ok(&["export", "A.btf", "--format", "ubo2003", "--image", "exr", "-o", "ex"]);
    let img = files_with(&d.path("ex"), ".exr").pop().expect("the export wrote EXR images");
    std::fs::write(&img, &huge).unwrap();
    let name = img.file_name().unwrap().to_string_lossy().into_owned();
    refused_within_budget(&d, &["import", "ubo2003", "ex", "-o", "I.btf"], &[&name, "100000"]);

    // A raw capture one image of which claims 10¹⁰ pixels.
    d.ok(&[
        "synth",
        "capture",
        "--material",
        "lambert",
        "--size",
        "8",
        "--sampling",
        "rings:0x1",
        "--resolution",
        "64,48",
        "--out",
        "raw",
    ]);
    // The first image, as an EXR and as a PNG, each claiming 10¹⁰ pixels.
    let png = files_with(&d.path("raw"), ".png").remove(0);
    std::fs::remove_file(&png).unwrap();
    for (ext, bytes, field) in
        [("exr", &huge, "dataWindow"), ("png", &png_claiming(100_000, 100_000), "100000x100000")]
    {
        let img = png.with_extension(ext);
        std::fs::write(&img, bytes).unwrap();
        let name = img.file_name().unwrap().to_string_lossy().into_owned();
        refused_within_budget(
            &d,
            &["capture", "process", "raw", "-o", "m.btf", "--size", "8"],
            &[&name, field],
        );
        std::fs::remove_file(&img).unwrap();
    }

    // Environment maps: an EXR and a Radiance header, each claiming 10¹⁰ pixels.
    if crate::hostile::gpu_available() {
        std::fs::write(d.path("huge.exr"), &huge).unwrap();
        std::fs::write(
            d.path("huge.hdr"),
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n",
        )
        .unwrap();
        for map in ["huge.exr", "huge.hdr"] {
            let env = format!(
                "[[lights]]\nkind = \"environment\"\npath = \"{map}\"\nvisibility_res = 4\n"
            );
            std::fs::write(d.path("e.toml"), scene_toml(&env)).unwrap();
            refused_within_budget(&d, &["render", "e.toml", "-o", "o.png"], &[map]);
        }
    }
    assert_eq!(crate::hostile::leftovers(d.tmp.path()), Vec::<String>::new());
}
