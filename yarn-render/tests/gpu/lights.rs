//! Point lights with their tube shadow maps (one perspective map from afar, cube faces from
//! among the yarns) and the environment by SRBF lobes (soft or hard lobe shadows), against
//! the CPU reference on
//! stockinette (R-approx: the same fibers, no hairs), oblique BTF view, one bounce. The
//! scene, reference and GPU frame helpers serve `effects.rs` too.

use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::fiber::GenOptions;
use yarn::knit::Chart;
use yarn_precompute::{ImTable, SrbfFit};
use yarn_ref::patch::{KnitPatch, PatchOptions};
use yarn_ref::{
    Background, Camera, EnvLight, FiberScene, Light, PathSettings, RenderSettings, Scene,
    SceneOptions, Shading, render,
};
use yarn_render::{
    AoMode, FiberCamera, FiberEffects, FiberLight, FiberRenderer, FiberSettings, PackOptions,
    PackedYarns,
};

const SIZE: usize = 48;

pub(crate) struct Setup {
    pub(crate) patch: KnitPatch,
    pub(crate) packed: PackedYarns,
    pub(crate) bcsdf: FiberBcsdf,
    pub(crate) view: [f64; 3],
    /// The reference wraps the patch periodically (the GPU draws 3 × 3 copies); else both
    /// see the 4 × 4 stitches alone.
    periodic: bool,
}

pub(crate) fn setup(periodic: bool) -> Setup {
    setup_with(periodic, false)
}

/// [`setup`] with or without the yarn's hair flyaways in the patch.
pub(crate) fn setup_with(periodic: bool, hairs: bool) -> Setup {
    setup_fine(periodic, hairs, GenOptions::default().samples_per_turn)
}

/// [`setup_with`] with the reference's fibers sampled `samples_per_turn` points a turn.
pub(crate) fn setup_fine(periodic: bool, hairs: bool, samples_per_turn: u32) -> Setup {
    let chart = Chart::builtin("stockinette").unwrap();
    let params = crate::common::cotton();
    let g = GenOptions { hairs, seed: 5, samples_per_turn, ..Default::default() };
    let stitches = if periodic { None } else { Some([4, 4]) };
    let opts = PatchOptions { generation: g, stitches, ..Default::default() };
    let patch = KnitPatch::new(&chart, &params, &opts).unwrap();
    let tiles = if periodic { [3, 3] } else { [1, 1] };
    let packed = PackedYarns::new(
        &patch.yarns,
        std::slice::from_ref(&params),
        &PackOptions { seed: 5, frame_samples_per_segment: 16, tiles },
    )
    .unwrap();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let view = btf_core::Direction::new(45.0, 30.0).to_vector();
    Setup { patch, packed, bcsdf, view, periodic }
}

pub(crate) fn reference(s: &Setup, lights: &[Light], spp: u32) -> Vec<f32> {
    reference_image(s, lights, spp).rgb
}

/// The reference frame of [`reference`], with its coverage.
pub(crate) fn reference_image(s: &Setup, lights: &[Light], spp: u32) -> yarn_ref::Image {
    let period = s.periodic.then_some(s.patch.period);
    let scene =
        FiberScene::new(&s.patch.fibers, &SceneOptions { period, backing_z: None }).unwrap();
    let shading = Shading::Fiber { bcsdf: std::sync::Arc::new(s.bcsdf.clone()), tint: true };
    let sc = Scene { fibers: &scene, lights, shading: &shading };
    let p = s.patch.period;
    let cam = Camera::oblique(s.view, s.patch.z_ref, p.origin, p.size).unwrap();
    let mut rs = RenderSettings::new(SIZE, SIZE, spp);
    rs.path = PathSettings { max_bounces: 1, rr_start: 100, background: Background::Black };
    render(&sc, &cam, &rs).unwrap().0
}

pub(crate) fn renderer(gpu: &Gpu, s: &Setup, effects: FiberEffects) -> FiberRenderer {
    let settings = FiberSettings { lod_px: 0.0, hairs: false, effects, ..Default::default() };
    FiberRenderer::new(gpu, &s.packed, &s.bcsdf, settings).unwrap()
}

