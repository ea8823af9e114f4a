//! Class 5: NaN never passes through. A NaN in an eigen store's mean (with a valid
//! checksum) is refused by every command that reads it, naming the store, the array and
//! the view slot; nothing is written.

use crate::hostile::{assert_no_panic, fixture, leftovers};
use std::path::Path;

/// Puts `value` at element 0 of slot 0's chunk of `array` and fixes the checksum.
fn poison(chunk: &Path, value: f32) {
    let bytes = std::fs::read(chunk).unwrap();
    let mut payload = bytes[..bytes.len() - 4].to_vec();
    payload[..4].copy_from_slice(&value.to_le_bytes());
    let crc = crc32c::crc32c(&payload).to_le_bytes();
    payload.extend_from_slice(&crc);
    std::fs::write(chunk, payload).unwrap();
}

#[test]
fn nan_in_an_eigen_mean_is_refused_by_every_reader() {
    let d = fixture();
    poison(&d.path("B.eig/mean/c.0.0.0.0"), f32::NAN);
    let cases: &[&[&str]] = &[
        &["export", "B.eig", "--format", "exr", "--slot", "0", "-o", "o.exr"],
        &["export", "B.eig", "--format", "pvf", "-o", "o.pvf"],
        &["reconstruct", "B.eig", "--view", "0,0", "--light", "0,0", "-o", "o.exr"],
    ];
    for args in cases {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(err.contains("mean") && err.contains("view slot 0"), "btf {args:?}: {err}");
        assert!(err.contains("B.eig"), "btf {args:?}: {err}");
        assert!(!d.path("o.exr").exists() && !d.path("o.pvf").exists());
        assert_eq!(leftovers(d.tmp.path()), Vec::<String>::new());
    }
    if crate::hostile::gpu_available() {
        let err = d.fails(&["render", "s.toml", "-o", "o.png"]);
        assert!(err.contains("mean") && err.contains("view slot 0"), "{err}");
        assert!(!d.path("o.png").exists());
    }
}

#[test]
fn nan_in_a_btf_image_is_refused_naming_slot_and_light() {
    let d = fixture();
    poison(&d.path("A.btf/normtextures/c.1.2.0.0.0"), f32::INFINITY);
    for args in [
        &["compress", "A.btf", "-c", "2", "-o", "C.eig"][..],
        &["export", "A.btf", "--format", "npy", "--slot", "1", "-o", "o.npy"],
        &["export", "A.btf", "--format", "ubo2003", "-o", "ex"],
    ] {
        let err = d.fails(args);
        assert_no_panic(&err);
        assert!(err.contains("view slot 1") && err.contains("light 2"), "btf {args:?}: {err}");
        assert!(!d.path("C.eig").exists() && !d.path("o.npy").exists() && !d.path("ex").exists());
    }
}

#[test]
fn nan_in_a_mesh_is_refused_naming_the_file() {
    if !crate::hostile::gpu_available() {
        return;
    }
    let d = fixture();
    std::fs::write(
        d.path("plane.obj"),
        crate::hostile::common_plane().replacen("v 1 0 0", "v nan 0 0", 1),
    )
    .unwrap();
    let err = d.fails(&["render", "s.toml", "-o", "o.png"]);
    assert_no_panic(&err);
    assert!(err.contains("plane.obj"), "{err}");
    assert!(!d.path("o.png").exists());
}
