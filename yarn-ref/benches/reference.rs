//! Reference renderer speed (issue 18): rays per second on a knit patch, scaling with the
//! fiber count (BVH build time, memory per fiber, closest-hit cost against log n), and yarn
//! BTF generation time at 32² for a few directions.
//!
//! `cargo bench -p yarn-ref --bench reference` prints the scaling table and the BTF timing
//! (one run each; the 10⁶-fiber row needs ~1 GB), then runs the criterion groups.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{Criterion, criterion_group};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::Chart;
use yarn::params::YarnParams;
use yarn_ref::btf::{YarnBtfSpec, prepare};
use yarn_ref::patch::{KnitPatch, PatchOptions, fibers_from_polylines};
use yarn_ref::rng::Rng;
use yarn_ref::{Camera, FiberScene, Light, RenderSettings, Scene, SceneOptions, Shading, render};

/// `n` random 8-segment fibers (length 0.16, radius 0.004) in a slab of thickness 0.1
/// whose side grows as `√(n/1000)`: the fiber density is the same at every `n`, like a
/// larger and larger cloth, so a ray meets the same local structure and its cost measures
/// the BVH depth alone.
fn random_fibers(n: usize) -> (yarn::fiber::Fibers, f64) {
    let mut rng = Rng::new(&[n as u64]);
    let side = (n as f64 / 1000.0).sqrt();
    let lines: Vec<Vec<[f64; 3]>> = (0..n)
        .map(|_| {
            let [u, v, w] = rng.uniform3();
            let p = [u * side, v * side, 0.1 * w];
            let a = std::f64::consts::TAU * rng.uniform();
            let d = [0.02 * a.cos(), 0.02 * a.sin(), 0.004 * (rng.uniform() - 0.5)];
            (0..=8)
                .map(|k| [p[0] + d[0] * k as f64, p[1] + d[1] * k as f64, p[2] + d[2] * k as f64])
                .collect()
        })
        .collect();
    (fibers_from_polylines(&lines, 0.004, [0.8; 3]), side)
}

fn scaling_table() {
    println!(
        "\n| fibers | capsules | BVH build (s) | BVH depth | scene bytes / fiber | closest hit (ns/ray) | hits |"
    );
    println!("|---|---|---|---|---|---|---|");
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        let (f, side) = random_fibers(n);
        let t = Instant::now();
        let scene = FiberScene::new(&f, &SceneOptions::default()).unwrap();
        let build = t.elapsed().as_secs_f64();
        drop(f);
        let mut rng = Rng::new(&[9]);
        let rays = 200_000;
        let t = Instant::now();
        let mut hits = 0;
        for _ in 0..rays {
            let [u, v, w] = rng.uniform3();
            let o = [u * side, v * side, 1.0];
            let d = btf_core::Direction::new(60.0 * w, 360.0 * v).to_vector().map(|x| -x);
            hits += scene.intersect(o, d, f64::INFINITY, None).is_some() as usize;
        }
        let ns = t.elapsed().as_secs_f64() / rays as f64 * 1e9;
        println!(
            "| {n} | {} | {build:.3} | {} | {:.0} | {ns:.0} | {:.3} |",
            scene.segment_count(),
            scene.bvh().depth(),
            scene.bytes() as f64 / n as f64,
            hits as f64 / rays as f64
        );
    }
}

fn patch_scene() -> (KnitPatch, FiberScene) {
    let p = KnitPatch::new(
        &Chart::builtin("stockinette").unwrap(),
        &YarnParams::preset("cotton-2ply").unwrap(),
        &PatchOptions::default(),
    )
    .unwrap();
    let s = FiberScene::new(
        &p.fibers,
        &SceneOptions { period: Some(p.period), backing_z: Some(p.backing_z()) },
    )
    .unwrap();
    (p, s)
}

fn patch_rays_per_second() {
    let (p, scene) = patch_scene();
    let lights = [Light::directional(btf_core::Direction::new(30.0, 60.0).to_vector(), [1.0; 3])];
    let shading = Shading::Fiber {
        bcsdf: Arc::new(FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap()),
        tint: true,
    };
    let sc = Scene { fibers: &scene, lights: &lights, shading: &shading };
    let cam = Camera::oblique(
        btf_core::Direction::new(45.0, 200.0).to_vector(),
        p.z_ref,
        p.period.origin,
        p.period.size,
    )
    .unwrap();
    for bounces in [1, 8] {
        let mut s = RenderSettings::new(64, 64, 16);
        s.path.max_bounces = bounces;
        let (_, st) = render(&sc, &cam, &s).unwrap();
        println!(
            "knit patch (stockinette 4×4, cotton-2ply, {} fibers, {} capsules), 64² × 16 spp, {bounces} bounce(s), {} threads: {:.2} Mrays/s ({} rays, {:.2} s)",
            p.fibers.fiber_count(),
            scene.segment_count(),
            rayon::current_num_threads(),
            st.rays_per_second() * 1e-6,
            st.rays,
            st.seconds
        );
    }
}

fn btf_timing() {
    let spec = YarnBtfSpec::new(
        Chart::builtin("stockinette").unwrap(),
        "stockinette",
        YarnParams::preset("cotton-2ply").unwrap(),
        32,
    );
    let t = Instant::now();
    let prep = prepare(&spec).unwrap();
    let prep_s = t.elapsed().as_secs_f64();
    let dirs = [(0.0, 0.0), (45.0, 90.0), (75.0, 200.0)];
    let t = Instant::now();
    let mut rays = 0;
    for (vt, vp) in dirs {
        for (lt, lp) in dirs {
            let v = btf_core::Direction::new(vt, vp).to_vector();
            let l = btf_core::Direction::new(lt, lp).to_vector();
            rays += prep.normtexture(&spec, v, l, 1).unwrap().1;
        }
    }
    let per = t.elapsed().as_secs_f64() / 9.0;
    println!(
        "yarn BTF 32², 16 spp, 8 bounces, cotton-2ply stockinette: patch {prep_s:.2} s, {per:.3} s per image ({:.2} Mrays/s); ubo81 (6561 images) ≈ {:.0} min, 64² ≈ {:.0} min (extrapolated ×4)",
        rays as f64 / (per * 9.0) * 1e-6,
        per * 6561.0 / 60.0,
        4.0 * per * 6561.0 / 60.0
    );
}

fn bench(c: &mut Criterion) {
    let (p, scene) = patch_scene();
    let mut g = c.benchmark_group("reference");
    g.sample_size(10);
    g.bench_function("bvh_build_cotton_patch", |b| {
        b.iter(|| {
            FiberScene::new(
                black_box(&p.fibers),
                &SceneOptions { period: Some(p.period), backing_z: None },
            )
            .unwrap()
        })
    });
    let mut rng = Rng::new(&[1]);
    let rays: Vec<([f64; 3], [f64; 3])> = (0..4096)
        .map(|_| {
            let [u, v, w] = rng.uniform3();
            let d = btf_core::Direction::new(60.0 * w, 360.0 * v).to_vector();
            ([u * p.period.size[0], v * p.period.size[1], p.z_ref + 1e-3], [-d[0], -d[1], -d[2]])
        })
        .collect();
    g.bench_function("closest_hit_4096_rays_wrapped_patch", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|(o, d)| scene.intersect(*o, *d, f64::INFINITY, None).is_some())
                .count()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    scaling_table();
    patch_rays_per_second();
    btf_timing();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
