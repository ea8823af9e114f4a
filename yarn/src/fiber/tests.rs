//! Generator checks: KS of the radii against R·p(R), pitches and ply distance on a straight
//! yarn, migration bounds and period, flyaway counts (Poisson), thread-count determinism and
//! exact periodicity of periodic courses.

use super::*;
use crate::curve::{YarnCurve, YarnSet};
use crate::frame::CurveFrames;
use crate::params::YarnParams;
use crate::quad;
use crate::stats::{ks_p_value, ks_statistic};
use crate::vec3::{self, V3};
use std::f64::consts::TAU;

/// A straight yarn along +x from 0 to `length`, surface normal +z (so N = z, B = −y).
fn straight(length: f64, n: usize) -> YarnCurve {
    let pts: Vec<V3> = (0..=n).map(|i| [length * i as f64 / n as f64, 0.0, 0.0]).collect();
    YarnCurve::open(pts).unwrap().with_normals(vec![[0.0, 0.0, 1.0]; n + 1]).unwrap()
}

/// Slope of a least-squares line through `(x, y)`.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

fn unwrap(angles: &mut [f64]) {
    for i in 1..angles.len() {
        let d = angles[i] - angles[i - 1];
        angles[i] -= TAU * (d / TAU).round();
    }
}

#[test]
fn sampled_radii_follow_r_times_p_of_r() {
    let mut p = YarnParams::preset("cotton-2ply").unwrap();
    p.ply_count = 1;
    p.fibers_per_ply = 10_000;
    let t = FiberTable::new(&p, 42, 0);
    let r: Vec<f64> = t.fibers.iter().map(|f| f.r).collect();
    let norm = quad::adaptive(0.0, p.r_max, 1e-14, |x| x * p.density_p(x));
    let cdf =
        |x: f64| quad::adaptive(0.0, x.clamp(0.0, p.r_max), 1e-14, |s| s * p.density_p(s)) / norm;
    let d = ks_statistic(&r, cdf);
    let pv = ks_p_value(d, r.len());
    eprintln!("KS of 10⁴ radii against R·p(R): D = {d:.5}, p = {pv:.3}");
    assert!(pv > 0.01, "p = {pv}");
    assert!(r.windows(2).all(|w| w[0] <= w[1]), "sorted by R_i");
    assert_eq!(t.fibers.iter().filter(|f| f.core).count(), 4000);
}

#[test]
fn twist_pitches_ply_distance_and_migration_are_exact_on_a_straight_yarn() {
    let mut p = YarnParams::preset("fleece-3ply").unwrap();
    p.hair_density = 0.0;
    p.loop_density = 0.0;
    let curve = straight(0.05, 50);
    let frames = CurveFrames::new(&curve, 8);
    let mut table = FiberTable::new(&p, 7, 0);
    table.fibers[0].r = 0.0; // a fiber on the ply centre line of ply 0
    let model = FiberModel { params: &p, table: &table, twist: EffectiveTwist::nominal(&p) };
    let (mut zs, mut ply_a, mut fib_a) = (vec![], vec![], vec![]);
    let fiber = 17;
    let f = *table.fiber(0, fiber);
    for k in 0..=4000 {
        let u = 50.0 * k as f64 / 4000.0;
        let yp = YarnPoint::at(&curve, &frames, u);
        let centre = model.point(&yp, 0, 0);
        let d = vec3::sub(centre, yp.position);
        let (a, b) = (vec3::dot(d, yp.frame.n), vec3::dot(d, yp.frame.b));
        assert!(((a * a + b * b).sqrt() / p.ply_center_distance - 1.0).abs() < 1e-12);
        zs.push(yp.z);
        ply_a.push(b.atan2(a));
        // The fiber in its ply frame, normalised by the ellipse.
        let q = vec3::sub(model.point(&yp, 0, fiber), yp.position);
        let (qa, qb) = (vec3::dot(q, yp.frame.n) - a, vec3::dot(q, yp.frame.b) - b);
        let phi = b.atan2(a);
        let (x, y) = (qa * phi.cos() + qb * phi.sin(), -qa * phi.sin() + qb * phi.cos());
        let (xn, yn) = (x / p.ply_ellipse_n, y / p.ply_ellipse_b);
        fib_a.push(yn.atan2(xn));
        let r = (xn * xn + yn * yn).sqrt();
        let tol = 1e-12 * f.r.max(1e-3);
        assert!(r >= p.rho_min * f.r - tol && r <= p.rho_max * f.r + tol, "r = {r}");
        // Period α/s of the migration.
        let later = model.migration_radius(yp.z + p.fiber_pitch.abs() / p.migration_rate, 0, fiber);
        assert!((later - model.migration_radius(yp.z, 0, fiber)).abs() < 1e-12);
    }
    unwrap(&mut ply_a);
    unwrap(&mut fib_a);
    let ply_pitch = TAU / slope(&zs, &ply_a);
    let fib_pitch = TAU / slope(&zs, &fib_a);
    let (e1, e2) = ((ply_pitch / p.ply_pitch - 1.0).abs(), (fib_pitch / p.fiber_pitch - 1.0).abs());
    eprintln!(
        "measured pitches: ply {ply_pitch:.9e} (rel. error {e1:.1e}), fiber {fib_pitch:.9e} ({e2:.1e})"
    );
    assert!(e1 < 1e-6 && e2 < 1e-6);
}