pub(crate) fn frame(gpu: &Gpu, s: &Setup, r: &FiberRenderer, lights: &[FiberLight]) -> Vec<f32> {
    let p = s.patch.period;
    let cam = FiberCamera::oblique(s.view, s.patch.z_ref, p.origin, p.size);
    let img = r.render(gpu, &cam, lights, (SIZE as u32, SIZE as u32), [0.0; 4]).unwrap();
    img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
}

pub(crate) fn rel_rmse(a: &[f32], b: &[f32]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        num += (*x as f64 - *y as f64).powi(2);
        den += (*y as f64).powi(2);
    }
    (num / den).sqrt()
}

pub(crate) fn mean(a: &[f32]) -> f64 {
    a.iter().map(|x| *x as f64).sum::<f64>() / a.len() as f64
}

/// The patch centre (x, y at the period's middle, z halfway between top and bottom).
pub(crate) fn centre(s: &Setup) -> [f64; 3] {
    let p = s.patch.period;
    [
        p.origin[0] + 0.5 * p.size[0],
        p.origin[1] + 0.5 * p.size[1],
        0.5 * (s.patch.z_ref + s.patch.z_bottom),
    ]
}

#[test]
fn a_far_point_light_casts_the_directional_lights_yarn_shadows() {
    let Some(gpu) = Gpu::for_tests("a_far_point_light_casts") else { return };
    let s = setup(true);
    let to_light = btf_core::Direction::new(30.0, 200.0).to_vector();
    // 300 patch widths away: the irradiance varies by < 0.4 % over the patch.
    let d = 300.0 * s.patch.period.size[0];
    let c = centre(&s);
    let position = [0, 1, 2].map(|a| c[a] + to_light[a] * d);
    let point = [FiberLight::Point { position, intensity: [3.0 * d * d; 3] }];
    let dir = [FiberLight::Directional { to_light, irradiance: [3.0; 3] }];
    let on = renderer(&gpu, &s, FiberEffects::default());
    let off = renderer(&gpu, &s, FiberEffects { yarn_shadows: false, ..FiberEffects::default() });
    let (p_on, d_on) = (frame(&gpu, &s, &on, &point), frame(&gpu, &s, &on, &dir));
    let (p_off, d_off) = (frame(&gpu, &s, &off, &point), frame(&gpu, &s, &off, &dir));
    let shadowed = rel_rmse(&d_on, &d_off);
    let (e_on, e_off) = (rel_rmse(&p_on, &d_on), rel_rmse(&p_off, &d_off));
    eprintln!(
        "far point light vs directional (48²): yarn shadows change the directional frame by \
         {shadowed:.3}; point vs directional {e_on:.4} with shadows, {e_off:.4} without"
    );
    // The shadows matter here, and the point light's perspective map casts the same ones:
    // the two frames differ by the irradiance's 0.4 % spread and the maps' resampling
    // (a perspective texel against an orthographic one), far below the shadows' effect.
    // Measured: shadows 0.440, point vs directional 0.021 with them, 0.0024 without.
    assert!(shadowed > 0.1, "yarn shadows change the frame by {shadowed}");
    assert!(e_off < 0.01, "without yarn shadows the lights differ by {e_off}");
    assert!(e_on < 0.08 * shadowed + e_off, "point vs directional {e_on}");
}

#[test]
fn point_light_shadows_from_afar_and_among_the_yarns_against_the_reference() {
    let Some(gpu) = Gpu::for_tests("point_light_shadows_from_afar") else { return };
    let s = setup(false);
    let c = centre(&s);
    let w = s.patch.period.size[0];
    let to = btf_core::Direction::new(35.0, 200.0).to_vector();
    let cases = [
        // Afar: one perspective map (the patch subtends ~11°).
        ("afar", [0, 1, 2].map(|a| c[a] + to[a] * 5.0 * w), 25.0),
        // Over the patch, inside the yarns' bounding sphere: cube faces.
        ("among", [c[0] + 0.1 * w, c[1] - 0.05 * w, s.patch.z_ref + 0.3 * w], 1.0),
    ];
    let on = renderer(&gpu, &s, FiberEffects::default());
    let off = renderer(&gpu, &s, FiberEffects { yarn_shadows: false, ..FiberEffects::default() });
    for (name, position, scale) in cases {
        let i = 3.0 * scale * w * w;
        let r = reference(&s, &[Light::Point { position, intensity: [i; 3] }], 32);
        let l = [FiberLight::Point { position, intensity: [i; 3] }];
        let (g_on, g_off) = (frame(&gpu, &s, &on, &l), frame(&gpu, &s, &off, &l));
        let (e_on, e_off) = (rel_rmse(&g_on, &r), rel_rmse(&g_off, &r));
        let ratio = mean(&g_on) / mean(&r);
        eprintln!(
            "point light {name}: rel. RMSE without yarn shadows {e_off:.3}, with {e_on:.3}; \
             mean {ratio:.3} of the reference's"
        );
        assert!(e_on < e_off, "{name}: yarn shadows did not help ({e_on} ≥ {e_off})");
        assert!((ratio - 1.0).abs() < 0.3, "{name}: mean ratio {ratio}");
    }
}

