//! The kernels against naive sums, and the AVX-512 and portable versions against each other.

use super::*;

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
    load_shifted(&rows_of(x, rows, m), c0, w, None, &mut b, None);
    b
}

#[test]
fn dot_acc_matches_naive_sums_for_both_kernels() {
    // Odd shapes (rows not multiples of the tiles, widths not of 8), accumulated over two
    // blocks of columns; a 12- or 16-row A takes the 4-row tiles; B rows past a multiple
    // of 5 (1 to 4 of them) take the narrow tiles, symmetric diagonals the triangular one.
    let m = 600; // the second block spans more than one 256-column sub-block
    for (na, nb) in [(11, 7), (12, 9), (16, 21), (21, 8), (14, 5)] {
        let xa = values(na * m, 1);
        let xb = values(nb * m, 2);
        let naive = |i: usize, j: usize, xb: &[f32]| -> f64 {
            (0..m).map(|t| xa[i * m + t] as f64 * xb[j * m + t] as f64).sum()
        };
        for simd in [false, true] {
            let mut acc = DotAcc::new(na, nb, false);
            let mut gram = DotAcc::new(na, na, true);
            for (c0, w) in [(0, 24), (24, m - 24)] {
                let (a, b) = (block(&xa, na, m, c0, w), block(&xb, nb, m, c0, w));
                acc.add_with(&a, &b, simd);
                gram.add_with(&a, &a, simd);
            }
            let ld = nb + 3;
            let mut out = vec![1.0; na * ld];
            acc.finish(&mut out, ld);
            for i in 0..na {
                for j in 0..ld {
                    let want = if j < nb { 1.0 + naive(i, j, &xb) } else { 1.0 };
                    assert!(
                        (out[i * ld + j] - want).abs() < 1e-12 * (1.0 + want.abs()),
                        "simd {simd} ({i}, {j})"
                    );
                }
            }
            // Upper triangle of a·aᵀ; the strict lower triangle is left alone.
            let mut g = vec![0.0; na * na];
            gram.finish(&mut g, na);
            for i in 0..na {
                for j in 0..na {
                    let want = if j >= i { naive(i, j, &xa) } else { 0.0 };
                    assert!(
                        (g[i * na + j] - want).abs() < 1e-12 * (1.0 + want.abs()),
                        "simd {simd} gram ({i}, {j})"
                    );
                }
            }
        }
    }
}

#[test]
fn lift_rows32_matches_naive_sums_for_both_kernels() {
    // 13 rows of f16 data widened to f32, 24 components (one group of 16, one of 8: both
    // kernels), 48 columns, offset c0: the block
    // pitch is the f32 block's.
    let (n, w, cp, c0) = (13, 48, 24, 8);
    let x: Vec<Vec<half::f16>> = (0..n)
        .map(|i| values(w, 10 + i as u64).iter().map(|&v| half::f16::from_f32(v)).collect())
        .collect();
    let rows: Vec<&[half::f16]> = x.iter().map(|r| &r[..]).collect();
    let mut y = Block32::default();
    y.widen_from(&rows, 0, w);
    let coef: Vec<f64> = values(n * cp, 4).iter().map(|&v| v as f64).collect();
    let ldo = c0 + y.stride + 3;
    for simd in [false, true] {
        let mut out = vec![7.0; cp * ldo];
        lift_rows32_with(&y, &coef, cp, &mut out, ldo, c0, simd);
        for k in 0..cp {
            for t in c0..c0 + w {
                let want: f64 = (0..n).map(|i| coef[i * cp + k] * x[i][t - c0].to_f64()).sum();
                assert!((out[k * ldo + t] - want).abs() < 1e-12, "simd {simd} ({k}, {t})");
            }
            assert!(out[k * ldo..k * ldo + c0].iter().all(|&v| v == 7.0), "before c0");
        }
    }
}

#[test]
fn load_shifted_is_exact_and_reports_statistics_for_both_kernels() {
    // 37 columns: two groups of 16 and a tail of 5.
    let (n, m, c0, w) = (3, 50, 4, 37);
    let mut x = values(n * m, 5);
    x[m + 9] = 1e5; // a large value next to small ones: x − s stays exact in f64
    let shift: Vec<f32> = values(m, 6).iter().map(|v| v * 1e-4).collect();
    for simd in [false, true] {
        let mut b = Block::default();
        let mut colsum = vec![0.5; w];
        let load = |x: &[f32], b: &mut Block, colsum: &mut [f64]| {
            load_shifted_with(&rows_of(x, n, m), c0, w, Some(&shift), b, Some(colsum), simd)
                .unwrap()
        };
        let st = load(&x, &mut b, &mut colsum);
        let mut energy = 0f64;
        for i in 0..n {
            for t in 0..b.stride {
                let want =
                    if t < w { x[i * m + c0 + t] as f64 - shift[c0 + t] as f64 } else { 0.0 };
                assert_eq!(b.data[i * b.stride + t], want, "simd {simd} ({i}, {t})");
            }
            energy += (0..w).map(|t| (x[i * m + c0 + t] as f64).powi(2)).sum::<f64>();
        }
        assert!(b.data[n * b.stride..].iter().all(|&v| v == 0.0), "padding rows are zero");
        for t in 0..w {
            let want = 0.5 + (0..n).map(|i| b.data[i * b.stride + t]).sum::<f64>();
            assert!((colsum[t] - want).abs() < 1e-12);
        }
        assert!((st.energy - energy).abs() <= 1e-12 * energy);
        assert_eq!(st.peak, 1e5);
        assert!(st.finite);
        // A NaN in the 16-wide body and an infinity in the tail are both seen.
        for (pos, bad) in [(2 * m + c0 + 12, f32::NAN), (m + c0 + 35, f32::INFINITY)] {
            let mut y = x.clone();
            y[pos] = bad;
            let st = load(&y, &mut b, &mut colsum);
            assert!(!st.finite, "simd {simd}: {bad} at {pos}");
        }
    }
}

#[test]
fn f16_rows_load_as_their_f32_values_for_both_kernels() {
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
    for simd in [false, true] {
        for stats in [false, true] {
            let (mut bh, mut bf) = (Block::default(), Block::default());
            let (mut ch, mut cf) = (vec![0.0; w], vec![0.0; w]);
            let sh = Some(rows_h[1]);
            let sf = Some(&wide[m..2 * m]);
            let (ch, cf) =
                if stats { (Some(&mut ch[..]), Some(&mut cf[..])) } else { (None, None) };
            let a = load_shifted_with(&rows_h, c0, w, sh, &mut bh, ch, simd);
            let b = load_shifted_with(&rows_of(&wide, n, m), c0, w, sf, &mut bf, cf, simd);
            assert_eq!(bh.data, bf.data, "simd {simd}, stats {stats}");
            let key = |s: Option<LoadStats>| s.map(|s| (s.energy, s.peak, s.finite));
            assert_eq!(key(a), key(b), "simd {simd}, stats {stats}");
        }
    }
}
