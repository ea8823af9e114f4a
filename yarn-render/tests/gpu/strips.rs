//! The yarn strips of [H25] on the GPU against what they were baked from: on the straight
//! yarn of the bake, the rendered strip must carry the baked model's radiance (its CPU
//! mirror `StripBake::model_at` over the texels, within 5 %), stay near the bake's own
//! reference (the integral over the strip of coverage × path-traced radiance at a bake
//! direction), and its coverage must follow the baked profile along the yarn at the
//! screw-symmetric u — for the eye at azimuth 0 and at 90°, where the profile shifts by a
//! quarter of the ply pitch.

use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, KhungurnParams};
use yarn::{YarnCurve, YarnParams, YarnSet};
use yarn_precompute::{StripBake, StripBakeSettings};
use yarn_render::{
    FiberCamera, FiberLight, PackOptions, PackedYarns, StripRenderer, StripSettings,
};

const COLOR: [f32; 3] = [0.8, 0.6, 0.4];

fn cotton() -> YarnParams {
    YarnParams::preset("cotton-2ply").unwrap()
}

#[test]
fn strips_carry_their_bake_on_the_baked_yarn() {
    let Some(gpu) = Gpu::for_tests("strips_carry_their_bake_on_the_baked_yarn") else { return };
    let p = cotton();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let s = StripBakeSettings { spp: 16, ..StripBakeSettings::small() };
    let bake = StripBake::bake(&p, &bcsdf, COLOR, &s, &|_| {}).unwrap();
    let alpha_ply = bake.ply_pitch.abs();
    // A straight yarn along +z with N = +x (the bake's frame), 12 ply turns long.
    let length = 12.0 * alpha_ply;
    let n_cp = 48;
    let pts: Vec<[f64; 3]> =
        (0..=n_cp).map(|i| [0.0, 0.0, length * i as f64 / n_cp as f64]).collect();
    let curve =
        YarnCurve::open(pts).unwrap().with_normals(vec![[1.0, 0.0, 0.0]; n_cp + 1]).unwrap();
    let set = YarnSet::new(vec![curve.with_color(COLOR)], None).unwrap();
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&p),
        &PackOptions { seed: 1, frame_samples_per_segment: 16, tiles: [1, 1] },
    )
    .unwrap();
    let settings = StripSettings { n_sub: 16, ..StripSettings::default() };
    let r =
        StripRenderer::new(&gpu, &packed, std::slice::from_ref(&bake), &bcsdf, settings).unwrap();
    // Bake direction (θ bin 1, φ bin 2) = (−22.5°, +45°) in the frame (N, B, T) = (x, y, z).
    let (a, b) = (1, 2);
    let (theta, phi) = s.direction(a, b);
    let to_light = [theta.cos() * phi.cos(), theta.cos() * phi.sin(), theta.sin()];
    // Four ply turns in the middle, 48 px per turn.
    let (rows, per_turn) = (192u32, 48.0);
    let z_mid = 6.0 * alpha_ply;
    let px = alpha_ply / per_turn;
    let cols = ((3.0 * bake.half_width / px).ceil() as u32).max(8);
    let h_m = rows as f64 * px;
    let light = [FiberLight::Directional { to_light, irradiance: [1.0; 3] }];
    let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];

    for psi_deg in [0.0f64, 90.0] {
        let psi = psi_deg.to_radians();
        let eye = [0.05 * psi.cos(), 0.05 * psi.sin(), z_mid];
        let cam = FiberCamera::orthographic(eye, [0.0, 0.0, z_mid], [0.0, 0.0, 1.0], h_m);
        // The light turns with the eye, so that it is the same bake direction relative to it.
        let (c, sn) = (psi.cos(), psi.sin());
        let l =
            [to_light[0] * c - to_light[1] * sn, to_light[0] * sn + to_light[1] * c, to_light[2]];
        let light = [FiberLight::Directional { to_light: l, irradiance: [1.0; 3] }];
        let img = r.render(&gpu, &cam, &light, (cols, rows), [0.0; 4]).unwrap();
        // Radiance integrated over the image (W/m per unit length of yarn) and covered width
        // per row.
        let mut total = 0.0;
        let mut width_rows = vec![0.0; rows as usize];
        for y in 0..rows as usize {
            for x in 0..cols as usize {
                let q = img.pixels[y * cols as usize + x];
                total += lum([q[0], q[1], q[2]].map(f64::from)) * px * px;
                width_rows[y] += q[3] as f64 * px;
            }
        }
        let per_length = total / h_m;
        // The bake: mean over texels of α·L_ref at that direction, times the strip width.
        let nd = s.directions * s.directions;
        let n = s.width * s.height;
        let k = a * s.directions + b;
        let mean: f64 = (0..n)
            .map(|t| bake.alpha[t] as f64 * lum(bake.l_ref[t * nd + k].map(f64::from)))
            .sum::<f64>()
            / n as f64;
        let expected = mean * 2.0 * bake.half_width;
        // What the CPU mirror of the shader gives on the texels (no interpolation).
        let model: f64 = (0..n)
            .map(|t| bake.alpha[t] as f64 * lum(bake.model_at(&bcsdf, t, theta, phi)))
            .sum::<f64>()
            / n as f64
            * 2.0
            * bake.half_width;
        let rel = (per_length - expected) / expected;
        // Coverage profile along the yarn against the bake's at u = z/α − ψ/2π.
        let profile = |u: f64| -> f64 {
            let i = ((u - u.floor()) * s.width as f64).floor() as usize % s.width;
            (0..s.height).map(|j| bake.alpha[j * s.width + i] as f64).sum::<f64>()
                * 2.0
                * bake.half_width
                / s.height as f64
        };
        let (mut num, mut den, mut num_off) = (0.0, 0.0, 0.0);
        for (y, w) in width_rows.iter().enumerate() {
            // Row 0 is the top of the frame (largest z).
            let z = z_mid + h_m * (0.5 - (y as f64 + 0.5) / rows as f64);
            let u = z / bake.ply_pitch - psi / std::f64::consts::TAU;
            num += (w - profile(u)).powi(2);
            num_off += (w - profile(u + 0.25)).powi(2);
            den += profile(u).powi(2);
        }
        let (err, off) = ((num / den).sqrt(), (num_off / den).sqrt());
        eprintln!(
            "eye azimuth {psi_deg}°: radiance per length {per_length:.4e} against the bake's {expected:.4e} \
             ({:+.1} %; the baked model on the texels {model:.4e}); coverage profile error {err:.3} (a quarter turn off: {off:.3})",
            100.0 * rel
        );
        // The renderer against its CPU mirror: f16 target and MSAA coverage only.
        let mirror = (per_length - model) / model;
        assert!(mirror.abs() < 0.05, "GPU {per_length} against the CPU mirror {model}");
        // The bake's model against its own reference: its fit error at this direction
        // (16 spp, 4 × 4 directions: −19 %), a bound on gross errors of the bake.
        assert!(rel.abs() < 0.3, "radiance {per_length} against the bake's {expected}");
        assert!(err < 0.15 && err < 0.6 * off, "profile error {err}, shifted {off}");
    }
    let _ = light;
}

