//! Tests of the per-slot PCA against an independent SVD, Eckart–Young, storage precision and
//! the hard cases of DESIGN.md §6.

use super::*;
use crate::eigen::dequantize;
use crate::reconstruct::reconstruct_sample;

/// A deterministic pseudo-random generator (no dependency needed for tests).
fn lcg(seed: &mut u64) -> f64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64) / ((1u64 << 53) as f64)
}

/// `n` images of `m` values: a few smooth "lighting modes" plus noise, all positive.
fn slot_data(n: usize, m: usize, seed: u64) -> SlotData {
    let mut s = seed;
    let modes: Vec<Vec<f64>> = (0..5).map(|_| (0..m).map(|_| lcg(&mut s)).collect()).collect();
    let mut data = Vec::with_capacity(n * m);
    for i in 0..n {
        let coef: Vec<f64> = (0..5)
            .map(|k| ((i + 1) as f64 * 0.7 * (k + 1) as f64).cos() / (k + 1) as f64)
            .collect();
        for t in 0..m {
            let v: f64 =
                1.0 + (0..5).map(|k| coef[k] * modes[k][t]).sum::<f64>() + 0.01 * lcg(&mut s);
            data.push(v as f32);
        }
    }
    SlotData { view: 3, n_lights: n, texel_values: m, data }
}

fn as_slot(r: &SlotPca, c: usize, q: Quantization) -> crate::eigen::EigenSlot {
    crate::eigen::EigenSlot {
        view: 0,
        mean: r.stored.mean.clone(),
        basis: dequantize(&r.stored.eigentextures, &r.stored.scale_offset, q),
        weights: r.stored.weights.clone(),
        eigenvalues: r.stored.eigenvalues.clone(),
        components: c,
    }
}

/// The eigenvalues of the centred Gram matrix of `n` rows of `m` values (centred on their
/// mean in `f64`), from an SVD, largest first.
fn centred_spectrum(data: &[f32], n: usize, m: usize) -> Vec<f64> {
    let mut x = DMatrix::<f64>::from_fn(n, m, |i, t| data[i * m + t] as f64);
    let mean = x.row_mean();
    for i in 0..n {
        for t in 0..m {
            x[(i, t)] -= mean[t];
        }
    }
    let mut sv: Vec<f64> = x.svd(false, false).singular_values.iter().map(|s| s * s).collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    sv
}

#[test]
fn eigenvalues_match_svd_and_eckart_young_holds() {
    let (n, m) = (20, 3 * 17 * 13);
    let input = slot_data(n, m, 7);
    // Independent reference: SVD of the centred data in f64.
    let mut x = DMatrix::<f64>::zeros(n, m);
    for i in 0..n {
        for t in 0..m {
            x[(i, t)] = input.data[i * m + t] as f64;
        }
    }
    let mean = x.row_mean();
    for i in 0..n {
        for t in 0..m {
            x[(i, t)] -= mean[t] as f32 as f64;
        }
    }
    let svd = x.clone().svd(true, true);
    let mut sv: Vec<f64> = svd.singular_values.iter().map(|s| s * s).collect();
    sv.sort_by(|a, b| b.total_cmp(a));
    for c in [1, 3, 6] {
        let slot = &input;
        let r = pca_slot(slot, c, Quantization::F16).unwrap();
        for k in 0..8 {
            assert!(
                (r.stored.eigenvalues[k] - sv[k]).abs() <= 1e-9 * sv[0],
                "λ{k}: {} vs {}",
                r.stored.eigenvalues[k],
                sv[k]
            );
        }
        let discarded: f64 = sv[c..].iter().sum();
        // Eckart–Young: measured squared error of the exact basis = discarded eigenvalues.
        assert!(
            (r.sse - r.discarded_eigen_sum).abs() <= 1e-6 * r.discarded_eigen_sum,
            "c={c}: {} vs {}",
            r.sse,
            r.discarded_eigen_sum
        );
        assert!((r.discarded_eigen_sum - discarded).abs() <= 1e-6 * discarded);
        // Brute force: residual of the stored reconstruction equals sse_stored.
        let es = as_slot(&r, c, Quantization::F16);
        let mut brute = 0f64;
        for i in 0..n {
            let rec = reconstruct_sample(&es, i, c);
            brute += crate::metrics::sse(input.row(i), &rec);
        }
        assert!(
            (brute - r.sse_stored).abs() <= 1e-3 * r.sse_stored + 1e-9,
            "c={c}: brute {brute} vs {}",
            r.sse_stored
        );
        // Quantisation can only add error, and little of it.
        assert!(
            r.sse_stored >= r.sse * (1.0 - 1e-9) && r.sse_stored <= r.sse * 1.05 + 1e-6,
            "{} {}",
            r.sse_stored,
            r.sse
        );
    }
}

