//! The lumislice renderer [C03 §5] against the CPU volumetric reference
//! (`yarn_ref::volume`, DESIGN §1.5) on the same density, light and camera, and the
//! compositing rules: eq. 10's shadows help where one yarn shades another, and an opaque
//! occluder keeps its pixels bit for bit.

use crate::common::cotton;
use btf_render::Gpu;
use std::sync::Arc;
use yarn::density::{CrossSectionDensity, DensityOptions};
use yarn::{YarnCurve, YarnParams, YarnSet};
use yarn_precompute::{Lumislice, LumisliceSettings};
use yarn_ref::volume::{
    ExtinctionLaw, Phase, SliceDensity, VolumeScene, VolumeSettings, render_volume,
};
use yarn_ref::{Camera, Light, RenderSettings};
use yarn_render::{
    FiberCamera, FiberLight, LumisliceRenderSettings, LumisliceRenderer, PackOptions, PackedYarns,
};

const ALBEDO: [f32; 3] = [0.8, 0.6, 0.4];

fn table(p: &YarnParams) -> (Lumislice, LumisliceSettings) {
    let s =
        LumisliceSettings { res: 32, multiple: false, density_samples: 128, ..Default::default() };
    (Lumislice::compute(p, ALBEDO, &s, &|_| {}).unwrap(), s)
}

/// The reference: the same density (grid, samples, seed) in the volumetric marcher.
fn reference(
    set: &YarnSet,
    p: &YarnParams,
    s: &LumisliceSettings,
    lights: &[Light],
    cam: &Camera,
    (w, h): (usize, usize),
) -> Vec<[f32; 3]> {
    let d = CrossSectionDensity::from_params(
        p,
        &DensityOptions { res: s.res, samples: s.density_samples, seed: s.seed, loops: true },
    )
    .unwrap();
    let step = d.cell_size() / 2.0;
    let dens: Arc<dyn SliceDensity> = Arc::new(d);
    let vol =
        VolumeScene::new(set, std::slice::from_ref(p), &[dens], ExtinctionLaw::Anisotropic, 16)
            .unwrap();
    let mut vs = VolumeSettings::new(step);
    vs.albedo = 1.0; // ϖ per channel below
    vs.phase = Phase::KajiyaKay;
    let (img, _) = render_volume(&vol, lights, cam, &RenderSettings::new(w, h, 16), &vs).unwrap();
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let c = img.pixel(x, y);
            [c[0] * ALBEDO[0], c[1] * ALBEDO[1], c[2] * ALBEDO[2]]
        })
        .collect()
}

/// With `LUMI_DUMP=DIR`, the GPU frame beside the reference as `DIR/NAME.png` (×6).
fn dump(name: &str, (w, h): (usize, usize), g: &[[f32; 4]], r: &[[f32; 3]]) {
    let Ok(dir) = std::env::var("LUMI_DUMP") else { return };
    let z = 6u32;
    let mut buf = image::RgbImage::new(2 * w as u32 * z, h as u32 * z);
    let to = |v: f32| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0) as u8;
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (g[y * w + x], r[y * w + x]);
            for (i, j) in (0..z).flat_map(|i| (0..z).map(move |j| (i, j))) {
                let (px, py) = (x as u32 * z + i, y as u32 * z + j);
                buf.put_pixel(px, py, image::Rgb([to(a[0]), to(a[1]), to(a[2])]));
                buf.put_pixel(px + w as u32 * z, py, image::Rgb([to(b[0]), to(b[1]), to(b[2])]));
            }
        }
    }
    buf.save(format!("{dir}/{}.png", name.replace(' ', "-"))).unwrap();
}

/// Relative RMSE over the pixels where the reference is brighter than 5 % of its peak.
fn rel_rmse(gpu: &[[f32; 4]], reference: &[[f32; 3]]) -> (f64, usize) {
    let peak = reference.iter().map(|c| c[0]).fold(0.0f32, f32::max) as f64;
    let (mut num, mut den, mut n) = (0.0, 0.0, 0);
    for (g, r) in gpu.iter().zip(reference) {
        if (r[0] as f64) < 0.05 * peak {
            continue;
        }
        for c in 0..3 {
            num += (g[c] as f64 - r[c] as f64).powi(2);
            den += (r[c] as f64).powi(2);
        }
        n += 1;
    }
    ((num / den.max(1e-30)).sqrt(), n)
}