#[test]
fn white_furnace_through_srbfs_and_the_strip_shader() {
    let Some(gpu) = Gpu::for_tests("white_furnace_through_srbfs_and_the_strip_shader") else {
        return;
    };
    let p = cotton();
    // The paper's normalisation: an albedo that varies with θ_o (the energy-conserving one
    // is 1 everywhere and would hide a wrong θ_o or Δφ lookup).
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams {
        normalization: yarn::bcsdf::Normalization::Paper,
        ..KhungurnParams::default()
    })
    .unwrap();
    let s = StripBakeSettings {
        width: 4,
        height: 2,
        directions: 2,
        spp: 1,
        ao_rays: 1,
        bounces: 1,
        tangents: 1,
        seed: 1,
    };
    let bake = StripBake::bake(&p, &bcsdf, COLOR, &s, &|_| {}).unwrap();
    let length = 0.02;
    let pts: Vec<[f64; 3]> = (0..=16).map(|i| [0.0, 0.0, length * i as f64 / 16.0]).collect();
    let curve = YarnCurve::open(pts).unwrap().with_normals(vec![[1.0, 0.0, 0.0]; 17]).unwrap();
    let set = YarnSet::new(vec![curve.with_color(COLOR)], None).unwrap();
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&p),
        &PackOptions { seed: 1, frame_samples_per_segment: 16, tiles: [1, 1] },
    )
    .unwrap();
    // Plain strips (the BCSDF at the yarn tangent, coverage 1), no shadows: what reaches
    // the eye is Σ_j W_j I_M(θ_j, θ_o, Δφ_j) = ∫ f cos dω = A(θ_o) under a white sky.
    let settings =
        StripSettings { textures: false, shadows: false, msaa: 1, ..StripSettings::default() };
    let mut r =
        StripRenderer::new(&gpu, &packed, std::slice::from_ref(&bake), &bcsdf, settings).unwrap();
    let env = btf_image::EnvMap::constant(128, [1.0; 3]).unwrap();
    let fit = yarn_precompute::SrbfFit::fit(&env, 16).unwrap();
    let table = yarn_precompute::ImTable::build(&bcsdf, fit.lambda).unwrap();
    r.set_environment(&gpu, Some((&fit, &table))).unwrap();
    let amb = yarn::bcsdf::AmbientTable::build(&bcsdf, 256);
    let mut worst = 0.0f64;
    for elev in [0.0f64, 30.0, 60.0] {
        // The eye at elevation `elev` above the yarn's normal plane: θ_o = elev.
        let e = elev.to_radians();
        let eye = [0.05 * e.cos(), 0.0, 0.5 * length + 0.05 * e.sin()];
        let cam = FiberCamera::orthographic(eye, [0.0, 0.0, 0.5 * length], [0.0, 1.0, 0.0], 0.004);
        let img = r.render(&gpu, &cam, &[], (32, 32), [0.0; 4]).unwrap();
        let c = img.pixels[16 * 32 + 16];
        assert!(c[3] > 0.99, "the centre pixel is on the strip");
        let a = amb.at(e);
        for k in 0..3 {
            let want = a[k] * COLOR[k] as f64;
            let rel = (c[k] as f64 - want).abs() / want;
            worst = worst.max(rel);
        }
        eprintln!(
            "furnace θ_o {elev}°: GPU {:?} against A(θ_o)·tint {:?}",
            &c[..3],
            [0, 1, 2].map(|k| a[k] * COLOR[k] as f64)
        );
    }
    assert!(worst < 0.02, "white furnace off by {worst}");
}

