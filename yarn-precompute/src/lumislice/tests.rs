//! Closed forms, identities and the furnace of the lumislice (DESIGN §1.5).

use super::*;

fn disk_grid(res: usize, half_width: f64, radius: f64, sigma: f64) -> SliceGrid {
    let mut g = SliceGrid { res, half_width, sigma: vec![0.0; res * res] };
    for j in 0..res {
        for i in 0..res {
            let [x, y] = g.centre(i, j);
            if x.hypot(y) <= radius {
                g.sigma[j * res + i] = sigma;
            }
        }
    }
    g
}

#[test]
fn uniform_cylinder_transmittance_matches_the_closed_form() {
    // σ⊥ constant inside radius R, 0 outside, twisted or not: the optical depth from p
    // towards l is σ⊥ × the in-plane distance to the circle (anisotropic: σ⊥ sin β over
    // the 3-D length s, and s sin β is the in-plane length), σ⊥ × s (isotropic).
    let (r, sig) = (1e-3, 2500.0);
    let disk = |x: f64, y: f64| if x.hypot(y) <= r { sig } else { 0.0 };
    for law in [Extinction::Anisotropic, Extinction::Isotropic] {
        for twist in [0.0, TAU / 3e-3] {
            let yarn = TwistedYarn { sigma: &disk, reach: r, twist_rate: twist, law };
            for (p, th, ph) in [
                ([0.0, 0.0], 0.3f64, 0.0f64),
                ([4e-4, -2e-4], 2.0, 0.4),
                ([-7e-4, 5e-4], -1.1, -1.2),
                ([9e-4, 0.0], 0.0, 0.7),
            ] {
                let l = [ph.cos() * f64::cos(th), ph.cos() * f64::sin(th), f64::sin(ph)];
                let (ux, uy) = (th.cos(), th.sin());
                let pd = p[0] * ux + p[1] * uy;
                let inplane = -pd + (pd * pd - (p[0] * p[0] + p[1] * p[1] - r * r)).sqrt();
                let want = match law {
                    Extinction::Anisotropic => sig * inplane,
                    Extinction::Isotropic => sig * inplane / ph.cos(),
                };
                let got = yarn.optical_depth(p, 0.0, l, r / 256.0);
                assert!(
                    ((-got).exp() / (-want).exp() - 1.0).abs() < 1e-4,
                    "{law:?} twist {twist} p {p:?}: τ {got} vs {want}"
                );
            }
            // Along the axis: nothing (anisotropic), everything (isotropic).
            let t = yarn.optical_depth([1e-4, 0.0], 0.0, [0.0, 0.0, 1.0], r / 64.0);
            match law {
                Extinction::Anisotropic => assert_eq!(t, 0.0),
                Extinction::Isotropic => assert!((-t).exp() < 1e-30),
            }
        }
    }
}

#[test]
fn transparent_yarn_keeps_the_bare_phase_and_no_multiple_scattering() {
    // γ → 0: T = 1, M = 0, so V = ϖ Ψ(L) exactly.
    let g = disk_grid(8, 1e-3, 0.9e-3, 1e-9);
    let mut s = LumisliceSettings::small();
    s.res = 8;
    s.multiple = true;
    s.paths = 16;
    let a = [0.8, 0.5, 0.2];
    let l = Lumislice::from_grid(&g, 2e-3, a, &s, &|_| {}).unwrap();
    assert_eq!(l.levels.len(), 1);
    let mut worst: f64 = 0.0;
    for k in 0..DIRECTIONS {
        let d = direction(k);
        let psi = (d[0] * d[0] + d[1] * d[1]).sqrt() / (PI * PI);
        for v in 0..64 {
            for c in 0..3 {
                let want = a[c] as f64 * psi;
                worst = worst.max((l.levels[0].vrf[k * 64 + v][c] as f64 - want).abs());
            }
        }
    }
    assert!(worst < 1e-6, "worst |V − ϖΨ| = {worst}");
}

