//! The strip bake's tests (DESIGN §3.5): the rank-1 fit recovers a rank-1 matrix, the
//! baked model reproduces the measured reference at the bake directions within twice its
//! own residual (through the lookups the shader mirrors), held-out directions are
//! reported, and the cache round-trips and rebuilds a corrupt file.

use super::*;
use yarn::bcsdf::KhungurnParams;

fn yarn() -> YarnParams {
    YarnParams::preset("cotton-2ply").unwrap()
}

fn bcsdf() -> FiberBcsdf {
    FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap()
}

const COLOR: [f32; 3] = [0.8, 0.6, 0.4];

#[test]
fn rank1_recovers_a_rank1_matrix_and_reports_the_residual() {
    let d = 5;
    let p: Vec<f64> = (0..d).map(|a| 0.5 + a as f64 * 0.3).collect();
    let q: Vec<f64> = (0..d).map(|b| 1.0 - 0.15 * b as f64).collect();
    let x: Vec<f64> = (0..d * d).map(|k| p[k / d] * q[k % d]).collect();
    let w = vec![1.0; d * d];
    let (a, b, r) = rank1(&x, &w, d);
    assert!(r < 1e-12, "residual {r}");
    for k in 0..d * d {
        assert!((a[k / d] * b[k % d] - x[k]).abs() < 1e-12);
    }
    assert!((b.iter().cloned().fold(0.0, f64::max) - 1.0).abs() < 1e-15);
    // One cell off by +1 with zero weight changes nothing; with weight it shows.
    let mut y = x.clone();
    y[7] += 1.0;
    let mut w0 = w.clone();
    w0[7] = 0.0;
    assert!(rank1(&y, &w0, d).2 < 1e-12);
    assert!(rank1(&y, &w, d).2 > 0.05);
}

#[test]
fn baked_model_reproduces_the_reference_within_its_residual() {
    // 64 spp: the residual holds the Monte-Carlo noise of L_ref too (0.55 at 4 spp, 0.37
    // at 16, 0.24 at 64 on this yarn).
    let s = StripBakeSettings { width: 8, spp: 64, ..StripBakeSettings::small() };
    let b = StripBake::bake(&yarn(), &bcsdf(), COLOR, &s, &|_| {}).unwrap();
    let d = s.directions;
    let n = s.width * s.height;
    let cover: f64 = b.alpha.iter().map(|&a| a as f64).sum::<f64>() / n as f64;
    // The strip spans the widest extent (loops included); a 2-ply yarn seen with its plies
    // one behind the other covers about one ply's width of it.
    assert!((0.35..=0.95).contains(&cover), "mean coverage {cover}");
    assert!(b.psi_m.iter().chain(&b.psi_n).all(|x| x.is_finite() && *x >= 0.0));
    assert!(b.xi_m.iter().chain(&b.xi_n).flatten().all(|x| x.is_finite() && *x > 0.0));
    // Through the shader's lookups at the bin centres: the model against L_ref.
    let st = setup(&yarn(), &bcsdf(), COLOR, &s).unwrap();
    let dirs = s.directions_grid();
    let wdirs: Vec<V3> = dirs.iter().map(|&x| light_dir(&st, x)).collect();
    let (mut num, mut den, mut res2) = (0.0, 0.0, 0.0);
    for t in 0..n {
        if b.alpha[t] <= 0.0 {
            continue;
        }
        let lm =
            model_unshadowed(&st, &b.tangent[t * s.tangents..(t + 1) * s.tangents], COLOR, &wdirs);
        let (mut tn, mut td) = (0.0, 0.0);
        for (k, &(th, ph)) in dirs.iter().enumerate() {
            let (psi, xi) = b.factors_at(t, th, ph);
            let model = std::array::from_fn(|c| lm[k][c] * psi * xi[c]);
            let r = lum(b.l_ref[t * d * d + k].map(f64::from));
            tn += (r - lum(model)).powi(2);
            td += r * r;
        }
        let a = b.alpha[t] as f64;
        num += a * tn;
        den += a * td;
        res2 += a * td * (b.residual[t] as f64).powi(2);
    }
    let err = (num / den).sqrt();
    let res = (res2 / den).sqrt();
    eprintln!(
        "bake-direction error {err:.4}, residual {res:.4}, mean residual {:.4}",
        b.mean_residual()
    );
    assert!(err <= 2.0 * res + 1e-6, "model error {err} against residual {res}");
    assert!(res < 0.35, "a rank-1 model that misses a third of the radiance: {res}");
}