#[test]
fn flyaway_counts_match_density_times_length() {
    let p = YarnParams::preset("cotton-2ply").unwrap();
    let len = 0.2;
    let set = YarnSet::new(vec![straight(len, 40)], None).unwrap();
    let fib = generate_fibers(&set, std::slice::from_ref(&p), &GenOptions::default()).unwrap();
    for (what, got, density) in
        [("hairs", fib.hair_count(), p.hair_density), ("loops", fib.loop_count, p.loop_density)]
    {
        let expect = density * len * p.ply_count as f64;
        let z = (got as f64 - expect) / expect.sqrt();
        eprintln!("{what}: {got} against {expect:.0} (z = {z:+.2})");
        assert!(z.abs() < 3.0, "{what}: {got} vs {expect}");
    }
    assert!(fib.points.iter().all(|q| q.iter().all(|x| x.is_finite())));
}

#[test]
fn output_is_bit_identical_for_any_thread_count() {
    let p = YarnParams::preset("fine-2ply").unwrap();
    let pts: Vec<V3> = (0..8).map(|i| [0.002 * i as f64, 0.0005 * (i as f64).sin(), 0.0]).collect();
    let set = YarnSet::new(
        vec![YarnCurve::open(pts.clone()).unwrap(), YarnCurve::closed(pts[..5].to_vec()).unwrap()],
        None,
    )
    .unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            generate_fibers(&set, std::slice::from_ref(&p), &GenOptions::default()).unwrap()
        })
    };
    let (a, b, c) = (run(1), run(2), run(3));
    let bits = |f: &Fibers| f.points.iter().flat_map(|q| q.map(f32::to_bits)).collect::<Vec<u32>>();
    assert!(a.hair_count() > 0 && a.fiber_count() > 200);
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(bits(&a), bits(&c));
    assert_eq!(a, b);
}