#[test]
fn sub_pixel_strips_keep_their_coverage() {
    let Some(gpu) = Gpu::for_tests("sub_pixel_strips_keep_their_coverage") else { return };
    let p = cotton();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let s = StripBakeSettings { spp: 4, directions: 2, ..StripBakeSettings::small() };
    let bake = StripBake::bake(&p, &bcsdf, COLOR, &s, &|_| {}).unwrap();
    let rows = 1024u32;
    let light = [FiberLight::Directional { to_light: [1.0, 0.3, 0.2], irradiance: [1.0; 3] }];
    // A straight yarn filling a 1024-row frame, at 4, 1, 0.5 and 0.25 pixels per strip
    // width (the yarn's length chosen for it): the covered width per metre must agree.
    let mut widths = Vec::new();
    for px_per_strip in [4.0, 1.0, 0.5, 0.25] {
        let length = 2.0 * bake.half_width * rows as f64 / px_per_strip;
        let n = ((length / 2e-3).ceil() as usize).max(8);
        let pts: Vec<[f64; 3]> =
            (0..=n).map(|i| [0.0, 0.0, length * i as f64 / n as f64]).collect();
        let curve =
            YarnCurve::open(pts).unwrap().with_normals(vec![[1.0, 0.0, 0.0]; n + 1]).unwrap();
        let set = YarnSet::new(vec![curve.with_color(COLOR)], None).unwrap();
        let packed = PackedYarns::new(
            &set,
            std::slice::from_ref(&p),
            &PackOptions { seed: 1, frame_samples_per_segment: 16, tiles: [1, 1] },
        )
        .unwrap();
        let r = StripRenderer::new(
            &gpu,
            &packed,
            std::slice::from_ref(&bake),
            &bcsdf,
            StripSettings::default(),
        )
        .unwrap();
        let cam = FiberCamera::orthographic(
            [1.0, 0.0, 0.5 * length],
            [0.0, 0.0, 0.5 * length],
            [0.0, 0.0, 1.0],
            length,
        );
        let img = r.render(&gpu, &cam, &light, (16, rows), [0.0; 4]).unwrap();
        let px = length / rows as f64;
        widths.push(img.pixels.iter().map(|q| q[3] as f64).sum::<f64>() * px * px / length);
    }
    eprintln!("covered width per metre of yarn at 4, 1, 0.5, 0.25 px per strip: {widths:?}");
    for w in &widths[1..] {
        assert!((w / widths[0] - 1.0).abs() < 0.15, "{widths:?}");
    }
}

