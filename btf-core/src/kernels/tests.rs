//! The kernels on every path this CPU runs (and the NEON path, which is portable code and
//! runs anywhere): against naive sums within the bound their arithmetic allows, and the
//! SIMD paths against each other bit for bit (they perform the same fused multiply-adds in
//! the same order). The scalar path sums in the same order without fusing; where no
//! product rounds (the loads, whose squares of `f32` values are exact in `f64`) it too
//! agrees bit for bit.

use super::*;

/// Every path the tests run here: those this CPU supports, and NEON.
fn paths() -> Vec<Isa> {
    let mut p = Isa::supported_all();
    if !p.contains(&Isa::Neon) {
        p.push(Isa::Neon);
    }
    p
}

/// `γ_k = k·u / (1 − k·u)`, the relative bound of a sum of `k` products in `f64`
/// (Higham, *Accuracy and Stability of Numerical Algorithms*, §3.1).
fn gamma(k: usize) -> f64 {
    let ku = k as f64 * f64::EPSILON / 2.0;
    ku / (1.0 - ku)
}

fn values(len: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..len)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 0.5
        })
        .collect()
}

/// The rows of a row-major `rows × m` matrix.
fn rows_of(x: &[f32], rows: usize, m: usize) -> Vec<&[f32]> {
    x.chunks_exact(m).take(rows).collect()
}

/// A `rows × w` block of the given values (no shift).
fn block(x: &[f32], rows: usize, m: usize, c0: usize, w: usize) -> Block {
    let mut b = Block::default();
    load_shifted_with(&rows_of(x, rows, m), c0, w, None, &mut b, None, Isa::Scalar);
    b
}

#[test]
fn dot_acc_matches_naive_sums_on_every_path_and_the_simd_paths_agree_bitwise() {
    // Odd shapes (rows not multiples of the tiles, widths not of 8), accumulated over two
    // blocks of columns; a 12- or 16-row A takes the 4-row tiles; B rows past a multiple
    // of 5 (1 to 4 of them) take the narrow tiles, symmetric diagonals the triangular one.
    let m = 600; // the second block spans more than one 256-column sub-block
    for (na, nb) in [(11, 7), (12, 9), (16, 21), (21, 8), (14, 5)] {
        let xa = values(na * m, 1);
        let xb = values(nb * m, 2);
        // The naive sum and Σ|a·b|, which bounds the rounding of any order of summation.
        let naive = |i: usize, j: usize, xb: &[f32]| -> (f64, f64) {
            (0..m)
                .map(|t| xa[i * m + t] as f64 * xb[j * m + t] as f64)
                .fold((0.0, 0.0), |(s, a), p| (s + p, a + p.abs()))
        };
        let mut first: Option<(Vec<f64>, Vec<f64>)> = None;
        for isa in paths() {
            let mut acc = DotAcc::new(na, nb, false);
            let mut gram = DotAcc::new(na, na, true);
            for (c0, w) in [(0, 24), (24, m - 24)] {
                let (a, b) = (block(&xa, na, m, c0, w), block(&xb, nb, m, c0, w));
                acc.add_with(&a, &b, isa);
                gram.add_with(&a, &a, isa);
            }
            let ld = nb + 3;
            let mut out = vec![1.0; na * ld];
            acc.finish(&mut out, ld);
            // Both sums (ours in 8 lanes + 8, the naive one) are within γ_m·Σ|a·b| of the
            // exact value (and `out` holds 1 + the sum, rounded once more).
            let tol =
                |abs: f64, want: f64| 2.0 * gamma(m) * abs + f64::EPSILON * (1.0 + want.abs());
            for i in 0..na {
                for j in 0..ld {
                    let (want, abs) = if j < nb { naive(i, j, &xb) } else { (0.0, 0.0) };
                    let got = out[i * ld + j] - 1.0;
                    assert!(
                        (got - want).abs() <= tol(abs, want),
                        "{isa} ({i}, {j}): {got} vs {want}"
                    );
                }
            }
            // Upper triangle of a·aᵀ; the strict lower triangle is left alone.
            let mut g = vec![0.0; na * na];
            gram.finish(&mut g, na);
            for i in 0..na {
                for j in 0..na {
                    let (want, abs) = if j >= i { naive(i, j, &xa) } else { (0.0, 0.0) };
                    let got = g[i * na + j];
                    assert!((got - want).abs() <= tol(abs, 0.0), "{isa} gram ({i}, {j})");
                }
            }
            if isa != Isa::Scalar {
                match &first {
                    None => first = Some((out, g)),
                    Some(f) => assert!(*f == (out, g), "{isa} differs from the other SIMD paths"),
                }
            }
        }
    }
}