#[test]
fn periodic_courses_give_exactly_periodic_fibers() {
    let p = YarnParams::preset("cotton-2ply").unwrap();
    let px = 0.012;
    let pts: Vec<V3> = (0..6)
        .map(|i| {
            let a = TAU * i as f64 / 6.0;
            [px * i as f64 / 6.0, 0.0008 * a.sin(), 0.0004 * (2.0 * a).cos()]
        })
        .collect();
    let curve = YarnCurve::periodic(pts, [px, 0.0, 0.0]).unwrap();
    let frames = CurveFrames::new(&curve, 16);
    let table = FiberTable::new(&p, 3, 0);
    let twist = EffectiveTwist::for_curve(&p, &curve);
    let change = twist.max_relative_change(&p);
    eprintln!(
        "periodic course of {:.3} mm: pitch change {:.2} %",
        1e3 * curve.length_wrap,
        100.0 * change
    );
    assert!(
        change <= p.fiber_pitch.abs().max(p.ply_pitch.abs()) / (2.0 * curve.length_wrap) + 1e-12
    );
    let model = FiberModel { params: &p, table: &table, twist };
    let n = curve.segment_count() as f64;
    let slots = twist.slots_per_wrap.unwrap() as i64;
    for f in 0..p.fibers_per_ply as usize {
        for k in -3..3 {
            assert_eq!(model.period_kind(1, f, k), model.period_kind(1, f, k + slots));
        }
    }
    let mut worst: f64 = 0.0;
    for j in 0..200 {
        let u = j as f64 * 0.0301;
        let (a, b) = (YarnPoint::at(&curve, &frames, u), YarnPoint::at(&curve, &frames, u + n));
        for (ply, f) in [(0, 0), (1, 5), (0, 79), (1, 40)] {
            let d = vec3::sub(
                vec3::add(model.point(&a, ply, f), [px, 0.0, 0.0]),
                model.point(&b, ply, f),
            );
            worst = worst.max(vec3::length(d) / px);
        }
    }
    eprintln!("periodicity: worst |fiber(u + period) − fiber(u) − shift| / px = {worst:.2e}");
    assert!(worst < 1e-9);
    let set = YarnSet::new(vec![curve], Some([px, 0.01])).unwrap();
    let fib = generate_fibers(&set, std::slice::from_ref(&p), &GenOptions::default()).unwrap();
    for k in 0..fib.fiber_count() {
        if fib.kind[k] == FiberKind::Hair {
            continue;
        }
        let pts = fib.fiber_points(k);
        let (first, last) = (pts[0], pts[pts.len() - 1]);
        assert!(
            ((first[0] + px as f32) - last[0]).abs() < 1e-6 && (first[1] - last[1]).abs() < 1e-6
        );
    }
}

#[test]
fn vanishing_fibers_and_tiny_loops_stay_finite() {
    let mut p = YarnParams::preset("fleece-3ply").unwrap();
    p.fiber_radius = 0.0;
    p.rho_min = p.rho_max;
    p.migration_rate = 0.0;
    let tri =
        YarnCurve::closed(vec![[0.0, 0.0, 0.0], [0.004, 0.0, 0.0], [0.002, 0.003, 0.001]]).unwrap();
    let set = YarnSet::new(vec![tri], None).unwrap();
    let fib = generate_fibers(&set, std::slice::from_ref(&p), &GenOptions::default()).unwrap();
    assert!(fib.points.iter().all(|q| q.iter().all(|x| x.is_finite())));
    assert!(fib.radii.iter().all(|r| *r == 0.0));
    assert_eq!(fib.offsets.len(), fib.fiber_count() + 1);
    // An empty set gives no fibers (DESIGN §4.4).
    let empty = generate_fibers(&YarnSet::default(), &[], &GenOptions::default()).unwrap();
    assert_eq!((empty.fiber_count(), empty.points.len()), (0, 0));
    let mut bad = p.clone();
    bad.fibers_per_ply = 5000;
    let big = GenOptions { max_points: 10_000, ..GenOptions::default() };
    let e = generate_fibers(&set, &[bad], &big).unwrap_err().to_string();
    assert!(e.contains("limit"), "{e}");
    // A huge samples_per_turn is refused before its samples are allocated (it was an
    // out-of-memory kill: ~10^10 yarn samples a curve).
    let dense = GenOptions { samples_per_turn: u32::MAX, ..GenOptions::default() };
    let e = generate_fibers(&set, std::slice::from_ref(&p), &dense).unwrap_err().to_string();
    assert!(e.contains("curve 0") && e.contains("samples_per_turn"), "{e}");
}
