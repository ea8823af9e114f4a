//! `btf demo` end to end at a tiny size: every stage runs, the report and pictures exist,
//! the headline numbers agree with the stores and the sweep, the garment fills the frame,
//! the terminal gets a short summary, and a second run reuses the finished stages.

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
        "report.html",
        "details.md",
        "details.html",
        "swatch.png",
        "material.btf/zarr.json",
        "material.eig/zarr.json",
        "sweep/report.md",
        "garment.obj",
        "sky.exr",
        "knit/knit.png",
        "knit/knit.json",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    // A summary, not the report: at most 10 lines, pointing at the report.
    assert!(stdout.lines().count() <= 10, "{stdout}");
    assert!(stdout.contains("report.html") && !stdout.contains("| "), "{stdout}");
    let m: serde_json::Value =
        serde_json::from_str(&d.ok(&["inspect", "out/material.eig", "--json"])).unwrap();
    assert_eq!((m["n_views"].as_u64(), m["components"].as_u64()), (Some(81), Some(8)));
    let b: serde_json::Value =
        serde_json::from_str(&d.ok(&["inspect", "out/material.btf", "--json"])).unwrap();
    // The headline sizes are the stores' sizes (MB = 10⁶ bytes, one decimal).
    let mb = |v: &serde_json::Value| format!("{:.1} MB", v["bytes"].as_u64().unwrap() as f64 / 1e6);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    for text in [&stdout, &report, &html] {
        let sizes = format!("{} instead of {}", mb(&m), mb(&b));
        assert!(text.contains(&mb(&m)) && text.contains(&mb(&b)), "{sizes}: {text}");
    }
    assert!(report.contains(&format!("{} instead of {}", mb(&m), mb(&b))), "{report}");
    // Sweep: the error falls from 2 to 8 components.
    let csv = std::fs::read_to_string(out.join("sweep/sweep.csv")).unwrap();
    let errs: Vec<f64> =
        csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap().parse().unwrap()).collect();
    assert!(errs.len() == 2 && errs[1] < errs[0] && errs[1] > 0.0, "{errs:?}");
    // The headline error is the store's (c = 8, the sweep's last row, same compression):
    // equal to the rounding of two decimals in per cent.
    let pct = format!("error {:.2} %", 100.0 * errs[1]);
    assert!(stdout.contains(&pct) && stdout.contains("8 components"), "{pct}: {stdout}");
    assert!(report.contains(&format!("{:.2} %", 100.0 * errs[1])), "{report}");
    // The report is self-contained: relative images that exist, no scripts or remote files.
    assert!(!html.contains("<script") && !html.contains("http"));
    for src in html.split("src=\"").skip(1).map(|t| t.split('"').next().unwrap()) {
        assert!(out.join(src).exists(), "report.html shows a missing {src}");
    }
    // The knit close-up: fibers drawn (core strips at least), timed against plain tubes.
    let k: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("knit/knit.json")).unwrap())
            .unwrap();
    assert!(k["fiber_instances"].as_u64().unwrap() > k["control_points"].as_u64().unwrap());
    assert!(k["fibers_ms"].as_f64().unwrap() > 0.0 && k["tubes_ms"].as_f64().unwrap() > 0.0);
    assert!(report.contains("Knitwear, fiber by fiber") && report.contains("knit/knit.png"));
    // The knot solver's panel: the patch stretched 30 % along its wales.
    assert_eq!(k["stretch"].as_f64().unwrap(), 0.3);
    assert!(k["knot_solve_ms"].as_f64().unwrap() > 0.0);
    // With the relaxed stitch template the yarns touch (0.88 × 2r without it).
    let c = k["stretch_clearance"].as_f64().unwrap();
    let plain = k["stretch_clearance_plain"].as_f64().unwrap();
    assert!(c > 0.95 && c < 1.5 && plain < 0.9, "clearance / 2r {c} ({plain} without)");
    assert!(
        out.join("knit/knit-stretch.png").is_file() && report.contains("knit/knit-stretch.png")
    );
    // The yarn strips' panel, timed, with its bake.
    assert!(k["strips_ms"].as_f64().unwrap() > 0.0 && k["strips_bake_s"].as_f64().unwrap() > 0.0);
    assert!(
        k["lumislice_ms"].as_f64().unwrap() > 0.0 && k["lumislice_table_s"].as_f64().unwrap() > 0.0
    );
    assert!(out.join("knit/knit-strips.png").is_file() && report.contains("knit/knit-strips.png"));
    // The shadows panel: the tube model, every fiber, and that at 4 × 4 frames a pixel.
    let ms = |key: &str| k[key].as_f64().unwrap();
    assert!(ms("fiber_shadows_ms") > 0.0 && ms("fiber_shadows_supersampled_ms") > 0.0);
    let width = |f: &str| image::image_dimensions(out.join(f)).unwrap().0;
    let (one, three) = (width("knit/knit.png"), width("knit/knit-shadows.png"));
    assert!(three >= 3 * one, "{three} px for three panels of {one}");
    assert!(report.contains("4 × 4 times a pixel"), "{report}");
    let details = std::fs::read_to_string(out.join("details.md")).unwrap();
    assert!(report.contains("(details.html)") && details.contains("| synthesise material |"));
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
        // Framed: the rows the garment covers span ≥ 60 % of the frame's height.
        let rows: Vec<u32> = (0..72)
            .filter(|&y| {
                (0..96).any(|x| {
                    let p = img.get_pixel(x, y).0;
                    p.iter().zip(bg).map(|(a, b)| (*a as i32 - b as i32).abs()).sum::<i32>() > 30
                })
            })
            .collect();
        let span = (rows.last().unwrap() - rows[0] + 1) as f64 / 72.0;
        assert!(span >= 0.6, "the garment spans {span} of the height");
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
        assert!(details.contains("env visibility maps"), "{details}");
        assert!(stdout.contains("render: 96×72 frame in"), "{stdout}");
        // Render cost sweep: c = 4, 8 × two evaluations × two blendings, with its checks.
        let cost = std::fs::read_to_string(out.join("render-cost/render-cost.csv")).unwrap();
        assert_eq!(cost.lines().count(), 1 + 8, "{cost}");
        // The shadow comparison is readable: two captioned panels of ≥ 400 px.
        let eq6 = image::open(out.join("render-cost/eq6-on-off.png")).unwrap();
        assert!(eq6.width() >= 2 * 400 && eq6.height() >= 300, "{}×{}", eq6.width(), eq6.height());
        assert!(
            details.contains("read_bound_ms") && details.contains("render-cost/render-cost.png")
        );
    } else {
        assert!(!gpu_required, "BTF_REQUIRE_GPU=1 but the demo rendered nothing");
    }
    // Second run: everything reused, same report numbers.
    let again = d.ok(&args);
    // The knit close-up: fibers drawn (core strips at least), timed against plain tubes.
    let k: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("knit/knit.json")).unwrap())
            .unwrap();
    assert!(k["fiber_instances"].as_u64().unwrap() > k["control_points"].as_u64().unwrap());
    assert!(k["fibers_ms"].as_f64().unwrap() > 0.0 && k["tubes_ms"].as_f64().unwrap() > 0.0);
    assert!(report.contains("Knitwear, fiber by fiber") && report.contains("knit/knit.png"));
    let details = std::fs::read_to_string(out.join("details.md")).unwrap();
    assert!(details.matches("reused").count() >= 3, "{details}");
    // Same headline numbers from the kept stores.
    assert_eq!(again.lines().nth(1), stdout.lines().nth(1), "{again}");
}
