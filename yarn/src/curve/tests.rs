//! Curve checks: interpolation, analytic derivatives, arc length and length coordinates,
//! wrapping of closed and periodic curves, and the hard cases of DESIGN §4.4.

use super::*;
use crate::vec3::{distance, length};

fn helix(n: usize, turns: f64) -> Vec<V3> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * turns * i as f64 / (n - 1) as f64;
            [a.cos(), a.sin(), 0.3 * a]
        })
        .collect()
}

#[test]
fn evaluation_interpolates_and_the_derivative_is_analytic() {
    let c = YarnCurve::open(helix(9, 1.0)).unwrap();
    for (i, p) in c.points.iter().enumerate() {
        assert!(distance(c.point(i as f64), *p) < 1e-14);
    }
    let h = 1e-6;
    for k in 0..40 {
        let u = 0.013 + k as f64 * 0.19;
        let fd = vec3::scale(vec3::sub(c.point(u + h), c.point(u - h)), 0.5 / h);
        assert!(distance(fd, c.derivative(u)) < 1e-7, "u = {u}");
        let fd2 = vec3::scale(vec3::sub(c.derivative(u + h), c.derivative(u - h)), 0.5 / h);
        assert!(distance(fd2, c.second_derivative(u)) < 1e-6, "u = {u}");
    }
}

#[test]
fn straight_uniform_curve_has_exact_length_coordinates() {
    let pts: Vec<V3> = (0..6).map(|i| [0.25 * i as f64, 0.0, 0.0]).collect();
    let c = YarnCurve::open(pts).unwrap();
    assert!((c.length() - 1.25).abs() < 1e-14);
    for k in 0..=50 {
        let u = k as f64 * 0.1;
        assert!((c.length_coord(u) - 0.25 * u).abs() < 1e-14);
        assert!((c.param_at_length_coord(0.25 * u).unwrap() - u).abs() < 1e-12);
    }
}

#[test]
fn arc_length_of_a_catmull_rom_helix_matches_dense_chords() {
    let c = YarnCurve::open(helix(13, 1.5)).unwrap();
    let poly = c.sample_polyline(20_000);
    let chords: f64 = poly.windows(2).map(|w| distance(w[0], w[1])).sum();
    // Chord sums converge as O(h²): at 2·10⁴ chords per segment the gap is ~1e-10.
    assert!((c.length() - chords).abs() / chords < 1e-9, "{} vs {chords}", c.length());
    let half = c.arc_length(0.0, 6.3);
    assert!((half + c.arc_length(6.3, 12.0) - c.length()).abs() < 1e-12);
    // z(u) interpolates the control points' arc lengths; its inverse is exact.
    for k in 0..25 {
        let z = c.length() * k as f64 / 24.0;
        let u = c.param_at_length_coord(z).unwrap();
        assert!((c.length_coord(u) - z).abs() < 1e-12, "{z}");
    }
}

#[test]
fn closed_and_periodic_curves_wrap() {
    let tri = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let c = YarnCurve::closed(tri).unwrap();
    assert_eq!(c.segment_count(), 3);
    for k in 0..30 {
        let u = k as f64 * 0.1;
        assert!(distance(c.point(u), c.point(u + 3.0)) < 1e-14);
        assert!(vec3::is_finite(c.tangent(u)) && (length(c.tangent(u)) - 1.0).abs() < 1e-12);
    }
    assert!((c.length_coord(3.0) - c.length_wrap).abs() < 1e-14);
    let course = YarnCurve::periodic(
        vec![[0.0, 0.0, 0.0], [0.3, 0.2, 0.0], [0.6, -0.1, 0.1], [0.8, 0.0, 0.0]],
        [1.0, 0.0, 0.0],
    )
    .unwrap();
    for k in 0..40 {
        let u = -2.0 + k as f64 * 0.173;
        let a = vec3::add(course.point(u), [1.0, 0.0, 0.0]);
        assert!(distance(a, course.point(u + 4.0)) < 1e-14);
        assert!(
            (course.length_coord(u) + course.length_wrap - course.length_coord(u + 4.0)).abs()
                < 1e-13
        );
        let back = course.param_at_length_coord(course.length_coord(u)).unwrap();
        assert!((back - u).abs() < 1e-10, "{u} → {back}");
    }
}

#[test]
fn coincident_points_give_finite_tangents_and_degenerate_curves_are_refused() {
    let pts = vec![
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 1.0, 0.0],
    ];
    let c = YarnCurve::open(pts).unwrap();
    for k in 0..=60 {
        let u = k as f64 * 0.1;
        let t = c.tangent(u);
        assert!(vec3::is_finite(t) && (length(t) - 1.0).abs() < 1e-12, "u = {u}: {t:?}");
        assert!(vec3::is_finite(c.point(u)));
    }
    // The zero-length segment 3 → 4 (all four window points equal) uses the chord onwards.
    let t = c.tangent(3.5);
    assert!((t[0] - 2f64.sqrt() / 2.0).abs() < 1e-12 && (t[1] - 2f64.sqrt() / 2.0).abs() < 1e-12);
    assert_eq!(c.segment_length(3), 0.0);
    let e = YarnCurve::open(vec![[1.0, 2.0, 3.0]; 4]).unwrap_err().to_string();
    assert!(e.contains("coincide"), "{e}");
    let e = YarnCurve::closed(vec![[0.0; 3], [1.0, 0.0, 0.0]]).unwrap_err().to_string();
    assert!(e.contains("at least 3"), "{e}");
    let e = YarnCurve::open(vec![[0.0; 3], [f64::NAN, 0.0, 0.0]]).unwrap_err().to_string();
    assert!(e.contains("control point 1"), "{e}");
    let mut bad = c.clone();
    bad.length_coords[2] = -1.0;
    let set = YarnSet { curves: vec![c.clone(), bad], period: None };
    let e = set.validate().unwrap_err().to_string();
    assert!(e.contains("curve 1, control point 2"), "{e}");
}
