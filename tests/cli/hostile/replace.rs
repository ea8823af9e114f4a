//! Class 2: an existing output is replaced only when the toolkit made it (a store it
//! wrote, a folder carrying its marker, a file of the format being written); a user's file
//! or folder is refused by name and survives byte for byte.

use crate::hostile::{assert_no_panic, fixture, snapshot};

#[test]
fn foreign_files_and_folders_are_not_replaced() {
    let d = fixture();
    std::fs::write(d.path("notes.eig"), "my notes").unwrap();
    std::fs::write(d.path("notes.png"), "my notes").unwrap();
    std::fs::create_dir(d.path("photos")).unwrap();
    std::fs::write(d.path("photos/holiday.jpg"), "a photo").unwrap();
    d.ok(&["synth", "env", "--kind", "sky", "--width", "16", "-o", "sky.exr"]);
    let before = snapshot(d.tmp.path());
    let cases: &[&[&str]] = &[
        &["compress", "A.btf", "-c", "2", "-o", "notes.eig"],
        &["compress", "A.btf", "-c", "2", "-o", "photos"],
        &["compress", "A.btf", "--sweep", "1", "--report", "photos"],
        &["export", "A.btf", "--format", "ubo2003", "-o", "photos"],
        &["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "notes.png"],
        &["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "photos"],
        &["reconstruct", "B.eig", "--view", "0,0", "--light", "0,0", "-o", "notes.png"],
        &[
            "synth",
            "material",
            "--kind",
            "lambert",
            "--size",
            "8",
            "--sampling",
            "rings:0x1",
            "-o",
            "notes.eig",
        ],
        &[
            "synth",
            "material",
            "--kind",
            "lambert",
            "--size",
            "8",
            "--sampling",
            "rings:0x1",
            "-o",
            "photos",
        ],
        &["synth", "env", "--kind", "sky", "--width", "16", "-o", "notes.png"],
        &[
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
            "photos",
        ],
        &["render", "s.toml", "-o", "notes.png"],
        &["relight", "s.toml", "--env", "sky.exr", "-o", "photos", "--fresh"],
        &["demo", "-o", "photos", "--fresh"],
        &["thin", "demo", "-o", "photos", "--fresh"],
        &["view", "s.toml", "--turntable", "1", "-o", "photos"],
    ];
    for args in cases {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(err.contains("refusing to replace"), "btf {args:?}: {err}");
        assert_eq!(snapshot(d.tmp.path()), before, "btf {args:?} changed the folder");
    }
}

#[test]
fn what_the_toolkit_made_is_replaced() {
    let d = fixture();
    // A store over a store, an export over an export, a PNG over a PNG.
    d.ok(&["compress", "A.btf", "-c", "3", "-o", "B.eig"]);
    let inspect = d.ok(&["inspect", "B.eig", "--json"]);
    assert!(inspect.contains("\"components\": 3"), "{inspect}");
    d.ok(&["export", "A.btf", "--format", "ubo2003", "-o", "ex"]);
    d.ok(&["export", "A.btf", "--format", "ubo2003", "--image", "png", "-o", "ex"]);
    assert!(d.path("ex/btf-export.json").is_file());
    d.ok(&[
        "reconstruct",
        "B.eig",
        "--view",
        "0,0",
        "--light",
        "0,0",
        "-o",
        "r.exr",
        "--png",
        "r.png",
    ]);
    d.ok(&[
        "reconstruct",
        "B.eig",
        "--view",
        "10,0",
        "--light",
        "0,0",
        "-o",
        "r.exr",
        "--png",
        "r.png",
    ]);
}

#[test]
fn fresh_clears_only_what_the_command_wrote() {
    if !crate::hostile::gpu_available() {
        return;
    }
    let d = fixture();
    d.ok(&["synth", "env", "--kind", "sky", "--width", "32", "-o", "sky.exr"]);
    let args = ["relight", "s.toml", "--env", "sky.exr", "--rotations", "1", "-o", "out"];
    d.ok(&args);
    assert!(d.path("out/sky_r000.png").is_file());
    // A user's file put into the job's folder survives `--fresh`; the job's frames do not.
    std::fs::write(d.path("out/mine.txt"), "keep me").unwrap();
    std::fs::write(d.path("out/sky_r007.png"), "a stale frame").unwrap();
    let mut fresh = args.to_vec();
    fresh.push("--fresh");
    d.ok(&fresh);
    assert_eq!(std::fs::read_to_string(d.path("out/mine.txt")).unwrap(), "keep me");
    assert!(!d.path("out/sky_r007.png").exists(), "--fresh kept a frame of the job");
    assert!(d.path("out/sky_r000.png").is_file());
}