fn bent_yarn(y0: f64, z0: f64, along_y: bool) -> YarnCurve {
    let pts = (0..9)
        .map(|i| {
            let s = (i as f64 - 4.0) * 1e-3;
            let bend = 0.5e-3 * (i as f64 * 0.4).sin();
            if along_y { [y0 + bend, s, z0] } else { [s, y0 + bend, z0] }
        })
        .collect();
    YarnCurve::open(pts).unwrap()
}

#[test]
fn one_yarn_matches_the_volume_reference() {
    let Some(gpu) = Gpu::for_tests("lumislice_one_yarn") else { return };
    let p = cotton();
    let (l, s) = table(&p);
    let set = YarnSet::new(vec![bent_yarn(0.0, 0.0, false)], None).unwrap();
    let (w, h) = (96usize, 48usize);
    let (eye, target, up, fov) = ([0.0, -2.5e-3, 2e-3], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 40.0);
    let (to_light, irradiance) = ([0.3, -0.5, 0.8], [3.0, 3.0, 3.0]);
    let r = reference(
        &set,
        &p,
        &s,
        &[Light::Directional { to_light, irradiance }],
        &Camera::perspective(eye, target, up, fov).unwrap(),
        (w, h),
    );
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let mut results = Vec::new();
    for (name, rs) in [
        ("fine steps", LumisliceRenderSettings { step_cells: 0.5, n_sub: 8, ..Default::default() }),
        ("default", LumisliceRenderSettings::default()),
    ] {
        let ren = LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(&l), rs).unwrap();
        let img = ren
            .render(
                &gpu,
                &FiberCamera::perspective(eye, target, up, fov),
                &[FiberLight::Directional { to_light, irradiance }],
                (w as u32, h as u32),
                [0.0; 4],
            )
            .unwrap();
        let (e, n) = rel_rmse(&img.pixels, &r);
        dump(&format!("one-{name}"), (w, h), &img.pixels, &r);
        let (sg, sr): (f64, f64) = img
            .pixels
            .iter()
            .zip(&r)
            .map(|(g, r)| (g[0] as f64, r[0] as f64))
            .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        eprintln!(
            "lumislice {name}: rel. RMSE {e:.4} over {n} pixels, mean GPU/reference {:.4}",
            sg / sr
        );
        results.push((e, sg / sr, n));
    }
    for (e, ratio, n) in results {
        assert!(n > 200, "the yarn covers the frame: {n} pixels");
        assert!(e < 0.08, "rel. RMSE {e}");
        assert!((ratio - 1.0).abs() < 0.03, "mean ratio {ratio}");
    }
}

#[test]
fn eq10_shadows_bring_a_crossing_yarn_towards_the_reference() {
    let Some(gpu) = Gpu::for_tests("lumislice_eq10") else { return };
    let p = cotton();
    let (l, s) = table(&p);
    // A yarn along y 2 mm above one along x, the light low from +x: the upper casts a
    // shadow band across the lower.
    let set =
        YarnSet::new(vec![bent_yarn(0.0, 0.0, false), bent_yarn(0.0, 2e-3, true)], None).unwrap();
    let (w, h) = (80usize, 64usize);
    let (eye, target, up, fov) =
        ([0.5e-3, -3.5e-3, 4e-3], [0.0, 0.0, 0.5e-3], [0.0, 0.0, 1.0], 45.0);
    let (to_light, irradiance) = ([0.6, 0.0, 0.8], [3.0, 3.0, 3.0]);
    let r = reference(
        &set,
        &p,
        &s,
        &[Light::Directional { to_light, irradiance }],
        &Camera::perspective(eye, target, up, fov).unwrap(),
        (w, h),
    );
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let mut errs = Vec::new();
    for (name, shadows, variant) in [
        ("no eq. 10", false, yarn_precompute::lumislice::ShadowVariant::Physical),
        ("eq. 10 physical", true, yarn_precompute::lumislice::ShadowVariant::Physical),
        ("eq. 10 empirical", true, yarn_precompute::lumislice::ShadowVariant::Empirical),
    ] {
        let rs = LumisliceRenderSettings { shadows, shadow_variant: variant, ..Default::default() };
        let ren = LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(&l), rs).unwrap();
        let img = ren
            .render(
                &gpu,
                &FiberCamera::perspective(eye, target, up, fov),
                &[FiberLight::Directional { to_light, irradiance }],
                (w as u32, h as u32),
                [0.0; 4],
            )
            .unwrap();
        let (e, n) = rel_rmse(&img.pixels, &r);
        dump(&format!("crossing-{name}"), (w, h), &img.pixels, &r);
        eprintln!("crossing yarns, {name}: rel. RMSE {e:.4} over {n} pixels");
        errs.push(e);
    }
    assert!(errs[1] < errs[0] - 0.02, "eq. 10 (physical) helps: {errs:?}");
    assert!(errs[1] < 0.08 && errs[2] < 0.08, "{errs:?}");
}