#[test]
fn the_flyaway_overlay_adds_the_baked_hair_coverage() {
    let Some(gpu) = Gpu::for_tests("the_flyaway_overlay_adds_the_baked_hair_coverage") else {
        return;
    };
    let p = cotton();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let s = StripBakeSettings { spp: 4, directions: 2, ..StripBakeSettings::small() };
    let bake = StripBake::bake(&p, &bcsdf, COLOR, &s, &|_| {}).unwrap();
    let fly = yarn_precompute::FlyawayBake::bake(&p, 32, 32, 3, 4, 1).unwrap();
    // The flyaways' expected covered width (m) beside the regular strip (|v|·H_f > H) and
    // over it.
    let (mut out_w, mut in_w) = (0.0, 0.0);
    for k in 0..fly.count * fly.width * fly.height {
        let j = (k / fly.width) % fly.height;
        let v = -1.0 + 2.0 * (j as f64 + 0.5) / fly.height as f64;
        let w = fly.texels[k][3] as f64 * 2.0 * fly.half_width
            / fly.height as f64
            / (fly.count * fly.width) as f64;
        if v.abs() * fly.half_width > bake.half_width { out_w += w } else { in_w += w }
    }
    let rows = 1024u32;
    let length = 2.0 * fly.half_width * rows as f64 / 6.0; // the flyaway strip 6 px wide
    let n = ((length / 2e-3).ceil() as usize).max(8);
    let pts: Vec<[f64; 3]> = (0..=n).map(|i| [0.0, 0.0, length * i as f64 / n as f64]).collect();
    let curve = YarnCurve::open(pts).unwrap().with_normals(vec![[1.0, 0.0, 0.0]; n + 1]).unwrap();
    let set = YarnSet::new(vec![curve.with_color(COLOR)], None).unwrap();
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&p),
        &PackOptions { seed: 1, frame_samples_per_segment: 16, tiles: [1, 1] },
    )
    .unwrap();
    let light = [FiberLight::Directional { to_light: [1.0, 0.3, 0.2], irradiance: [1.0; 3] }];
    let cam = FiberCamera::orthographic(
        [1.0, 0.0, 0.5 * length],
        [0.0, 0.0, 0.5 * length],
        [0.0, 0.0, 1.0],
        length,
    );
    let px = length / rows as f64;
    let width = |fl: bool| {
        let mut r = StripRenderer::new(
            &gpu,
            &packed,
            std::slice::from_ref(&bake),
            &bcsdf,
            StripSettings { flyaways: fl, ..Default::default() },
        )
        .unwrap();
        r.set_flyaways(&gpu, std::slice::from_ref(&fly)).unwrap();
        let img = r.render(&gpu, &cam, &light, (16, rows), [0.0; 4]).unwrap();
        (img.pixels.iter().map(|q| q[3] as f64).sum::<f64>() * px * px / length, img.pixels)
    };
    let ((w0, _), (w1, _)) = (width(false), width(true));
    eprintln!(
        "covered width per metre: regular {w0:.4e}, with flyaways {w1:.4e} (+{:.4e}); baked flyaway width beside the strip {out_w:.4e}, over it {in_w:.4e}",
        w1 - w0
    );
    assert!(out_w > 0.0, "the bake has hairs beside the yarn");
    assert!(w1 > w0 * 1.01, "the overlay adds coverage: {w0} → {w1}");
    assert!(w1 - w0 >= 0.7 * out_w && w1 - w0 <= 1.3 * (out_w + in_w), "{w0} → {w1}");
    // No hairs: the overlay draws nothing, bit for bit.
    let mut bald = p.clone();
    bald.hair_density = 0.0;
    let fz = yarn_precompute::FlyawayBake::bake(&bald, 8, 8, 3, 2, 1).unwrap();
    let pair: Vec<Vec<[f32; 4]>> = [false, true]
        .iter()
        .map(|&fl| {
            let mut r = StripRenderer::new(
                &gpu,
                &packed,
                std::slice::from_ref(&bake),
                &bcsdf,
                StripSettings { flyaways: fl, ..Default::default() },
            )
            .unwrap();
            r.set_flyaways(&gpu, std::slice::from_ref(&fz)).unwrap();
            r.render(&gpu, &cam, &light, (16, 256), [0.0; 4]).unwrap().pixels
        })
        .collect();
    assert!(pair[0] == pair[1], "an empty overlay changed the frame");
}