/// A sky of 0.2 with a sun of half-width ~4° and 40× its radiance, 35° above the horizon.
fn sun_and_sky() -> btf_image::EnvMap {
    let sun = btf_core::Direction::new(55.0, 120.0).to_vector();
    btf_image::EnvMap::from_fn(64, move |d| {
        let c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
        let v = 0.2 + 8.0 * (400.0 * (c - 1.0)).exp();
        [v, v, v]
    })
    .unwrap()
}

#[test]
fn srbf_environment_against_the_constant_ambient_and_the_reference() {
    let Some(gpu) = Gpu::for_tests("srbf_environment_against") else { return };
    let s = setup(true);
    let ambient_fx = FiberEffects { ao: AoMode::Texture, ..FiberEffects::default() };
    for (name, map) in [
        ("constant sky", btf_image::EnvMap::constant(32, [1.0; 3]).unwrap()),
        ("sun", sun_and_sky()),
    ] {
        let r = reference(&s, &[Light::Environment(EnvLight::new(map.clone(), 1.0))], 64);
        let fit = SrbfFit::fit(&map, 16).unwrap();
        let table = ImTable::build(&s.bcsdf, fit.lambda).unwrap();
        // [W19]: the uniform radiance of the same power, with AO.
        let mut amb = renderer(&gpu, &s, ambient_fx);
        amb.set_ambient(map.integral().map(|x| (x / (4.0 * std::f64::consts::PI)) as f32));
        let g_amb = frame(&gpu, &s, &amb, &[]);
        let mut srbf = renderer(&gpu, &s, FiberEffects::default());
        srbf.set_environment(&gpu, Some((&fit, &table))).unwrap();
        let g_srbf = frame(&gpu, &s, &srbf, &[]);
        let mut unshadowed =
            renderer(&gpu, &s, FiberEffects { yarn_shadows: false, ..FiberEffects::default() });
        unshadowed.set_environment(&gpu, Some((&fit, &table))).unwrap();
        let g_free = frame(&gpu, &s, &unshadowed, &[]);
        let rotated = fit.rotated_z(90.0);
        srbf.set_environment(&gpu, Some((&rotated, &table))).unwrap();
        let g_rot = frame(&gpu, &s, &srbf, &[]);
        // The lobes' shadows hard (3 × 3 PCF, as a delta light's) instead of PCSS.
        let hard_settings =
            FiberSettings { lod_px: 0.0, soft_lobes: false, hairs: false, ..Default::default() };
        let mut hard = FiberRenderer::new(&gpu, &s.packed, &s.bcsdf, hard_settings).unwrap();
        hard.set_environment(&gpu, Some((&fit, &table))).unwrap();
        let g_hard = frame(&gpu, &s, &hard, &[]);
        hard.set_environment(&gpu, Some((&rotated, &table))).unwrap();
        let hard_turned = rel_rmse(&frame(&gpu, &s, &hard, &[]), &g_hard);
        let e_hard = rel_rmse(&g_hard, &r);
        let m = mean(&r);
        let (e_amb, e_srbf, e_free) =
            (rel_rmse(&g_amb, &r), rel_rmse(&g_srbf, &r), rel_rmse(&g_free, &r));
        let turned = rel_rmse(&g_rot, &g_srbf);
        eprintln!(
            "{name} (fit error {:.3}, λ {:.1}): mean ambient + AO texture {:.3}, SRBFs {:.3}, \
             SRBFs without yarn shadows {:.3} of the reference's; rel. RMSE {e_amb:.3} / \
             {e_srbf:.3} / {e_free:.3}; turned 90° about z the SRBF frame changes by {turned:.3}; \
             with hard lobe shadows: mean {:.3}, rel. RMSE {e_hard:.3}, turned {hard_turned:.3}",
            fit.rel_error,
            fit.lambda,
            mean(&g_amb) / m,
            mean(&g_srbf) / m,
            mean(&g_free) / m,
            mean(&g_hard) / m,
        );
        // The lobes' tube shadow maps block the sky behind the other yarns, which AO (a
        // yarn's own fibers) cannot: closer to the reference in the mean and per pixel.
        assert!(
            (mean(&g_srbf) / m - 1.0).abs() < (mean(&g_amb) / m - 1.0).abs(),
            "{name}: SRBF mean not closer than the ambient's"
        );
        assert!(e_srbf < e_amb, "{name}: SRBF error {e_srbf} ≥ ambient {e_amb}");
        // And near the reference's brightness in itself (measured 1.17 and 0.94): a dark or
        // unlit frame would also score "closer than the ambient term" above.
        let ratio = mean(&g_srbf) / m;
        assert!((0.8..1.3).contains(&ratio), "{name}: SRBF mean {ratio} of the reference's");
        assert!(e_srbf < e_free, "{name}: yarn shadows of the lobes did not help");
        // Soft lobes depend less on where the lobe centres fall: the frame moves less when
        // the map turns (measured: constant sky 0.085 soft against 0.182 hard, sun 0.152
        // against 0.264), and the error is no larger (0.530 / 0.496 against 0.538 / 0.510).
        assert!(turned < hard_turned, "{name}: soft lobes turned {turned} ≥ hard {hard_turned}");
        assert!(e_hard < e_free && e_hard < e_amb, "{name}: hard lobes {e_hard}");
        if name == "sun" {
            // The sun's direction is in the lobes: turning the map moves the highlights.
            assert!(turned > 0.1, "turning the sun changed the frame by {turned}");
        }
    }
}

