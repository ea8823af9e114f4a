//! The Python driver of sharded jobs (`python/btf_jobs`, issue #23) on a Dask
//! `LocalCluster` of 2 worker processes: a compression of an 81-slot store in 4 shards,
//! one worker process killed (SIGKILL) while it runs a shard; Dask reschedules the shard,
//! the binary resumes it, and the finalised store is byte-identical to a single-process
//! run's (but for the slots' wall-clock seconds).
//!
//! Needs `python3` with `dask[distributed]`: without it the test fails when `CI` or
//! `BTF_REQUIRE_PYTHON` is set and is skipped with a printed reason otherwise.

use crate::common::Dir;
use crate::shards::{assert_same_tree, store_81, strip_seconds, tree};
use std::process::Command;

const PACKAGE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/python/btf_jobs");

fn dask_or_skip() -> bool {
    let probe = Command::new("python3").args(["-c", "import dask.distributed"]).output();
    let why = match probe {
        Err(e) => format!("python3 does not run: {e}"),
        Ok(o) if !o.status.success() => format!(
            "python3 lacks dask.distributed (python3 -m pip install 'dask[distributed]'): {}",
            String::from_utf8_lossy(&o.stderr).lines().last().unwrap_or("")
        ),
        Ok(_) => return true,
    };
    let required = std::env::var_os("CI").is_some()
        || std::env::var("BTF_REQUIRE_PYTHON").is_ok_and(|v| v == "1");
    assert!(!required, "{why} (CI or BTF_REQUIRE_PYTHON=1 is set)");
    eprintln!("skipped: {why}");
    false
}

#[test]
fn dask_runs_four_shards_on_two_workers_survives_a_killed_worker_and_matches_one_process() {
    if !dask_or_skip() {
        return;
    }
    let d = Dir::new();
    store_81(&d.path("m.btf"), 0.0);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "single.eig"]);
    let script = format!("{PACKAGE}/tests/kill_a_worker.py");
    let o = Command::new("python3")
        .args([&script, env!("CARGO_BIN_EXE_btf"), "dk.eig", "4", "--"])
        .args(["compress", "m.btf", "-c", "4", "-o", "dk.eig"])
        .env("PYTHONPATH", PACKAGE)
        .current_dir(d.tmp.path())
        .output()
        .expect("python3 runs");
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "the Dask job failed:\n{out}\n{err}");
    let r: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert!(r["killed"]["pid"].as_u64().is_some(), "no worker was killed: {r}");
    assert!(r["killed"]["units_done"].as_u64().is_some_and(|n| (2..21).contains(&n)), "{r}");
    let killed = r["killed"]["shard"].as_u64().unwrap() as usize;
    assert!(err.contains("Restarting worker"), "the nanny did not restart the worker:\n{err}");
    let shards = r["shards"].as_array().unwrap();
    assert_eq!(shards.len(), 4);
    // The shard whose worker died was run again and kept what the killed attempt wrote
    // (at least the slots counted at the kill, less one whose statistics were being
    // written).
    let again = shards[killed].as_str().unwrap();
    let kept: u64 = again
        .split(" computed, ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!((1..21).contains(&kept), "shard {killed} kept no work of the killed attempt: {again}");
    assert!(r["finalize"].as_str().is_some_and(|f| f.starts_with("finalised dk.eig: 81 slots")));
    let (a, b) = (tree(&d.path("single.eig")), tree(&d.path("dk.eig")));
    assert_same_tree(&a, &b, strip_seconds);
}
