//! Class 7: no panic. A closed standard output ends a command quietly (as Unix tools do),
//! and a frame larger than the adapter can hold is refused naming the limit.

use crate::hostile::{assert_no_panic, fixture};
use std::process::{Command, Stdio};

#[test]
fn a_closed_stdout_ends_quietly() {
    let d = fixture();
    for args in [
        &["inspect", "A.btf"][..],
        &["inspect", "B.eig", "--json"],
        &["compress", "A.btf", "-c", "2", "-o", "C.eig", "--json"],
        &["thin", "validate", "--photons", "1000"],
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_btf"))
            .args(args)
            .current_dir(d.tmp.path())
            .env("BTF_NO_PROGRESS", "1")
            .stdout(Stdio::from(writer))
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_no_panic(&err);
        assert!(out.status.success(), "btf {args:?}: {:?} {err}", out.status);
        assert!(!err.contains("error"), "btf {args:?}: {err}");
    }
}

#[test]
fn a_frame_beyond_the_adapter_is_refused_naming_the_limit() {
    if !crate::hostile::gpu_available() {
        return;
    }
    let d = fixture();
    for size in ["16384", "20000"] {
        let o = d.btf(&["render", "s.toml", "-o", "big.png", "--width", size, "--height", size]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert_no_panic(&err);
        assert!(
            err.contains("max_texture_dimension_2d")
                || err.contains("max_buffer_size")
                || err.contains("render targets")
                || err.contains("output.width/height"),
            "{size}: {err}"
        );
        assert!(!d.path("big.png").exists());
    }
}

#[test]
fn the_binary_prints_through_the_pipe_safe_macro_only() {
    // `println!` panics on a closed pipe; every command prints through `outln!`.
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut stack = vec![src];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).unwrap();
                for (i, line) in text.lines().enumerate() {
                    let code = line.split("//").next().unwrap_or("");
                    let hit = code.contains("println!(") && !code.contains("eprintln!(")
                        || code.contains(" print!(");
                    assert!(!hit, "{}:{}: use outln! instead of println!", p.display(), i + 1);
                }
            }
        }
    }
}