/// Relative RMS (coverage-weighted luminance) of `b`'s model against `m`'s reference.
fn model_error(b: &StripBake, m: &Measured, s: &StripBakeSettings) -> f64 {
    let st = setup(&yarn(), &bcsdf(), COLOR, s).unwrap();
    let wdirs: Vec<V3> = m.dirs.iter().map(|&x| light_dir(&st, x)).collect();
    let (mut num, mut den) = (0.0, 0.0);
    let nd = m.dirs.len();
    for t in 0..s.width * s.height {
        if b.alpha[t] <= 0.0 {
            continue;
        }
        let lm =
            model_unshadowed(&st, &b.tangent[t * s.tangents..(t + 1) * s.tangents], COLOR, &wdirs);
        for (k, &(th, ph)) in m.dirs.iter().enumerate() {
            let (psi, xi) = b.factors_at(t, th, ph);
            let model = std::array::from_fn(|c| lm[k][c] * psi * xi[c]);
            let r = lum(m.l_ref[t * nd + k].map(f64::from));
            num += b.alpha[t] as f64 * (r - lum(model)).powi(2);
            den += b.alpha[t] as f64 * r * r;
        }
    }
    (num / den).sqrt()
}

#[test]
fn held_out_directions_are_measured_and_reported() {
    // [H25]'s 8 × 8 directions: 4 × 4 (45° bins) misses the forward-scattering peak of
    // TT behind the yarn (held-out error 1.7, the model 3.3× the reference at θ = 0,
    // φ = 180°).
    let s = StripBakeSettings {
        width: 8,
        height: 4,
        directions: 8,
        spp: 32,
        ..StripBakeSettings::small()
    };
    let b = StripBake::bake(&yarn(), &bcsdf(), COLOR, &s, &|_| {}).unwrap();
    let d = s.directions;
    // An independent measurement (another seed) at the bake directions: the error floor
    // of Monte-Carlo noise plus the rank-1 fit.
    let other = StripBakeSettings { seed: s.seed + 1, ..s };
    let same = measure(&yarn(), &bcsdf(), COLOR, &other, &s.directions_grid(), &|_| {}).unwrap();
    // Midpoints between bake directions (interior θ, every φ).
    let dirs: Vec<(f64, f64)> = (0..d - 1)
        .flat_map(|a| (0..d).map(move |c| (a, c)))
        .map(|(a, c)| {
            let (t0, p0) = s.direction(a, c);
            (t0 + 0.5 * PI / d as f64, p0 + PI / d as f64)
        })
        .collect();
    let mid = measure(&yarn(), &bcsdf(), COLOR, &other, &dirs, &|_| {}).unwrap();
    let (e_same, e_mid) = (model_error(&b, &same, &s), model_error(&b, &mid, &s));
    eprintln!(
        "bake residual {:.4}; independent measurement: bake directions {e_same:.4}, held-out midpoints {e_mid:.4}",
        b.mean_residual()
    );
    // 45° bins interpolated linearly: the midpoints may be worse, not grossly.
    assert!(e_mid <= 2.0 * e_same, "held-out {e_mid} against {e_same} at the bake directions");
}

#[test]
fn cache_round_trips_and_rebuilds_a_corrupt_file() {
    let dir = std::env::temp_dir().join(format!("strip-bake-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let s = StripBakeSettings {
        width: 4,
        height: 2,
        directions: 2,
        spp: 1,
        ao_rays: 1,
        bounces: 2,
        tangents: 2,
        seed: 3,
    };
    let a = StripBake::for_params(&yarn(), &bcsdf(), COLOR, &s, Some(&dir), &|_| {}).unwrap();
    assert!(!a.from_cache);
    let b = StripBake::for_params(&yarn(), &bcsdf(), COLOR, &s, Some(&dir), &|_| {}).unwrap();
    assert!(b.from_cache);
    assert_eq!(StripBake { from_cache: false, ..b }, a);
    let file = std::fs::read_dir(&dir).unwrap().next().unwrap().unwrap().path();
    let mut bytes = std::fs::read(&file).unwrap();
    let k = bytes.len() - 5;
    bytes[k] ^= 0x40;
    std::fs::write(&file, &bytes).unwrap();
    let c = StripBake::for_params(&yarn(), &bcsdf(), COLOR, &s, Some(&dir), &|_| {}).unwrap();
    assert!(!c.from_cache, "a corrupt cache file must be rebaked");
    assert_eq!(c, StripBake { seconds: c.seconds, ..a });
    // Bad settings name the field.
    let e = StripBake::bake(
        &yarn(),
        &bcsdf(),
        COLOR,
        &StripBakeSettings { directions: 1, ..s },
        &|_| {},
    );
    assert!(e.unwrap_err().to_string().contains("directions"));
    let _ = std::fs::remove_dir_all(&dir);
}
