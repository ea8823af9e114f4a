//! The volumetric reference (DESIGN §1.5): closed-form transmittance through a uniform
//! cylinder, the Beer–Lambert calibration of the density model against explicit fibers
//! (in and out of the cross-section plane, three extinction laws), and the volumetric
//! white furnace.

use std::sync::Arc;
use yarn::curve::{YarnCurve, YarnSet};
use yarn::density::{CrossSectionDensity, DensityOptions};
use yarn::fiber::{GenOptions, generate_fibers};
use yarn::params::YarnParams;
use yarn::vec3;
use yarn_ref::rng::Rng;
use yarn_ref::volume::{
    ExtinctionLaw, Phase, SliceDensity, UniformDisk, VolumeScene, VolumeSettings, render_volume,
};
use yarn_ref::{Background, Camera, EnvLight, FiberScene, Light, RenderSettings, SceneOptions};

fn straight(half_length: f64) -> YarnSet {
    let pts =
        (0..=8).map(|i| [-half_length + 2.0 * half_length * i as f64 / 8.0, 0.0, 0.0]).collect();
    YarnSet::new(vec![YarnCurve::open(pts).unwrap()], None).unwrap()
}

#[test]
fn uniform_cylinder_transmittance_is_closed_form() {
    let (r, rf, na) = (1e-3, 1e-5, 2e7); // σ = 2 r_f n_A = 400 m⁻¹
    let sigma = 2.0 * rf * na;
    let disk: Arc<dyn SliceDensity> =
        Arc::new(UniformDisk { n_a: na, radius: r, fiber_radius: rf });
    for law in [ExtinctionLaw::Anisotropic, ExtinctionLaw::Isotropic] {
        let vol = VolumeScene::with_density(&straight(0.02), disk.clone(), 1.0, law, 4).unwrap();
        for elev_deg in [0.0f64, 30.0, 60.0, 80.0] {
            let e = elev_deg.to_radians();
            for dd in [0.0, 0.3, 0.7, 0.95] {
                let d = vec3::normalize([e.sin(), 0.0, -e.cos()]).unwrap();
                let p = [0.0, dd * r, 0.0];
                let o = vec3::add_scaled(p, d, -0.01);
                let t = vol.transmittance(o, d, 0.02, r / 256.0, 0.5);
                let chord = 2.0 * (r * r - dd * dd * r * r).sqrt();
                let tau = match law {
                    ExtinctionLaw::Isotropic => sigma * chord / e.cos(),
                    _ => sigma * chord,
                };
                let want = (-tau).exp();
                assert!(
                    (t / want - 1.0).abs() < 1e-4,
                    "{law:?} elevation {elev_deg}° d {dd}: {t} vs {want}"
                );
            }
        }
    }
}

struct Bin {
    n: usize,
    blocked: usize,
    density_t: [f64; 3],
}

