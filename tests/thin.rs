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
