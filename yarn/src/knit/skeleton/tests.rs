//! Skeleton checks: C¹ across cells, exact periodicity, the minimum centre-line distance
//! between courses (reported per chart), frame continuity along the courses.

use super::*;
use crate::knit::chart::Chart;

/// Smallest distance between centre lines of different courses (periodic images in both
/// directions included), by dense sampling and local refinement.
pub(crate) fn min_course_distance(set: &YarnSet, lattice: Option<[V3; 2]>) -> f64 {
    let per = 24;
    let samples: Vec<Vec<(f64, V3)>> = set
        .curves
        .iter()
        .map(|c| {
            let m = c.segment_count() * per;
            (0..=m)
                .map(|k| {
                    let u = k as f64 / per as f64;
                    (u, c.point(u))
                })
                .collect()
        })
        .collect();
    let shifts: Vec<(i64, i64)> = match lattice {
        Some(_) => (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))).collect(),
        None => vec![(0, 0)],
    };
    let mut best = (f64::INFINITY, 0, 0, 0.0, 0.0, [0.0; 3]);
    for (i, a) in samples.iter().enumerate() {
        for (j, b) in samples.iter().enumerate() {
            for &(sx, sy) in &shifts {
                if i == j && sy == 0 {
                    continue; // the same course (its x-images are the same yarn)
                }
                let off = lattice.map_or([0.0; 3], |l| {
                    vec3::add(vec3::scale(l[0], sx as f64), vec3::scale(l[1], sy as f64))
                });
                for (ua, pa) in a {
                    for (ub, pb) in b {
                        let d = vec3::distance(*pa, vec3::add(*pb, off));
                        if d < best.0 {
                            best = (d, i, j, *ua, *ub, off);
                        }
                    }
                }
            }
        }
    }
    // Refine around the best pair by coordinate descent on (ua, ub).
    let (mut d, i, j, mut ua, mut ub, off) = best;
    let (ca, cb) = (&set.curves[i], &set.curves[j]);
    let dist = |x: f64, y: f64| vec3::distance(ca.point(x), vec3::add(cb.point(y), off));
    let mut step = 1.0 / per as f64;
    while step > 1e-9 {
        let mut moved = false;
        for (dx, dy) in [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)] {
            let e = dist(ua + dx, ub + dy);
            if e < d {
                d = e;
                ua += dx;
                ub += dy;
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    if std::env::var("SKEL_DEBUG").is_ok() {
        eprintln!(
            "closest: course {i} u {ua:.3} {:?} / course {j} u {ub:.3} {:?}",
            ca.point(ua),
            vec3::add(cb.point(ub), off)
        );
    }
    d
}

#[test]
fn skeleton_is_c1_across_cells_and_exactly_periodic() {
    let r = 0.5e-3;
    let p = SkeletonParams::new(r);
    let (sw, sc) = p.default_spacing();
    for name in ["stockinette", "rib2x2", "cable2x2", "garter"] {
        let chart = Chart::builtin(name).unwrap();
        let mesh = StitchMesh::flat(&chart, chart.width * 2, chart.height, sw, sc).unwrap();
        let set = chen_skeleton(&mesh, &p).unwrap();
        assert_eq!(set.curves.len(), mesh.courses);
        assert_eq!(set.period, Some([chart.width as f64 * 2.0 * sw, chart.height as f64 * sc]));
        let mut worst: f64 = 0.0;
        for c in &set.curves {
            let n = c.segment_count() as isize;
            for s in 0..n {
                let left = c.segment_derivative(s - 1, 1.0);
                let right = c.segment_derivative(s, 0.0);
                let scale = vec3::length(right).max(1e-300);
                worst = worst.max(vec3::distance(left, right) / scale);
                assert!(
                    vec3::distance(c.segment_point(s - 1, 1.0), c.segment_point(s, 0.0)) < 1e-15
                );
            }
            // Exact periodicity along the course.
            for k in 0..20 {
                let u = 0.37 * k as f64;
                let a = vec3::add(c.point(u), mesh.lattice.unwrap()[0]);
                assert!(vec3::distance(a, c.point(u + n as f64)) < 1e-15);
            }
        }
        assert!(worst < 1e-9, "{name}: tangent jump {worst}");
        // Periodic across courses: course c + H on the same mesh is course c shifted.
        let twice = StitchMesh::flat(&chart, chart.width * 2, 2 * chart.height, sw, sc).unwrap();
        let set2 = chen_skeleton(&twice, &p).unwrap();
        let l1 = [0.0, chart.height as f64 * sc, 0.0];
        for c in 0..chart.height {
            let (a, b) = (&set2.curves[c], &set2.curves[c + chart.height]);
            for k in 0..=40 {
                let u = 0.3 * k as f64;
                assert!(vec3::distance(vec3::add(a.point(u), l1), b.point(u)) < 1e-15, "{name}");
            }
        }
    }
}

#[test]
fn courses_keep_their_distance() {
    let r = 0.5e-3;
    let p = SkeletonParams::new(r);
    let (sw, sc) = p.default_spacing();
    let chen_only = SkeletonParams { interlock_points: false, ..p.clone() };
    for name in
        ["stockinette", "reverse-stockinette", "garter", "rib1x1", "rib2x2", "seed", "cable2x2"]
    {
        let chart = Chart::builtin(name).unwrap();
        let mesh = StitchMesh::flat(&chart, chart.width, chart.height.max(2), sw, sc).unwrap();
        let d = min_course_distance(&chen_skeleton(&mesh, &p).unwrap(), mesh.lattice) / r;
        let d6 = min_course_distance(&chen_skeleton(&mesh, &chen_only).unwrap(), mesh.lattice) / r;
        eprintln!(
            "min centre-line distance between courses, {name}: {d:.3} r (six Chen points alone: {d6:.3} r)"
        );
        if name != "cable2x2" {
            assert!(d >= 1.6, "{name}: {d} r");
        }
    }
}

#[test]
fn frames_stay_continuous_along_skeleton_courses() {
    let p = SkeletonParams::new(0.5e-3);
    let (sw, sc) = p.default_spacing();
    let mesh = StitchMesh::flat(&Chart::builtin("cable2x2").unwrap(), 8, 4, sw, sc).unwrap();
    let set = chen_skeleton(&mesh, &p).unwrap();
    for c in &set.curves {
        let f = crate::frame::CurveFrames::new(c, 16);
        let m = c.segment_count() * 64;
        let mut prev = f.frame_at(c, 0.0);
        let mut worst: f64 = 0.0;
        for k in 1..=m {
            let fr = f.frame_at(c, k as f64 / 64.0);
            worst = worst.max(vec3::dot(prev.n, fr.n).clamp(-1.0, 1.0).acos());
            prev = fr;
        }
        assert!(worst < 0.2, "frame step {worst} rad");
    }
}