#[test]
fn an_opaque_plate_keeps_its_pixels_bit_for_bit() {
    let Some(gpu) = Gpu::for_tests("lumislice_plate") else { return };
    let p = cotton();
    let s =
        LumisliceSettings { res: 16, multiple: false, density_samples: 32, ..Default::default() };
    let l = Lumislice::compute(&p, ALBEDO, &s, &|_| {}).unwrap();
    let set = YarnSet::new(vec![bent_yarn(0.0, 0.0, false)], None).unwrap();
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let ren = LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(&l), Default::default())
        .unwrap();
    let (w, h) = (48u32, 32u32);
    let cam = FiberCamera::perspective([0.0, -6e-3, 5e-3], [0.0; 3], [0.0, 0.0, 1.0], 45.0);
    let lights = [FiberLight::Directional { to_light: [0.3, -0.5, 0.8], irradiance: [3.0; 3] }];
    let clear = [0.25, 0.5, 0.75, 1.0];
    // A plate filling the frame at NDC depth `z`: the depth buffer cleared to it.
    let frame = |plate: Option<f32>| {
        let t = yarn_render::passes::draw::FrameTargets::new(&gpu, "plate", (w, h), 4).unwrap();
        let (cv, rv, dv) = t.views();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let _ = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("plate"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &cv,
                    depth_slice: None,
                    resolve_target: rv.as_ref(),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: clear[0],
                            g: clear[1],
                            b: clear[2],
                            a: clear[3],
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &dv,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(plate.unwrap_or(1.0)),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        ren.encode_into(&gpu, &mut enc, (&cv, rv.as_ref(), &dv), (w, h), &cam, &lights).unwrap();
        gpu.queue.submit([enc.finish()]);
        t.read(&gpu).unwrap()
    };
    let free = frame(None);
    let covered = free.iter().filter(|c| (c[0] - 0.25).abs() > 1e-3).count();
    assert!(covered > 100, "the yarn shows without the plate: {covered} pixels");
    // In front of the yarn (NDC depth ~0: at the near plane): every pixel is the plate's.
    let hidden = frame(Some(1e-6));
    let background: [f32; 4] = [0.25, 0.5, 0.75, 1.0].map(|x: f32| half::f16::from_f32(x).to_f32());
    assert!(hidden.iter().all(|c| *c == background), "the plate's pixels changed");
    // Behind it (just inside the far plane): the yarn exactly as without the plate.
    let behind = frame(Some(0.999_999));
    assert_eq!(behind, free, "a plate behind the yarn changes nothing");
}

/// DESIGN §1.5's edge-on curve: a straight yarn seen at angles θ from its axis, the paper's
/// instanced slices against the ray march, both against the volumetric reference. The
/// slices are cross-sections ⟂ the yarn: face-on when looking along it, edge-on (vanishing)
/// at 90°, where the ray march has no degeneracy.
#[test]
fn slices_fail_edge_on_where_the_ray_march_does_not() {
    let Some(gpu) = Gpu::for_tests("lumislice_edge_on") else { return };
    let p = cotton();
    let (l, s) = table(&p);
    let pts = (0..9).map(|i| [(i as f64 - 4.0) * 1.5e-3, 0.0, 0.0]).collect();
    let set = YarnSet::new(vec![YarnCurve::open(pts).unwrap()], None).unwrap();
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let (w, h) = (64usize, 48usize);
    let (to_light, irradiance) = ([0.2, -0.6, 0.8], [3.0, 3.0, 3.0]);
    let mut curve = Vec::new();
    for theta in [20.0f64, 45.0, 70.0, 90.0] {
        let t = theta.to_radians();
        let (target, up, fov) = ([0.0; 3], [0.0, 0.0, 1.0], 30.0);
        let eye = [6e-3 * t.cos(), -6e-3 * t.sin(), 1.5e-3];
        let r = reference(
            &set,
            &p,
            &s,
            &[Light::Directional { to_light, irradiance }],
            &Camera::perspective(eye, target, up, fov).unwrap(),
            (w, h),
        );
        let mut row = vec![theta];
        for slices in [0u32, 8] {
            let rs = LumisliceRenderSettings { n_sub: 8, slices, ..Default::default() };
            let ren = LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(&l), rs).unwrap();
            let img = ren
                .render(
                    &gpu,
                    &FiberCamera::perspective(eye, target, up, fov),
                    &[FiberLight::Directional { to_light, irradiance }],
                    (w as u32, h as u32),
                    [0.0; 4],
                )
                .unwrap();
            dump(&format!("edge-{theta}-{slices}"), (w, h), &img.pixels, &r);
            row.push(rel_rmse(&img.pixels, &r).0);
        }
        eprintln!("θ = {theta:>4}°: ray march {:.4}, slices {:.4}", row[1], row[2]);
        curve.push(row);
    }
    for r in &curve {
        assert!(r[1] < 0.10, "the ray march at every angle: {curve:?}");
    }
    let last = &curve[curve.len() - 1];
    assert!(last[2] > 2.0 * last[1] && last[2] > curve[0][2], "slices edge-on: {curve:?}");
}

