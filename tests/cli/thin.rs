//! End-to-end test of `btf thin validate`: the first-order slab terms against the
//! Monte-Carlo slab, as JSON and as a report folder, and clear refusals of bad arguments.

use std::process::{Command, Output};

fn btf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .env("BTF_NO_PROGRESS", "1")
        .output()
        .expect("run btf")
}

#[test]
fn thin_validate_reports_the_first_order_error() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("report");
    let out = btf(&[
        "thin",
        "validate",
        "--tau",
        "0.05,1",
        "--photons",
        "20000",
        "--json",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    // The formulas are exact for single scattering: only Monte-Carlo noise remains
    // (≤ 4 standard errors; the relative standard error is reported beside).
    for r in rows {
        let (e, s) = (r["single_rel_err"].as_f64().unwrap(), r["mc_rel_std_err"].as_f64().unwrap());
        assert!(e < 4.0 * s + 1e-3, "{r}");
    }
    // Multiple scattering matters more in the thicker slab.
    assert!(rows[1]["reflect_rel_err"].as_f64() > rows[0]["reflect_rel_err"].as_f64());
    let md = std::fs::read_to_string(report.join("thin-validate.md")).unwrap();
    assert!(md.contains("| 0.05 |") && md.contains("| 1 |"), "{md}");
    assert!(report.join("thin-validate.json").is_file());
}

#[test]
fn thin_validate_refuses_bad_arguments() {
    for (arg, key) in
        [("--tau=-1", "--tau"), ("--albedo=2", "--albedo"), ("--photons=5", "--photons")]
    {
        let out = btf(&["thin", "validate", arg]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(key), "{arg}: {err}");
    }
}

/// `btf thin demo` at 48² with 4 light positions (front, edge, back, edge): the frames,
/// contact sheet and report exist; front-lit the thin curtain reflects a share of the
/// opaque one's point light, back-lit the light comes through the thin curtain but not the
/// opaque one (Fig. 2); the sky shows through with `α ≤ e^{−τ₁}` and `α(2τ₁) = α(τ₁)²`;
/// a second run reuses the finished frames.
#[test]
fn thin_demo_orbits_a_light_round_the_curtain() {
    let dir = tempfile::tempdir().unwrap();
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_btf"))
            .args(["thin", "demo", "-o", "out", "--frames", "4", "--size", "48"])
            .args(["--texels", "8", "-c", "4", "--tau", "0.6", "--material", "weave-lambert"])
            .current_dir(dir.path())
            .env("BTF_NO_PROGRESS", "1")
            .output()
            .unwrap()
    };
    let o = run();
    let stderr = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() && stderr.contains("GPU") {
        assert!(std::env::var("BTF_REQUIRE_GPU").is_err(), "BTF_REQUIRE_GPU=1: {stderr}");
        eprintln!("thin demo skipped: no GPU adapter");
        return;
    }
    assert!(o.status.success(), "{stderr}");
    let out = dir.path().join("out");
    for f in ["contact.png", "report.md", "scene-thin.toml", "frames/frame-003.png"] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let (front, back, alpha) = (&r["front"], &r["back"], &r["alpha"]);
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    assert_eq!((front["frames"].as_u64(), back["frames"].as_u64()), (Some(1), Some(1)));
    // Front-lit: the thin sheet reflects its share of the opaque curtain's light
    // (1 − e^{−τ₁(1/μ + 1/μ₀)} ∈ (0.5, 1) for τ₁ = 0.6 and the curtain's angles).
    let share = f(front, "point_thin") / f(front, "point_opaque");
    assert!(share > 0.5 && share < 1.0, "front-lit share {share}");
    // Back-lit: the light shows through the thin curtain, not through the opaque one.
    assert!(f(back, "point_thin") > 20.0 * f(back, "point_opaque").max(0.0), "{back}");
    assert!(f(back, "point_thin") > 1e-3, "{back}");
    // Fig. 2: front-lit the light's part is reflection and brighter than what comes through.
    assert!(f(front, "point_thin") > 2.0 * f(back, "point_thin"), "{front} vs {back}");
    // The sky shows through with the model's alpha.
    let bound = (-0.6f64).exp();
    assert!((f(alpha, "bound") - bound).abs() < 1e-12);
    assert!(f(alpha, "max_alpha") <= bound + 1e-4, "{alpha}");
    assert!(
        f(alpha, "mean_alpha") > bound.powf(1.0 / 0.3) && f(alpha, "values") > 500.0,
        "{alpha}"
    );
    assert!(f(alpha, "max_square_error") < 1e-4, "{alpha}");
    let ratio = f(&r, "frame_time_ratio");
    assert!(ratio.is_finite() && ratio > 0.0, "{ratio}");
    // Resume: a deleted frame is rendered again, the others are reused unchanged.
    let frame0 = std::fs::read(out.join("frames/frame-000.json")).unwrap();
    let t0 = std::fs::metadata(out.join("frames/frame-000.png")).unwrap().modified().unwrap();
    std::fs::remove_file(out.join("frames/frame-002.png")).unwrap();
    assert!(run().status.success());
    assert!(out.join("frames/frame-002.png").is_file());
    assert_eq!(std::fs::read(out.join("frames/frame-000.json")).unwrap(), frame0);
    let t1 = std::fs::metadata(out.join("frames/frame-000.png")).unwrap().modified().unwrap();
    assert_eq!(t0, t1, "frame 0 must be reused");
}
