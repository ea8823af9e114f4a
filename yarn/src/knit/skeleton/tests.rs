//! Skeleton checks: C¹ across cells, exact periodicity, the minimum centre-line distance
//! between courses (reported per chart, by [`crate::knit::knot::min_clearance`]), frame
//! continuity along the courses.

use super::*;
use crate::knit::chart::Chart;
use crate::knit::knot::min_clearance;

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
        let d = min_clearance(&chen_skeleton(&mesh, &p).unwrap(), mesh.lattice, r, 24).distance / r;
        let d6 = min_clearance(&chen_skeleton(&mesh, &chen_only).unwrap(), mesh.lattice, r, 24)
            .distance
            / r;
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