#[test]
fn full_rank_reconstructs_input_to_storage_precision() {
    let (n, m) = (9, 3 * 8 * 8);
    let input = slot_data(n, m, 11);
    for q in [Quantization::F16, Quantization::U8] {
        let c = max_components(n);
        let slot = &input;
        let r = pca_slot(slot, c, q).unwrap();
        let es = as_slot(&r, c, q);
        for i in 0..n {
            let rec = reconstruct_sample(&es, i, c);
            // Each stored value is off by at most half a quantisation step: 2^-11·scale for
            // f16 (values in [-1, 1]), scale/2 for u8. The error of a texel is bounded by
            // Σ_k |p_ik| · step_k plus f32 rounding of the sums.
            let bound: f64 = (0..c)
                .map(|k| {
                    let s = r.stored.scale_offset[k][0] as f64;
                    let step = if q == Quantization::F16 { s * 2f64.powi(-11) } else { s * 0.5 };
                    (es.weights_of(i)[k] as f64).abs() * step
                })
                .sum::<f64>()
                + 1e-5;
            for t in 0..m {
                let e = (rec[t] as f64 - input.row(i)[t] as f64).abs();
                assert!(e <= bound, "{q:?} light {i} value {t}: error {e} > bound {bound}");
            }
        }
    }
}

#[test]
fn signs_are_deterministic() {
    let input = slot_data(12, 300, 5);
    let a = &input;
    let r = pca_slot(a, 4, Quantization::F16).unwrap();
    let es = as_slot(&r, 4, Quantization::F16);
    for k in 0..4 {
        let row = es.basis_row(k);
        let big = row.iter().copied().fold(0f32, |a, v| if v.abs() > a.abs() { v } else { a });
        assert!(big > 0.0);
    }
    // Negating the input flips no stored sign and negates the weights.
    let mut neg = input.clone();
    neg.data.iter_mut().for_each(|v| *v = -*v);
    let rn = pca_slot(&neg, 4, Quantization::F16).unwrap();
    assert_eq!(r.stored.eigentextures, rn.stored.eigentextures);
    for (a, b) in r.stored.weights.iter().zip(&rn.stored.weights) {
        assert!((a + b).abs() <= 1e-4 * a.abs().max(1e-3));
    }
}

#[test]
fn constant_and_duplicate_images_are_rank_deficient_but_finite() {
    // Constant images: zero variance, reconstruction = mean = input.
    let slot = SlotData { view: 0, n_lights: 6, texel_values: 30, data: vec![0.25; 180] };
    let r = pca_slot(&slot, 4, Quantization::F16).unwrap();
    assert_eq!(r.effective_components, 0);
    assert!(r.stored.eigenvalues.iter().all(|&l| l == 0.0));
    assert!(r.stored.weights.iter().all(|&w| w == 0.0));
    assert!(r.stored.mean.iter().all(|&v| v == 0.25));
    assert_eq!(r.sse_stored, 0.0);
    // Duplicates: 8 images that are copies of 2 distinct ones → rank 1 after centring.
    let base = slot_data(2, 60, 3);
    let mut data = Vec::new();
    for i in 0..8 {
        data.extend_from_slice(base.row(i % 2));
    }
    let slot = SlotData { view: 0, n_lights: 8, texel_values: 60, data };
    let r = pca_slot(&slot, 5, Quantization::F16).unwrap();
    assert_eq!(r.effective_components, 1);
    assert!(r.sse <= 1e-10 * r.energy, "{}", r.sse);
    assert!(r.stored.weights.iter().all(|w| w.is_finite()));
}

