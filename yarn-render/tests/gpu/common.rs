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

/// One fiber of radius 0.3 mm on the axis (1 µm from it) of an open yarn bent gently in
/// the plane z = 0, 8 mm long; no flyaways, no migration. (Wound about the axis, the
/// fiber's far side would shadow its near side.)
pub fn single_fiber_yarn() -> (YarnSet, YarnParams) {
    let mut p = cotton();
    p.name = "one fiber".into();
    p.ply_count = 1;
    p.fibers_per_ply = 1;
    p.ply_center_distance = 0.0;
    p.ply_ellipse_n = 1e-6;
    p.ply_ellipse_b = 1e-6;
    p.fiber_pitch = 6e-3;
    p.ply_pitch = 6e-3;
    p.rho_min = 1.0;
    p.rho_max = 1.0;
    p.migration_rate = 0.0;
    p.fiber_radius = 3e-4;
    p.hair_density = 0.0;
    p.loop_density = 0.0;
    p.core_fraction = 0.0;
    p.density_epsilon = 0.5;
    let pts: Vec<[f64; 3]> =
        (0..9).map(|i| [i as f64 * 1e-3, 0.6e-3 * (i as f64 * 0.5).sin(), 0.0]).collect();
    let c = YarnCurve::open(pts).unwrap();
    (YarnSet::new(vec![c], None).unwrap(), p)
}