#[test]
fn lift_matches_naive_sums_on_every_path_and_the_simd_paths_agree_bitwise() {
    // 13 rows of f16 data widened to f32, 24 components (one group of 16, one of 8: both
    // AVX-512 kernels), 48 columns, offset c0: the block pitch is the f32 block's.
    let (n, w, cp, c0) = (13, 48, 24, 8);
    let x: Vec<Vec<half::f16>> = (0..n)
        .map(|i| values(w, 10 + i as u64).iter().map(|&v| half::f16::from_f32(v)).collect())
        .collect();
    let rows: Vec<&[half::f16]> = x.iter().map(|r| &r[..]).collect();
    let coef: Vec<f64> = values(n * cp, 4).iter().map(|&v| v as f64 * 0.37).collect();
    let ldo = c0 + 48 + 3;
    let mut first: Option<Vec<f64>> = None;
    for isa in paths() {
        let mut y = Block32::default();
        y.widen_from_with(&rows, 0, w, isa);
        let mut out = vec![7.0; cp * ldo];
        lift_rows32_with(&y, &coef, cp, &mut out, ldo, c0, isa);
        for k in 0..cp {
            for t in c0..c0 + w {
                let terms = (0..n).map(|i| coef[i * cp + k] * x[i][t - c0].to_f64());
                let (want, abs) = terms.fold((0.0, 0.0), |(s, a), p| (s + p, a + p.abs()));
                let got = out[k * ldo + t];
                assert!((got - want).abs() <= 2.0 * gamma(n) * abs, "{isa} ({k}, {t})");
            }
            assert!(out[k * ldo..k * ldo + c0].iter().all(|&v| v == 7.0), "before c0");
        }
        if isa != Isa::Scalar {
            match &first {
                None => first = Some(out),
                Some(f) => assert!(*f == out, "{isa} differs from the other SIMD paths"),
            }
        }
    }
}

#[test]
fn load_shifted_is_exact_and_gives_the_same_statistics_on_every_path() {
    // 37 columns: two groups of 16 and a tail of 5.
    let (n, m, c0, w) = (3, 50, 4, 37);
    let mut x = values(n * m, 5);
    x[m + 9] = 1e5; // a large value next to small ones: x − s stays exact in f64
    let shift: Vec<f32> = values(m, 6).iter().map(|v| v * 1e-4).collect();
    let mut energies = Vec::new();
    for isa in paths() {
        let mut b = Block::default();
        let mut colsum = vec![0.5; w];
        let load = |x: &[f32], b: &mut Block, colsum: &mut [f64]| {
            load_shifted_with(&rows_of(x, n, m), c0, w, Some(&shift), b, Some(colsum), isa).unwrap()
        };
        let st = load(&x, &mut b, &mut colsum);
        let mut energy = 0f64;
        for i in 0..n {
            for t in 0..b.stride {
                let want =
                    if t < w { x[i * m + c0 + t] as f64 - shift[c0 + t] as f64 } else { 0.0 };
                assert_eq!(b.data[i * b.stride + t], want, "{isa} ({i}, {t})");
            }
            energy += (0..w).map(|t| (x[i * m + c0 + t] as f64).powi(2)).sum::<f64>();
        }
        assert!(b.data[n * b.stride..].iter().all(|&v| v == 0.0), "padding rows are zero");
        for t in 0..w {
            let want = 0.5 + (0..n).map(|i| b.data[i * b.stride + t]).sum::<f64>();
            assert_eq!(colsum[t], want, "{isa}: column sums add the rows in order");
        }
        assert!((st.energy - energy).abs() <= 2.0 * gamma(n * w) * energy);
        energies.push(st.energy.to_bits());
        assert_eq!(st.peak, 1e5);
        assert!(st.finite);
        // A NaN in the 16-wide body and an infinity in the tail are both seen.
        for (pos, bad) in [(2 * m + c0 + 12, f32::NAN), (m + c0 + 35, f32::INFINITY)] {
            let mut y = x.clone();
            y[pos] = bad;
            let st = load(&y, &mut b, &mut colsum);
            assert!(!st.finite, "{isa}: {bad} at {pos}");
        }
    }
    // The squares are exact and every path adds them in the same lanes and order.
    assert!(energies.iter().all(|&e| e == energies[0]), "energy differs between paths");
}