#[test]
fn huge_dynamic_range_stays_finite_and_accurate() {
    // Values from 1e-4 to 1e5 (a specular highlight next to deep shadow).
    let (n, m) = (10, 300);
    let mut input = slot_data(n, m, 9);
    for (t, v) in input.data.iter_mut().enumerate() {
        let e = ((t * 7919) % 10) as i32 - 4; // exponents -4 ..= 5
        *v *= 10f32.powi(e);
    }
    let slot = &input;
    let c = max_components(n);
    let r = pca_slot(slot, c, Quantization::F16).unwrap();
    assert!(r.stored.weights.iter().all(|w| w.is_finite()));
    assert!(r.stored.eigenvalues.iter().all(|l| l.is_finite()));
    let rel = crate::metrics::rel_rmse_from(r.sse_stored, r.energy);
    assert!(rel < 2e-3, "relative RMSE {rel}");
}

#[test]
fn non_finite_input_is_refused_with_slot_and_light() {
    let mut slot = slot_data(5, 30, 1);
    slot.data[2 * 30 + 4] = f32::INFINITY;
    let err = pca_slot(&slot, 2, Quantization::F16).unwrap_err().to_string();
    assert!(err.contains("view slot 3") && err.contains("light 2"), "{err}");
}

#[test]
fn single_light_slot_keeps_one_zero_component() {
    assert_eq!(max_components(1), 1);
    assert_eq!(max_components(81), 80);
    let slot = slot_data(1, 30, 1);
    let r = pca_slot(&slot, 1, Quantization::U8).unwrap();
    assert_eq!(r.effective_components, 0);
    assert_eq!(r.sse_stored, 0.0);
}

#[test]
fn large_mean_costs_no_precision() {
    // Spread ≈ 1 on a mean of 10⁴: the Gram matrix of the images shifted by the first one
    // loses nothing to the mean (an uncentred Gram matrix would cancel ~8 of f64's digits).
    let (n, m) = (12, 3 * 10 * 10);
    let mut input = slot_data(n, m, 13);
    input.data.iter_mut().for_each(|v| *v += 1e4);
    let sv = centred_spectrum(&input.data, n, m);
    let mean: Vec<f64> = (0..m)
        .map(|t| (0..n).map(|i| input.data[i * m + t] as f64).sum::<f64>() / n as f64)
        .collect();
    let c = 4;
    let r = pca_slot(&input, c, Quantization::F16).unwrap();
    for k in 0..n - 1 {
        let e = (r.stored.eigenvalues[k] - sv[k]).abs();
        assert!(e <= 1e-10 * sv[0], "λ{k}: {} vs {}", r.stored.eigenvalues[k], sv[k]);
    }
    let discarded: f64 = sv[c..].iter().sum();
    assert!((r.sse - discarded).abs() <= 1e-6 * discarded, "{} vs {discarded}", r.sse);
    assert!((r.discarded_eigen_sum - discarded).abs() <= 1e-6 * discarded);
    // The stored mean is the f32 rounding of the exact mean.
    for t in 0..m {
        assert_eq!(r.stored.mean[t], mean[t] as f32, "texel value {t}");
    }
}

