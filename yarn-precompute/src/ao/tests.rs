use super::*;
use crate::settings::BakeSettings;
use crate::sigma::field_for;
use yarn::YarnParams;
use yarn::density::{CrossSectionDensity, DensityOptions};
use yarn::fiber::{EffectiveTwist, FiberKind, FiberModel, FiberTable, Fibers};
use yarn::hash::KeyRng;
use yarn_ref::{FiberScene, SceneOptions};

fn small() -> AoSettings {
    AoSettings { res: 32, directions: 64, radial_bins: 16 }
}

#[test]
fn empty_density_gives_ao_one() {
    let mut p = YarnParams::preset("cotton-2ply").unwrap();
    p.fiber_radius = 0.0;
    let f = field_for(&p, &BakeSettings::default()).unwrap();
    let t = AoTexture::bake(&f.symmetrized(), &small(), 1);
    assert!(t.ao.iter().all(|a| *a == 1.0));
    let c = AoCubic::fit(&t, p.yarn_radius(), 16);
    assert!((c.eval(0.0) - 1.0).abs() < 1e-12 && (c.eval(1e-4) - 1.0).abs() < 1e-12, "{c:?}");
}

#[test]
fn radially_symmetric_density_gives_ao_non_decreasing_in_radius() {
    let (h, w, s0) = (1e-3, 3e-4, 8e3); // σ(r) = s0·exp(−r²/2w²), optical depth ~ 6 across
    let f = SigmaField::from_fn(64, h, |x, y| s0 * (-(x * x + y * y) / (2.0 * w * w)).exp());
    // Deterministic midpoint directions: AO(r) exactly as the bake computes it, no noise.
    let mut last = 0.0;
    for k in 0..=20 {
        let r = 0.9 * h * k as f64 / 20.0;
        let a = ao_point(&f, [r, 0.0], 256, |_| 0.5);
        assert!(a >= last - 1e-9, "AO({r}) = {a} < {last}");
        last = a;
    }
    // At the centre every direction crosses half the Gaussian: depth s0·w·√(π/2) ≈ 3.
    let centre = ao_point(&f, [0.0, 0.0], 256, |_| 0.5);
    let expect = (-s0 * w * (std::f64::consts::PI / 2.0).sqrt()).exp();
    assert!((centre - expect).abs() < 2e-3 * expect.max(1e-2) + 1e-3, "{centre} vs {expect}");
    assert!(last > centre + 0.5, "{last}");
    // The stratified texture's radial means too, up to its Monte-Carlo noise.
    let t = AoTexture::bake(&f, &small(), 3);
    let mean = t.radial_mean(h, 8);
    for k in 1..mean.len() {
        assert!(mean[k].0 >= mean[k - 1].0 - 0.01, "{mean:?}");
    }
    let c = AoCubic::fit(&t, h, 16);
    eprintln!("gaussian density: cubic {:?}, rms residual {:.4}", c.coeffs, c.rms_residual);
    assert!(c.rms_residual < 0.03, "{c:?}");
}