/// Point lights cast strip shadows too: from afar (one perspective map) the frame is the
/// directional light's of the same irradiance, shadows and all; from among the yarns (cube
/// faces) the upper yarn's shadow darkens the lower one.
#[test]
fn point_lights_cast_strip_shadows_like_the_directional_light() {
    let Some(gpu) = Gpu::for_tests("point_lights_cast_strip_shadows") else { return };
    let p = cotton();
    let r = p.yarn_radius();
    let bcsdf = FiberBcsdf::khungurn(&KhungurnParams::default()).unwrap();
    let s = StripBakeSettings { spp: 4, directions: 2, ..StripBakeSettings::small() };
    let bake = StripBake::bake(&p, &bcsdf, COLOR, &s, &|_| {}).unwrap();
    // Two straight yarns 40 radii long crossing, the upper 4 radii above the lower.
    let line = |a: [f64; 3], b: [f64; 3], up: [f64; 3]| {
        let pts: Vec<[f64; 3]> =
            (0..=20).map(|i| [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * i as f64 / 20.0)).collect();
        YarnCurve::open(pts).unwrap().with_normals(vec![up; 21]).unwrap().with_color(COLOR)
    };
    let l = 20.0 * r;
    let set = YarnSet::new(
        vec![
            line([-l, 0.0, 0.0], [l, 0.0, 0.0], [0.0, 0.0, 1.0]),
            line([0.0, -l, 4.0 * r], [0.0, l, 4.0 * r], [0.0, 0.0, 1.0]),
        ],
        None,
    )
    .unwrap();
    let packed = PackedYarns::new(
        &set,
        std::slice::from_ref(&p),
        &PackOptions { seed: 1, frame_samples_per_segment: 16, tiles: [1, 1] },
    )
    .unwrap();
    let cam = FiberCamera::orthographic([0.0, 0.0, 1.0], [0.0; 3], [0.0, 1.0, 0.0], 2.0 * l);
    let frame = |shadows: bool, light: FiberLight| {
        let settings = StripSettings { shadows, light_angle_deg: 0.0, ..Default::default() };
        let rd = StripRenderer::new(&gpu, &packed, std::slice::from_ref(&bake), &bcsdf, settings)
            .unwrap();
        rd.render(&gpu, &cam, &[light], (96, 96), [0.0; 4]).unwrap().pixels
    };
    let rel = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        let (mut num, mut den) = (0.0, 0.0);
        for (x, y) in a.iter().zip(b) {
            for c in 0..3 {
                num += (x[c] as f64 - y[c] as f64).powi(2);
                den += (y[c] as f64).powi(2);
            }
        }
        (num / den).sqrt()
    };
    let mean = |a: &[[f32; 4]]| a.iter().map(|q| (q[0] + q[1] + q[2]) as f64).sum::<f64>();
    let dir = [0.5f64, 0.0, 0.866];
    let d = 300.0 * l;
    let directional = FiberLight::Directional { to_light: dir, irradiance: [2.0; 3] };
    let far = FiberLight::Point { position: dir.map(|x| x * d), intensity: [2.0 * d * d; 3] };
    let near = FiberLight::Point { position: [2.0 * r, 0.0, 10.0 * r], intensity: [2e-6; 3] };
    let (d_on, d_off) = (frame(true, directional), frame(false, directional));
    let (f_on, f_off) = (frame(true, far), frame(false, far));
    let (n_on, n_off) = (frame(true, near), frame(false, near));
    let shadow = rel(&d_on, &d_off);
    let (e_on, e_off) = (rel(&f_on, &d_on), rel(&f_off, &d_off));
    let darker = mean(&n_on) / mean(&n_off);
    eprintln!(
        "strips: the shadow changes the directional frame by {shadow:.3}; far point vs \
         directional {e_on:.4} with shadows, {e_off:.4} without; the near point light's \
         shadows keep {darker:.3} of its light"
    );
    assert!(shadow > 0.05, "the upper yarn must shadow the lower: {shadow}");
    assert!(e_on < 0.1 * shadow + e_off, "far point light vs directional: {e_on}");
    assert!(darker < 0.99, "the cube faces' shadow: {darker}");
}