#[test]
fn f16_basis_is_the_rounded_exact_basis_at_a_power_of_two_scale() {
    // The fused pass rounds at unit scale and renormalises by powers of two: every stored
    // row then has its largest magnitude in (½, 1], a power-of-two scale, and equals the
    // f16 rounding of the exact (u8 path's f64) basis up to that scale.
    let (n, m) = (10, 3 * 20 * 11);
    let input = slot_data(n, m, 21);
    let c = 5;
    let r = pca_slot(&input, c, Quantization::F16).unwrap();
    let es = as_slot(&r, c, Quantization::F16);
    let exact = pca_slot(&input, c, Quantization::U8).unwrap();
    let ex = as_slot(&exact, c, Quantization::U8);
    for k in 0..c {
        let s = r.stored.scale_offset[k][0];
        assert_eq!(s, 2f32.powi(s.log2().round() as i32), "component {k}: scale {s}");
        let row = es.basis_row(k);
        let top = row.iter().fold(0f32, |a, v| a.max(v.abs()));
        assert!(top > 0.5 * s && top <= s, "component {k}: {top} vs scale {s}");
        // Same direction as the u8 path's basis, to its 8-bit precision.
        let (ur, us) = (ex.basis_row(k), exact.stored.scale_offset[k][0]);
        for t in 0..m {
            assert!((row[t] - ur[t]).abs() <= us * 0.51 + s * 1e-3, "({k}, {t})");
        }
    }
}

#[test]
fn f16_data_gets_an_f32_gram_within_its_bound_and_every_path_agrees() {
    // Two blocks of columns (1024 + 416) of f16 values; the f32-lane Gram matrix (the
    // default for f16 rows) against an f64 SVD of the same values: every eigenvalue within
    // ε·tr(YYᵀ) (Y = X − 1x₀ᵀ, [`GRAM32_EPS`]), Eckart–Young to the same bound, the
    // stored error equal to a brute-force reconstruction's.
    let (n, m) = (20, 3 * 24 * 20);
    let input = slot_data(n, m, 7);
    let halves: Vec<half::f16> = input.data.iter().map(|&v| half::f16::from_f32(v)).collect();
    let wide = SlotData { data: halves.iter().map(|h| h.to_f32()).collect(), ..input.clone() };
    let x = |i: usize, t: usize| wide.data[i * m + t] as f64;
    let tr_y: f64 = (0..n).map(|i| (0..m).map(|t| (x(i, t) - x(0, t)).powi(2)).sum::<f64>()).sum();
    let sv = centred_spectrum(&wide.data, n, m);
    let bound = GRAM32_EPS * tr_y;
    let rows =
        SlotRows::<half::f16> { view: 3, rows: halves.chunks_exact(m).collect(), texel_values: m };
    let c = 6;
    let mut simd: Option<SlotPca> = None;
    for isa in Isa::supported_all() {
        let mut scratch = PcaScratch::for_isa(isa);
        let r = pca_rows_in(&rows, c, Quantization::F16, &mut scratch, None).unwrap();
        for k in 0..n - 1 {
            let e = (r.stored.eigenvalues[k] - sv[k]).abs();
            assert!(
                e <= bound,
                "{isa} λ{k}: {} vs {} (bound {bound})",
                r.stored.eigenvalues[k],
                sv[k]
            );
        }
        let discarded: f64 = sv[c..].iter().sum();
        let slack = (n - c) as f64 * bound;
        assert!((r.discarded_eigen_sum - discarded).abs() <= slack, "{isa}");
        assert!((r.sse - r.discarded_eigen_sum).abs() <= slack, "{isa}");
        let es = as_slot(&r, c, Quantization::F16);
        let brute: f64 =
            (0..n).map(|i| crate::metrics::sse(wide.row(i), &reconstruct_sample(&es, i, c))).sum();
        assert!((brute - r.sse_stored).abs() <= 1e-3 * r.sse_stored + slack, "{isa}: {brute}");
        match (&simd, isa) {
            (_, Isa::Scalar) => {}
            (None, _) => simd = Some(r),
            (Some(f), _) => {
                assert_eq!(f.stored.eigenvalues, r.stored.eigenvalues, "{isa}");
                assert_eq!(f.stored.eigentextures, r.stored.eigentextures, "{isa}");
                assert_eq!(f.stored.weights, r.stored.weights, "{isa}");
            }
        }
    }
    // In f64 the f16 rows give the f32 rows' result bit for bit, and the f32 lanes really
    // rounded elsewhere (else the bounds above were tested on the f64 arithmetic).
    let mut scratch = PcaScratch::default().with_gram(GramPrecision::F64);
    let r64 = pca_rows_in(&rows, c, Quantization::F16, &mut scratch, None).unwrap();
    let r32 = pca_slot(&wide, c, Quantization::F16).unwrap();
    assert_eq!(r64.stored.eigenvalues, r32.stored.eigenvalues);
    assert_eq!(r64.stored.weights, r32.stored.weights);
    assert_ne!(r64.stored.eigenvalues, simd.unwrap().stored.eigenvalues);
}

