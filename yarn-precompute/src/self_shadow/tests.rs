use super::*;
use crate::settings::{BakeSettings, ShadowSettings};
use crate::sigma::{SigmaField, field_for};
use yarn::YarnParams;
use yarn::curve::{YarnCurve, YarnSet};
use yarn::fiber::{GenOptions, generate_fibers};
use yarn::hash::KeyRng;
use yarn::vec3;
use yarn_ref::{FiberScene, SceneOptions};

fn volume(p: &YarnParams) -> SelfShadowVolume {
    let s = BakeSettings::default();
    SelfShadowVolume::bake(&field_for(p, &s).unwrap(), p.ply_count as usize, &s.shadow)
}

#[test]
fn slice_at_two_pi_over_n_equals_slice_zero() {
    for name in ["cotton-2ply", "fleece-3ply"] {
        let p = YarnParams::preset(name).unwrap();
        let v = volume(&p);
        let last = v.slices - 1;
        let mut worst: f64 = 0.0;
        for j in 0..v.res {
            for i in 0..v.res {
                let (a, b) = (v.texel(0, j, i), v.texel(last, j, i));
                worst = worst.max(((-a).exp() - (-b).exp()).abs());
            }
        }
        let d_max = v.depth.iter().copied().fold(0.0f32, f32::max);
        eprintln!("{name}: max optical depth {d_max:.2}, |T(2π/n) − T(0)| ≤ {worst:.1e}");
        assert!(worst < 1e-3 && d_max > 1.0, "{name}: {worst}, {d_max}");
        let g = TAU / p.ply_count as f64;
        let (x, y) = (0.3 * v.half_width, -0.1 * v.half_width);
        // Turning the point and the light together by 2π/n_ply changes nothing.
        let (sg, cg) = g.sin_cos();
        let (xr, yr) = (cg * x - sg * y, sg * x + cg * y);
        let (t0, t1) = (v.transmittance(x, y, 0.4), v.transmittance(xr, yr, 0.4 + g));
        assert!((t0 - t1).abs() < 1e-3, "{t0} {t1}");
    }
}

#[test]
fn hard_cases_stay_finite() {
    let base = YarnParams::preset("cotton-2ply").unwrap();
    type Edit = fn(&mut YarnParams);
    let cases: [(&str, Edit); 4] = [
        ("r_f = 0", |p| p.fiber_radius = 0.0),
        ("rho_min = rho_max", |p| p.rho_min = p.rho_max),
        ("s = 0", |p| p.migration_rate = 0.0),
        ("n_ply = 1", |p| p.ply_count = 1),
    ];
    for (name, edit) in cases {
        let mut p = base.clone();
        edit(&mut p);
        let v = volume(&p);
        assert!(v.depth.iter().all(|d| d.is_finite() && *d >= 0.0), "{name}");
        for light in [[1.0, 0.0, 0.0], [0.3, -0.2, 0.9], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]] {
            let t = v.transmittance_for_light(0.1 * v.half_width, 0.0, light);
            assert!((0.0..=1.0).contains(&t), "{name}: {t}");
            if p.fiber_radius == 0.0 {
                assert_eq!(t, 1.0, "{name}");
            }
        }
    }
    // Light exactly along the yarn: the azimuthal mean, between the extremes.
    let v = volume(&base);
    let q = (0.2 * v.half_width, 0.1 * v.half_width);
    let along = v.transmittance_for_light(q.0, q.1, [0.0, 0.0, 1.0]);
    let ts: Vec<f64> = (0..64).map(|k| v.transmittance(q.0, q.1, TAU * k as f64 / 64.0)).collect();
    let (lo, hi) = ts.iter().fold((1.0f64, 0.0f64), |(a, b), t| (a.min(*t), b.max(*t)));
    assert!(lo < along && along < hi, "{lo} {along} {hi}");
    let mean = ts.iter().sum::<f64>() / 64.0;
    assert!((along - mean).abs() < 0.02, "{along} vs {mean}");
}