#[test]
fn white_furnace_through_the_table() {
    // ϖ = 1, isotropic phase, light of radiance 1 from every direction: the source
    // function ∫ V dL = (1/4π)∫(T + M) dL is 1 at every voxel of the medium (everything
    // scattered is eventually either seen or escapes; what enters balances).
    let (res, hw) = (8, 1e-3);
    let g = disk_grid(res, hw, 0.95e-3, 1200.0); // optical radius ≈ 1.1
    let s = LumisliceSettings {
        res,
        min_res: 8,
        phase: Phase::Isotropic,
        multiple: true,
        paths: 400,
        max_order: 512,
        step: 0.25,
        ..LumisliceSettings::default()
    };
    let l = Lumislice::from_grid(&g, 3e-3, [1.0; 3], &s, &|_| {}).unwrap();
    // Solid-angle quadrature on the table's grid (midpoint in longitude, trapezoid in
    // altitude, weight cos φ).
    let (dth, dph) = (TAU / LONGITUDES as f64, PI / (ALTITUDES - 1) as f64);
    let weight = |k: usize| {
        let j = k / LONGITUDES;
        let ph = -FRAC_PI_2 + j as f64 * dph;
        let edge = if j == 0 || j == ALTITUDES - 1 { 0.5 } else { 1.0 };
        ph.cos() * dth * dph * edge
    };
    let wsum: f64 = (0..DIRECTIONS).map(weight).sum();
    assert!((wsum / (4.0 * PI) - 1.0).abs() < 5e-3, "quadrature {wsum}");
    let mut vals = Vec::new();
    let mut ss_only = Vec::new();
    for v in 0..res * res {
        if g.sigma[v] == 0.0 {
            continue;
        }
        let e: f64 =
            (0..DIRECTIONS).map(|k| weight(k) * l.levels[0].vrf[k * res * res + v][0] as f64).sum();
        vals.push(e * 4.0 * PI / wsum);
        let t: f64 = (0..DIRECTIONS)
            .map(|k| {
                let p = g.centre(v % res, v / res);
                let lum = |x: f64, y: f64| g.at(x, y);
                let y = TwistedYarn {
                    sigma: &lum,
                    reach: g.reach(),
                    twist_rate: 0.0,
                    law: s.extinction,
                };
                weight(k) * (-y.optical_depth(p, 0.0, direction(k), 0.25 * g.cell())).exp()
                    / (4.0 * PI)
            })
            .sum();
        ss_only.push(t * 4.0 * PI / wsum);
    }
    let mean = vals.iter().sum::<f64>() / vals.len() as f64;
    let ss = ss_only.iter().sum::<f64>() / ss_only.len() as f64;
    eprintln!(
        "furnace: ∫V = {mean:.4} over {} voxels (single scattering alone {ss:.4})",
        vals.len()
    );
    assert!(ss < 0.8, "the medium is thick enough for the test to mean something: {ss}");
    assert!((mean - 1.0).abs() < 0.02, "furnace ∫V = {mean}");
    // Each voxel is its own 400-path estimate (≈ 3.5 % standard error, measured): 4 SE.
    for v in &vals {
        assert!((v - 1.0).abs() < 0.15, "voxel ∫V = {v}");
    }
}

