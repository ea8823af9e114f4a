//! What accuracy costs in time against plain texturing and the read bound (issue #5;
//! BENCHMARKS.md "What accuracy costs in time"): the cost sweep of `btf render-sweep`
//! (`btf_render::cost_sweep`) on the example sphere-over-plane mesh, synthetic 64² checker
//! store with 32 components (f16), one point light, no shadows.
//!
//! Per setting (c × per-pixel/per-vertex × four/nearest) the sweep measures the relative
//! RMSE against the per-pixel, all-components, four/four frame, the texture reads per pixel,
//! and the BTF pass's median time over `BTF_SWEEP_REPEATS` frames. **Baselines**: plain
//! texture mapping and the read bound (the same reads, summed; the faster of its two forms),
//! timed interleaved frame by frame with the BTF pass in the same loop — so this bench keeps
//! its own timing loop instead of criterion's, and prints the markdown table, the linear fits
//! `ms = a + b·c` and the checks.
//!
//! `cargo bench -p btf-render --bench sweep`; `BTF_SWEEP_SIZE` (default 128),
//! `BTF_SWEEP_COMPONENTS=4,32` (default 4,8,16,32) and `BTF_SWEEP_REPEATS` (default 5) set the
//! size, the component counts and the timed frames per cell; `BTF_PASS_WGSL` (read by the
//! renderer) swaps the BTF pass's shader (`benches/shader_variants.py`). Arguments are
//! ignored, so `benches/sweep_ab.sh` can alternate this binary (built with `cargo bench -p
//! btf-render --bench sweep --no-run`) with another. Without a GPU adapter it prints why and
//! exits 0.

mod common;

use btf_core::eigen::Quantization;
use btf_render::Scene;
use btf_render::cost_sweep::{SweepConfig, run};
use common::*;

fn main() {
    let Some(gpu) = gpu_or_skip("sweep") else { return };
    let size: u32 = env_or("BTF_SWEEP_SIZE", 128);
    let dir = tempfile::tempdir().unwrap();
    write_store(dir.path(), "m.eigen", Pattern::Checker, 64, 64, 32, Quantization::F16);
    sphere_on_plane(dir.path());
    let text = format!(
        r#"
        [output]
        width = {size}
        height = {size}
        [[meshes]]
        path = "mesh.obj"
        [[materials]]
        store = "m.eigen"
        uv_scale = 2.0
        [camera]
        eye = [0.0, 1.8, 2.6]
        target = [0.0, 0.4, 0.0]
        [[lights]]
        kind = "point"
        position = [1.2, 2.2, 0.8]
        intensity = [4.0, 4.0, 4.0]
        "#
    );
    let scene = Scene::load(&write(dir.path(), "scene.toml", &text)).unwrap();
    let components = std::env::var("BTF_SWEEP_COMPONENTS")
        .ok()
        .map(|s| s.split(',').map(|c| c.trim().parse().unwrap()).collect())
        .unwrap_or_else(|| vec![4, 8, 16, 32]);
    let repeats = env_or("BTF_SWEEP_REPEATS", 5);
    let config = SweepConfig { components, repeats };
    let r = run(&gpu, &scene, &config, &mut |d, n| eprint!("\r{d}/{n}")).unwrap();
    eprintln!();
    println!("\n## sweep: {size}², median of {repeats} frames per cell\n");
    println!(
        "| c | evaluation | blending | rel. RMSE | reads/px | BTF ms | plain ms | bound ms | × plain | × bound |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for x in &r.rows {
        println!(
            "| {} | {} | {} | {:.2e} | {:.1} | {:.2} | {:.2} | {:.2} | {:.1} | {:.2} |",
            x.components,
            x.evaluation,
            x.blending,
            x.rel_rmse,
            x.reads_per_pixel,
            x.btf_ms,
            x.plain_ms,
            x.read_bound_ms,
            x.ratio_plain,
            x.ratio_read_bound
        );
    }
    println!();
    for f in &r.fits {
        println!("fit {}: {:.3} + {:.4}·c ms, R² {:.4}", f.mode, f.intercept, f.slope, f.r2);
    }
    println!(
        "worst × read bound {:.2}; per-pixel reads ≤ per-vertex: {}",
        r.worst_read_bound_ratio, r.per_pixel_reads_le_per_vertex
    );
}