#[test]
fn f16_duplicates_stay_rank_deficient_with_an_f32_gram() {
    // 8 f16 images, copies of 2: identical rows give identical f32 sums, so the centred
    // matrix has rank 1 up to f64 rounding and the bound keeps the rest out.
    let base = slot_data(2, 1100, 3);
    let halves: Vec<half::f16> =
        (0..8).flat_map(|i| base.row(i % 2).iter().map(|&v| half::f16::from_f32(v))).collect();
    let rows = SlotRows::<half::f16> {
        view: 0,
        rows: halves.chunks_exact(1100).collect(),
        texel_values: 1100,
    };
    let r = pca_rows_in(&rows, 5, Quantization::F16, &mut PcaScratch::default(), None).unwrap();
    assert_eq!(r.effective_components, 1);
    assert!(r.sse <= GRAM32_EPS * r.energy, "{}", r.sse);
    assert!(r.stored.weights.iter().all(|w| w.is_finite()));
}

#[test]
fn a_component_below_the_f32_gram_bound_is_not_effective() {
    // Six f16 images of 2048 values: 1.5 + a_i·u + b_i·v with u = ±¼ and v = ±2⁻¹⁰ (the f16
    // quantum at 1.5), all exact in f16. The v component's eigenvalue, Σb²·2⁻²⁰·m ≈ 0.0039,
    // is below ε·tr(YYᵀ) ≈ 3.9·10⁻⁶·1440 ≈ 0.0057: in f32 lanes it is not a component, in
    // f64 it is.
    let (n, m) = (6, 2048);
    let (a, b) = ([0.0, 1.5, -1.5, 1.5, -1.5, 1.5], [0.0, 1.0, -1.0, 0.0, 0.0, 0.0]);
    let sign = |t: usize, k: usize| if ((t * 2_654_435_761) >> k) & 1 == 0 { 1.0 } else { -1.0 };
    let halves: Vec<half::f16> = (0..n * m)
        .map(|q| {
            let (i, t) = (q / m, q % m);
            let v = 1.5 + a[i] * 0.25 * sign(t, 7) + b[i] * 2f64.powi(-10) * sign(t, 13);
            let h = half::f16::from_f64(v);
            assert_eq!(h.to_f64(), v, "({i}, {t}) is not an f16 value");
            h
        })
        .collect();
    let rows =
        SlotRows::<half::f16> { view: 0, rows: halves.chunks_exact(m).collect(), texel_values: m };
    let run = |gram: GramPrecision| {
        let mut scratch = PcaScratch::default().with_gram(gram);
        pca_rows_in(&rows, 3, Quantization::F16, &mut scratch, None).unwrap()
    };
    let (r32, r64) = (run(GramPrecision::F32), run(GramPrecision::F64));
    assert_eq!((r32.effective_components, r64.effective_components), (1, 2));
    // The second eigenvalue itself agrees (to the bound); only its count differs.
    let tr_y: f64 = (0..n)
        .map(|i| {
            (0..m).map(|t| (halves[i * m + t].to_f64() - halves[t].to_f64()).powi(2)).sum::<f64>()
        })
        .sum();
    let (l32, l64) = (r32.stored.eigenvalues[1], r64.stored.eigenvalues[1]);
    assert!(l64 < GRAM32_EPS * tr_y && (l32 - l64).abs() <= GRAM32_EPS * tr_y, "{l32} {l64}");
    assert!(r32.stored.weights.iter().all(|w| w.is_finite()));
}
