//! ꟻLIP on 512² (criterion): LDR-ꟻLIP and HDR-ꟻLIP of a rendering-like pair (smooth shading
//! with texture, the test carrying noise as a path tracer with few samples would). The
//! baseline is NVIDIA's `flip_evaluator` (C++ with OpenMP behind nanobind) on the same
//! pair, timed by `btf-image/benches/flip_reference_timing.py` in the same session;
//! btf-image/README.md has the commands and figures.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use btf_image::flip::{DEFAULT_PPD, flip_hdr, flip_ldr};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const N: usize = 512;

/// A reference (peak ≈ `peak`) and a noisy test image, `N × N` linear RGB.
fn pair(peak: f32) -> (Vec<f32>, Vec<f32>) {
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut reference = Vec::with_capacity(N * N * 3);
    let mut test = Vec::with_capacity(N * N * 3);
    for i in 0..N * N {
        let (x, y) = ((i % N) as f32 / N as f32, (i / N) as f32 / N as f32);
        let shade = (1.0 - (x - 0.4).hypot(y - 0.5)).max(0.0).powi(3);
        let weave = 0.75 + 0.25 * (x * 180.0).sin() * (y * 180.0).cos();
        for c in [0.9, 0.6, 0.4] {
            let v = peak * shade * weave * c;
            reference.push(v);
            test.push(v * (0.6 + 0.8 * rnd()));
        }
    }
    (reference, test)
}

fn bench(c: &mut Criterion) {
    let (r, t) = pair(1.0);
    c.bench_function("flip_ldr 512²", |b| {
        b.iter(|| flip_ldr(black_box(&r), black_box(&t), N, N, DEFAULT_PPD).unwrap())
    });
    let (r, t) = pair(20.0);
    let n = flip_hdr(&r, &t, N, N, DEFAULT_PPD, None).unwrap().exposures.unwrap().count;
    c.bench_function(&format!("flip_hdr 512² ({n} exposures)"), |b| {
        b.iter(|| flip_hdr(black_box(&r), black_box(&t), N, N, DEFAULT_PPD, None).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
