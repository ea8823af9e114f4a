//! Ground-truth checks of the synthetic materials: the analytic Lambert case, the energy
//! bound, corduroy's anisotropy, determinism and resuming.

use btf_core::store::{BtfStore, BtfWriter};
use btf_core::zarr::DType;
use btf_core::{Ring, Sampling};
use datasets::material::{GenerateOptions, Material, MaterialKind, MaterialSpec, generate};
use std::f64::consts::PI;

fn small_sampling() -> Sampling {
    let ring = |t, c| Ring { theta_deg: t, count: c, phi_offset_deg: 0.0 };
    Sampling::new("custom", vec![ring(0.0, 1), ring(60.0, 4)]).unwrap()
}

#[test]
fn lambert_equals_analytic_btf_to_1e6() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lambert.btf");
    let mut spec = MaterialSpec::new(MaterialKind::Lambert, 8);
    spec.albedo = Some([0.9, 0.5, 0.2]);
    // The pole, ubo81's rings and a ring just above the horizon (19 directions, so the
    // test writes 361 images rather than 6561).
    let ring = |t, c| Ring { theta_deg: t, count: c, phi_offset_deg: 0.0 };
    let s =
        Sampling::new("custom", vec![ring(0.0, 1), ring(30.0, 4), ring(75.0, 6), ring(89.5, 8)])
            .unwrap();
    spec.sampling = s.clone();
    generate(&spec, &path, &GenerateOptions::default()).unwrap();
    let store = BtfStore::open(&path).unwrap();
    let material = Material::build(&spec).unwrap();
    let mut max_err = 0f64;
    for view in 0..s.len() {
        for light in 0..s.len() {
            let img = store.read_image(view, light).unwrap();
            let cos_l = s.direction(light).cos_theta();
            for y in 0..8 {
                for x in 0..8 {
                    let rho = material.surface().albedo_texel(x, y);
                    for c in 0..3 {
                        let want = rho[c] / PI * cos_l;
                        max_err = max_err.max((img[(y * 8 + x) * 3 + c] as f64 - want).abs());
                    }
                }
            }
        }
    }
    assert!(max_err < 1e-6, "max |BTF - rho/pi cos| = {max_err}");
    // The albedo really varies over the sample and follows --albedo.
    let a = material.surface().albedo_texel(0, 0);
    let b = material.surface().albedo_texel(4, 0);
    assert!((a[0] - b[0]).abs() > 0.1 && a[0] / a[2] > 4.0 - 1e-9);
}

/// Directional-hemispherical reflectance averaged over the texels, by a cosine-weighted
/// midpoint grid over the view hemisphere.
fn reflectance(m: &Material, light: [f64; 3]) -> [f64; 3] {
    let (nu, nv) = (16, 32);
    let n = m.surface().size();
    let mut sum = [0.0; 3];
    for iu in 0..nu {
        let cos_v = ((iu as f64 + 0.5) / nu as f64).sqrt();
        let sin_v = (1.0 - cos_v * cos_v).sqrt();
        for iv in 0..nv {
            let phi = 2.0 * PI * (iv as f64 + 0.5) / nv as f64;
            let view = [sin_v * phi.cos(), sin_v * phi.sin(), cos_v];
            for hit in m.view_hits(view) {
                let v = m.shade(&hit, view, light);
                (0..3).for_each(|c| sum[c] += v[c]);
            }
        }
    }
    sum.map(|s| PI * s / (nu * nv * n * n) as f64 / light[2])
}

#[test]
fn hemispherical_reflectance_at_most_one_for_every_kind() {
    for kind in MaterialKind::ALL {
        let mut spec = MaterialSpec::new(kind, 12);
        // A white base albedo is the worst case for energy.
        spec.albedo = Some([1.0, 1.0, 1.0]);
        let m = Material::build(&spec).unwrap();
        for theta in [0.0f64, 45.0, 75.0, 85.0] {
            let t = theta.to_radians();
            let light = [t.sin() * 0.8, t.sin() * 0.6, t.cos()];
            let r = reflectance(&m, light);
            assert!(
                r.iter().all(|&x| x <= 1.0 + 0.01 && x > 0.02),
                "{kind:?} theta {theta}: {r:?}"
            );
        }
    }
}

#[test]
fn corduroy_lit_across_ribs_at_grazing_angle_is_darker_than_along() {
    let mut spec = MaterialSpec::new(MaterialKind::Corduroy, 16);
    spec.params = Some(datasets::MaterialParams {
        repeats: 2,
        ..datasets::MaterialParams::default_for(MaterialKind::Corduroy, 16)
    });
    let m = Material::build(&spec).unwrap();
    let s = Sampling::ubo81();
    let t = 75f64.to_radians();
    let mean = |light: [f64; 3]| {
        let mut sum = 0.0;
        for view in 0..s.len() {
            let v = s.direction(view).to_vector();
            sum += m
                .view_hits(v)
                .iter()
                .map(|h| m.shade(h, v, light).iter().sum::<f64>())
                .sum::<f64>();
        }
        sum
    };
    let across = mean([t.sin(), 0.0, t.cos()]);
    let along = mean([0.0, t.sin(), t.cos()]);
    assert!(across < 0.85 * along, "across {across} along {along}");
    // Below and at the horizon nothing is reflected.
    let hit = m.view_hits([0.0, 0.0, 1.0])[5];
    assert_eq!(m.shade(&hit, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]), [0.0; 3]);
    assert_eq!(m.shade(&hit, [0.0, 0.0, 1.0], [0.6, 0.0, -0.8]), [0.0; 3]);
}

fn all_chunks(path: &std::path::Path) -> Vec<Vec<u8>> {
    let store = BtfStore::open(path).unwrap();
    let n = store.meta().n_views();
    (0..n * n).map(|k| bytemuck_bytes(&store.read_image(k / n, k % n).unwrap())).collect()
}

fn bytemuck_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn same_seed_same_bytes_other_seed_differs_and_resume_keeps_images() {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = MaterialSpec::new(MaterialKind::Knit, 16);
    spec.sampling = small_sampling();
    spec.seed = 7;
    let (a, b, c) = (dir.path().join("a.btf"), dir.path().join("b.btf"), dir.path().join("c.btf"));
    generate(&spec, &a, &GenerateOptions::default()).unwrap();
    generate(&spec, &b, &GenerateOptions::default()).unwrap();
    assert_eq!(all_chunks(&a), all_chunks(&b));
    spec.seed = 8;
    generate(&spec, &c, &GenerateOptions::default()).unwrap();
    assert_ne!(all_chunks(&a), all_chunks(&c));

    // An interrupted run left two images; resuming renders only the 23 others.
    spec.seed = 7;
    let d = dir.path().join("d.btf");
    // The partial carries the job's record as a killed run leaves it: the same metadata
    // (samplings, size and the generator's provenance) as the finished store of seed 7.
    let a_store = BtfStore::open(&a).unwrap();
    let w = BtfWriter::create(&d, a_store.meta().clone(), DType::F32, false).unwrap();
    w.write_image(0, 0, &a_store.read_image(0, 0).unwrap()).unwrap();
    w.write_image(3, 1, &a_store.read_image(3, 1).unwrap()).unwrap();
    drop(w);
    let opts = GenerateOptions { resume: true, ..GenerateOptions::default() };
    let report = generate(&spec, &d, &opts).unwrap();
    assert_eq!((report.images_written, report.images_skipped), (23, 2));
    assert_eq!(all_chunks(&a), all_chunks(&d));
}