#[test]
fn lod_rules_keep_what_they_claim() {
    let res = 16;
    let mut lv = LumisliceLevel {
        res,
        sigma: vec![0.0; res * res],
        vrf: vec![[0.0; 3]; DIRECTIONS * res * res],
    };
    let mut rng = KeyRng::new(&[7]);
    for v in 0..res * res {
        lv.sigma[v] = if rng.uniform() < 0.2 { 0.0 } else { (3000.0 * rng.uniform()) as f32 };
        for k in 0..DIRECTIONS {
            lv.vrf[k * res * res + v] = [rng.uniform() as f32, 0.5, 0.25];
        }
    }
    let cell = 2e-3 / res as f64;
    let depth = 2.0 * cell;
    let a = downsample(&lv, cell, LodRule::Eq11);
    let b = downsample(&lv, cell, LodRule::Transmittance);
    let mut gap: f64 = 0.0;
    for j in 0..res / 2 {
        for i in 0..res / 2 {
            let idx = [
                (2 * j) * res + 2 * i,
                (2 * j) * res + 2 * i + 1,
                (2 * j + 1) * res + 2 * i,
                (2 * j + 1) * res + 2 * i + 1,
            ];
            let s: Vec<f64> = idx.iter().map(|&v| lv.sigma[v] as f64).collect();
            let mean = s.iter().sum::<f64>() / 4.0;
            let mean_t = s.iter().map(|x| (-x * depth).exp()).sum::<f64>() / 4.0;
            let c = j * res / 2 + i;
            assert!(
                (a.sigma[c] as f64 - mean).abs() <= 1e-6 * mean.max(1.0),
                "eq. 11 mean optical depth"
            );
            let tb = (-(b.sigma[c] as f64) * depth).exp();
            assert!((tb - mean_t).abs() < 1e-6, "transmittance kept: {tb} vs {mean_t}");
            // Jensen: eq. 11 is the more opaque.
            assert!(a.sigma[c] as f64 >= b.sigma[c] as f64 - 1e-3);
            gap = gap.min((-mean * depth).exp() - mean_t);
            // The table: density-weighted mean.
            let sum: f64 = s.iter().sum();
            for k in [0, 100, DIRECTIONS - 1] {
                let want: f64 = if sum > 0.0 {
                    idx.iter()
                        .zip(&s)
                        .map(|(&v, w)| w * lv.vrf[k * res * res + v][0] as f64)
                        .sum::<f64>()
                        / sum
                } else {
                    idx.iter().map(|&v| lv.vrf[k * res * res + v][0] as f64).sum::<f64>() / 4.0
                };
                assert!((a.vrf[k * (res / 2) * (res / 2) + c][0] as f64 - want).abs() < 1e-6);
            }
        }
    }
    eprintln!("most negative Jensen gap (transmittance, one coarse cell): {gap:.4}");
    assert!(gap < -1e-3, "a mixed block makes eq. 11 darker than the mean transmittance: {gap}");
    // Uniform blocks: both rules agree.
    let u =
        LumisliceLevel { res: 8, sigma: vec![1234.0; 64], vrf: vec![[0.3; 3]; DIRECTIONS * 64] };
    let (ua, ub) =
        (downsample(&u, cell, LodRule::Eq11), downsample(&u, cell, LodRule::Transmittance));
    for (x, y) in ua.sigma.iter().zip(&ub.sigma) {
        assert!((x - y).abs() <= 1e-6 * x, "{x} {y}");
    }
}

#[test]
fn level_choice_is_the_smallest_power_of_two_at_least_m() {
    let g = disk_grid(32, 1e-3, 0.9e-3, 1000.0);
    let l = Lumislice::from_grid(
        &g,
        2e-3,
        [0.5; 3],
        &LumisliceSettings { res: 32, multiple: false, ..Default::default() },
        &|_| {},
    )
    .unwrap();
    assert_eq!(l.levels.iter().map(|l| l.res).collect::<Vec<_>>(), vec![32, 16, 8]);
    for (m, res) in [
        (100.0, 32),
        (32.0, 32),
        (31.0, 32),
        (16.5, 32),
        (16.0, 16),
        (9.0, 16),
        (8.0, 8),
        (3.0, 8),
        (0.2, 8),
    ] {
        let got = l.levels[l.level_for(m)].res;
        assert_eq!(got, res, "m = {m}");
        // 2ⁿ ≥ m and 2ⁿ⁻¹ < m where the pyramid allows it.
        if (8.0..=32.0).contains(&m) {
            assert!(got as f64 >= m && (got as f64) / 2.0 < m);
        }
    }
}

