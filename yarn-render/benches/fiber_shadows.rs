//! What shadows of every fiber cost the GPU fiber renderer (issue #19, BENCHMARKS.md "Fiber
//! shadow maps"): frame time with the tube maps and the self-shadow volume of [W19 §4.1]
//! (the default) and with fiber shadow maps (`FiberEffects::fiber_shadows`) of 1024² to
//! 4096² texels, as a ratio to the plain tubes of the same camera measured in the same run
//! — with the whole patch in view and from close up (LoD at 1 px in both), plus the fiber
//! instances the camera and the light's map drew; and the close-up at 2 × 2 and 4 × 4
//! frames a pixel (`FiberSettings::supersample`, what a converged frame costs).
//!
//! Scene: the `hairs` bench's — Crane's plain-knit patch, 22 × 22 stitches (3 872 control
//! points, not periodic), cotton-2ply with its hairs, one directional light, 256², MSAA 4,
//! default effects; the whole-patch orthographic camera (35° off the normal) and a
//! perspective close-up of a fifth of the patch.
//!
//! `cargo bench -p yarn-render --bench fiber_shadows --profile dev -- --quick` (the timed
//! work is lavapipe's). Group `fiber-shadows`, one case per setup, each iteration one frame
//! (shadow, LoD and draw passes, the 256² read-back). Without a GPU adapter it prints why
//! and exits 0.

mod common;

use btf_render::Gpu;
use criterion::Criterion;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn_render::{FiberEffects, FiberLight, FiberRenderer, FiberSettings};

const SIZE: (u32, u32) = (256, 256);

fn main() {
    let Ok(gpu) = Gpu::new() else {
        eprintln!("fiber_shadows: no adapter, nothing measured");
        return;
    };
    let (packed, _, whole, c, span) = common::crane_scene();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let close = common::close_camera(c, span);
    let cams = [whole, close];
    let light = [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] }];
    // `map` 0: tube maps and the volume; else fiber maps of that side; `k × k` frames a
    // pixel.
    let make_k = |tubes: bool, map: u32, supersample: u32| {
        let effects = FiberEffects { fiber_shadows: map > 0, ..Default::default() };
        let shadow_map = if map > 0 { map } else { 1024 };
        let settings =
            FiberSettings { tubes, effects, shadow_map, supersample, ..Default::default() };
        FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap()
    };
    let make = |tubes: bool, map: u32| make_k(tubes, map, 1);
    let case = |name, baseline, renderer, camera| common::Case { name, baseline, renderer, camera };
    let cases = [
        case("whole/tubes", "whole/tubes", make(true, 0), 0),
        case("whole/tube-maps", "whole/tubes", make(false, 0), 0),
        case("whole/fiber-maps-1024", "whole/tubes", make(false, 1024), 0),
        case("whole/fiber-maps-2048", "whole/tubes", make(false, 2048), 0),
        case("whole/fiber-maps-4096", "whole/tubes", make(false, 4096), 0),
        case("close/tubes", "close/tubes", make(true, 0), 1),
        case("close/tube-maps", "close/tubes", make(false, 0), 1),
        case("close/fiber-maps-1024", "close/tubes", make(false, 1024), 1),
        case("close/fiber-maps-2048", "close/tubes", make(false, 2048), 1),
        case("close/fiber-maps-4096", "close/tubes", make(false, 4096), 1),
        case("close/fiber-maps-2048-ss2", "close/tubes", make_k(false, 2048, 2), 1),
        case("close/fiber-maps-2048-ss4", "close/tubes", make_k(false, 2048, 4), 1),
    ];
    let mut cr = Criterion::default().configure_from_args();
    let (stats, samples) =
        common::run_cases(&mut cr, &gpu, "fiber-shadows", &cases, &cams, &light, SIZE);
    println!("\n{} control points, 256², MSAA 4", packed.control_points());
    println!("| case | instances | in the light's map | frame ms (median) | × tubes |");
    println!("|---|---:|---:|---:|---:|");
    for (c, st) in cases.iter().zip(&stats) {
        let ms = samples.median(c.name);
        println!(
            "| {} | {} | {} | {ms:.1} | {:.2} |",
            c.name,
            st.instances,
            st.shadow_instances,
            ms / samples.median(c.baseline)
        );
    }
    cr.final_summary();
}
