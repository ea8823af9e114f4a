//! The Gram kernel's throughput against the core's peak (BENCHMARKS.md #2): `DotAcc::add`
//! of one `rows × columns` `f64` block with itself (upper triangle, the block in the cache),
//! and twelve independent chains of register-only AVX-512 FMAs, both in 8-lane FMAs per second,
//! best of five, on one thread: `gram_rate [ROWS [COLUMNS]]` (default 81 × 1024).
#![allow(unsafe_code)] // the peak loop uses AVX-512 intrinsics directly

use btf_core::kernels::{Block, DotAcc};
use std::time::Instant;

fn gram_rate(n: usize, w: usize) -> f64 {
    let mut blk = Block::default();
    blk.shape(n, w);
    for i in 0..n {
        for (t, v) in blk.row_mut(i)[..w].iter_mut().enumerate() {
            *v = ((i * 31 + t * 17) % 97) as f64 * 1e-2;
        }
    }
    let products = (n * (n + 1) / 2) as f64;
    let reps = (4e9 / (products * w as f64)) as usize + 1;
    let mut best = 0f64;
    for _ in 0..5 {
        let mut acc = DotAcc::new(n, n, true);
        let t = Instant::now();
        for _ in 0..reps {
            acc.add(&blk, &blk);
        }
        best = best.max(reps as f64 * products * w as f64 / 8.0 / t.elapsed().as_secs_f64());
        let mut g = vec![0f64; n * n];
        acc.finish(&mut g, n);
        std::hint::black_box(g);
    }
    best
}

#[cfg(target_arch = "x86_64")]
fn peak_rate() -> Option<f64> {
    use std::arch::x86_64::*;
    /// Twelve independent chains of FMAs in registers (named, so that nothing spills).
    #[target_feature(enable = "avx512f")]
    fn chains(iters: usize) -> f64 {
        let (a, b) = (_mm512_set1_pd(1.000_000_1), _mm512_set1_pd(0.999_999_9));
        let one = _mm512_set1_pd(1.0);
        let (mut v0, mut v1, mut v2, mut v3, mut v4, mut v5) = (one, one, one, one, one, one);
        let (mut v6, mut v7, mut v8, mut v9, mut v10, mut v11) = (one, one, one, one, one, one);
        for _ in 0..iters {
            v0 = _mm512_fmadd_pd(v0, a, b);
            v1 = _mm512_fmadd_pd(v1, a, b);
            v2 = _mm512_fmadd_pd(v2, a, b);
            v3 = _mm512_fmadd_pd(v3, a, b);
            v4 = _mm512_fmadd_pd(v4, a, b);
            v5 = _mm512_fmadd_pd(v5, a, b);
            v6 = _mm512_fmadd_pd(v6, a, b);
            v7 = _mm512_fmadd_pd(v7, a, b);
            v8 = _mm512_fmadd_pd(v8, a, b);
            v9 = _mm512_fmadd_pd(v9, a, b);
            v10 = _mm512_fmadd_pd(v10, a, b);
            v11 = _mm512_fmadd_pd(v11, a, b);
        }
        [v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11]
            .iter()
            .fold(0.0, |s, x| s + _mm512_reduce_add_pd(*x))
    }
    if !std::arch::is_x86_feature_detected!("avx512f") {
        return None;
    }
    let iters = 20_000_000;
    let mut best = 0f64;
    for _ in 0..5 {
        let t = Instant::now();
        // SAFETY: AVX-512F detected just above; the function is safe code otherwise.
        std::hint::black_box(unsafe { chains(iters) });
        best = best.max(iters as f64 * 12.0 / t.elapsed().as_secs_f64());
    }
    Some(best)
}

#[cfg(not(target_arch = "x86_64"))]
fn peak_rate() -> Option<f64> {
    None
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(81, |a| a.parse().expect("ROWS: a number"));
    let w: usize = args.get(2).map_or(1024, |a| a.parse().expect("COLUMNS: a number"));
    let g = gram_rate(n, w);
    println!("Gram kernel, {n} × {w}: {:.2} G 8-lane FMAs/s (needed products)", g / 1e9);
    match peak_rate() {
        Some(p) => println!(
            "register-only FMA loop: {:.2} G/s; the kernel reaches {:.0} %",
            p / 1e9,
            100.0 * g / p
        ),
        None => println!("no AVX-512: no peak loop"),
    }
}
