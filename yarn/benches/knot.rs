//! Knot solver speed (issue 20, DESIGN §3.4): milliseconds per frame for 10³, 10⁴ and 10⁵
//! stitch faces (a 1×1 rib under 30 % shear and 20 % wale stretch, 3 Gauss–Newton
//! iterations), in parallel (rayon, all cores) and serial, against naive interpolation of
//! the rest CPs measured in the same run (the cheapest way to move yarns with a mesh), and
//! how the cost grows with the faces; and the cost of turning a solved frame into yarn
//! curves (at the CPs, and up-sampled 4×).
//!
//! `cargo bench -p yarn --bench knot` prints the scaling table (median of 5 per row), then
//! runs the criterion groups at 10³ and 10⁴ faces.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{Criterion, criterion_group};
use std::hint::black_box;
use std::time::Instant;
use yarn::knit::{Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh};

fn setup(side: usize) -> (KnotModel, StitchMesh, f64) {
    let sk = SkeletonParams::new(2e-4);
    let (sw, sc) = sk.default_spacing();
    let chart = Chart::builtin("rib1x1").unwrap();
    let rest = StitchMesh::flat(&chart, side, side, sw, sc).unwrap();
    let t = Instant::now();
    let model = KnotModel::new(&rest, &sk, (sw, sc)).unwrap();
    let build = t.elapsed().as_secs_f64();
    let mesh = rest.shear(0.3).unwrap().stretch(0.0, 0.2).unwrap();
    (model, mesh, build)
}

fn median_ms(mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..5)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[2]
}

fn scaling_table() {
    println!(
        "\n| faces | CPs | model build (s) | naive (ms) | knots, 0 it. (ms) | 3 it. parallel (ms) | 3 it. serial (ms) | parallel / naive | µs per face (parallel) | yarn curves, CPs / 4× up-sampled (ms) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let p = KnotParams::default();
    for side in [32usize, 100, 316] {
        let (model, mesh, build) = setup(side);
        let naive = median_ms(|| {
            black_box(model.naive(&mesh).unwrap());
        });
        let zero = median_ms(|| {
            black_box(model.solve(&mesh, &KnotParams { iterations: 0, ..p }).unwrap());
        });
        let par = median_ms(|| {
            black_box(model.solve(&mesh, &p).unwrap());
        });
        let ser = median_ms(|| {
            black_box(model.solve_with(&mesh, &p, true).unwrap());
        });
        let frame = model.solve(&mesh, &p).unwrap();
        let curves1 = median_ms(|| {
            black_box(model.yarn_set(&frame, 1).unwrap());
        });
        let curves4 = median_ms(|| {
            black_box(model.yarn_set(&frame, 4).unwrap());
        });
        let faces = model.knot_faces();
        println!(
            "| {faces} | {} | {build:.2} | {naive:.2} | {zero:.2} | {par:.2} | {ser:.2} | {:.1} | {:.2} | {curves1:.2} / {curves4:.2} |",
            model.cp_count(),
            par / naive,
            par * 1e3 / faces as f64
        );
    }
}

fn bench(c: &mut Criterion) {
    let p = KnotParams::default();
    let mut g = c.benchmark_group("knot_solve");
    g.sample_size(10);
    for side in [32usize, 100] {
        let (model, mesh, _) = setup(side);
        g.bench_function(format!("{}_faces", model.knot_faces()), |b| {
            b.iter(|| black_box(model.solve(&mesh, &p).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    scaling_table();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
