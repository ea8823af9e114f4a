//! Class 6: extreme but finite values. An environment map with radiance near the `f32`
//! maximum (EXR pixels of 3e38, an RGBE exponent at its top) and lights of 3e38 are
//! refused by name with the limit (`btf_core::MAX_RADIANCE`), instead of rendering
//! infinities.

use crate::hostile::{assert_no_panic, fixture, scene_toml};

fn env_scene(map: &str) -> String {
    scene_toml(&format!(
        "[[lights]]\nkind = \"environment\"\npath = \"{map}\"\nvisibility_res = 4\n"
    ))
}

#[test]
fn lights_near_the_float_maximum_are_refused_before_rendering() {
    let d = fixture();
    std::fs::write(d.path("hot.toml"), scene_toml("").replace("[2.0, 2.0, 2.0]", "[3e38, 1, 1]"))
        .unwrap();
    let err = d.fails(&["render", "hot.toml", "-o", "o.png"]);
    assert_no_panic(&err);
    assert!(err.contains("lights[0].irradiance") && err.contains("1e12"), "{err}");
    std::fs::write(
        d.path("hot.toml"),
        scene_toml("").replace("width = 16", "width = 16\nexposure = 1e30"),
    )
    .unwrap();
    let err = d.fails(&["render", "hot.toml", "-o", "o.png"]);
    assert!(err.contains("output.exposure"), "{err}");
}

#[test]
fn environment_maps_near_the_float_maximum_are_refused_by_name() {
    if !crate::hostile::gpu_available() {
        return;
    }
    let d = fixture();
    // An EXR with one pixel of 3e38.
    let (w, h) = (8usize, 4usize);
    exr::prelude::write_rgb_file(d.path("hot.exr"), w, h, |x, y| {
        if (x, y) == (3, 1) { (3e38f32, 1.0, 1.0) } else { (1.0, 1.0, 1.0) }
    })
    .unwrap();
    // An RGBE file whose exponent byte is at its top (255 → ~1.7e38 · mantissa).
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n".to_vec();
    for i in 0..32 {
        hdr.extend_from_slice(if i == 9 { &[200, 200, 200, 255] } else { &[128, 128, 128, 129] });
    }
    std::fs::write(d.path("hot.hdr"), hdr).unwrap();
    for map in ["hot.exr", "hot.hdr"] {
        std::fs::write(d.path("e.toml"), env_scene(map)).unwrap();
        let out = format!("rl-{map}");
        for args in [
            &["render", "e.toml", "-o", "o.png"][..],
            &["relight", "s.toml", "--env", map, "--rotations", "1", "-o", out.as_str()],
        ] {
            let err = d.fails(args);
            assert_no_panic(&err);
            assert!(err.contains(map) && err.contains("1e12"), "btf {args:?}: {err}");
            assert!(!err.contains("non-finite values (please report"), "{err}");
            assert!(!d.path("o.png").exists());
        }
    }
}
