//! Frame time of the yarn strips [H25] on lavapipe against the plain tubes and the GPU
//! fibers [W19] on the same yarns, in one run (issue #20, "what accuracy costs in time";
//! BENCHMARKS.md "Yarn strips (issue #20)"): does "strips beat explicit fibers at equal
//! quality" hold here, and how does each grow with the control points?
//!
//! Scene: Crane's plain-knit patch of cotton-2ply, `s × s` stitches (8·s² control points,
//! ~10³ to ~6·10⁴), the orthographic 35° camera of `benches/fibers.rs`, one directional
//! light, 256² frames, MSAA 4. Cases per size: `strips` (the default bake, cached in the
//! system temp folder, and `StripSettings::default()`), `tubes` (plain tubes of the fiber
//! renderer) and `fibers` (`FiberSettings::default()`: LoD at 1 px, core strips, shadows).
//! Each iteration is one frame timed around `render` (all passes and the 256² read-back).
//!
//! `cargo bench -p yarn-render --bench strips --profile dev -- --quick`. Without a GPU
//! adapter it prints why and exits 0.

use btf_render::Gpu;
use criterion::{Criterion, SamplingMode};
use std::time::Duration;
use yarn::YarnParams;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::knit::crane::CraneKnit;
use yarn_precompute::StripBakeSettings;
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns, StripRenderer,
    StripSettings,
};

const SIZE: (u32, u32) = (256, 256);
const LIGHTS: [FiberLight; 1] =
    [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] }];
const SIDES: [usize; 4] = [11, 22, 45, 89];

fn camera(packed: &PackedYarns) -> FiberCamera {
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (s, co) = 35f64.to_radians().sin_cos();
    let d = 2.0 * span;
    FiberCamera::orthographic([c[0], c[1] - d * s, c[2] + d * co], c, [0.0, 1.0, 0.0], 1.1 * span)
}

fn main() {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("strips bench: no GPU adapter ({e}), nothing to measure");
            return;
        }
    };
    let p = YarnParams::preset("cotton-2ply").unwrap();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let cache = std::env::temp_dir().join("btf-strips-bench-cache");
    let mut c = Criterion::default().configure_from_args();
    let mut g = c.benchmark_group("strips-scale");
    g.sampling_mode(SamplingMode::Flat).sample_size(10).warm_up_time(Duration::from_millis(500));
    for s in SIDES {
        let k = CraneKnit::for_yarn_radius(p.yarn_radius());
        let mut set = k.yarn_set(s, s, 8).unwrap();
        set.period = None;
        let packed =
            PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
        let cam = camera(&packed);
        let cps = 8 * s * s;
        let bakes = yarn_render::strips::bakes_for(
            &set,
            std::slice::from_ref(&p),
            &bcsdf,
            &StripBakeSettings::default(),
            Some(&cache),
            &|_| {},
        )
        .unwrap();
        let strips =
            StripRenderer::new(&gpu, &packed, &bakes, &bcsdf, StripSettings::default()).unwrap();
        let tubes = FiberRenderer::new(
            &gpu,
            &packed,
            &bcsdf,
            FiberSettings { tubes: true, ..Default::default() },
        )
        .unwrap();
        let fibers = FiberRenderer::new(&gpu, &packed, &bcsdf, FiberSettings::default()).unwrap();
        g.bench_function(format!("strips/{cps}"), |b| {
            b.iter(|| strips.render(&gpu, &cam, &LIGHTS, SIZE, [0.0; 4]).unwrap())
        });
        g.bench_function(format!("tubes/{cps}"), |b| {
            b.iter(|| tubes.render(&gpu, &cam, &LIGHTS, SIZE, [0.0; 4]).unwrap())
        });
        g.bench_function(format!("fibers/{cps}"), |b| {
            b.iter(|| fibers.render(&gpu, &cam, &LIGHTS, SIZE, [0.0; 4]).unwrap())
        });
    }
    g.finish();
    c.final_summary();
}
