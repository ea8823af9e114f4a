//! The lighting effects of [W19 §4] against the CPU reference on a periodic stockinette
//! patch (R-approx: the same fibers, no hairs), oblique BTF view, direct light only:
//! self-shadows and yarn shadows must bring the GPU image towards the reference's
//! exact fiber-level shadows, and a constant environment through the ambient integral
//! and AO must give the reference's mean radiance.

use crate::lights::{Setup, mean, reference, rel_rmse, renderer, setup};
use btf_render::Gpu;
use yarn_ref::{EnvLight, Light};
use yarn_render::{AoMode, FiberEffects, FiberLight};

fn gpu_image(gpu: &Gpu, s: &Setup, lights: &[FiberLight], effects: FiberEffects) -> Vec<f32> {
    crate::lights::frame(gpu, s, &renderer(gpu, s, effects), lights)
}

#[test]
fn shadows_bring_the_gpu_patch_to_the_reference() {
    let Some(gpu) = Gpu::for_tests("shadows_bring_the_gpu_patch_to_the_reference") else { return };
    let s = setup(true);
    let to_light = btf_core::Direction::new(30.0, 200.0).to_vector();
    let r = reference(&s, &[Light::Directional { to_light, irradiance: [3.0; 3] }], 32);
    let l = [FiberLight::Directional { to_light, irradiance: [3.0; 3] }];
    let off = gpu_image(&gpu, &s, &l, FiberEffects::none());
    let self_only =
        gpu_image(&gpu, &s, &l, FiberEffects { yarn_shadows: false, ..FiberEffects::default() });
    let all = gpu_image(&gpu, &s, &l, FiberEffects::default());
    let (e_off, e_self, e_all) = (rel_rmse(&off, &r), rel_rmse(&self_only, &r), rel_rmse(&all, &r));
    let (m_off, m_all, m_ref) = (mean(&off), mean(&all), mean(&r));
    eprintln!(
        "patch vs reference (48², 32 spp): rel. RMSE no shadows {e_off:.3}, self-shadows \
         {e_self:.3}, self + yarn shadows {e_all:.3}; mean radiance {m_off:.4} / {m_all:.4} \
         against {m_ref:.4}"
    );
    // Each shadow term must help; together they must at least halve the error.
    assert!(e_self < e_off && e_all < e_self && e_all < 0.5 * e_off);
    assert!((m_all / m_ref - 1.0).abs() < 0.3, "mean ratio {}", m_all / m_ref);
}

#[test]
fn constant_environment_through_the_ambient_integral_and_ao() {
    let Some(gpu) = Gpu::for_tests("constant_environment_through_the_ambient") else { return };
    let s = setup(true);
    let env = EnvLight::new(btf_image::EnvMap::constant(32, [1.0; 3]).unwrap(), 1.0);
    let r = reference(&s, &[Light::Environment(env)], 32);
    let mut out = Vec::new();
    for ao in [AoMode::Off, AoMode::Cubic, AoMode::Texture] {
        let fx = FiberEffects { ao, ambient: [1.0; 3], ..FiberEffects::default() };
        out.push(mean(&gpu_image(&gpu, &s, &[], fx)));
    }
    let m_ref = mean(&r);
    eprintln!(
        "constant sky L = 1: mean radiance GPU AO off {:.4}, cubic {:.4}, texture {:.4}; \
         reference {m_ref:.4}",
        out[0], out[1], out[2]
    );
    // AO only darkens, and each AO brings the frame closer to the reference. Measured
    // (48², 32 spp): off 0.590, cubic 0.265, texture 0.178 against 0.085. Two gaps stay
    // and are reported, not hidden: [W19]'s distance cubic is fitted to the radial *mean*
    // of the texture, but fibers sit where the density — and the occlusion — is highest,
    // so the cubic is 49 % brighter than the texture at the fibers; and AO covers a yarn's
    // own fibers only, while the reference's sky is also blocked by the other yarns of the
    // patch ([W19 §4.2] leaves that to "existing techniques").
    assert!(out[1] < out[0] && out[2] < out[1]);
    assert!((out[2] - m_ref).abs() < (out[1] - m_ref).abs());
    assert!((out[1] - m_ref).abs() < (out[0] - m_ref).abs());
}
