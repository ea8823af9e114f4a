//! What each light costs the GPU fiber renderer (issue #19, BENCHMARKS.md "Point lights and
//! the environment by SRBFs"): frame time per light setup as a ratio to the plain tubes
//! under one directional light, measured in the same run — a directional light with its
//! orthographic tube shadow map, a point light afar (one perspective map), a point light
//! among the yarns (cube faces), [W19]'s constant ambient term, and an environment by
//! 16 SRBF lobes ([H25 eq. 14–17] at each fiber's tangent) with and without the lobes'
//! tube shadow maps; plus the shadow maps each setup renders.
//!
//! Scene: Crane's plain-knit patch, 22 × 22 stitches (3 872 control points, not periodic),
//! cotton-2ply, the orthographic camera of the `fibers` bench (35° off the normal, the
//! whole patch), 256², MSAA 4, default settings (LoD at 1 px, self-shadows, yarn shadows,
//! AO), a sky of 0.2 with a sun of 8 (half-width ≈ 4°) fitted by 16 SRBFs.
//!
//! `cargo bench -p yarn-render --bench lights --profile dev -- --quick` (the timed work is
//! lavapipe's). Group `fiber-lights`, one case per setup, each iteration one frame (LoD,
//! shadow and draw passes, the 256² read-back). Without a GPU adapter it prints why and
//! exits 0.

mod common;

use btf_render::Gpu;
use criterion::Criterion;
use std::time::Instant;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn_precompute::{ImTable, SrbfFit};
use yarn_render::{FiberEffects, FiberLight, FiberRenderer, FiberSettings};

const SIZE: (u32, u32) = (256, 256);

struct Case {
    name: &'static str,
    renderer: FiberRenderer,
    lights: Vec<FiberLight>,
    maps: usize,
}

fn main() {
    let Ok(gpu) = Gpu::new() else {
        eprintln!("lights: no adapter, nothing measured");
        return;
    };
    let (packed, _, cam, c, span) = common::crane_scene();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let dir = FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] };
    let far = 3.0 * span;
    let afar = FiberLight::Point {
        position: [c[0] + 0.3 * far, c[1] - 0.5 * far, c[2] + far],
        intensity: [2.0 * far * far; 3],
    };
    let h = 0.15 * span;
    let among = FiberLight::Point { position: [c[0], c[1], c[2] + h], intensity: [2.0 * h * h; 3] };
    let sun = [0.3f64, -0.5, 0.81];
    let map = btf_image::EnvMap::from_fn(64, move |w| {
        let cs = w[0] * sun[0] + w[1] * sun[1] + w[2] * sun[2];
        let v = 0.2 + 8.0 * (400.0 * (cs - 1.0)).exp();
        [v, v, v]
    })
    .unwrap();
    let fit = SrbfFit::fit(&map, 16).unwrap();
    let table = ImTable::build(&bcsdf, fit.lambda).unwrap();
    let ambient = map.integral().map(|x| (x / (4.0 * std::f64::consts::PI)) as f32);
    let make = |tubes: bool, effects: FiberEffects| {
        let settings = FiberSettings { tubes, effects, ..Default::default() };
        FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap()
    };
    let fx = FiberEffects::default();
    let mut cases = vec![
        Case { name: "tubes", renderer: make(true, fx), lights: vec![dir], maps: 0 },
        Case { name: "directional", renderer: make(false, fx), lights: vec![dir], maps: 1 },
        Case { name: "point-afar", renderer: make(false, fx), lights: vec![afar], maps: 1 },
        Case { name: "point-among", renderer: make(false, fx), lights: vec![among], maps: 6 },
    ];
    let mut amb = make(false, FiberEffects { ambient, ..fx });
    amb.set_ambient(ambient);
    cases.push(Case { name: "ambient", renderer: amb, lights: vec![], maps: 0 });
    let mut srbf = make(false, fx);
    srbf.set_environment(&gpu, Some((&fit, &table))).unwrap();
    let kept = srbf.srbf_lobes();
    cases.push(Case { name: "srbf16", renderer: srbf, lights: vec![], maps: kept });
    let hard_settings = FiberSettings { soft_lobes: false, ..Default::default() };
    let mut hard = FiberRenderer::new(&gpu, &packed, &bcsdf, hard_settings).unwrap();
    hard.set_environment(&gpu, Some((&fit, &table))).unwrap();
    cases.push(Case { name: "srbf16-hard", renderer: hard, lights: vec![], maps: kept });
    let mut free = make(false, FiberEffects { yarn_shadows: false, ..fx });
    free.set_environment(&gpu, Some((&fit, &table))).unwrap();
    cases.push(Case { name: "srbf16-no-yarn-shadows", renderer: free, lights: vec![], maps: 0 });
    let frame = |c: &Case| {
        let t = Instant::now();
        let img = c.renderer.render(&gpu, &cam, &c.lights, SIZE, [0.0; 4]).unwrap();
        std::hint::black_box(img.pixels.len());
        (t.elapsed().as_secs_f64() * 1e3, img)
    };
    // One warm-up frame each (pipelines, bakes); the mean radiance for the table.
    let means: Vec<f64> = cases
        .iter()
        .map(|c| {
            let (_, img) = frame(c);
            img.pixels.iter().map(|q| (q[0] + q[1] + q[2]) as f64 / 3.0).sum::<f64>()
                / img.pixels.len() as f64
        })
        .collect();
    let mut cr = Criterion::default().configure_from_args();
    let names: Vec<&'static str> = cases.iter().map(|c| c.name).collect();
    let samples = common::time_cases(&mut cr, "fiber-lights", &names, |i| frame(&cases[i]).0);
    let tubes = samples.median("tubes");
    println!(
        "\n{} control points, 256², MSAA 4; SRBF fit: 16 lobes ({kept} of non-zero weight), \
         λ {:.2}, fit error {:.3}",
        packed.control_points(),
        fit.lambda,
        fit.rel_error
    );
    println!("| setup | shadow maps | frame ms (median) | × tubes | mean radiance |");
    println!("|---|---:|---:|---:|---:|");
    for (c, m) in cases.iter().zip(&means) {
        let ms = samples.median(c.name);
        println!("| {} | {} | {ms:.1} | {:.2} | {m:.4} |", c.name, c.maps, ms / tubes);
    }
    cr.final_summary();
}