/// What the per-pixel error on a knit patch is made of (the 5 % bound of DESIGN §2.5 holds
/// where the shadow model is exact, `reference.rs`, not here): at 48² the fibers are
/// sub-pixel and each covers 0 to 4 of a pixel's MSAA samples, where the reference averages
/// 64 rays. Rendering at 2× and averaging 2 × 2 (16 samples a pixel) removes about
/// half of the error; what stays is the model — [W19]'s statistical self-shadow volume and
/// the strips' coverage — not noise.
#[test]
fn half_the_knit_patch_error_is_sample_mask_noise() {
    let Some(gpu) = Gpu::for_tests("half_the_knit_patch_error_is_sample_mask_noise") else {
        return;
    };
    let s = setup(true);
    let to_light = btf_core::Direction::new(30.0, 200.0).to_vector();
    let reference_frame =
        reference(&s, &[Light::Directional { to_light, irradiance: [3.0; 3] }], 64);
    let lights = [FiberLight::Directional { to_light, irradiance: [3.0; 3] }];
    let r = renderer(&gpu, &s, FiberEffects::default());
    let direct = frame(&gpu, &s, &r, &lights);
    let p = s.patch.period;
    let cam = FiberCamera::oblique(s.view, s.patch.z_ref, p.origin, p.size);
    let n = 2 * SIZE;
    let img = r.render(&gpu, &cam, &lights, (n as u32, n as u32), [0.0; 4]).unwrap();
    let mut averaged = vec![0.0f32; SIZE * SIZE * 3];
    for y in 0..n {
        for x in 0..n {
            for c in 0..3 {
                averaged[((y / 2) * SIZE + x / 2) * 3 + c] += 0.25 * img.pixels[y * n + x][c];
            }
        }
    }
    let (e1, e2) = (rel_rmse(&direct, &reference_frame), rel_rmse(&averaged, &reference_frame));
    eprintln!(
        "stockinette 48², 64 spp reference: rel. RMSE {e1:.4} at 4 samples a pixel, {e2:.4} \
         at 16 (2× and averaged); mean / reference {:.4} / {:.4}",
        mean(&direct) / mean(&reference_frame),
        mean(&averaged) / mean(&reference_frame)
    );
    // Measured 0.616 → 0.374.
    assert!(e2 < 0.7 * e1, "{e1} → {e2}");
}
