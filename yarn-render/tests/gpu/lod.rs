//! Level of detail and culling: λ of [W19 eq. 4] continuous and monotone, the GPU's
//! per-segment fiber counts equal to the CPU's formula, and conservative culling that
//! changes no pixel (DESIGN §2.5).

use crate::common::{cotton, crane_patch};
use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn_render::passes::lod::{counts, lambda};
use yarn_render::view::ViewSetup;
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

#[test]
fn lambda_is_continuous_at_both_thresholds_and_monotone() {
    let (wf, wp) = (0.3, 4.0);
    // At ω^LoD = ω^fiber the middle branch is 1; at ω^LoD = ω^ply it is 0.
    for eps in [1e-3, 1e-6, 1e-9] {
        assert!((lambda(wf, wp, wf + eps) - 1.0).abs() < 2.0 * eps / wf + 1e-12);
        assert!((lambda(wf, wp, wf - eps) - 1.0).abs() < 1e-15);
        assert!(lambda(wf, wp, wp - eps).abs() < 2.0 * eps + 1e-12);
        assert!(lambda(wf, wp, wp + eps).abs() < 1e-15);
    }
    assert_eq!(lambda(wf, wp, wf), 1.0);
    assert_eq!(lambda(wf, wp, wp), 0.0);
    let mut prev = 1.0;
    for i in 0..=2000 {
        let l = lambda(wf, wp, i as f64 * 0.0025);
        assert!(l <= prev + 1e-12 && (0.0..=1.0).contains(&l), "not monotone at {i}");
        prev = l;
    }
    // LoD off and λ = 1: every fiber, every subdivision.
    assert_eq!(lambda(wf, wp, 0.0), 1.0);
    assert_eq!(counts(1.0, 63, 8), (63, 8));
    assert_eq!(counts(0.0, 63, 8), (1, 2));
}

fn setup() -> (PackedYarns, FiberBcsdf) {
    let p = cotton();
    let mut set = crane_patch(4, 4);
    set.period = None;
    let packed = PackedYarns::new(&set, &[p], &PackOptions::default()).unwrap();
    (packed, FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap())
}

fn camera(packed: &PackedYarns, dist: f64) -> FiberCamera {
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    FiberCamera::perspective(
        [c[0] + 0.2 * dist, c[1] - dist, c[2] + dist],
        c,
        [0.0, 0.0, 1.0],
        30.0,
    )
}

const LIGHT: [FiberLight; 1] =
    [FiberLight::Directional { to_light: [0.3, -0.5, 1.0], irradiance: [2.0; 3] }];

