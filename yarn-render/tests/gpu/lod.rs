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
    for (dist, lod_px) in [(0.004, 1.0), (0.02, 1.0), (0.02, 0.25), (0.06, 0.5), (0.02, 0.0)] {
        let settings = FiberSettings { lod_px, cull: false, msaa: 1, ..Default::default() };
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
            expect += 2 * counts(l, p.fibers_per_ply, settings.n_sub).0 as u64;
        }
        let got = img.stats.instances as u64;
        let mean_l = lambdas.iter().sum::<f64>() / lambdas.len() as f64;
        eprintln!(
            "distance {dist} m, ω^LoD {lod_px} px: mean λ {mean_l:.3}, instances GPU {got}, \
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
        "culling: {} of {} segments culled, instances {} vs {}",
        on.stats.culled, on.stats.segments, on.stats.instances, off.stats.instances
    );
    assert!(on.stats.culled * 3 > on.stats.segments, "the view culls too little to test");
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