/// [C03 eq. 9]: slices composited back to front make the geometric series
/// `Σ_k c α (1 − α)^k = c (1 − (1 − α)^N)`, so seen along a straight, untwisted yarn of
/// uniform density (isotropic extinction σ, length L, N slabs of `α = 1 − e^{−σL/N}`) the
/// coverage is `1 − e^{−σL}` for every slice count, and so is the ray march's (its steps
/// compose the same series in f32). The colour per coverage is the slab's `c` in every
/// mode. Bounds: the frame is f16 (2⁻¹¹ relative per blend), with 2 pieces × N slices
/// blended one after another: `2N · 2⁻¹¹` relative for the coverage.
#[test]
fn slices_composite_to_eq9s_geometric_series() {
    let Some(gpu) = Gpu::for_tests("lumislice_eq9") else { return };
    let mut p = cotton();
    p.ply_pitch = 1e3; // no twist: every slab is the same cross-section
    let r = p.yarn_radius();
    let (res, sigma, length) = (32usize, 450.0, 2e-3);
    let mut grid = yarn_precompute::lumislice::SliceGrid {
        res,
        half_width: 1.25 * r,
        sigma: vec![0.0; res * res],
    };
    for j in 0..res {
        for i in 0..res {
            let [x, y] = grid.centre(i, j);
            if x.hypot(y) <= r {
                grid.sigma[j * res + i] = sigma;
            }
        }
    }
    let s = LumisliceSettings {
        res,
        multiple: false,
        extinction: yarn::density::Extinction::Isotropic,
        ..Default::default()
    };
    let l = Lumislice::from_grid(&grid, p.ply_pitch, ALBEDO, &s, &|_| {}).unwrap();
    // Along +z from 0 to L (3 CPs: two pieces with n_sub = 1), seen from above along it.
    let curve =
        YarnCurve::open(vec![[0.0, 0.0, 0.0], [0.0, 0.0, 0.5 * length], [0.0, 0.0, length]])
            .unwrap();
    let set = YarnSet::new(vec![curve], None).unwrap();
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let (w, h) = (33u32, 33u32);
    let cam = FiberCamera::perspective([0.0, 0.0, 0.05], [0.0; 3], [0.0, 1.0, 0.0], 2.0);
    let lights = [FiberLight::Directional { to_light: [0.6, 0.0, 0.8], irradiance: [1.0; 3] }];
    let centre = (h / 2 * w + w / 2) as usize;
    let want = 1.0 - (-sigma * length).exp();
    let mut colours = Vec::new();
    for slices in [0u32, 1, 3, 8] {
        let rs = LumisliceRenderSettings { n_sub: 1, shadows: false, slices, ..Default::default() };
        let ren = LumisliceRenderer::new(&gpu, &packed, std::slice::from_ref(&l), rs).unwrap();
        let img = ren.render(&gpu, &cam, &lights, (w, h), [0.0; 4]).unwrap();
        let px = img.pixels[centre];
        let bound = 2.0 * slices.max(1) as f64 * 2f64.powi(-11) * want + 1e-4;
        let cover = px[3] as f64;
        eprintln!(
            "eq. 9, {}: coverage {cover:.5} (1 − e^(−σL) = {want:.5}), colour / coverage {:.5}",
            if slices == 0 { "ray march".to_string() } else { format!("{slices} slices") },
            px[0] as f64 / cover
        );
        assert!((cover - want).abs() <= bound, "{slices} slices: coverage {cover} vs {want}");
        colours.push(px[0] as f64 / cover);
    }
    for c in &colours {
        assert!(*c > 0.0 && (c / colours[0] - 1.0).abs() < 0.01, "colour per coverage {colours:?}");
    }
}
