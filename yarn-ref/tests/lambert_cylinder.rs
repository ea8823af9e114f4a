//! The reference against an analytic opaque Lambert cylinder (DESIGN §4.3 part A): a fat
//! straight capsule seen straight down by the orthographic camera under a directional
//! light. Across the cylinder the radiance is `ρ/π·E·max(0, n·l)` with
//! `n = (0, y/r, √(1 − y²/r²))`, so each pixel row's exact value is that profile averaged
//! over the row's footprint; the covered width is `2r` per unit length.

use std::f64::consts::PI;
use yarn_ref::patch::fibers_from_polylines;
use yarn_ref::{
    Camera, FiberScene, Light, PathSettings, PixelSampler, RenderSettings, Scene, SceneOptions,
    Shading, render,
};

const R: f64 = 0.5e-3;
const RHO: f64 = 0.8;
const ROWS: usize = 64;
const COLS: usize = 4;
const HALF_Y: f64 = 1.25 * R;

fn light_dir() -> [f64; 3] {
    // 35° from the zenith towards +y: a terminator on the −y side of the cylinder.
    let a = 35f64.to_radians();
    [0.0, a.sin(), a.cos()]
}

/// Exact pixel values: the profile integrated over each row's y-range (substituting
/// y = r sin α and summing 4000 midpoints in α).
fn analytic() -> Vec<f64> {
    let l = light_dir();
    let dy = 2.0 * HALF_Y / ROWS as f64;
    (0..ROWS)
        .map(|j| {
            let (y0, y1) = (-HALF_Y + j as f64 * dy, -HALF_Y + (j + 1) as f64 * dy);
            let (a0, a1) =
                ((y0.max(-R) / R).clamp(-1.0, 1.0).asin(), (y1.min(R) / R).clamp(-1.0, 1.0).asin());
            if a1 <= a0 {
                return 0.0;
            }
            let n = 4000;
            let h = (a1 - a0) / n as f64;
            let mut s = 0.0;
            for k in 0..n {
                let a = a0 + (k as f64 + 0.5) * h;
                let ndotl = (a.sin() * l[1] + a.cos() * l[2]).max(0.0);
                s += RHO / PI * ndotl * R * a.cos() * h;
            }
            s / dy
        })
        .collect()
}

fn render_profile(spp: u32, sampler: PixelSampler, seed: u64) -> (Vec<f64>, f64) {
    let fibers = fibers_from_polylines(&[vec![[-0.02, 0.0, 0.0], [0.02, 0.0, 0.0]]], R, [1.0; 3]);
    let scene = FiberScene::new(&fibers, &SceneOptions::default()).unwrap();
    let lights = [Light::directional(light_dir(), [1.0; 3])];
    let shading = Shading::Lambert { albedo: Some([RHO; 3]) };
    let sc = Scene { fibers: &scene, lights: &lights, shading: &shading };
    let cam = Camera::oblique([0.0, 0.0, 1.0], R, [-2e-3, -HALF_Y], [4e-3, 2.0 * HALF_Y]).unwrap();
    let mut s = RenderSettings::new(COLS, ROWS, spp);
    s.sampler = sampler;
    s.seed = seed;
    s.path = PathSettings { max_bounces: 1, ..PathSettings::default() };
    let (img, _) = render(&sc, &cam, &s).unwrap();
    // Average the columns (the cylinder is uniform along x) of the red channel.
    let prof: Vec<f64> = (0..ROWS)
        .map(|j| (0..COLS).map(|i| img.pixel(i, j)[0] as f64).sum::<f64>() / COLS as f64)
        .collect();
    // Covered width = Σ coverage · pixel area / imaged length.
    let dy = 2.0 * HALF_Y / ROWS as f64;
    let width = img.coverage.iter().map(|c| *c as f64).sum::<f64>() * dy / COLS as f64;
    (prof, width)
}

fn l1_error(prof: &[f64], exact: &[f64]) -> f64 {
    prof.iter().zip(exact).map(|(a, b)| (a - b).abs()).sum::<f64>() / exact.iter().sum::<f64>()
}

#[test]
fn profile_and_coverage_match_the_analytic_cylinder_within_one_percent() {
    let exact = analytic();
    let (prof, width) = render_profile(64, PixelSampler::Stratified, 1);
    let err = l1_error(&prof, &exact);
    let peak = exact.iter().cloned().fold(0.0, f64::max);
    // The worst single row among those above 5 % of the peak (edge and terminator rows
    // included), for the report.
    let worst_row = prof
        .iter()
        .zip(&exact)
        .filter(|(_, e)| **e > 0.05 * peak)
        .map(|(a, e)| ((a - e) / e).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "Lambert cylinder, 64 spp stratified: relative L1 error {:.4} %, worst lit row {:.3} %, \
         coverage width {:.6} r (2 expected)",
        100.0 * err,
        100.0 * worst_row,
        width / R
    );
    assert!(err < 0.01, "profile error {err}");
    assert!((width / (2.0 * R) - 1.0).abs() < 0.01, "width {} r", width / R);
}

/// Least-squares slope of `log e` against `log spp`.
fn slope(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = xs.iter().zip(ys).map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

#[test]
fn profile_error_falls_as_one_over_root_spp() {
    let exact = analytic();
    let spps = [4u32, 16, 64, 256];
    let mut random = Vec::new();
    let mut strat = Vec::new();
    for &spp in &spps {
        // Average the error over 6 seeds so the slope is a property of the estimator, not
        // of one draw.
        let mean = |sampler| {
            (0..6)
                .map(|seed| l1_error(&render_profile(spp, sampler, 100 + seed).0, &exact))
                .sum::<f64>()
                / 6.0
        };
        random.push(mean(PixelSampler::Random));
        strat.push(mean(PixelSampler::Stratified));
    }
    let xs: Vec<f64> = spps.iter().map(|s| *s as f64).collect();
    let (sr, ss) = (slope(&xs, &random), slope(&xs, &strat));
    eprintln!(
        "relative L1 error vs spp {spps:?}: random {random:.5?} (slope {sr:.3}), stratified {strat:.5?} (slope {ss:.3})"
    );
    // Independent samples: the error of a mean falls as spp^(−1/2).
    assert!((sr + 0.5).abs() < 0.1, "random-sampling slope {sr}");
    // Jittered strata do at least as well (edges: spp^(−3/4) in 2-D).
    assert!(ss < -0.5, "stratified slope {ss}");
}
