//! What hair flyaways cost the GPU fiber renderer (issue #19, BENCHMARKS.md "Hair flyaways
//! on the GPU fibers"): frame time with and without the yarn's hairs as a ratio to the plain
//! tubes of the same camera, measured in the same run — with the whole patch in view (LoD
//! at 1 px) and from close up (LoD at 1 px, and full detail), where most segments are
//! culled but still scanned for hairs that reach into the view; plus the hairs and
//! instances listed. (Full detail of the whole patch takes about a minute a frame here.)
//!
//! Scene: Crane's plain-knit patch, 22 × 22 stitches (3 872 control points, not periodic),
//! cotton-2ply (3 000 hairs per metre and ply), one directional light, 256², MSAA 4, default
//! effects; the whole-patch camera of the `fibers` and `lights` benches (orthographic, 35°
//! off the normal) and a perspective close-up of a fifth of the patch.
//!
//! `cargo bench -p yarn-render --bench hairs --profile dev -- --quick` (the timed work is
//! lavapipe's). Group `fiber-hairs`, one case per setup, each iteration one frame (LoD,
//! shadow and draw passes, the 256² read-back). Without a GPU adapter it prints why and
//! exits 0.

mod common;

use btf_render::Gpu;
use criterion::Criterion;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn_render::{FiberLight, FiberRenderer, FiberSettings};

const SIZE: (u32, u32) = (256, 256);

fn main() {
    let Ok(gpu) = Gpu::new() else {
        eprintln!("hairs: no adapter, nothing measured");
        return;
    };
    let (packed, _, whole, c, span) = common::crane_scene();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let close = common::close_camera(c, span);
    let cams = [whole, close];
    let light = [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] }];
    let make = |tubes: bool, hairs: bool, lod_px: f32| {
        let settings = FiberSettings { tubes, hairs, lod_px, ..Default::default() };
        FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap()
    };
    let case = |name, baseline, renderer, camera| common::Case { name, baseline, renderer, camera };
    let cases = [
        case("whole/tubes", "whole/tubes", make(true, false, 1.0), 0),
        case("whole/no-hairs", "whole/tubes", make(false, false, 1.0), 0),
        case("whole/hairs", "whole/tubes", make(false, true, 1.0), 0),
        case("close/tubes", "close/tubes", make(true, false, 1.0), 1),
        case("close/no-hairs", "close/tubes", make(false, false, 1.0), 1),
        case("close/hairs", "close/tubes", make(false, true, 1.0), 1),
        case("close/full-no-hairs", "close/tubes", make(false, false, 0.0), 1),
        case("close/full-hairs", "close/tubes", make(false, true, 0.0), 1),
    ];
    let mut cr = Criterion::default().configure_from_args();
    let (stats, samples) =
        common::run_cases(&mut cr, &gpu, "fiber-hairs", &cases, &cams, &light, SIZE);
    println!("\n{} control points, 256², MSAA 4", packed.control_points());
    println!("| case | segments culled | hairs | instances | frame ms (median) | × tubes |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (c, st) in cases.iter().zip(&stats) {
        let ms = samples.median(c.name);
        println!(
            "| {} | {} | {} | {} | {ms:.1} | {:.2} |",
            c.name,
            st.culled,
            st.hairs,
            st.instances,
            ms / samples.median(c.baseline)
        );
    }
    cr.final_summary();
}