#[test]
fn f32_blocks_get_the_rounded_differences_and_the_same_sums_and_statistics_on_every_path() {
    // The single-precision Gram matrix's load: the f64 load's values rounded to nearest,
    // its column sums and statistics bit for bit (both exact, from the unrounded
    // differences); f32 and f16 rows, 37 columns (two groups of 16, a tail of 5).
    let (n, m, c0, w) = (4, 50, 4, 37);
    let mut x = values(n * m, 21);
    x[m + 9] = 1e5; // its difference from the shift rounds in f32, not in f64
    let halves: Vec<half::f16> = x.iter().map(|&v| half::f16::from_f32(v)).collect();
    let x16: Vec<f32> = halves.iter().map(|h| h.to_f32()).collect();
    let rows_h: Vec<&[half::f16]> = halves.chunks_exact(m).collect();
    for isa in paths() {
        for (label, wide) in [("f32", &x), ("f16", &x16)] {
            let rows = rows_of(wide, n, m);
            let shift = Some(rows[2]);
            let (mut b64, mut b32) = (Block::default(), Block32::default());
            let (mut c64, mut c32) = (vec![0.25; w], vec![0.25; w]);
            let s64 = load_shifted_with(&rows, c0, w, shift, &mut b64, Some(&mut c64), isa);
            let s32 = if label == "f16" {
                load_shifted_with(&rows_h, c0, w, Some(rows_h[2]), &mut b32, Some(&mut c32), isa)
            } else {
                load_shifted_with(&rows, c0, w, shift, &mut b32, Some(&mut c32), isa)
            };
            let key = |s: Option<LoadStats>| s.map(|s| (s.energy.to_bits(), s.peak, s.finite));
            assert_eq!(key(s32), key(s64), "{isa} {label}: statistics");
            assert_eq!(c32, c64, "{isa} {label}: column sums");
            for i in 0..n {
                for t in 0..b32.stride {
                    let want = if t < w { b64.data[i * b64.stride + t] as f32 } else { 0.0 };
                    assert_eq!(b32.data[i * b32.stride + t], want, "{isa} {label} ({i}, {t})");
                }
            }
            assert!(b32.data[n * b32.stride..].iter().all(|&v| v == 0.0), "padding rows");
            // Without statistics: shifted or not, the same rounding.
            for shift in [None, shift] {
                load_shifted_with(&rows, c0, w, shift, &mut b64, None, isa);
                load_shifted_with(&rows, c0, w, shift, &mut b32, None, isa);
                for i in 0..n {
                    for t in 0..w {
                        let want = b64.data[i * b64.stride + t] as f32;
                        assert_eq!(b32.data[i * b32.stride + t], want, "{isa} {label} plain");
                    }
                }
            }
        }
    }
}

#[test]
fn f16_rows_load_as_their_f32_values_on_every_path() {
    // 37 columns from 4: two groups of 16 and a tail of 5; values of every f16 magnitude
    // (subnormals, ±65504) load exactly as the same values stored as f32.
    let (n, m, c0, w) = (3, 50, 4, 37);
    let mut halves: Vec<half::f16> =
        values(n * m, 7).iter().map(|&v| half::f16::from_f32(v)).collect();
    for (pos, v) in [(9, 65504.0), (60, -65504.0), (70, 3e-7), (110, -6e-5)] {
        halves[pos] = half::f16::from_f32(v);
    }
    let wide: Vec<f32> = halves.iter().map(|h| h.to_f32()).collect();
    let rows_h: Vec<&[half::f16]> = halves.chunks_exact(m).collect();
    for isa in paths() {
        for stats in [false, true] {
            let (mut bh, mut bf) = (Block::default(), Block::default());
            let (mut ch, mut cf) = (vec![0.0; w], vec![0.0; w]);
            let sh = Some(rows_h[1]);
            let sf = Some(&wide[m..2 * m]);
            let (ch, cf) =
                if stats { (Some(&mut ch[..]), Some(&mut cf[..])) } else { (None, None) };
            let a = load_shifted_with(&rows_h, c0, w, sh, &mut bh, ch, isa);
            let b = load_shifted_with(&rows_of(&wide, n, m), c0, w, sf, &mut bf, cf, isa);
            assert_eq!(bh.data, bf.data, "{isa}, stats {stats}");
            let key = |s: Option<LoadStats>| s.map(|s| (s.energy, s.peak, s.finite));
            assert_eq!(key(a), key(b), "{isa}, stats {stats}");
        }
        // And widened to f32 blocks alike.
        let (mut yh, mut yf) = (Block32::default(), Block32::default());
        yh.widen_from_with(&rows_h, c0, w, isa);
        yf.widen_from_with(&rows_of(&wide, n, m), c0, w, isa);
        assert_eq!(yh.data, yf.data, "{isa}");
    }
}

#[test]
fn the_scalar_path_differs_from_the_fused_ones_only_by_rounding() {
    // Products of f32 values are exact in f64, fused or not; those of full f64 values (a
    // shifted block, the lift's coefficients) round, and then the paths are not
    // bit-identical, but close. This guards the tests above against comparing a path
    // with itself.
    let (n, m) = (9, 512);
    let x = values(n * m, 11);
    let mut blk = block(&x, n, m, 0, m);
    blk.data.iter_mut().for_each(|v| *v /= 3.0);
    let mut gs = Vec::new();
    for isa in [Isa::Scalar, Isa::Neon] {
        let mut acc = DotAcc::new(n, n, true);
        acc.add_with(&blk, &blk, isa);
        let mut g = vec![0.0; n * n];
        acc.finish(&mut g, n);
        gs.push(g);
    }
    assert_ne!(gs[0], gs[1], "the fused path should round differently somewhere");
    for (a, b) in gs[0].iter().zip(&gs[1]) {
        assert!((a - b).abs() <= 1e-12 * (1.0 + a.abs()));
    }
}
