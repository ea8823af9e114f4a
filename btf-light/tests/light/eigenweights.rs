//! Eigenweightsets (`[S03 eq. 13]`): exact at `e = A − 1` and 360° the identity, the metric
//! form of the error equal to the plain error of `U = G·P` (`[S03 eq. 12]`), the `γ*`
//! basis equal to `γ*` of the reconstruction, and the per-vertex fill of `[S03 eq. 11]`
//! through the camera's basis equal to the direct path.

use crate::common::*;
use btf_core::InterpMode;
use btf_core::eigen::Quantization;
use btf_light::tangent::compute_tangents;
use btf_light::{EigenWeightSets, EnvCube, Radiances};

#[test]
fn eigenweightsets_reproduce_every_rotation_and_360_is_identity() {
    // A sphere standing on a floor: rotations change the lighting and the occlusion.
    let mut mesh = sphere(12);
    let floor = corner_mesh(10.0, 0.1, 0.1);
    let b = mesh.positions.len() as u32;
    for p in &floor.positions[..25] {
        mesh.positions.push([p[0] * 5.0, p[1] * 5.0, -0.5]);
        mesh.normals.push([0.0, 0.0, 1.0]);
        mesh.uvs.push([p[0], p[1]]);
    }
    mesh.triangles.extend(floor.triangles[..32].iter().map(|t| t.map(|i| i + b)));
    mesh.triangle_material = vec![0; mesh.triangles.len()];
    let (s, _d) = setup(&mesh, 8, Pattern::Checker, 4);
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let cube = EnvCube::new(&env, 8);
    let a_n = 30;
    let sets: Vec<Radiances> = (0..a_n).map(|a| s.gather(&cube, a as f64 * 12.0)).collect();
    let metric = s.p.metric();
    let full = s.gather(&cube, 360.0);
    assert!(btf_light::eigenweights::relative_error(&full, &sets[0], &metric) < 1e-6);
    let ews = EigenWeightSets::build(&sets, &metric, a_n - 1).unwrap();
    for (a, set) in sets.iter().enumerate() {
        let r = ews.reconstruct(a as f64 * 12.0, a_n - 1);
        let e = btf_light::eigenweights::relative_error(&r, set, &metric);
        assert!(e < 1e-6, "U_{a}: relative error {e}");
    }
    // The metric form equals the plain error of U = G·P.
    let (u0, ur) = (sets[3].full_u(&s.p), ews.reconstruct(36.0, 3).full_u(&s.p));
    let num: f64 = u0.iter().zip(&ur).map(|(a, b)| ((a - b) as f64).powi(2)).sum();
    let den: f64 = u0.iter().map(|a| (*a as f64).powi(2)).sum();
    let via_metric =
        btf_light::eigenweights::relative_error(&ews.reconstruct(36.0, 3), &sets[3], &metric);
    assert!(
        ((num / den).sqrt() - via_metric).abs() < 1e-4 * via_metric.max(1e-3),
        "{} vs {via_metric}",
        (num / den).sqrt()
    );
    let r1 = ews.reconstruct(100.0, 5);
    assert_eq!(r1.g, ews.reconstruct(460.0, 5).g);
}

#[test]
fn gamma_basis_equals_gamma_star_of_the_reconstruction() {
    let mesh = crumpled_sheet();
    let (s, _d) = setup(&mesh, 8, Pattern::Checker, 4);
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let cube = EnvCube::new(&env, 8);
    let sets: Vec<Radiances> = (0..12).map(|a| s.gather(&cube, a as f64 * 30.0)).collect();
    let ews = EigenWeightSets::build(&sets, &s.p.metric(), 5).unwrap();
    let picks: Vec<(usize, usize)> = (0..s.frames.len()).map(|f| (f, f % s.p.slots)).collect();
    let basis = ews.gamma_basis(&s.p, &picks, 5).unwrap();
    let k3 = 3 * s.p.per_slot();
    let mut fast = vec![0f32; picks.len() * k3];
    let mut slow = vec![0f32; k3];
    for delta in [0.0, 47.0, 200.0] {
        basis.at(&ews.coefficients_at(delta, 5), &mut fast);
        let g = ews.reconstruct(delta, 5);
        for (n, &(f, j)) in picks.iter().enumerate() {
            g.gamma_star(&s.p, f, j, &mut slow);
            let scale = slow.iter().fold(1e-6f32, |m, x| m.max(x.abs()));
            for (a, b) in fast[n * k3..(n + 1) * k3].iter().zip(&slow) {
                // Same sums in another order: f32 rounding of ~100 terms.
                assert!((a - b).abs() <= 1e-4 * scale, "δ {delta}, pick {n}: {a} vs {b}");
            }
        }
    }
    assert!(ews.gamma_basis(&s.p, &[(s.frames.len(), 0)], 5).is_err());
}