/// One compared cell: elevation (deg), explicit unoccluded fraction, its standard error,
/// the texture's mean transmittance over the same rays.
struct Cell {
    elev_deg: f64,
    explicit: f64,
    se: f64,
    texture: f64,
}

/// Shadow rays from points of the cross-section (random length coordinate over one ply
/// twist, jittered inside one slice texel) to a light at relative angle γ and elevation
/// `e`, through the explicit fibers of a straight yarn, against the texture.
fn beer_lambert(p: &YarnParams, slices: usize, rays: usize, elevations: &[f64]) -> Vec<Cell> {
    // The texture describes the ensemble of yarns the density stands for; the explicit side
    // samples four realizations (seeds), and so does the density (a single realization
    // leaves its own outermost fibers in the symmetrised field: a 5 % shadow where the
    // explicit yarn of another seed has none).
    let seeds = [1u64, 2, 3, 4];
    let fields: Vec<SigmaField> = seeds
        .iter()
        .map(|&seed| {
            let s =
                BakeSettings { loops: false, seed, density_res: 256, ..BakeSettings::default() };
            field_for(p, &s).unwrap()
        })
        .collect();
    let h = fields.iter().map(|f| f.half_width).fold(0.0, f64::max);
    let field = SigmaField::from_fn(256, h, |x, y| {
        fields.iter().map(|f| f.at(x, y)).sum::<f64>() / fields.len() as f64
    });
    let shadow = ShadowSettings { slices, ..BakeSettings::default().shadow };
    let vol = SelfShadowVolume::bake(&field, p.ply_count as usize, &shadow);
    let r = p.yarn_radius();
    let twist = p.ply_pitch.abs();
    let margin = 4.0 * r * 3.0f64.sqrt() + 1e-3;
    let length = twist + 2.0 * margin;
    let pts: Vec<[f64; 3]> = (0..=8).map(|i| [0.0, 0.0, length * i as f64 / 8.0]).collect();
    let curve = YarnCurve::open(pts).unwrap().with_normals(vec![[1.0, 0.0, 0.0]; 9]).unwrap();
    let set = YarnSet::new(vec![curve], None).unwrap();
    let opts =
        GenOptions { hairs: false, loops: false, samples_per_turn: 48, ..GenOptions::default() };
    let scenes: Vec<FiberScene> = seeds
        .iter()
        .map(|&seed| {
            let opts = GenOptions { seed, ..opts.clone() };
            let fibers = generate_fibers(&set, std::slice::from_ref(p), &opts).unwrap();
            FiberScene::new(&fibers, &SceneOptions::default()).unwrap()
        })
        .collect();
    let gamma: f64 = 0.3; // between slices 1 and 2 of 16
    let (l, lp) = ([gamma.cos(), gamma.sin()], [-gamma.sin(), gamma.cos()]);
    let cell = 2.0 * vol.half_width / vol.res as f64;
    let mut out = Vec::new();
    for &elev_deg in elevations {
        let e = f64::to_radians(elev_deg);
        for (ci, (sc, tc)) in [-0.3, 0.1, 0.5]
            .iter()
            .flat_map(|s| [-0.4, 0.0, 0.4].map(|t| (s * r, t * r)))
            .enumerate()
        {
            let mut rng = KeyRng::new(&[7, elev_deg as u64, ci as u64]);
            let (mut free, mut tex) = (0usize, 0.0);
            for ray in 0..rays {
                let scene = &scenes[ray % scenes.len()];
                let [u1, u2, u3] = rng.uniform3();
                let (sq, tq) = (sc + (u1 - 0.5) * cell, tc + (u2 - 0.5) * cell);
                let q = [sq * l[0] + tq * lp[0], sq * l[1] + tq * lp[1]];
                tex += vol.transmittance(q[0], q[1], gamma);
                let z0 = margin + u3 * twist;
                let (st, ct) = (TAU * z0 / p.ply_pitch).sin_cos();
                let rot = |v: [f64; 2]| [ct * v[0] - st * v[1], st * v[0] + ct * v[1]];
                let (qy, ly) = (rot(q), rot(l));
                let d = vec3::normalize([-e.cos() * ly[0], -e.cos() * ly[1], e.sin()]).unwrap();
                if !scene.occluded([qy[0], qy[1], z0], d, 3.0 * r / e.cos(), None) {
                    free += 1;
                }
            }
            let n = rays as f64;
            let pf = free as f64 / n;
            let se = (pf * (1.0 - pf) / n).sqrt().max(0.5 / n);
            out.push(Cell { elev_deg, explicit: pf, se, texture: tex / n });
        }
    }
    out
}

