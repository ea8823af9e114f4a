//! Test scenes: a periodic Crane plain-knit patch (closed curves, whole turns per wrap) and
//! an open wavy yarn lying on a surface with normals (frame anchoring), both cotton.

use yarn::knit::crane::CraneKnit;
use yarn::{YarnCurve, YarnParams, YarnSet};

pub fn cotton() -> YarnParams {
    YarnParams::preset("cotton-2ply").unwrap()
}

/// `stitches × courses` of Crane's plain knit at the cotton yarn's radius, 8 points a stitch.
pub fn crane_patch(stitches: usize, courses: usize) -> YarnSet {
    let k = CraneKnit::for_yarn_radius(cotton().yarn_radius());
    k.yarn_set(stitches, courses, 8).unwrap()
}

/// An open yarn waving over the plane z = 0 with the plane's normal (tilted where it
/// bends), 12 control points about 1.5 mm apart.
pub fn open_wave() -> YarnSet {
    let pts: Vec<[f64; 3]> = (0..12)
        .map(|i| {
            let x = i as f64 * 1.5e-3;
            [x, 0.6e-3 * (x * 900.0).sin(), 0.4e-3 * (x * 1300.0).cos()]
        })
        .collect();
    let normals = (0..12).map(|i| [0.2 * (i as f64).sin(), 0.1, 1.0]).collect();
    let c = YarnCurve::open(pts).unwrap().with_normals(normals).unwrap();
    YarnSet::new(vec![c], None).unwrap()
}