#[test]
fn stratified_error_shrinks_with_direction_count() {
    let p = YarnParams::preset("cotton-2ply").unwrap();
    let f = field_for(&p, &BakeSettings::default()).unwrap().symmetrized();
    let h = f.half_width;
    let pts: Vec<[f64; 2]> = (0..24)
        .map(|k| {
            let a = TAU * k as f64 / 24.0;
            let r = 0.6 * h * ((k % 6) as f64 + 0.5) / 6.0;
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let truth: Vec<f64> = pts.iter().map(|q| ao_point(&f, *q, 2048, |_| 0.5)).collect();
    let mut logs = Vec::new();
    for n in [2usize, 4, 8, 16, 32] {
        let mut se = 0.0;
        for rep in 0..4u64 {
            for (i, q) in pts.iter().enumerate() {
                let jit = |s: usize| unit_f64(hash_keys(&[rep, i as u64, s as u64, n as u64]));
                se += (ao_point(&f, *q, n, jit) - truth[i]).powi(2);
            }
        }
        let rms = (se / (4 * pts.len()) as f64).sqrt();
        eprintln!("stratified AO, {n:>3} directions: RMS error {rms:.5}");
        logs.push(((n as f64).ln(), rms.ln()));
    }
    let mx = logs.iter().map(|l| l.0).sum::<f64>() / logs.len() as f64;
    let my = logs.iter().map(|l| l.1).sum::<f64>() / logs.len() as f64;
    let slope = logs.iter().map(|l| (l.0 - mx) * (l.1 - my)).sum::<f64>()
        / logs.iter().map(|l| (l.0 - mx).powi(2)).sum::<f64>();
    eprintln!("fitted log-log slope {slope:.2}");
    assert!(slope <= -0.5, "{slope}");
}

/// cotton-2ply with 4× the fibers of ¼ the radius (same σ, a quarter of the packing).
fn dilute() -> YarnParams {
    let mut p = YarnParams::preset("cotton-2ply").unwrap();
    p.fiber_radius /= 4.0;
    p.fibers_per_ply *= 4;
    p.hair_density = 0.0;
    p.loop_density = 0.0;
    p
}

#[test]
fn two_d_ao_equals_three_d_visibility_through_straight_fibers() {
    // K cross-sections of the yarn (the density's own K length samples over one ply twist,
    // in the slice frame), each extruded into straight fibers: the density of the texture is
    // exactly their splat, and a 3-D ray in scene k meets cross-section k at every height.
    let p = dilute();
    let k_sec = 8;
    let opts = DensityOptions { res: 64, samples: k_sec, seed: 1, loops: false };
    let d = CrossSectionDensity::from_params(&p, &opts).unwrap();
    let field = SigmaField::from_density(&d, 1);
    let tex = AoTexture::bake(&field, &AoSettings { res: 48, directions: 64, radial_bins: 8 }, 5);
    let table = FiberTable::new(&p, 1, 0);
    let model = FiberModel { params: &p, table: &table, twist: EffectiveTwist::nominal(&p) };
    let r_yarn = p.yarn_radius();
    let len = 100.0 * r_yarn;
    let scenes: Vec<FiberScene> = (0..k_sec)
        .map(|k| {
            let z = p.ply_pitch.abs() * (k as f64 + 0.5) / k_sec as f64;
            let (s, c) = (TAU * z / p.ply_pitch).sin_cos();
            let mut f = Fibers { palette: vec![[1.0; 3]], offsets: vec![0], ..Default::default() };
            for ply in 0..p.ply_count as usize {
                for i in 0..p.fibers_per_ply as usize {
                    let [a, b] = model.fiber_offset(z, ply, i);
                    let (x, y) = (c * a + s * b, -s * a + c * b);
                    for zz in [-len, len] {
                        f.points.push([x as f32, y as f32, zz as f32]);
                        f.radii.push(p.fiber_radius as f32);
                        f.color_ids.push(0);
                    }
                    f.offsets.push(f.points.len() as u32);
                    f.yarn.push(0);
                    f.ply.push(ply as u16);
                    f.fiber.push(i as u32);
                    f.kind.push(FiberKind::Regular);
                    f.params_id.push(0);
                }
            }
            FiberScene::new(&f, &SceneOptions::default()).unwrap()
        })
        .collect();
    let bins = 4;
    let rays = 2000;
    let mut bad = 0;
    for b in 0..bins {
        let mut rng = KeyRng::new(&[11, b as u64]);
        let (mut free, mut tex_sum) = (0usize, 0.0);
        for ray in 0..rays {
            let [u1, u2, u3] = rng.uniform3();
            let u4 = rng.uniform();
            // Uniform in the annulus [b, b+1)·R/bins.
            let (r0, r1) = (b as f64 / bins as f64 * r_yarn, (b + 1) as f64 / bins as f64 * r_yarn);
            let r = (r0 * r0 + u1 * (r1 * r1 - r0 * r0)).sqrt();
            let q = [r * (TAU * u2).cos(), r * (TAU * u2).sin()];
            tex_sum += tex.at(q[0], q[1]);
            let cz = 2.0 * u3 - 1.0;
            let sz = (1.0 - cz * cz).max(0.0).sqrt();
            let dir = [sz * (TAU * u4).cos(), sz * (TAU * u4).sin(), cz];
            if !scenes[ray % k_sec].occluded([q[0], q[1], 0.0], dir, len, None) {
                free += 1;
            }
        }
        let n = rays as f64;
        let pf = free as f64 / n;
        let se = (pf * (1.0 - pf) / n).sqrt().max(0.5 / n);
        let t = tex_sum / n;
        let tol = 4.0 * se + 0.03;
        let fail = (t - pf).abs() > tol;
        bad += fail as usize;
        eprintln!(
            "|q|/R in [{:.2}, {:.2}): 3-D explicit {pf:.3} ± {se:.3}, 2-D texture {t:.3}, error {:+.3} (tol {tol:.3}){}",
            b as f64 / bins as f64,
            (b + 1) as f64 / bins as f64,
            t - pf,
            if fail { "  FAIL" } else { "" }
        );
    }
    assert_eq!(bad, 0);
}