#[test]
fn yarn_shadow_table_matches_eq10_for_a_uniform_cylinder() {
    let (r, sig, k0) = (1e-3, 900.0, 0.8);
    let e =
        YarnShadowLut::new(&|x| if x <= r { sig } else { 0.0 }, r, k0, ShadowVariant::Empirical)
            .unwrap();
    let p = YarnShadowLut::new(&|x| if x <= r { sig } else { 0.0 }, r, k0, ShadowVariant::Physical)
        .unwrap();
    let tau = |d: f64| 2.0 * sig * (r * r - d * d).max(0.0).sqrt();
    let n = YarnShadowLut::ENTRIES;
    for i in 0..n - 1 {
        let d = r * i as f64 / (n - 1) as f64;
        let we = 1.0 - k0 * (1.0 - (-tau(d)).exp()) / (1.0 - (-tau(0.0)).exp());
        assert!(
            (e.values[i] as f64 - we).abs() < 1e-5,
            "empirical at {d}: {} vs {we}",
            e.values[i]
        );
        assert!((p.values[i] as f64 - (-tau(d)).exp()).abs() < 1e-5);
    }
    assert!((e.at(0.0) - 0.2).abs() < 1e-6);
    assert_eq!(e.at(r), 1.0);
    assert_eq!(e.at(2.0 * r), 1.0);
    assert!(e.values.windows(2).all(|w| w[1] >= w[0]), "monotone");
    assert!(YarnShadowLut::new(&|_| 1.0, r, 1.5, ShadowVariant::Empirical).is_err());
    // Both variants from one set of depths: the same tables.
    let [be, bp] = YarnShadowLut::both(&|x| if x <= r { sig } else { 0.0 }, r, k0).unwrap();
    assert_eq!((be, bp), (e, p));
}

#[test]
fn real_yarn_table_cache_and_bad_settings() {
    let p = YarnParams::preset("fine-2ply").unwrap();
    let s = LumisliceSettings::small();
    let dir = tempfile::tempdir().unwrap();
    let a = Lumislice::for_params(&p, [0.7, 0.6, 0.5], &s, Some(dir.path()), &|_| {}).unwrap();
    assert!(!a.from_cache);
    assert_eq!(a.levels.iter().map(|l| l.res).collect::<Vec<_>>(), vec![16, 8]);
    // Every entry within [0, ϖ/π²] (single scattering: T ≤ 1, Ψ ≤ 1/π²) and some shade:
    // light across the yarn through the core is dimmer than at the rim.
    let bound = 0.7 / (PI * PI) + 1e-6;
    assert!(
        a.levels[0]
            .vrf
            .iter()
            .all(|c| c.iter().all(|x| x.is_finite() && (*x as f64) <= bound && *x >= 0.0))
    );
    let l = [1.0, 0.0, 0.0];
    let hw = a.half_width;
    let near = a.vrf_at(0, 0.6 * hw, 0.0, l)[0];
    let far = a.vrf_at(0, -0.6 * hw, 0.0, l)[0];
    assert!(near > far, "the lit side is brighter: {near} vs {far}");
    let b = Lumislice::for_params(&p, [0.7, 0.6, 0.5], &s, Some(dir.path()), &|_| {}).unwrap();
    assert!(b.from_cache);
    assert_eq!(a.levels, b.levels);
    // A corrupt file is rebuilt, not trusted.
    let f = std::fs::read_dir(dir.path()).unwrap().next().unwrap().unwrap().path();
    let mut bytes = std::fs::read(&f).unwrap();
    let n = bytes.len();
    bytes[n - 5] ^= 0x55;
    std::fs::write(&f, &bytes).unwrap();
    let c = Lumislice::for_params(&p, [0.7, 0.6, 0.5], &s, Some(dir.path()), &|_| {}).unwrap();
    assert!(!c.from_cache);
    assert_eq!(a.levels, c.levels);
    for (bad, field) in [
        (LumisliceSettings { res: 12, ..s }, "res"),
        (LumisliceSettings { min_res: 32, ..s }, "min_res"),
        (LumisliceSettings { step: 0.0, ..s }, "step"),
        (LumisliceSettings { multiple: true, paths: 0, ..s }, "paths"),
    ] {
        let e = Lumislice::compute(&p, [0.5; 3], &bad, &|_| {}).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
    assert!(
        Lumislice::compute(&p, [1.5, 0.0, 0.0], &s, &|_| {})
            .unwrap_err()
            .to_string()
            .contains("albedo")
    );
}
