use super::*;
use crate::settings::{BakeSettings, CoreMigration, CoreSettings};

fn cotton() -> YarnParams {
    YarnParams::preset("cotton-2ply").unwrap()
}

/// The texture, the scene it was cast from and its half-width.
fn bake(p: &YarnParams) -> CoreTexture {
    CoreTexture::bake(p, 1, &BakeSettings::default().core).unwrap()
}

/// Coverage IoU and mean normal angle (degrees) of the core strip + texture against a
/// direct orthographic ray cast of the explicit real-space core fibers, at eye azimuth `psi`.
fn screw_metrics(
    p: &YarnParams,
    tex: &CoreTexture,
    migration: CoreMigration,
    psi: f64,
    mode: CoreTexcoord,
) -> (f64, f64) {
    let (w_px, h_px, ss) = (tex.width, tex.height, 2usize);
    let alpha = p.fiber_pitch;
    let margin = 0.05 * alpha.abs();
    let z_range = [alpha.min(0.0) - margin, alpha.max(0.0) + margin];
    let fib = core_fibers(p, 1, tex.core_fibers, migration, false, z_range, 96);
    let scene = FiberScene::new(&fib, &SceneOptions::default()).unwrap();
    let e = [psi.cos(), psi.sin(), 0.0];
    let w = [-psi.sin(), psi.cos(), 0.0];
    let half = tex.view(0.0, e, mode).half_width;
    let reach = 4.0 * tex.half_width_circ;
    let (mut inter, mut union, mut ang, mut n_ang) = (0.0, 0.0, 0.0, 0usize);
    for j in 0..h_px {
        for i in 0..w_px {
            let (mut hits, mut nsum) = (0usize, [0.0; 3]);
            for b in 0..ss {
                for a in 0..ss {
                    let z = (i as f64 + (a as f64 + 0.5) / ss as f64) / w_px as f64 * alpha;
                    let v = (j as f64 + (b as f64 + 0.5) / ss as f64) / h_px as f64;
                    let s = (2.0 * v - 1.0) * half;
                    let o = vec3::add_scaled(vec3::add_scaled([0.0, 0.0, z], w, s), e, reach);
                    if let Some(hit) = scene.intersect(o, vec3::scale(e, -1.0), 2.0 * reach, None)
                        && let yarn_ref::geometry::scene::HitKind::Fiber { segment, v } = hit.kind
                    {
                        hits += 1;
                        nsum = vec3::add(nsum, scene.surface(segment, v, hit.position).normal);
                    }
                }
            }
            let a_ref = hits as f64 / (ss * ss) as f64;
            let z = (i as f64 + 0.5) / w_px as f64 * alpha;
            let view = tex.view(TAU * z / alpha, e, mode);
            let surf = tex.lookup(&view, (j as f64 + 0.5) / h_px as f64);
            inter += a_ref.min(surf.alpha);
            union += a_ref.max(surf.alpha);
            if a_ref > 0.5 && surf.alpha > 0.5 {
                let n = vec3::normalize(nsum).unwrap();
                ang += vec3::dot(n, surf.normal).clamp(-1.0, 1.0).acos();
                n_ang += 1;
            }
        }
    }
    (inter / union.max(1e-300), (ang / n_ang.max(1) as f64).to_degrees())
}

#[test]
fn column_u0_equals_column_u1() {
    let p = cotton();
    let s = BakeSettings::default().core;
    let tex = bake(&p);
    // Cast the column that starts at u = 1 exactly as the bake casts column 0.
    let alpha = p.fiber_pitch;
    let margin = 0.05 * alpha.abs() + 4.0 * p.fiber_radius;
    let fib = core_fibers(
        &p,
        1,
        tex.core_fibers,
        s.migration,
        true,
        [alpha.min(0.0) - margin, alpha.max(0.0) + 2.0 * alpha.abs()],
        s.samples_per_turn,
    );
    let scene = FiberScene::new(&fib, &SceneOptions::default()).unwrap();
    let h = tex.half_width_circ;
    let mut worst: f64 = 0.0;
    for j in 0..tex.height {
        let mut acc = Acc::default();
        for b in 0..s.supersample {
            let v = (j as f64 + (b as f64 + 0.5) / s.supersample as f64) / tex.height as f64;
            for a in 0..s.supersample {
                let u = 1.0 + ((a as f64 + 0.5) / s.supersample as f64) / tex.width as f64;
                cast(&scene, (2.0 * v - 1.0) * h, u * alpha, 2.0 * h, &mut acc);
            }
        }
        let k = 4 * j * tex.width;
        let a0 = tex.tex_a[k] as f64;
        let a1 = acc.hits as f64 / (s.supersample * s.supersample) as f64;
        worst = worst.max((a0 - a1).abs());
        if acc.hits > 0 {
            let hh = acc.height / acc.hits as f64 / h;
            worst = worst.max((hh - tex.tex_a[k + 1] as f64).abs());
            let n = vec3::normalize(acc.normal).unwrap();
            worst = worst.max((n[0] - tex.tex_a[k + 2] as f64).abs());
            worst = worst.max((n[2] - tex.tex_a[k + 3] as f64).abs());
        }
    }
    eprintln!("tiling: worst channel difference between column u=0 and u=1: {worst:.2e}");
    assert!(worst < 1e-3, "{worst}");
    // The lookup repeats in u.
    for v in [0.1, 0.5, 0.77] {
        assert_eq!(tex.sample(0.0, v), tex.sample(1.0, v));
    }
}

