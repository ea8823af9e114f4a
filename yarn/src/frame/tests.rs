//! Frame checks: exact anchoring, continuity where the tangent turns through the surface
//! normal (the step shrinks with the sampling step), closure on loops and periodic courses.

use super::*;
use crate::vec3::{dot, length};

/// Largest angle (radians) between the normals of consecutive frames at `k` steps per
/// segment, and checks of orthonormality.
fn max_step_angle(c: &YarnCurve, f: &CurveFrames, k: usize) -> f64 {
    let m = c.segment_count() * k;
    let mut worst: f64 = 0.0;
    let mut prev = f.frame_at(c, 0.0);
    for j in 1..=m {
        let fr = f.frame_at(c, j as f64 / k as f64);
        assert!((length(fr.n) - 1.0).abs() < 1e-12 && dot(fr.n, fr.t).abs() < 1e-12);
        assert!((length(fr.b) - 1.0).abs() < 1e-12);
        worst = worst.max(dot(prev.n, fr.n).clamp(-1.0, 1.0).acos());
        prev = fr;
    }
    worst
}

fn helix(n: usize) -> Vec<V3> {
    (0..n)
        .map(|i| {
            let a = 0.5 * i as f64;
            [a.cos(), a.sin(), 0.2 * a]
        })
        .collect()
}

#[test]
fn anchored_frames_follow_the_surface_normal_exactly() {
    let pts: Vec<V3> = (0..8).map(|i| [i as f64, (0.7 * i as f64).sin(), 0.0]).collect();
    let normals = vec![[0.0, 0.0, 1.0]; 8];
    let c = YarnCurve::open(pts).unwrap().with_normals(normals).unwrap();
    let f = CurveFrames::new(&c, 8);
    for j in 0..=140 {
        let u = j as f64 * 0.05;
        let fr = f.frame_at(&c, u);
        assert!((fr.n[2] - 1.0).abs() < 1e-12, "u = {u}: {:?}", fr.n);
    }
}

#[test]
fn frames_stay_continuous_where_the_tangent_turns_along_the_normal() {
    // A loop in the xz-plane: its tangent is parallel to the surface normal +z twice.
    let pts: Vec<V3> = (0..12)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 12.0;
            [a.cos(), 0.1 * (2.0 * a).sin(), a.sin()]
        })
        .collect();
    let c = YarnCurve::closed(pts).unwrap().with_normals(vec![[0.0, 0.0, 1.0]; 12]).unwrap();
    let f = CurveFrames::new(&c, 16);
    // Continuity: the largest step between consecutive frames shrinks in proportion to
    // the step (a jump would stay put).
    let coarse = max_step_angle(&c, &f, 400);
    let fine = max_step_angle(&c, &f, 1600);
    eprintln!("largest frame step: {coarse:.4} rad at 1/400, {fine:.4} rad at 1/1600");
    assert!(fine < 0.3 * coarse && coarse < 0.05, "{coarse} → {fine}");
    let a = f.frame_at(&c, 0.3);
    let b = f.frame_at(&c, 12.3);
    assert!(vec3::distance(a.n, b.n) < 1e-12, "closed frame must repeat");
}

#[test]
fn rotation_minimising_frames_close_on_loops_and_are_smooth_on_open_curves() {
    let open = YarnCurve::open(helix(20)).unwrap();
    let f = CurveFrames::new(&open, 8);
    assert!(max_step_angle(&open, &f, 200) < 0.01);
    let tri = YarnCurve::closed(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.3], [0.2, 1.0, -0.4]]).unwrap();
    let f = CurveFrames::new(&tri, 32);
    assert!(max_step_angle(&tri, &f, 300) < 0.05);
    for j in 0..30 {
        let u = 0.1 * j as f64;
        let (a, b) = (f.frame_at(&tri, u), f.frame_at(&tri, u + 3.0));
        assert!(vec3::distance(a.n, b.n) < 1e-12, "u = {u}");
    }
    // A periodic course without normals: periodic frames, continuous across the seam.
    let course = YarnCurve::periodic(
        vec![[0.0, 0.0, 0.0], [0.25, 0.1, 0.05], [0.5, 0.0, -0.05], [0.75, -0.1, 0.0]],
        [1.0, 0.0, 0.0],
    )
    .unwrap();
    let f = CurveFrames::new(&course, 16);
    assert!(max_step_angle(&course, &f, 400) < 0.01);
    let (a, b) = (f.frame_at(&course, 3.999_999), f.frame_at(&course, 4.0));
    assert!(vec3::distance(a.n, b.n) < 1e-5);
}