/// cotton-2ply with 4× the fibers of ¼ the radius (the same σ, a quarter of the packing
/// fraction, where Beer–Lambert's independent-fiber assumption holds to ~2 %), no flyaways.
fn dilute_cotton(pitch_scale: f64) -> YarnParams {
    let mut p = YarnParams::preset("cotton-2ply").unwrap();
    p.fiber_radius /= 4.0;
    p.fibers_per_ply *= 4;
    p.hair_density = 0.0;
    p.loop_density = 0.0;
    p.ply_pitch *= pitch_scale;
    p.fiber_pitch *= pitch_scale;
    p
}

/// Prints every cell; counts the failures, but with `skip_rim` not among cells the texture
/// barely shadows (T ≥ 0.9). Known: with 16 slices (12° apart for two plies) a shadow ray
/// that grazes a ply's rim changes its depth faster in γ than the linear blend of two
/// slices follows (T = 0.918 against 1.000 measured); 32 slices bring it to 0.986.
fn check(cells: &[Cell], label: &str, skip_rim: bool) -> usize {
    let mut bad = 0;
    for c in cells {
        let tol = 4.0 * c.se + 0.03;
        let err = c.texture - c.explicit;
        let rim = skip_rim && c.texture >= 0.9;
        let flag = match (err.abs() > tol, rim) {
            (true, false) => {
                bad += 1;
                "  FAIL"
            }
            (true, true) => "  (rim, not asserted)",
            _ => "",
        };
        eprintln!(
            "{label} {:>2}°: explicit {:.3} ± {:.3}, texture {:.3}, error {err:+.3} (tol {tol:.3}){flag}",
            c.elev_deg, c.explicit, c.se, c.texture
        );
    }
    bad
}

#[test]
fn beer_lambert_matches_explicit_shadow_rays_at_three_elevations() {
    // Pitches ×32: the fibers run along the yarn and the plies turn < 10° along the
    // longest oblique shadow ray, the regime the slice describes exactly.
    let p = dilute_cotton(32.0);
    let el = [0.0, 30.0, 60.0];
    assert_eq!(check(&beer_lambert(&p, 16, 500, &el), "aligned, 16 slices", true), 0);
    assert_eq!(check(&beer_lambert(&p, 32, 500, &el), "aligned, 32 slices", false), 0);
}

#[test]
#[ignore = "measurement: 5·10⁵ rays, 3 yarns × 4 elevations; run with --ignored --nocapture"]
fn beer_lambert_measurement() {
    let el = [0.0, 30.0, 60.0, 80.0];
    let a = beer_lambert(&dilute_cotton(32.0), 32, 5000, &el);
    let b = beer_lambert(&dilute_cotton(1.0), 32, 5000, &el);
    let c = beer_lambert(&YarnParams::preset("cotton-2ply").unwrap(), 32, 5000, &el);
    eprintln!(
        "failures: aligned {}, preset pitches {}, preset packing {}",
        check(&a, "aligned", false),
        check(&b, "twisted", false),
        check(&c, "packed", false)
    );
}
