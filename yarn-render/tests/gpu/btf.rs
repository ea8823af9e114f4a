//! The yarn BTF rendered by the GPU fibers (`--method fibers`) against the same BTF from
//! the CPU reference (direct light, no hairs): an ordinary store with the reference's
//! definition, whose images follow the reference's view/light dependence.

use btf_core::store::BtfStore;
use btf_render::Gpu;
use yarn::knit::Chart;
use yarn_ref::btf::{YarnBtfOptions, YarnBtfSpec, generate_yarn_btf};
use yarn_render::FiberSettings;

#[test]
fn the_fiber_yarn_btf_follows_the_reference_btf() {
    let Some(gpu) = Gpu::for_tests("the_fiber_yarn_btf_follows_the_reference_btf") else { return };
    let chart = Chart::builtin("stockinette").unwrap();
    let mut spec = YarnBtfSpec::new(chart, "stockinette", crate::common::cotton(), 24);
    spec.sampling = btf_core::sampling::Sampling::new(
        "custom",
        vec![
            btf_core::Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 },
            btf_core::Ring { theta_deg: 50.0, count: 3, phi_offset_deg: 20.0 },
        ],
    )
    .unwrap();
    spec.spp = 16;
    spec.bounces = 1;
    spec.hairs = false;
    let dir = tempfile::tempdir().unwrap();
    let (rp, fp) = (dir.path().join("ref.btf"), dir.path().join("fib.btf"));
    generate_yarn_btf(&spec, &rp, &YarnBtfOptions::default()).unwrap();
    let r = yarn_render::btf::generate_fiber_btf(
        &gpu,
        &spec,
        FiberSettings { lod_px: 0.0, ..FiberSettings::default() },
        &fp,
        &YarnBtfOptions::default(),
    )
    .unwrap();
    assert_eq!((r.images_written, r.images_skipped), (16, 0));
    let (a, b) = (BtfStore::open(&rp).unwrap(), BtfStore::open(&fp).unwrap());
    assert_eq!(b.meta().provenance["method"], "fibers");
    let (mut ma, mut mb) = (Vec::new(), Vec::new());
    for v in 0..4 {
        for l in 0..4 {
            let (x, y) = (a.read_image(v, l).unwrap(), b.read_image(v, l).unwrap());
            assert!(y.iter().all(|t| t.is_finite() && *t >= 0.0));
            let m = |z: &[f32]| z.iter().map(|t| *t as f64).sum::<f64>() / z.len() as f64;
            ma.push(m(&x));
            mb.push(m(&y));
        }
    }
    // Off the diagonal every image agrees; on it (light = view) the reference has the
    // knit's hot spot — the fibers it sees are exactly the lit ones — which [W19]'s
    // self-shadow volume, a mean over the cross-section uncorrelated with what is seen,
    // cannot have. Measured at full detail: off-diagonal ratios within 0.184 of 1, diagonal
    // 0.50–0.59 (top view 0.59).
    let mut worst: f64 = 0.0;
    let mut diag = Vec::new();
    for v in 0..4 {
        for l in 0..4 {
            let ratio = mb[v * 4 + l] / ma[v * 4 + l];
            if v == l {
                diag.push(ratio);
            } else {
                worst = worst.max((ratio - 1.0).abs());
            }
        }
    }
    eprintln!(
        "yarn BTF 24², 4 × 4 directions, full detail: off-diagonal |ratio − 1| ≤ {worst:.3}; \
         diagonal (hot spot) ratios {diag:.3?}"
    );
    assert!(worst < 0.25, "off-diagonal image ratio off by {worst}");
    assert!(diag.iter().all(|r| *r < 1.0), "the hot spot gap closed: update the docs");
}