#[test]
fn screw_symmetry_iou_and_normals_beat_eq3() {
    let p = cotton();
    let tex = bake(&p);
    let mut rows = Vec::new();
    for mode in [
        CoreTexcoord::ScrewSymmetric,
        CoreTexcoord::ScrewSymmetricUncorrected,
        CoreTexcoord::PaperEq3,
    ] {
        let (mut iou_min, mut iou_sum, mut ang_max, mut ang_sum) = (1.0f64, 0.0, 0.0f64, 0.0);
        for k in 0..8 {
            let psi = TAU * k as f64 / 8.0 + 0.1;
            let (iou, ang) = screw_metrics(&p, &tex, CoreMigration::MeanRadius, psi, mode);
            iou_min = iou_min.min(iou);
            iou_sum += iou;
            ang_max = ang_max.max(ang);
            ang_sum += ang;
        }
        eprintln!(
            "{mode:?}: IoU min {iou_min:.3} mean {:.3}; normal angle mean {:.2}° max {ang_max:.2}°",
            iou_sum / 8.0,
            ang_sum / 8.0
        );
        rows.push((iou_min, iou_sum / 8.0, ang_max, ang_sum / 8.0));
    }
    // What migration costs (reported): the paper's s = 1 core against its own fibers, and
    // our mean-radius core against the s = 1 fibers it stands in for.
    let s1 = CoreSettings { migration: CoreMigration::PaperS1, ..BakeSettings::default().core };
    let tex_s1 = CoreTexture::bake(&p, 1, &s1).unwrap();
    for (label, t, fibers) in [
        ("s = 1 core vs s = 1 fibers", &tex_s1, CoreMigration::PaperS1),
        ("mean-radius core vs s = 1 fibers", &tex, CoreMigration::PaperS1),
    ] {
        let m: Vec<(f64, f64)> = (0..8)
            .map(|k| {
                screw_metrics(
                    &p,
                    t,
                    fibers,
                    TAU * k as f64 / 8.0 + 0.1,
                    CoreTexcoord::ScrewSymmetric,
                )
            })
            .collect();
        let iou_min = m.iter().map(|x| x.0).fold(1.0, f64::min);
        let ang = m.iter().map(|x| x.1).sum::<f64>() / 8.0;
        eprintln!("{label}: IoU min {iou_min:.3}, normal angle mean {ang:.2}°");
    }
    let (ours, eq3) = (rows[0], rows[2]);
    assert!(ours.0 >= 0.85, "IoU {}", ours.0);
    assert!(ours.2 <= 15.0, "normal angle {}", ours.2);
    assert!(eq3.1 < ours.1 - 0.05, "eq. 3 IoU {} is not worse than ours {}", eq3.1, ours.1);
}

#[test]
fn circular_ply_is_exact_up_to_filtering() {
    // e_N = e_B: the ellipse correction is the identity; only texel filtering remains
    // (a texel is 1/64 of the core, a fiber diameter ≈ 4 texels).
    let mut p = cotton();
    p.ply_ellipse_b = p.ply_ellipse_n;
    let tex = bake(&p);
    for k in 0..3 {
        let psi = TAU * k as f64 / 3.0 + 0.3;
        let (iou, ang) =
            screw_metrics(&p, &tex, CoreMigration::MeanRadius, psi, CoreTexcoord::ScrewSymmetric);
        eprintln!("circular ply, psi {psi:.2}: IoU {iou:.3}, normal angle {ang:.2}°");
        assert!(iou > 0.98 && ang < 4.0, "psi {psi}: IoU {iou}, angle {ang}");
    }
}

#[test]
fn eye_along_the_ply_and_empty_cores_stay_finite() {
    let p = cotton();
    let s = CoreSettings { width: 32, height: 8, supersample: 2, ..BakeSettings::default().core };
    let tex = CoreTexture::bake(&p, 1, &s).unwrap();
    for mode in [
        CoreTexcoord::ScrewSymmetric,
        CoreTexcoord::ScrewSymmetricUncorrected,
        CoreTexcoord::PaperEq3,
    ] {
        // Looking exactly along the ply: the strip is edge-on, any azimuth is as good.
        let view = tex.view(1.0, [0.0, 0.0, 1.0], mode);
        let surf = tex.lookup(&view, 0.3);
        assert!(view.u.is_finite() && view.half_width > 0.0, "{mode:?} {view:?}");
        assert!(surf.normal.iter().chain(&surf.direction).all(|x| x.is_finite()), "{surf:?}");
    }
    // [W19 eq. 3] in metres: the θ term is ~1e-6 θ, so u hardly moves along the yarn.
    let du = u_paper_eq3(TAU, p.ply_pitch, p.fiber_pitch, 0.0)
        - u_paper_eq3(0.0, p.ply_pitch, p.fiber_pitch, 0.0);
    let du = du.rem_euclid(1.0);
    assert!(du.min(1.0 - du) < 1e-5, "{du}");
    let none = CoreSettings { core_fibers: Some(0), ..s };
    let empty = CoreTexture::bake(&p, 1, &none).unwrap();
    let surf = empty.lookup(&empty.view(0.5, [1.0, 0.0, 0.0], CoreTexcoord::ScrewSymmetric), 0.5);
    assert_eq!(surf.alpha, 0.0);
    assert!(surf.normal.iter().all(|x| x.is_finite()));
}
