//! The knot solver's WGSL pass against the CPU solve in the same run (issue 20: "a WGSL
//! version only if it measures faster"): milliseconds per frame for 10³, 10⁴ and 10⁵
//! stitch faces of the CPU bench's scene (a 1×1 rib under 30 % shear and 20 % wale stretch,
//! 3 Gauss–Newton iterations), the GPU frame split into CPU preparation, upload, pass +
//! read-back and knot points, and the largest knot-point difference between the two.
//!
//! `cargo bench -p yarn-render --bench knot_gpu` prints the table (median of 5 per row;
//! needs an adapter — lavapipe here, which runs the pass on the same CPU cores), then runs
//! a criterion group at 10³ and 10⁴ faces.

use btf_render::Gpu;
use criterion::Criterion;
use std::hint::black_box;
use std::time::Instant;
use yarn::knit::{Chart, KnotModel, KnotParams, SkeletonParams, StitchMesh};
use yarn_render::knot::{KnotGpuSolver, KnotGpuTiming};

const R: f64 = 2e-4;

fn setup(side: usize) -> (KnotModel, StitchMesh) {
    let sk = SkeletonParams::new(R);
    let (sw, sc) = sk.default_spacing();
    let chart = Chart::builtin("rib1x1").unwrap();
    let rest = StitchMesh::flat(&chart, side, side, sw, sc).unwrap();
    let model = KnotModel::new(&rest, &sk, (sw, sc)).unwrap();
    (model, rest.shear(0.3).unwrap().stretch(0.0, 0.2).unwrap())
}

fn median<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut last = None;
    let mut t: Vec<f64> = (0..5)
        .map(|_| {
            let s = Instant::now();
            last = Some(f());
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    (t[2], last.expect("five runs"))
}

fn table(gpu: &Gpu) {
    println!("\nadapter: {} ({:?})", gpu.info.name, gpu.info.backend);
    println!(
        "\n| faces | CPU 3 it., all cores (ms) | GPU frame (ms) | prepare / upload / pass + read-back / finish, each its median (ms) | GPU / CPU | max |GPU − CPU| (r) |"
    );
    println!("|---:|---:|---:|---|---:|---:|");
    let p = KnotParams::default();
    for side in [32usize, 100, 316] {
        let (model, mesh) = setup(side);
        let solver = KnotGpuSolver::new(gpu, &model).unwrap();
        // One untimed frame each: pipeline caches, page faults.
        let cpu_frame = model.solve(&mesh, &p).unwrap();
        solver.solve(gpu, &model, &mesh, &p).unwrap();
        let (cpu, _) = median(|| black_box(model.solve(&mesh, &p).unwrap()));
        let mut parts: Vec<KnotGpuTiming> = Vec::new();
        let (gpu_ms, frame) = median(|| {
            let (frame, t) = solver.solve(gpu, &model, &mesh, &p).unwrap();
            parts.push(t);
            frame
        });
        // Each part's own median over the five frames.
        let part = |f: fn(&KnotGpuTiming) -> f64| {
            let mut v: Vec<f64> = parts.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let t = KnotGpuTiming {
            prepare: part(|t| t.prepare),
            upload: part(|t| t.upload),
            gpu: part(|t| t.gpu),
            finish: part(|t| t.finish),
        };
        let dev = cpu_frame
            .points
            .iter()
            .zip(&frame.points)
            .map(|(a, b)| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max)
            / R;
        println!(
            "| {} | {cpu:.2} | {gpu_ms:.2} | {:.2} / {:.2} / {:.2} / {:.2} | {:.2} | {dev:.1e} |",
            model.knot_faces(),
            t.prepare * 1e3,
            t.upload * 1e3,
            t.gpu * 1e3,
            t.finish * 1e3,
            gpu_ms / cpu
        );
    }
}

fn bench(c: &mut Criterion, gpu: &Gpu) {
    let p = KnotParams::default();
    let mut g = c.benchmark_group("knot_solve_gpu");
    g.sample_size(10);
    for side in [32usize, 100] {
        let (model, mesh) = setup(side);
        let solver = KnotGpuSolver::new(gpu, &model).unwrap();
        g.bench_function(format!("{}_faces_gpu", model.knot_faces()), |b| {
            b.iter(|| black_box(solver.solve(gpu, &model, &mesh, &p).unwrap()))
        });
        g.bench_function(format!("{}_faces_cpu", model.knot_faces()), |b| {
            b.iter(|| black_box(model.solve(&mesh, &p).unwrap()))
        });
    }
    g.finish();
}

fn benches() {
    let Ok(gpu) = Gpu::new() else {
        eprintln!("knot_gpu: no adapter, nothing measured");
        return;
    };
    table(&gpu);
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c, &gpu);
}

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
}
