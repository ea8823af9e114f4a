//! Class 1: an output path that is, contains or lies inside an input is refused, and the
//! input's bytes are untouched — compared by canonical path and inode, so `x/../A.btf`, a
//! path inside a store and a hard link are all seen through.

use crate::hostile::{assert_no_panic, fixture, snapshot};

#[test]
fn store_commands_refuse_their_input_as_output() {
    let d = fixture();
    let a = snapshot(&d.path("A.btf"));
    let b = snapshot(&d.path("B.eig"));
    let cases: &[&[&str]] = &[
        &["compress", "A.btf", "-c", "2", "-o", "A.btf"],
        &["compress", "A.btf", "-c", "2", "-o", "x/../A.btf"],
        &["compress", "A.btf", "-c", "2", "-o", "A.btf/c/inner.eig"],
        &["compress", "A.btf", "--sweep", "1,2", "--report", "A.btf"],
        &["compress", "A.btf", "--sweep", "1,2", "--report", "."],
        &["export", "A.btf", "--format", "ubo2003", "-o", "A.btf"],
        &["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "A.btf/zarr.json"],
        &["export", "B.eig", "--format", "pvf", "-o", "B.eig"],
        &["export", "B.eig", "--format", "exr", "--slot", "0", "-o", "B.eig/mean/zarr.json"],
        &["reconstruct", "B.eig", "--view", "0,0", "--light", "0,0", "-o", "B.eig/x.exr"],
        &["import", "ubo2003", "A.btf", "-o", "A.btf"],
        &["import", "ubo2014", "s.toml", "-o", "s.toml"],
    ];
    for args in cases {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(err.contains("refusing to write"), "btf {args:?}: {err}");
        assert_eq!(snapshot(&d.path("A.btf")), a, "btf {args:?} changed A.btf");
        assert_eq!(snapshot(&d.path("B.eig")), b, "btf {args:?} changed B.eig");
    }
}

#[test]
fn a_hard_link_to_an_input_is_the_input() {
    let d = fixture();
    std::fs::hard_link(d.path("s.toml"), d.path("link.exr")).unwrap();
    let before = std::fs::read(d.path("s.toml")).unwrap();
    let err = d.fails(&["render", "s.toml", "-o", "out.png", "--exr", "link.exr"]);
    assert!(err.contains("refusing to write --exr link.exr: it is the scene"), "{err}");
    assert_eq!(std::fs::read(d.path("s.toml")).unwrap(), before);
}

#[test]
fn scene_commands_refuse_outputs_over_their_inputs() {
    let d = fixture();
    let all = snapshot(d.tmp.path());
    let cases: &[&[&str]] = &[
        &["render", "s.toml", "-o", "out.png", "--exr", "s.toml"],
        &["render", "s.toml", "-o", "B.eig/out.png"],
        &["render", "s.toml", "-o", "out.png", "--exr", "plane.obj"],
        &["render", "s.toml", "-o", "o.png", "--exr", "./o.png"],
        &["render-sweep", "s.toml", "-o", "."],
        &["view", "s.toml", "--turntable", "2", "-o", "B.eig"],
    ];
    for args in cases {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(
            err.contains("refusing to write") || err.contains("same path"),
            "btf {args:?}: {err}"
        );
        assert_eq!(snapshot(d.tmp.path()), all, "btf {args:?} changed the folder");
    }
}

#[test]
fn capture_process_refuses_its_raw_folder() {
    let d = crate::common::Dir::new();
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
    let raw = snapshot(&d.path("raw"));
    for out in ["raw", "raw/m.btf", "."] {
        let err = d.fails(&["capture", "process", "raw", "-o", out, "--size", "8"]);
        assert!(err.contains("refusing to write"), "-o {out}: {err}");
        assert_eq!(snapshot(&d.path("raw")), raw, "-o {out} changed the raw folder");
    }
    let err = d.fails(&["capture", "score", "A.btf", "--truth", "raw", "--report", "raw"]);
    assert!(err.contains("refusing") || err.contains("cannot open"), "{err}");
}