#[test]
fn gpu_fiber_counts_follow_the_lod_formula() {
    let Some(gpu) = Gpu::for_tests("gpu_fiber_counts_follow_the_lod_formula") else { return };
    let (packed, bcsdf) = setup();
    let p = cotton();
    let size = (96, 96);
    let n_core = (p.core_fraction * p.fibers_per_ply as f64).round() as u32;
    for (core, dist, lod_px) in [
        (false, 0.004, 1.0),
        (false, 0.02, 1.0),
        (false, 0.02, 0.25),
        (false, 0.06, 0.5),
        (false, 0.02, 0.0),
        (true, 0.004, 1.0),
        (true, 0.02, 0.25),
        (true, 0.02, 0.0),
    ] {
        let effects = yarn_render::FiberEffects { core, ..yarn_render::FiberEffects::none() };
        let settings =
            FiberSettings { lod_px, cull: false, msaa: 1, effects, ..Default::default() };
        let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
        let cam = camera(&packed, dist);
        let img = r.render(&gpu, &cam, &LIGHT, size, [0.0; 4]).unwrap();
        // The CPU's prediction from the same view.
        let raw = r.view_raw(&cam, &LIGHT, size).unwrap();
        let (lo, hi) = packed.bounds;
        let centre = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]) - packed.origin[a]);
        let radius =
            (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt() * 0.5 + packed.max_reach;
        let v = ViewSetup::new(&cam, packed.origin, centre, radius, size).unwrap();
        let ply_r = p.ply_ellipse_n.max(p.ply_ellipse_b) * p.rho_max;
        let mut expect = 0u64;
        let mut lambdas = Vec::new();
        for s in &packed.segments {
            let q =
                |j: usize| nalgebra::Vector3::new(s.p[j][0], s.p[j][1], s.p[j][2]).cast::<f64>();
            let mid = (q(1) * 9.0 + q(2) * 9.0 - q(0) - q(3)) / 16.0;
            let depth = (mid - v.eye).dot(&v.forward);
            let px = |r: f64| r * v.px_per_metre / depth;
            let l = lambda(px(2.0 * p.fiber_radius), px(2.0 * ply_r), lod_px as f64);
            lambdas.push(l);
            expect += if core {
                // One core strip per ply, then round(λ²·n_regular) of the rest (maybe none).
                let n_reg = p.fibers_per_ply - n_core;
                2 * (1 + (l * l * n_reg as f64).round() as u64)
            } else {
                2 * counts(l, p.fibers_per_ply, settings.n_sub).0 as u64
            };
        }
        // Hairs are listed at every λ (fiber_lod); the formula counts regular fibers.
        let got = (img.stats.instances - img.stats.hairs) as u64;
        let mean_l = lambdas.iter().sum::<f64>() / lambdas.len() as f64;
        eprintln!(
            "core {core}, distance {dist} m, ω^LoD {lod_px} px: mean λ {mean_l:.3}, instances GPU {got}, \
             CPU {expect}, pixels/m {}",
            raw.viewport[2]
        );
        // Rounding of λ²·n at a .5 boundary may differ between f32 and f64 for a segment.
        assert!(got.abs_diff(expect) <= 4, "GPU {got} against CPU {expect}");
        assert_eq!(img.stats.overflow, 0);
    }
}

#[test]
fn culling_changes_no_pixel() {
    let Some(gpu) = Gpu::for_tests("culling_changes_no_pixel") else { return };
    let (packed, bcsdf) = setup();
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    // A close, narrow view of one corner: most segments are outside.
    let target = [lo[0] + 0.2 * (hi[0] - lo[0]), c[1], c[2]];
    let cam = FiberCamera::perspective(
        [target[0], target[1] - 0.004, target[2] + 0.004],
        target,
        [0.0, 0.0, 1.0],
        25.0,
    );
    let mut images = Vec::new();
    for cull in [true, false] {
        let settings = FiberSettings { cull, lod_px: 0.5, msaa: 4, ..Default::default() };
        let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
        images.push(r.render(&gpu, &cam, &LIGHT, (64, 64), [0.0; 4]).unwrap());
    }
    let (on, off) = (&images[0], &images[1]);
    eprintln!(
        "culling: {} of {} segments culled, instances {} vs {}, hairs {} vs {}",
        on.stats.culled,
        on.stats.segments,
        on.stats.instances,
        off.stats.instances,
        on.stats.hairs,
        off.stats.hairs
    );
    assert!(on.stats.culled * 3 > on.stats.segments, "the view culls too little to test");
    // Hair flyaways are drawn, from culled segments too where they reach into the view.
    assert!(on.stats.hairs > 0 && on.stats.hairs < off.stats.hairs, "{:?}", on.stats);
    assert_eq!(off.stats.culled, 0);
    let lit = on.pixels.iter().filter(|p| p[3] > 0.0).count();
    assert!(lit > 400, "only {lit} pixels see yarn");
    let differing = on.pixels.iter().zip(&off.pixels).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels differ");
}

