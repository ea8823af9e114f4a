//! Hemicube visibility of the synthetic shirt on the CPU (`[S03 §5.2]`; BENCHMARKS.md
//! "environment lighting", the visibility rows): the rasteriser (`VisibilityMaps::compute`)
//! against the reference ray cast (`VisibilityMaps::compute_ray_cast`, the **baseline**) on
//! the same vertex sides in the same run — every side of the low shirt, every 8th of the
//! high one — with their bits compared once before timing; plus the rasteriser over every
//! side and a load from the visibility cache.
//!
//! Hemicube 32² (3072 pixels per vertex side), two-sided cloth. Group `visibility`,
//! benchmarks `rasteriser all sides`, `cache load`, `ray cast subset` and, when the subset
//! is not every side, `rasteriser subset`;
//! after criterion a markdown table gives the medians, ms per vertex side, the ray cast /
//! rasteriser ratio, the differing pixels and the visible share.
//!
//! `cargo bench -p btf-light --bench visibility` (`-- --quick` for a short run);
//! `BTF_MEASURE_HIGH=1`: the 9160-vertex shirt instead of the 925-vertex one;
//! `BTF_ONE_SIDED=1`: the front sides only (what a `two_sided = false` scene computes);
//! `BTF_FAST_ONLY=1`: the rasteriser over every side alone (for `perf`; no ray cast).

mod common;

use btf_light::tangent::compute_tangents;
use btf_light::{Hemicube, HemicubeFrame, VisibilityMaps};
use common::*;
use criterion::SamplingMode;

fn differing(a: &VisibilityMaps, b: &VisibilityMaps) -> u32 {
    a.bits.iter().zip(&b.bits).map(|(x, y)| (x ^ y).count_ones()).sum()
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    let (name, mesh) = shirt(dir.path());
    let tangents = compute_tangents(&mesh);
    let cube = Hemicube::new(32).unwrap();
    let two_sided = !env_flag("BTF_ONE_SIDED");
    let fast_only = env_flag("BTF_FAST_ONLY");
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, two_sided);
    let (pos, tris) = (&mesh.positions, &mesh.triangles);
    let stride = if frames.len() > 4000 { 8 } else { 1 };
    let sub: Vec<HemicubeFrame> = frames.iter().step_by(stride).copied().collect();
    println!(
        "{name}: {} vertices, {} triangles, hemicube 32², {} ({} vertex sides; ray cast on {} of them)",
        pos.len(),
        tris.len(),
        if two_sided { "two-sided" } else { "front sides only" },
        frames.len(),
        sub.len()
    );
    let all = VisibilityMaps::compute(&cube, &frames, pos, tris);
    let visible: u32 = all.bits.iter().map(|w| w.count_ones()).sum();
    let differ = (!fast_only).then(|| {
        let fast = VisibilityMaps::compute(&cube, &sub, pos, tris);
        differing(&fast, &VisibilityMaps::compute_ray_cast(&cube, &sub, pos, tris))
    });

    let samples = Samples::default();
    let mut c = criterion();
    let mut g = c.benchmark_group("visibility");
    g.sampling_mode(SamplingMode::Flat);
    {
        let s = samples.clone();
        g.bench_function("rasteriser all sides", |b| {
            b.iter_custom(|n| {
                timed(n, &s, "all", || VisibilityMaps::compute(&cube, &frames, pos, tris))
            })
        });
    }
    if !fast_only {
        let cache = dir.path().join("cache");
        let s = samples.clone();
        let mut written = false;
        g.bench_function("cache load", |b| {
            if !written {
                let (_, hit) = VisibilityMaps::cached(&cache, &cube, &frames, pos, tris).unwrap();
                assert!(!hit);
                written = true;
            }
            b.iter_custom(|n| {
                timed(n, &s, "cache", || {
                    let (v, hit) =
                        VisibilityMaps::cached(&cache, &cube, &frames, pos, tris).unwrap();
                    assert!(hit);
                    v
                })
            })
        });
        // the low shirt's subset is every side: timed above as `rasteriser all sides`
        if stride > 1 {
            let s = samples.clone();
            g.bench_function("rasteriser subset", |b| {
                b.iter_custom(|n| {
                    timed(n, &s, "sub", || VisibilityMaps::compute(&cube, &sub, pos, tris))
                })
            });
        }
        let s = samples.clone();
        g.bench_function("ray cast subset", |b| {
            b.iter_custom(|n| {
                timed(n, &s, "ray", || VisibilityMaps::compute_ray_cast(&cube, &sub, pos, tris))
            })
        });
    }
    g.finish();
    c.final_summary();

    println!("\n## visibility: {name}, medians; baseline: the ray cast on the same sides\n");
    println!("| | ms | ms per vertex side | × rasteriser |");
    println!("|---|---:|---:|---:|");
    let per_side = |m: Option<f64>, k: usize| num(m.map(|m| m / k as f64), 3);
    let (all_ms, ray_ms) = (samples.median("all"), samples.median("ray"));
    let sub_ms = if stride > 1 { samples.median("sub") } else { all_ms };
    if all_ms.is_some() {
        println!(
            "| rasteriser, all {} sides | {} | {} | |",
            frames.len(),
            num(all_ms, 0),
            per_side(all_ms, frames.len())
        );
    }
    if samples.count("cache") > 0 {
        println!("| cache load, all sides | {} | | |", num(samples.median("cache"), 1));
    }
    if sub_ms.is_some() || ray_ms.is_some() {
        if stride > 1 {
            println!(
                "| rasteriser, {} sides (every {stride}th) | {} | {} | 1 |",
                sub.len(),
                num(sub_ms, 0),
                per_side(sub_ms, sub.len())
            );
        }
        println!(
            "| ray cast, the same sides (baseline) | {} | {} | **{}** |",
            num(ray_ms, 0),
            per_side(ray_ms, sub.len()),
            ratio(ray_ms, sub_ms, 1)
        );
    }
    println!(
        "\nVisible share {:.3}; differing pixels rasteriser vs ray cast: {}.",
        visible as f64 / (frames.len() * cube.len()) as f64,
        differ.map_or("not compared (BTF_FAST_ONLY=1)".into(), |d| d.to_string())
    );
}
