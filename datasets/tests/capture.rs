//! The virtual gonioreflectometer: markers visible in every raw image of a default
//! capture geometry, files named and described as documented, poses kept out of
//! `capture.toml`, resumable.

use btf_core::{Ring, Sampling};
use datasets::capture::render::{Camera, image_path, render_image, true_poses};
use datasets::capture::{CaptureSpec, capture, point_markers};
use datasets::{Material, MaterialKind, MaterialSpec};

#[test]
fn every_point_marker_is_visible_in_every_view_of_a_default_capture() {
    let spec = CaptureSpec::new(MaterialSpec::new(MaterialKind::Lambert, 16));
    let material = Material::build(&spec.material).unwrap();
    let poses = true_poses(&spec);
    let s = Sampling::ubo81();
    // All 81 views, under the frontal light and under the most grazing light ring.
    let lights = [0usize, 57, 70];
    let mut worst = f64::INFINITY;
    for view in 0..s.len() {
        let cam = Camera::new(s.direction(view).to_vector(), spec.width, spec.height);
        for &light in &lights {
            let img = render_image(&spec, &material, &poses[view], view, light);
            let at = |p: [f64; 2]| img[p[1] as usize * spec.width + p[0] as usize][1] as f64;
            // Plate between two markers, for the contrast reference.
            let plate = cam.project(poses[view].to_lab([-60.0, 30.0, 0.0])).unwrap();
            for m in point_markers() {
                let p = cam.project(poses[view].to_lab([m[0], m[1], 0.0])).unwrap();
                let inside = p[0] >= 1.0
                    && p[1] >= 1.0
                    && p[0] < spec.width as f64 - 1.0
                    && p[1] < spec.height as f64 - 1.0;
                assert!(inside, "view {view}: marker {m:?} projects to {p:?}");
                let mut best = 0f64;
                for dy in [-1.0, 0.0, 1.0] {
                    for dx in [-1.0, 0.0, 1.0] {
                        best = best.max(at([p[0] + dx, p[1] + dy]));
                    }
                }
                let contrast = best / at(plate).max(4.0);
                worst = worst.min(contrast);
                assert!(
                    contrast > 4.0,
                    "view {view} light {light} marker {m:?}: {best} vs {}",
                    at(plate)
                );
            }
        }
    }
    eprintln!("weakest marker/plate contrast {worst:.1}");
}

#[test]
fn capture_writes_named_images_and_keeps_truth_apart() {
    let ring = |t, c| Ring { theta_deg: t, count: c, phi_offset_deg: 0.0 };
    let mut m = MaterialSpec::new(MaterialKind::Corduroy, 16);
    m.sampling = Sampling::new("custom", vec![ring(0.0, 1), ring(60.0, 2)]).unwrap();
    let mut spec = CaptureSpec::new(m);
    (spec.width, spec.height) = (64, 48);
    let dir = tempfile::tempdir().unwrap();
    let r = capture(&spec, dir.path(), false).unwrap();
    assert_eq!((r.images_written, r.images_skipped), (9, 0));
    let p = dir.path().join("tv060_pv180/tl000_pl000_tv060_pv180.png");
    assert_eq!(
        image_path(spec.material.sampling.direction(2), spec.material.sampling.direction(0)),
        p.strip_prefix(dir.path()).unwrap()
    );
    let img = image::open(&p).unwrap().into_rgb16();
    assert_eq!(img.dimensions(), (64, 48));
    // 12-bit values stored left-aligned: the low four bits are zero.
    assert!(img.pixels().all(|px| px.0.iter().all(|v| v & 0xF == 0)));
    let capture_toml = std::fs::read_to_string(dir.path().join("capture.toml")).unwrap();
    assert!(capture_toml.contains("point_markers_mm") && capture_toml.contains("focal_px"));
    assert!(!capture_toml.contains("rotation") && !capture_toml.contains("translation"));
    let truth: toml::Value =
        toml::from_str(&std::fs::read_to_string(dir.path().join("truth.toml")).unwrap()).unwrap();
    assert_eq!(truth["view_poses"].as_array().unwrap().len(), 3);
    // Same seed, same bytes; a second run resumes and renders nothing.
    let before = std::fs::read(&p).unwrap();
    let r = capture(&spec, dir.path(), false).unwrap();
    assert_eq!((r.images_written, r.images_skipped), (0, 9));
    std::fs::remove_file(&p).unwrap();
    capture(&spec, dir.path(), false).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), before);
    assert_eq!(point_markers().len(), 9);
}