#[test]
fn plain_tubes_draw_one_strip_per_visible_segment_and_cover_the_fibers() {
    let Some(gpu) = Gpu::for_tests("plain_tubes_draw_one_strip") else { return };
    let (packed, bcsdf) = setup();
    let cam = camera(&packed, 0.01);
    let mut out = Vec::new();
    for tubes in [false, true] {
        let settings = FiberSettings { tubes, lod_px: 0.0, msaa: 4, ..Default::default() };
        let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
        out.push(r.render(&gpu, &cam, &LIGHT, (64, 64), [0.0; 4]).unwrap());
    }
    let (fib, tub) = (&out[0], &out[1]);
    assert_eq!(tub.stats.instances, tub.stats.segments - tub.stats.culled);
    let cover = |i: &yarn_render::FiberImage| i.pixels.iter().map(|p| p[3] as f64).sum::<f64>();
    eprintln!(
        "tubes: {} instances against {} fibers; coverage {:.0} against {:.0} px",
        tub.stats.instances,
        fib.stats.instances,
        cover(tub),
        cover(fib)
    );
    // The tube of the yarn radius contains every (non-flyaway) fiber.
    assert!(cover(tub) >= 0.97 * cover(fib));
}

#[test]
fn lod_with_core_strips_conserves_coverage_and_radiance() {
    let Some(gpu) = Gpu::for_tests("lod_with_core_strips_conserves") else { return };
    let chart = yarn::knit::Chart::builtin("stockinette").unwrap();
    let p = cotton();
    let sk = yarn::knit::SkeletonParams::new(p.yarn_radius());
    let (ws, cs) = sk.default_spacing();
    let set = yarn::knit::chen_skeleton(
        &yarn::knit::StitchMesh::flat(&chart, chart.width, chart.height, ws, cs).unwrap(),
        &sk,
    )
    .unwrap();
    let period = set.period.unwrap();
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&p),
        &PackOptions { tiles: [3, 3], frame_samples_per_segment: 16, ..Default::default() },
    )
    .unwrap();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let view = btf_core::Direction::new(30.0, 60.0).to_vector();
    let (_, hi) = yarn_ref::patch::centre_line_z(&set);
    let cam = FiberCamera::oblique(view, hi + p.yarn_radius(), [0.0, 0.0], period);
    let light = [FiberLight::Directional { to_light: [0.3, -0.4, 1.0], irradiance: [3.0; 3] }];
    let mut rows = Vec::new();
    for lod_px in [0.0f32, 0.25, 4.0] {
        let settings = FiberSettings { lod_px, ..Default::default() };
        let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
        let img = r.render(&gpu, &cam, &light, (64, 64), [0.0; 4]).unwrap();
        let n = img.pixels.len() as f64;
        let cov = img.pixels.iter().map(|q| q[3] as f64).sum::<f64>() / n;
        let rad = img.pixels.iter().map(|q| (q[0] + q[1] + q[2]) as f64).sum::<f64>() / n;
        eprintln!(
            "core strips, ω^LoD {lod_px} px: {} instances, coverage {cov:.4}, mean radiance {rad:.5}",
            img.stats.instances
        );
        rows.push((img.stats.instances, cov, rad));
    }
    let (n0, c0, r0) = rows[0];
    let (n2, c2, r2) = rows[2];
    assert!(n2 * 10 < n0, "LoD must drop most fibers: {n0} → {n2}");
    for &(_, c, r) in &rows[1..] {
        // DESIGN §2.5's bound for "LoD conserves appearance" holds for the radiance, hair
        // flyaways included (thinned with their coverage raised: measured −2.4 / −3.3 %;
        // a variant listing the hairs of the outermost round(λ²·n_fib) fibers without
        // raising their coverage, not kept, lost 8 % in the 4 px frame).
        assert!((r / r0 - 1.0).abs() < 0.05, "mean radiance {r} against {r0}");
        // Coverage does not: the paper's compensation (the core widened towards the ply
        // as λ² falls, DESIGN §2.3 item 7) loses 10 % of it here (measured 0.629 →
        // 0.567 / 0.566 with the hairs; 0.616 → 0.553 / 0.549 before them), because the core texture's alpha is the core fibers' and the
        // ply's own gaps stay open. A known gap, bounded here so it cannot grow unseen.
        assert!(c <= c0 * 1.02 && c > 0.85 * c0, "coverage {c} against {c0}");
    }
    assert!((c2 / c0 - 1.0).abs() < 0.15 && (r2 / r0 - 1.0).abs() < 0.05);
}
