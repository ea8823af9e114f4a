//! Temporal coherence (DESIGN §2.3 item 9, §2.5): a rigidly moved garment keeps every
//! fiber's phase at every material point. Moving the yarns, their surface normals, the
//! camera and the light by one rigid motion must give the same image (up to raster
//! rounding), and the packed fiber phases must not change at all.

use crate::common::{cotton, open_wave};
use btf_render::Gpu;
use yarn::bcsdf::{FiberBcsdf, SimpleParams};
use yarn::{YarnCurve, YarnSet};
use yarn_render::{
    FiberCamera, FiberLight, FiberRenderer, FiberSettings, PackOptions, PackedYarns,
};

/// Rotation by `angle` about the unit `axis`, then translation by `t`.
fn rigid(axis: [f64; 3], angle: f64, t: [f64; 3]) -> impl Fn([f64; 3], bool) -> [f64; 3] {
    move |v: [f64; 3], is_point: bool| {
        let (s, c) = angle.sin_cos();
        let k = axis;
        let kxv = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
        let kdv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
        let r: [f64; 3] = std::array::from_fn(|a| v[a] * c + kxv[a] * s + k[a] * kdv * (1.0 - c));
        if is_point { std::array::from_fn(|a| r[a] + t[a]) } else { r }
    }
}

fn moved(set: &YarnSet, m: &impl Fn([f64; 3], bool) -> [f64; 3]) -> YarnSet {
    let curves = set
        .curves
        .iter()
        .map(|c| {
            let mut d: YarnCurve = c.clone();
            d.points = c.points.iter().map(|&p| m(p, true)).collect();
            d.normals = c.normals.as_ref().map(|ns| ns.iter().map(|&n| m(n, false)).collect());
            d.shift = m(c.shift, false);
            d
        })
        .collect();
    YarnSet::new(curves, None).unwrap()
}

#[test]
fn a_rigid_motion_keeps_every_fiber_phase_and_the_image() {
    let Some(gpu) = Gpu::for_tests("a_rigid_motion_keeps_every_fiber_phase") else { return };
    let p = cotton();
    let set = open_wave();
    let m = rigid([0.6, 0.0, 0.8], 1.1, [0.31, -0.12, 0.05]);
    let set2 = moved(&set, &m);
    let opts = PackOptions::default();
    let a = PackedYarns::new(&set, std::slice::from_ref(&p), &opts).unwrap();
    let b = PackedYarns::new(&set2, std::slice::from_ref(&p), &opts).unwrap();
    // Length coordinates and phases are material: bit-identical after the motion.
    for (sa, sb) in a.segments.iter().zip(&b.segments) {
        assert_eq!(sa.phase, sb.phase);
        assert_eq!(sa.ids, sb.ids);
        for j in 0..4 {
            assert!((sa.p[j][3] - sb.p[j][3]).abs() <= 1e-9, "length coordinate moved");
        }
    }
    let bcsdf = FiberBcsdf::simple(&SimpleParams::default()).unwrap();
    let settings = FiberSettings { lod_px: 0.0, msaa: 4, ..Default::default() };
    let (lo, hi) = a.bounds;
    let c = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let eye = [c[0] + 0.002, c[1] - 0.01, c[2] + 0.008];
    let cam = FiberCamera::perspective(eye, c, [0.0, 0.0, 1.0], 40.0);
    let cam2 = FiberCamera::perspective(m(eye, true), m(c, true), m([0.0, 0.0, 1.0], false), 40.0);
    let dir = [0.2, -0.4, 1.0];
    let light = [FiberLight::Directional { to_light: dir, irradiance: [2.0; 3] }];
    let light2 = [FiberLight::Directional { to_light: m(dir, false), irradiance: [2.0; 3] }];
    let r1 = FiberRenderer::new(&gpu, &a, &bcsdf, settings).unwrap();
    let r2 = FiberRenderer::new(&gpu, &b, &bcsdf, settings).unwrap();
    let i1 = r1.render(&gpu, &cam, &light, (96, 96), [0.0; 4]).unwrap();
    let i2 = r2.render(&gpu, &cam2, &light2, (96, 96), [0.0; 4]).unwrap();
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in i1.pixels.iter().zip(&i2.pixels) {
        for k in 0..4 {
            num += (x[k] as f64 - y[k] as f64).powi(2);
            den += (x[k] as f64).powi(2);
        }
    }
    let rel = (num / den).sqrt();
    let lit = i1.pixels.iter().filter(|p| p[3] > 0.0).count();
    eprintln!("rigid motion: rel. RMSE {rel:.2e} over the frame ({lit} pixels see yarn)");
    assert!(lit > 500);
    assert!(rel < 1e-3, "{rel}");
}
