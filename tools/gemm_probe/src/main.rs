//! The Gram matrix `YYᵀ` of one `n × w` block (default 81 × 1024, the compressor's block)
//! four ways on one thread, best of seven, in microseconds a block: btf-core's `f64` tiles
//! (`DotAcc`, upper triangle), its `f32` lanes (`GramAcc32`, upper triangle), and the whole
//! product by `gemm` (`Parallelism::None`) and by `matrixmultiply`, in `f32` and `f64`.
//! Usage: `gemm_probe [ROWS [COLUMNS]]`.
#![allow(unsafe_code)]

use btf_core::kernels::{Block, Block32, DotAcc, GramAcc32};
use btf_core::simd::Isa;
use std::time::Instant;

/// Best time of seven runs of `reps` calls, in microseconds per call.
fn best_us(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::MAX;
    for _ in 0..7 {
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e6 / reps as f64);
    }
    best
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, name: &str, default: usize, most: usize| -> usize {
        let Some(a) = args.get(k) else { return default };
        match a.parse::<usize>() {
            Ok(v) if (1..=most).contains(&v) => v,
            _ => {
                eprintln!("gemm_probe [ROWS [COLUMNS]]: {name} '{a}' is not a number in 1..={most}");
                std::process::exit(2)
            }
        }
    };
    let (n, w) = (arg(1, "ROWS", 81, 1024), arg(2, "COLUMNS", 1024, 1 << 16));
    let value = |i: usize, t: usize| ((i * 31 + t * 17) % 97) as f64 * 1e-2 - 0.4;
    let y64: Vec<f64> = (0..n * w).map(|k| value(k / w, k % w)).collect();
    let y32: Vec<f32> = y64.iter().map(|&v| v as f32).collect();
    let (mut b64, mut b32) = (Block::default(), Block32::default());
    b64.shape(n, w);
    b32.shape(n, w);
    for i in 0..n {
        b64.row_mut(i)[..w].copy_from_slice(&y64[i * w..(i + 1) * w]);
        b32.row_mut(i)[..w].copy_from_slice(&y32[i * w..(i + 1) * w]);
    }
    let reps = (2e9 / (n * n * w) as f64) as usize + 1;
    let mut acc64 = DotAcc::new(n, n, true);
    let t_dot = best_us(reps, || acc64.add(&b64, &b64));
    let mut acc32 = GramAcc32::new(n);
    let t_g32 = best_us(reps, || acc32.add(&b32));
    let (mut g32, mut g64) = (vec![0f32; n * n], vec![0f64; n * n]);
    let (wi, ni) = (w as isize, n as isize);
    let par = gemm::Parallelism::None;
    // SAFETY: Y is n × w row-major (row stride w), Yᵀ read through swapped strides, G n × n.
    let t_gemm32 = best_us(reps, || unsafe {
        gemm::gemm(
            n, n, w, g32.as_mut_ptr(), 1, ni, false, y32.as_ptr(), 1, wi, y32.as_ptr(), wi, 1,
            0.0, 1.0, false, false, false, par,
        )
    });
    let t_gemm64 = best_us(reps, || unsafe {
        gemm::gemm(
            n, n, w, g64.as_mut_ptr(), 1, ni, false, y64.as_ptr(), 1, wi, y64.as_ptr(), wi, 1,
            0.0, 1.0, false, false, false, par,
        )
    });
    let t_mm32 = best_us(reps, || unsafe {
        matrixmultiply::sgemm(
            n, w, n, 1.0, y32.as_ptr(), wi, 1, y32.as_ptr(), 1, wi, 0.0, g32.as_mut_ptr(), ni, 1,
        )
    });
    let t_mm64 = best_us(reps, || unsafe {
        matrixmultiply::dgemm(
            n, w, n, 1.0, y64.as_ptr(), wi, 1, y64.as_ptr(), 1, wi, 0.0, g64.as_mut_ptr(), ni, 1,
        )
    });
    // The same matrix from every method (the f32 ones to f32 rounding).
    let mut ours = vec![0f64; n * n];
    let mut fresh = DotAcc::new(n, n, true);
    fresh.add(&b64, &b64);
    fresh.finish(&mut ours, n);
    let worst = (0..n)
        .flat_map(|i| (i..n).map(move |j| (i, j)))
        .map(|(i, j)| ((g32[i * n + j] as f64 - ours[i * n + j]) / ours[i * n + j].abs().max(1.0)).abs())
        .fold(0f64, f64::max);
    assert!(worst < 1e-4, "gemm's f32 Gram matrix differs by {worst}");
    println!("Gram matrix of {n} × {w}, one thread, btf-core path {} (µs a block, best of 7):", Isa::active());
    for (name, t) in [
        ("btf-core DotAcc, f64, upper triangle", t_dot),
        ("btf-core GramAcc32, f32 panels, upper triangle", t_g32),
        ("gemm 0.18, f32, whole product", t_gemm32),
        ("gemm 0.18, f64, whole product", t_gemm64),
        ("matrixmultiply, f32, whole product", t_mm32),
        ("matrixmultiply, f64, whole product", t_mm64),
    ] {
        println!("  {name}: {t:.1} µs ({:.2}× GramAcc32)", t / t_g32);
    }
}