#[test]
fn beer_lambert_density_model_matches_explicit_fibers() {
    let params = YarnParams::preset("cotton-2ply").unwrap();
    let half = 8e-3;
    let set = straight(half);
    let opts = GenOptions { hairs: false, samples_per_turn: 24, ..GenOptions::default() };
    let fibers = generate_fibers(&set, std::slice::from_ref(&params), &opts).unwrap();
    let scene = FiberScene::new(&fibers, &SceneOptions::default()).unwrap();
    let dens = CrossSectionDensity::from_params(&params, &DensityOptions::default()).unwrap();
    let dens: Arc<dyn SliceDensity> = Arc::new(dens);
    let laws = [ExtinctionLaw::Anisotropic, ExtinctionLaw::Isotropic, ExtinctionLaw::Tilted];
    let vols: Vec<VolumeScene> = laws
        .iter()
        .map(|&l| {
            VolumeScene::new(&set, std::slice::from_ref(&params), std::slice::from_ref(&dens), l, 8)
                .unwrap()
        })
        .collect();
    let r_yarn = params.yarn_radius();
    let period = params.ply_pitch.abs();
    let n_rays = 12_000;
    let bins = 6;
    let mut report = String::new();
    let mut failures = Vec::new();
    for elev_deg in [0.0f64, 30.0, 60.0, 80.0] {
        let e = elev_deg.to_radians();
        let mut rng = Rng::new(&[42, elev_deg as u64]);
        let mut acc: Vec<Bin> =
            (0..bins).map(|_| Bin { n: 0, blocked: 0, density_t: [0.0; 3] }).collect();
        for _ in 0..n_rays {
            let [u1, u2, u3] = rng.uniform3();
            let zc = half + period * u1 - half; // x of the crossing: one ply twist after the centre
            let psi = std::f64::consts::TAU * u2;
            let dd = r_yarn * (2.0 * u3 - 1.0);
            let inplane = [0.0, psi.cos(), psi.sin()];
            let perp = [0.0, -psi.sin(), psi.cos()];
            let w = vec3::normalize(vec3::add(vec3::scale(inplane, e.cos()), [e.sin(), 0.0, 0.0]))
                .unwrap();
            let pc = vec3::add_scaled([zc, 0.0, 0.0], perp, dd);
            let reach = 3.0 * r_yarn / e.cos().max(0.1);
            let o = vec3::add_scaled(pc, w, -reach);
            let b = ((dd.abs() / r_yarn) * bins as f64).min(bins as f64 - 1.0) as usize;
            acc[b].n += 1;
            if scene.occluded(o, w, 2.0 * reach, None) {
                acc[b].blocked += 1;
            }
            for (k, v) in vols.iter().enumerate() {
                acc[b].density_t[k] += v.transmittance(o, w, 2.0 * reach, r_yarn / 64.0, 0.5);
            }
        }
        for (bi, bin) in acc.iter().enumerate() {
            let n = bin.n as f64;
            let p = 1.0 - bin.blocked as f64 / n;
            let se = (p * (1.0 - p) / n).sqrt().max(0.5 / n);
            let tol = 4.0 * se + 0.03;
            let mut line = format!(
                "{elev_deg:>3}° |d|/R {:.2}-{:.2}: explicit {p:.4} ± {se:.4}",
                bi as f64 / bins as f64,
                (bi + 1) as f64 / bins as f64
            );
            for (k, law) in laws.iter().enumerate() {
                let t = bin.density_t[k] / n;
                line.push_str(&format!(", {law:?} {t:.4} ({:+.4})", t - p));
                // The tilt-corrected law must agree everywhere; the plain anisotropic law in
                // and near the cross-section plane (at 80° the cotton plies' ~28° helix
                // tilt dominates: DESIGN §2.3 item 10's caveat, measured and reported).
                let must = match law {
                    ExtinctionLaw::Tilted => true,
                    ExtinctionLaw::Anisotropic => elev_deg < 70.0,
                    ExtinctionLaw::Isotropic => false,
                };
                if must && (t - p).abs() > tol {
                    failures.push(format!(
                        "{law:?} {elev_deg}° bin {bi}: {t:.4} vs {p:.4} (tolerance {tol:.4})"
                    ));
                }
            }
            report.push_str(&line);
            report.push('\n');
        }
    }
    eprintln!("Beer–Lambert, cotton-2ply, {n_rays} rays per elevation:\n{report}");
    assert!(failures.is_empty(), "outside 4 SE + 0.03:\n{}", failures.join("\n"));
}

#[test]
fn volumetric_white_furnace() {
    let disk: Arc<dyn SliceDensity> =
        Arc::new(UniformDisk { n_a: 1.5e7, radius: 1e-3, fiber_radius: 1e-5 });
    let vol = VolumeScene::with_density(&straight(3e-3), disk, 1.0, ExtinctionLaw::Anisotropic, 4)
        .unwrap();
    let env = EnvLight::new(btf_image::EnvMap::constant(16, [1.0; 3]).unwrap(), 1.0);
    let lights = [Light::Environment(env)];
    let cam = Camera::oblique([0.3, 0.2, 1.0], 1e-3, [-2e-3, -1.5e-3], [4e-3, 3e-3]).unwrap();
    let mut vs = VolumeSettings::new(1e-3 / 16.0);
    vs.albedo = 1.0;
    vs.phase = Phase::Isotropic;
    vs.multiple = true;
    vs.max_order = 64;
    vs.background = Background::Environment;
    // The multiple-scattering estimator is right-skewed (rare long paths carry much of the
    // mean), so a pixel's standard error from 64 of its own samples is unreliable: one
    // seed gave a central pixel 0.922 ± 0.010 where two others gave 1.035 ± 0.041 and
    // 1.010 ± 0.034, and the same ray with 40 000 samples gives 0.998 ± 0.0016. The test
    // therefore pools: three seeds, the image mean against 4 pooled SE.
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
    for seed in [3, 4, 5] {
        let mut s = RenderSettings::new(8, 6, 64);
        s.seed = seed;
        let (img, _) = render_volume(&vol, &lights, &cam, &s, &vs).unwrap();
        for y in 0..6 {
            for x in 0..8 {
                sum += img.pixel(x, y)[0] as f64;
                var += img.std_error(x, y, 0).powi(2);
                n += 1.0;
            }
        }
    }
    let mean = sum / n;
    let se_mean = var.sqrt() / n;
    eprintln!(
        "volumetric furnace (ϖ = 1, isotropic, 3 seeds × 48 pixels × 64 spp): {mean:.5} ± {se_mean:.5}"
    );
    assert!((mean - 1.0).abs() <= 4.0 * se_mean + 2e-3, "mean {mean} ± {se_mean}");
}