/// The rotation a renderer makes through the eigenweightsets (`EnvCoefficients::fill`
/// streaming the camera's `γ*` basis) against the direct fill (`G(δ)`, then `γ*`), into the
/// full per-vertex layout (`2 + 3G` vec4 per vertex, light and blend position).
#[test]
fn renderer_rotation_through_the_camera_basis_equals_the_direct_path() {
    use btf_light::env_coefficients::fill_direct;
    use btf_light::math::Vec3;
    use btf_light::{EnvCoefficients, EnvironmentParams, SceneEnvironment, Slots};
    use btf_light::{EnvMesh, ViewInput};
    let mesh = crumpled_sheet();
    let dir = tempfile::tempdir().unwrap();
    let c = 4;
    let store = write_store(dir.path(), "m.eigen", Pattern::Checker, (2, 2), c, Quantization::F16);
    let (p, _, store) = coefficients(&store, c);
    let (env, _) = sun_env(128, [0.5, 0.3, 0.812]);
    let tangents = compute_tangents(&mesh);
    let em = EnvMesh {
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        triangles: &mesh.triangles,
    };
    let params = EnvironmentParams {
        rotation_deg: 10.0,
        exposure: 0.7,
        visibility_res: 8,
        two_sided: true,
        eigen: Some((12, 5)),
        cache_dir: None,
    };
    let mut s = SceneEnvironment::new(params, &env, &em, store.light_sampling(), vec![p]).unwrap();
    let n = mesh.positions.len();
    let stride = 2 + 3 * c.div_ceil(4);
    let (material_of, mats) = (vec![0usize; n], [store.view_sampling()]);
    let view_from = |eye: Vec3| ViewInput {
        eye,
        ortho_to_camera: None,
        view_mode: InterpMode::Four,
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        material_of: &material_of,
        view_samplings: &mats,
    };
    let blank = || vec![[0f32; 4]; n * 4 * stride];
    // The sheet is seen from both sides (the camera below it sees back sides).
    let view = view_from(Vec3::new(0.3, -2.0, -0.4));
    let at = Slots { l: 0, n_lights: 1, stride };
    let mut ec = EnvCoefficients::default();
    ec.fill(&s, &mut blank(), &view, at);
    assert!(!ec.used_basis(), "first fill at a camera: the direct path");
    for delta in [47.0, 200.0, 370.0] {
        s.set_rotation(delta);
        let (mut fast, mut slow) = (blank(), blank());
        ec.fill(&s, &mut fast, &view, at);
        assert!(ec.used_basis(), "δ {delta}: a rotation under the same camera streams the basis");
        fill_direct(&s, &mut slow, &view, at);
        let scale = slow.iter().flatten().fold(0f32, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for (a, b) in fast.iter().flatten().zip(slow.iter().flatten()) {
            // Same sums in another order: f32 rounding of ~100 terms.
            assert!((a - b).abs() <= 1e-4 * scale, "δ {delta}: {a} vs {b} (scale {scale})");
        }
    }
    // A camera move and an exact rotation take the direct path again.
    ec.fill(&s, &mut blank(), &view_from(Vec3::new(2.0, 0.5, 1.0)), at);
    assert!(!ec.used_basis());
    s.set_rotation_exact(30.0);
    ec.fill(&s, &mut blank(), &view, at);
    assert!(!ec.used_basis());
}
