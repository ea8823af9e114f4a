//! Milliseconds per step of the knit animation ([C03 §4]) against triangle count: the
//! scarf dropped onto a table at about 1k, 4k and 15k triangles (the paper's falling scarf
//! has "approximately 15000"), velocity Verlet with the paper's §6 constants, measured a
//! few steps into the fall.

#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
use datasets::sim::knit::KnitSim;
use datasets::sim::scenes::{DropTarget, ScarfDrop, ScarfSize};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("knit_sim_step");
    group.sample_size(10);
    for triangles in [1_000, 4_000, 15_000] {
        let size = if triangles == 15_000 {
            ScarfSize::FULL
        } else {
            ScarfSize::with_triangles(triangles)
        };
        let scene = ScarfDrop::new(size, DropTarget::Table);
        let shape = scene.collider();
        let x = scene.initial_positions().expect("scene");
        let mut sim = KnitSim::new(size.0, x, &scene.knit, Some(&shape)).expect("knit");
        for _ in 0..20 {
            sim.sim.step();
        }
        let n = sim.sim.cloth.triangles.len();
        group.bench_function(format!("{n}_triangles"), |b| b.iter(|| sim.sim.step()));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
