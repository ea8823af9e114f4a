//! The Gram kernels' throughput against the core's peak (BENCHMARKS.md #2 and "Instruction
//! sets"), on the path `BTF_SIMD` chooses: `DotAcc::add` of one `rows × columns` block with
//! itself in `f64` and `GramAcc32::add` of it in `f32` panels (upper triangle, the block in
//! the cache), and the fused pass's lift of the block to 16 rows in `f64` (`lift_rows32`),
//! against independent chains of register-only FMAs of the path's width (twelve 512-bit
//! chains under `avx512`, ten 256-bit ones under `avx2`), all in multiply-adds per second,
//! best of five, on one thread: `gram_rate [ROWS [COLUMNS]]` (default 81 × 1024).
#![allow(unsafe_code)] // the peak loops use intrinsics directly

use btf_core::kernels::{Block, Block32, DotAcc, GramAcc32, lift_rows32};
use btf_core::simd::Isa;
use std::time::Instant;

/// Multiply-adds per second of `add` (one block's upper triangle), best of five.
fn rate(n: usize, w: usize, add: impl FnMut()) -> f64 {
    rate_of((n * (n + 1) / 2 * w) as f64, add)
}

/// Multiply-adds per second of `add`, which does `products` of them, best of five.
fn rate_of(products: f64, mut add: impl FnMut()) -> f64 {
    let reps = (4e9 / products) as usize + 1;
    let mut best = 0f64;
    for _ in 0..5 {
        let t = Instant::now();
        for _ in 0..reps {
            add();
        }
        best = best.max(reps as f64 * products / t.elapsed().as_secs_f64());
    }
    best
}

fn value(i: usize, t: usize) -> f64 {
    ((i * 31 + t * 17) % 97) as f64 * 1e-2
}

/// The register-only peak in `f32` multiply-adds per second (an `f64` one is half of it).
#[cfg(target_arch = "x86_64")]
fn peak_f32(isa: Isa) -> Option<f64> {
    use std::arch::x86_64::*;
    /// Twelve independent chains of 16-lane FMAs in registers (named: nothing spills).
    #[target_feature(enable = "avx512f")]
    fn chains512(iters: usize) -> f32 {
        let (a, b) = (_mm512_set1_ps(1.000_000_1), _mm512_set1_ps(0.999_999_9));
        let one = _mm512_set1_ps(1.0);
        let (mut v0, mut v1, mut v2, mut v3, mut v4, mut v5) = (one, one, one, one, one, one);
        let (mut v6, mut v7, mut v8, mut v9, mut v10, mut v11) = (one, one, one, one, one, one);
        for _ in 0..iters {
            v0 = _mm512_fmadd_ps(v0, a, b);
            v1 = _mm512_fmadd_ps(v1, a, b);
            v2 = _mm512_fmadd_ps(v2, a, b);
            v3 = _mm512_fmadd_ps(v3, a, b);
            v4 = _mm512_fmadd_ps(v4, a, b);
            v5 = _mm512_fmadd_ps(v5, a, b);
            v6 = _mm512_fmadd_ps(v6, a, b);
            v7 = _mm512_fmadd_ps(v7, a, b);
            v8 = _mm512_fmadd_ps(v8, a, b);
            v9 = _mm512_fmadd_ps(v9, a, b);
            v10 = _mm512_fmadd_ps(v10, a, b);
            v11 = _mm512_fmadd_ps(v11, a, b);
        }
        [v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11]
            .iter()
            .fold(0.0, |s, x| s + _mm512_reduce_add_ps(*x))
    }
    /// Ten independent chains of 8-lane FMAs (ten of sixteen registers).
    #[target_feature(enable = "avx2,fma")]
    fn chains256(iters: usize) -> f32 {
        let (a, b) = (_mm256_set1_ps(1.000_000_1), _mm256_set1_ps(0.999_999_9));
        let one = _mm256_set1_ps(1.0);
        let (mut v0, mut v1, mut v2, mut v3, mut v4) = (one, one, one, one, one);
        let (mut v5, mut v6, mut v7, mut v8, mut v9) = (one, one, one, one, one);
        for _ in 0..iters {
            v0 = _mm256_fmadd_ps(v0, a, b);
            v1 = _mm256_fmadd_ps(v1, a, b);
            v2 = _mm256_fmadd_ps(v2, a, b);
            v3 = _mm256_fmadd_ps(v3, a, b);
            v4 = _mm256_fmadd_ps(v4, a, b);
            v5 = _mm256_fmadd_ps(v5, a, b);
            v6 = _mm256_fmadd_ps(v6, a, b);
            v7 = _mm256_fmadd_ps(v7, a, b);
            v8 = _mm256_fmadd_ps(v8, a, b);
            v9 = _mm256_fmadd_ps(v9, a, b);
        }
        let mut s = [0f32; 8];
        let sum = [v1, v2, v3, v4, v5, v6, v7, v8, v9].iter().fold(v0, |s, x| _mm256_add_ps(s, *x));
        // SAFETY: `s` holds eight values.
        unsafe { _mm256_storeu_ps(s.as_mut_ptr(), sum) };
        s.iter().sum()
    }
    let (chains, lanes): (usize, usize) = match isa {
        Isa::Avx512 => (12, 16),
        Isa::Avx2 => (10, 8),
        _ => return None,
    };
    let iters = 20_000_000;
    let mut best = 0f64;
    for _ in 0..5 {
        let t = Instant::now();
        // SAFETY: the path is one this CPU runs (`Isa::active` checked its features).
        let v = unsafe { if isa == Isa::Avx512 { chains512(iters) } else { chains256(iters) } };
        std::hint::black_box(v);
        best = best.max((iters * chains * lanes) as f64 / t.elapsed().as_secs_f64());
    }
    Some(best)
}

