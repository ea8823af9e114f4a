//! The oblique BTF camera (DESIGN §4.2) over a periodic knit patch drawn as its 3 × 3
//! neighbourhood: the fibers' coverage seen by the GPU equals the CPU reference's, which
//! wraps rays periodically instead. Coverage does not depend on shadows, so this checks
//! the projection, the tiling and the geometry at patch scale.

use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, SimpleParams};
use yarn::fiber::GenOptions;
use yarn::knit::Chart;
use yarn_ref::patch::{KnitPatch, PatchOptions};
use yarn_ref::{Camera, FiberScene, Light, RenderSettings, Scene, SceneOptions, Shading, render};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

#[test]
fn oblique_patch_coverage_matches_the_periodic_reference() {
    let Some(gpu) = Gpu::for_tests("oblique_patch_coverage_matches") else { return };
    let chart = Chart::builtin("stockinette").unwrap();
    let params = crate::common::cotton();
    let genopts = GenOptions { hairs: false, seed: 5, ..Default::default() };
    let popts = PatchOptions { generation: genopts.clone(), ..Default::default() };
    let patch = KnitPatch::new(&chart, &params, &popts).unwrap();
    let size = patch.period.size;
    // A window of a sixth of the period at 48² pixels: fibers about 1.4 px wide.
    let extent = [size[0] / 6.0, size[0] / 6.0];
    let origin = [0.31 * size[0], 0.42 * size[1]];
    let (w, h) = (48usize, 48usize);
    let view = btf_core::Direction::new(35.0, 40.0).to_vector();

    let scene = FiberScene::new(
        &patch.fibers,
        &SceneOptions { period: Some(patch.period), backing_z: None },
    )
    .unwrap();
    let lights = [Light::Directional { to_light: [0.0, 0.0, 1.0], irradiance: [1.0; 3] }];
    let shading = Shading::Lambert { albedo: Some([0.5; 3]) };
    let sc = Scene { fibers: &scene, lights: &lights, shading: &shading };
    let cam = Camera::oblique(view, patch.z_ref, origin, extent).unwrap();
    let mut s = RenderSettings::new(w, h, 16);
    s.path.max_bounces = 1;
    let (reference, _) = render(&sc, &cam, &s).unwrap();

    let packed = PackedYarns::new(
        &patch.yarns,
        std::slice::from_ref(&params),
        &PackOptions { seed: genopts.seed, frame_samples_per_segment: 16, tiles: [3, 3] },
    )
    .unwrap();
    let bcsdf = FiberBcsdf::simple(&SimpleParams::default()).unwrap();
    let settings = FiberSettings { lod_px: 0.0, n_sub: 16, hairs: false, ..Default::default() };
    let r = FiberRenderer::new(&gpu, &packed, &bcsdf, settings).unwrap();
    let img = r
        .render(
            &gpu,
            &FiberCamera::oblique(view, patch.z_ref, origin, extent),
            &[FiberLight::Directional { to_light: [0.0, 0.0, 1.0], irradiance: [1.0; 3] }],
            (w as u32, h as u32),
            [0.0; 4],
        )
        .unwrap();
    let gpu_cov: f64 = img.pixels.iter().map(|p| p[3] as f64).sum();
    let ref_cov: f64 = reference.coverage.iter().map(|&c| c as f64).sum();
    let mad: f64 = img
        .pixels
        .iter()
        .zip(&reference.coverage)
        .map(|(p, &c)| (p[3] as f64 - c as f64).abs())
        .sum::<f64>()
        / (w * h) as f64;
    eprintln!(
        "oblique patch window: coverage GPU {:.4}, reference {:.4} (of the frame); mean \
         |Δ| per pixel {mad:.4}; {} of {} segments culled",
        gpu_cov / (w * h) as f64,
        ref_cov / (w * h) as f64,
        img.stats.culled,
        img.stats.segments
    );
    assert!(ref_cov > 0.3 * (w * h) as f64, "the window sees too little yarn");
    assert!((gpu_cov / ref_cov - 1.0).abs() < 0.03, "coverage {gpu_cov} against {ref_cov}");
    assert!(mad < 0.1, "mean per-pixel coverage difference {mad}");
    assert!(img.stats.culled > img.stats.segments / 2, "the 3 × 3 copies outside are culled");
}
