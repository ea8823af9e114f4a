//! `kill -9` in the middle of every writer: whenever the process dies, the output is the
//! previous one or the new one, whole — never a mixture or a truncated file — and a rerun
//! (with `--resume` where the command has it) gives the bytes of an uninterrupted run.

use crate::hostile::{fixture, snapshot};
use std::collections::BTreeMap;
use std::process::{Command, Stdio};
use std::time::Duration;

/// A snapshot without the per-slot timings (`stats/*.json` record seconds).
fn content(path: &std::path::Path) -> BTreeMap<String, Vec<u8>> {
    let mut s = snapshot(path);
    s.retain(|k, _| !k.starts_with("stats/"));
    s
}

fn kill_after(dir: &std::path::Path, args: &[&str], ms: u64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .current_dir(dir)
        .env("BTF_NO_PROGRESS", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(ms));
    let _ = child.kill();
    let _ = child.wait();
}

struct Case {
    /// Makes the previous output.
    v1: Vec<&'static str>,
    /// The run that is killed, then rerun.
    v2: Vec<&'static str>,
    /// Appended to the rerun (`--resume`).
    rerun: &'static [&'static str],
    out: &'static str,
    gpu: bool,
}

#[test]
fn every_writer_survives_kill_9() {
    let cases = [
        Case {
            v1: vec![
                "synth",
                "material",
                "--kind",
                "lambert",
                "--size",
                "32",
                "--sampling",
                "rings:0x1,45x8",
                "-o",
                "M.btf",
            ],
            v2: vec![
                "synth",
                "material",
                "--kind",
                "lambert",
                "--size",
                "32",
                "--sampling",
                "rings:0x1,45x8",
                "--seed",
                "2",
                "-o",
                "M.btf",
            ],
            rerun: &["--resume"],
            out: "M.btf",
            gpu: false,
        },
        Case {
            v1: vec!["compress", "A.btf", "-c", "2", "-o", "C.eig"],
            v2: vec!["compress", "A.btf", "-c", "3", "-o", "C.eig"],
            rerun: &["--resume"],
            out: "C.eig",
            gpu: false,
        },
        Case {
            v1: vec!["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "s.npy"],
            v2: vec!["export", "A.btf", "--format", "npy", "--slot", "1", "-o", "s.npy"],
            rerun: &[],
            out: "s.npy",
            gpu: false,
        },
        Case {
            v1: vec!["export", "A.btf", "--format", "ubo2003", "--image", "png16", "-o", "ex"],
            v2: vec!["export", "A.btf", "--format", "ubo2003", "--image", "png", "-o", "ex"],
            rerun: &[],
            out: "ex",
            gpu: false,
        },
        Case {
            v1: vec!["synth", "env", "--kind", "sky", "--width", "64", "-o", "e.exr"],
            v2: vec!["synth", "env", "--kind", "studio", "--width", "64", "-o", "e.exr"],
            rerun: &[],
            out: "e.exr",
            gpu: false,
        },
        Case {
            v1: vec!["synth", "mesh", "--kind", "plane", "-o", "m.obj"],
            v2: vec!["synth", "mesh", "--kind", "sphere", "--resolution", "high", "-o", "m.obj"],
            rerun: &[],
            out: "m.obj",
            gpu: false,
        },
        Case {
            v1: vec!["render", "s.toml", "-o", "o.png"],
            v2: vec!["render", "s.toml", "-o", "o.png", "--width", "24"],
            rerun: &[],
            out: "o.png",
            gpu: true,
        },
    ];
    let gpu = crate::hostile::gpu_available();
    for c in cases.iter().filter(|c| gpu || !c.gpu) {
        let reference = fixture();
        reference.ok(&c.v2);
        let want_new = content(&reference.path(c.out));
        let d = fixture();
        d.ok(&c.v1);
        let old = content(&d.path(c.out));
        for ms in [2, 10, 40, 150] {
            kill_after(d.tmp.path(), &c.v2, ms);
            let now = content(&d.path(c.out));
            assert!(
                now == old || now == want_new,
                "btf {:?} killed after {ms} ms left a mixture",
                c.v2
            );
        }
        let mut rerun = c.v2.clone();
        rerun.extend_from_slice(c.rerun);
        d.ok(&rerun);
        assert_eq!(content(&d.path(c.out)), want_new, "rerun of btf {:?}", c.v2);
    }
}