#[cfg(not(target_arch = "x86_64"))]
fn peak_f32(_: Isa) -> Option<f64> {
    None
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    // ROWS and COLUMNS: positive and modest (a block is ROWS × COLUMNS values, twice).
    let arg = |k: usize, name: &str, default: usize, most: usize| -> usize {
        let Some(a) = args.get(k) else { return default };
        match a.parse::<usize>() {
            Ok(v) if (1..=most).contains(&v) => v,
            _ => {
                eprintln!("gram_rate [ROWS [COLUMNS]]: {name} '{a}' is not a number in 1..={most}");
                std::process::exit(2)
            }
        }
    };
    let (n, w) = (arg(1, "ROWS", 81, 1024), arg(2, "COLUMNS", 1024, 1 << 16));
    let isa = Isa::active();
    let (mut b64, mut b32) = (Block::default(), Block32::default());
    b64.shape(n, w);
    b32.shape(n, w);
    for i in 0..n {
        for t in 0..w {
            b64.row_mut(i)[t] = value(i, t);
            b32.row_mut(i)[t] = value(i, t) as f32;
        }
    }
    let mut acc64 = DotAcc::new(n, n, true);
    let g64 = rate(n, w, || acc64.add(&b64, &b64));
    let mut acc32 = GramAcc32::new(n);
    let g32 = rate(n, w, || acc32.add(&b32));
    let mut out = vec![0f64; n * n];
    acc64.finish(&mut out, n);
    acc32.finish(&mut out, n);
    std::hint::black_box(out);
    // The lift of the fused pass: 16 components of the block in f64 (lift_rows32).
    let cp = 16;
    let coef: Vec<f64> = (0..n * cp).map(|i| value(i, 3) - 0.4).collect();
    let ws = b32.stride;
    let mut lifted = vec![0f64; cp * ws];
    let l64 = rate_of((n * cp * w) as f64, || lift_rows32(&b32, &coef, cp, &mut lifted, ws, 0));
    std::hint::black_box(lifted);
    println!("path {isa}, Gram matrix of {n} × {w} (needed products only), lift to {cp} rows:");
    let peak = peak_f32(isa);
    let rows =
        [("f64 (DotAcc)", g64, 0.5), ("f32 panels (GramAcc32)", g32, 1.0), ("f64 lift", l64, 0.5)];
    for (name, g, per_peak) in rows {
        match peak {
            Some(p) => println!(
                "  {name}: {:.2} G multiply-adds/s, {:.0} % of the register-only FMA peak in its precision ({:.2} G/s)",
                g / 1e9,
                100.0 * g / (p * per_peak),
                p * per_peak / 1e9
            ),
            None => {
                println!("  {name}: {:.2} G multiply-adds/s (no peak loop on this path)", g / 1e9)
            }
        }
    }
}
