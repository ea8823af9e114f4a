//! `btf demo` end to end at a tiny size: every stage runs, the report and pictures exist,
//! the numbers in them are sane, and a second run reuses the finished stages.

use crate::common;
use common::*;

#[test]
fn demo_runs_end_to_end_and_resumes() {
    let d = Dir::new();
    let args = ["demo", "-o", "out", "--size", "8", "--width", "96", "-c", "8", "--sweep", "2,8"];
    let stdout = d.ok(&args);
    let out = d.path("out");
    for f in [
        "report.md",
        "material.btf/zarr.json",
        "material.eig/zarr.json",
        "sweep/report.md",
        "garment.obj",
        "sky.exr",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    assert!(stdout.contains("Compression (`material.eig`): 8 components"), "{stdout}");
    let m: serde_json::Value =
        serde_json::from_str(&d.ok(&["inspect", "out/material.eig", "--json"])).unwrap();
    assert_eq!((m["n_views"].as_u64(), m["components"].as_u64()), (Some(81), Some(8)));
    // Sweep: the error falls from 2 to 8 components.
    let csv = std::fs::read_to_string(out.join("sweep/sweep.csv")).unwrap();
    let errs: Vec<f64> =
        csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap().parse().unwrap()).collect();
    assert!(errs.len() == 2 && errs[1] < errs[0] && errs[1] > 0.0, "{errs:?}");
    let gpu_required = std::env::var("BTF_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let png = out.join("render-point.png");
    if png.exists() {
        // The garment covers a good part of the frame and is lit: count pixels that differ
        // from the background and are brighter than it.
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), (96, 72));
        let bg = img.get_pixel(0, 0).0;
        let lit = img
            .pixels()
            .filter(|p| p.0.iter().zip(bg).map(|(a, b)| *a as i32 - b as i32).sum::<i32>() > 30)
            .count();
        let frac = lit as f64 / (96.0 * 72.0);
        assert!(frac > 0.05 && frac < 0.9, "lit fraction {frac}");
        // Under the sky (exposure: horizontal irradiance 1) the garment is lit as well, and
        // the report lists the environment's one-off costs.
        let img = image::open(out.join("render-environment.png")).unwrap().to_rgb8();
        let bg = img.get_pixel(0, 0).0;
        let lit = img
            .pixels()
            .filter(|p| p.0.iter().zip(bg).map(|(a, b)| *a as i32 - b as i32).sum::<i32>() > 30)
            .count();
        let frac = lit as f64 / (96.0 * 72.0);
        assert!(frac > 0.05 && frac < 0.9, "environment: lit fraction {frac}");
        assert!(stdout.contains("env visibility maps"), "{stdout}");
        // Render cost sweep: c = 4, 8 × two evaluations × two blendings, with its checks.
        let cost = std::fs::read_to_string(out.join("render-cost/render-cost.csv")).unwrap();
        assert_eq!(cost.lines().count(), 1 + 8, "{cost}");
        assert!(out.join("render-cost/eq6-on-off.png").exists());
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(report.contains("× read bound") && report.contains("render-cost/render-cost.png"));
    } else {
        assert!(!gpu_required, "BTF_REQUIRE_GPU=1 but the demo rendered nothing");
    }
    // Second run: everything reused, same report numbers.
    let again = d.ok(&args);
    assert!(
        again.contains("| synthesise material | ") && again.matches("reused").count() >= 3,
        "{again}"
    );
}
