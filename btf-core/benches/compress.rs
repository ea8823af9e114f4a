//! Compression benchmarks (criterion): the per-slot PCA on one realistic 256² view slot, and
//! the whole 81 × 81 BTF compressed from its store (the store named by `BTF_BENCH_STORE`,
//! e.g. `btf synth material --kind corduroy --size 256 -o /tmp/bench/corduroy256.btf`, an
//! f32 store of 5.16 GB; without it that benchmark is skipped). The baseline
//! (scikit-learn's PCA on the same slots, exported with `btf export --format npy` or
//! `benches/export_slots_npy.py`) runs in the same session through
//! `benches/sklearn_baseline.py`; BENCHMARKS.md has the commands and figures.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use btf_core::eigen::Quantization;
use btf_core::pca::{GramPrecision, PcaScratch, SlotRows, pca_rows_in, pca_slot};
use btf_core::store::SlotData;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// A slot with the spectrum of a measured material: 81 light images of 256² texels built
/// from 40 spatial modes with power-law coefficients plus a little noise.
fn realistic_slot(size: usize) -> SlotData {
    let (n, m) = (81, size * size * 3);
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f32 / (1u64 << 53) as f32
    };
    let modes: Vec<Vec<f32>> = (0..40).map(|_| (0..m).map(|_| rnd()).collect()).collect();
    let mut data = vec![0f32; n * m];
    for i in 0..n {
        let row = &mut data[i * m..(i + 1) * m];
        for (k, mode) in modes.iter().enumerate() {
            let coef =
                ((i as f32 + 1.0) * 0.37 * (k as f32 + 1.0)).cos() / (1.0 + k as f32).powf(1.5);
            for (v, b) in row.iter_mut().zip(mode) {
                *v += coef * b;
            }
        }
        for v in row.iter_mut() {
            *v = v.abs() + 0.01 * rnd();
        }
    }
    SlotData { view: 0, n_lights: n, texel_values: m, data }
}

fn bench_pca_slot(c: &mut Criterion) {
    let slot = realistic_slot(256);
    let mut g = c.benchmark_group("pca_slot_256");
    g.sample_size(10);
    g.bench_function("c16_f16", |b| {
        b.iter(|| black_box(pca_slot(&slot, 16, Quantization::F16).unwrap()))
    });
    // The slot as an f16 store holds it: the Gram matrix in f32 (the default for f16
    // data) and, as the baseline, in f64.
    let halves: Vec<half::f16> = slot.data.iter().map(|&v| half::f16::from_f32(v)).collect();
    let m = slot.texel_values;
    let rows =
        SlotRows::<half::f16> { view: 0, rows: halves.chunks_exact(m).collect(), texel_values: m };
    for gram in [GramPrecision::F32, GramPrecision::F64] {
        let mut scratch = PcaScratch::default().with_gram(gram);
        g.bench_function(format!("c16_f16_rows_gram_{}", gram.name()), |b| {
            b.iter(|| {
                black_box(pca_rows_in(&rows, 16, Quantization::F16, &mut scratch, None).unwrap())
            })
        });
    }
    g.finish();
}

fn bench_store(c: &mut Criterion) {
    let Some(path) = std::env::var_os("BTF_BENCH_STORE") else {
        eprintln!("compress_store: set BTF_BENCH_STORE to a BTF store to run this benchmark");
        return;
    };
    let store =
        btf_core::store::BtfStore::open(std::path::Path::new(&path)).expect("bench store opens");
    let out = std::env::temp_dir().join(format!("btf-bench-{}.eig", std::process::id()));
    let mut g = c.benchmark_group("compress_store");
    g.sample_size(10);
    let m = store.meta();
    let name = format!("{}x{}_{}px_c16_f16", m.n_views(), m.n_lights(), m.width);
    g.bench_function(name, |b| {
        b.iter(|| {
            let params = btf_core::compress::CompressParams {
                components: 16,
                quantization: Quantization::F16,
                resume: false,
                ..Default::default()
            };
            let r = btf_core::compress::compress(&store, &out, params, &|| {}).unwrap();
            black_box(r.rel_rmse)
        })
    });
    g.finish();
    let params = btf_core::compress::CompressParams {
        components: 16,
        quantization: Quantization::F16,
        resume: false,
        ..Default::default()
    };
    let r = btf_core::compress::compress(&store, &out, params, &|| {}).unwrap();
    eprintln!(
        "compress_store: rel_rmse {:.4e} (exact PCA {:.4e}), {:.2} s",
        r.rel_rmse, r.rel_rmse_exact, r.seconds
    );
    std::fs::remove_dir_all(&out).ok();
}

criterion_group!(benches, bench_pca_slot, bench_store);
criterion_main!(benches);
