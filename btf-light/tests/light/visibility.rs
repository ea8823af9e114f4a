//! Visibility maps (`[S03 §5.2]`, the `V` of `[S03 eq. 9]`): a concave corner against its
//! analytic visible fraction, the fast rasteriser against the ray cast it replaces (bit for
//! bit), the cache (round trip, corruption, subsets), and environment files refused when
//! not finite.

use crate::common::*;
use btf_image::EnvMap;
use btf_light::tangent::compute_tangents;
use btf_light::{Hemicube, HemicubeFrame, VisibilityMaps};
use std::f64::consts::PI;

fn rect_solid_angle(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let f = |a: f64, b: f64| (a * b / (1.0 + a * a + b * b).sqrt()).atan();
    f(a1, b1) - f(a0, b1) - f(a1, b0) + f(a0, b0)
}

#[test]
fn concave_corner_matches_the_analytic_visible_fraction() {
    let (d, hw, h) = (0.1f32, 0.5f32, 0.3f32);
    let mesh = corner_mesh(d, hw, h);
    let centre = 12; // the grid vertex at the origin
    assert_eq!(mesh.positions[centre], [0.0, 0.0, 0.0]);
    let wall = rect_solid_angle(-(hw / d) as f64, (hw / d) as f64, 0.0, (h / d) as f64);
    let expect = 1.0 - wall / (2.0 * PI);
    for res in [16, 32, 64] {
        let (s, _d) = setup(&mesh, res, Pattern::Uniform, 1);
        let got = s.vis.visible_fraction(&s.cube, centre);
        eprintln!("corner: res {res}: visible {got:.5}, analytic {expect:.5}");
        // Pixels straddling the wall's outline are counted whole: the error is bounded by
        // the outline's pixels, O(1/res).
        assert!((got - expect).abs() < 1.0 / res as f64, "res {res}: {got} vs {expect}");
    }
}

#[test]
fn visibility_cache_round_trips_and_survives_corruption() {
    let mesh = corner_mesh(0.1, 0.5, 0.3);
    let cube = Hemicube::new(8).unwrap();
    let tangents = compute_tangents(&mesh);
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
    let dir = tempfile::tempdir().unwrap();
    let (a, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(!hit);
    let (b, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(hit && a == b);
    let file = std::fs::read_dir(dir.path()).unwrap().next().unwrap().unwrap().path();
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[30] ^= 0xff;
    std::fs::write(&file, bytes).unwrap();
    let (c, hit) =
        VisibilityMaps::cached(dir.path(), &cube, &frames, &mesh.positions, &mesh.triangles)
            .unwrap();
    assert!(!hit && c == a);
    // A different resolution is a different key.
    let (_, hit) = VisibilityMaps::cached(
        dir.path(),
        &Hemicube::new(4).unwrap(),
        &frames,
        &mesh.positions,
        &mesh.triangles,
    )
    .unwrap();
    assert!(!hit);
    // Back sides (two-sided cloth) of the floor see the lower hemisphere: unoccluded.
    assert!((a.visible_fraction(&cube, frames.len() / 2 + 12) - 1.0).abs() < 1e-12);
    // A subset of the frames: served by the maps of all frames when those are cached, else
    // computed and cached under a key of its own.
    let (pos, tris) = (&mesh.positions, &mesh.triangles);
    let wanted: Vec<bool> = (0..frames.len()).map(|f| f % 3 == 0).collect();
    let (d, hit, all) =
        VisibilityMaps::cached_some(dir.path(), &cube, &frames, Some(&wanted), pos, tris).unwrap();
    assert!(hit && all && d == a, "the full maps serve a subset");
    let fresh = tempfile::tempdir().unwrap();
    let run =
        || VisibilityMaps::cached_some(fresh.path(), &cube, &frames, Some(&wanted), pos, tris);
    let ((e, hit_e, all_e), (f, hit_f, all_f)) = (run().unwrap(), run().unwrap());
    assert!(!hit_e && hit_f && e == f && !all_e && !all_f);
    for k in 0..frames.len() {
        let expect = if wanted[k] { a.frame_bits(k).to_vec() } else { vec![0; a.words] };
        assert_eq!(e.frame_bits(k), &expect[..], "frame {k}");
    }
    let (g, hit) = VisibilityMaps::cached(fresh.path(), &cube, &frames, pos, tris).unwrap();
    assert!(!hit && g == a, "a subset never stands in for all frames");
}

#[test]
fn fast_visibility_equals_the_ray_cast() {
    let meshes = [
        ("sphere", sphere(16), 16),
        ("corner", corner_mesh(0.1, 0.5, 0.3), 32),
        // Rows of two mask words (96 = 64 + 32) and the smallest cube.
        ("corner", corner_mesh(0.1, 0.5, 0.3), 96),
        ("sphere", sphere(8), 2),
        ("crumpled sheet", crumpled_sheet(), 16),
        ("shirt low", shirt_low(), 8),
    ];
    for (name, mesh, res) in meshes {
        let cube = Hemicube::new(res).unwrap();
        let tangents = compute_tangents(&mesh);
        let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
        let (pos, tris) = (&mesh.positions, &mesh.triangles);
        let fast = VisibilityMaps::compute(&cube, &frames, pos, tris);
        let reference = VisibilityMaps::compute_ray_cast(&cube, &frames, pos, tris);
        let differ: u32 =
            fast.bits.iter().zip(&reference.bits).map(|(a, b)| (a ^ b).count_ones()).sum();
        let visible: u32 = reference.bits.iter().map(|w| w.count_ones()).sum();
        let share = visible as f64 / (frames.len() * cube.len()) as f64;
        eprintln!(
            "{name}: {} frames, {differ} differing pixels, visible share {share:.3}",
            frames.len()
        );
        assert_eq!(differ, 0, "{name}: fast visibility differs from the ray cast");
        // Not a trivial case: both occluded and visible pixels occur.
        assert!(share > 0.05 && share < 0.95, "{name}: visible share {share}");
    }
}

#[test]
fn non_finite_environment_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.exr");
    exr::prelude::write_rgb_file(&p, 16, 8, |x, y| {
        if (x, y) == (3, 2) { (f32::INFINITY, 0.0, 0.0) } else { (1.0, 1.0, 1.0) }
    })
    .unwrap();
    let e = EnvMap::load(&p).unwrap_err().to_string();
    assert!(e.contains("bad.exr") && e.contains("x=3, y=2") && e.contains("non-finite"), "{e}");
    let ok = dir.path().join("ok.exr");
    exr::prelude::write_rgb_file(&ok, 16, 8, |_, _| (0.5, 1.0, 2.0)).unwrap();
    let m = EnvMap::load(&ok).unwrap();
    assert_eq!((m.width, m.height, m.pixels[5]), (16, 8, [0.5, 1.0, 2.0]));
    assert!(EnvMap::load(&dir.path().join("x.png")).is_err());
}
