//! Sharded jobs end to end (issue #23): a compression of an 81-slot store and a relight job
//! of 200 frames, each split over 4 shards run as 4 concurrent processes into one output,
//! one shard killed with SIGKILL in the middle of its work (after the test has seen it
//! finish some units), `btf status` reporting it incomplete, the shard restarted, and
//! `btf finalize` making an output byte-identical to a single-process run's. Writers that
//! disagree with the job (another `-c`, another input store, other rotations) are refused
//! before they write anything.

use crate::common::Dir;
use crate::relight::{run_gpu, scene, setup};
use btf_core::Sampling;
use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An 81 × 81 (ubo81) store of 16² texels whose images vary smoothly with the light and
/// the view (a PCA with several real components), shifted by `offset`.
pub(crate) fn store_81(path: &Path, offset: f32) {
    let s = Sampling::ubo81();
    let w = BtfWriter::create(path, BtfMeta::new(s.clone(), s, 16, 16), DType::F32, false).unwrap();
    for v in 0..81 {
        for l in 0..81 {
            let img: Vec<f32> =
                (0..16 * 16 * 3).map(|t| crate::common::value(v, l, t) + offset).collect();
            w.write_image(v, l, &img).unwrap();
        }
    }
    w.finish().unwrap();
}

/// Starts `btf ARGS` in the folder without waiting; `delay_ms` slows each unit of work
/// (`BTF_TEST_UNIT_DELAY_MS`) so that the test can kill it in the middle.
fn spawn(d: &Dir, args: &[&str], delay_ms: u64) -> Child {
    Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .current_dir(d.tmp.path())
        .env("BTF_NO_PROGRESS", "1")
        .env("BTF_TEST_UNIT_DELAY_MS", delay_ms.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("btf starts")
}

fn wait_ok(child: Child, what: &str) -> String {
    let o = child.wait_with_output().unwrap();
    assert!(
        o.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// Waits until `done()` reaches `at_least` units, then kills `child` with SIGKILL (what
/// `Child::kill` sends on Unix); returns the units done at the kill.
fn kill_after(mut child: Child, at_least: usize, done: impl Fn() -> usize) -> usize {
    let t = Instant::now();
    while done() < at_least {
        if child.try_wait().unwrap().is_some() {
            let o = child.wait_with_output().unwrap();
            panic!(
                "the shard finished before the kill ({}):\n{}",
                o.status,
                String::from_utf8_lossy(&o.stderr)
            );
        }
        assert!(t.elapsed() < Duration::from_secs(60), "the shard never got going");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success());
    done()
}

/// Every file below `dir`, relative path → bytes.
pub(crate) fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// `tree` of a folder and of the partial store beside it, if any.
fn tree_with_partial(d: &Dir, name: &str) -> BTreeMap<String, Vec<u8>> {
    let mut t = BTreeMap::new();
    for n in [name.to_string(), format!("{name}.partial")] {
        if d.path(&n).exists() {
            t.extend(tree(&d.path(&n)).into_iter().map(|(k, v)| (format!("{n}/{k}"), v)));
        }
    }
    t
}

/// Asserts two trees hold the same files with the same bytes, after `normalise`.
pub(crate) fn assert_same_tree(
    a: &BTreeMap<String, Vec<u8>>,
    b: &BTreeMap<String, Vec<u8>>,
    normalise: impl Fn(&str, &[u8]) -> Vec<u8>,
) {
    let (ka, kb): (Vec<&String>, Vec<&String>) = (a.keys().collect(), b.keys().collect());
    assert_eq!(ka, kb, "the two outputs hold different files");
    for (k, va) in a {
        assert!(normalise(k, va) == normalise(k, &b[k]), "{k} differs");
    }
}

fn status_json(d: &Dir, out: &str) -> serde_json::Value {
    serde_json::from_str(&d.ok(&["status", out, "--json"])).unwrap()
}

#[test]
fn compress_in_four_shards_with_one_killed_matches_one_process() {
    let d = Dir::new();
    store_81(&d.path("m.btf"), 0.0);
    d.ok(&["compress", "m.btf", "-c", "4", "-o", "single.eig"]);
    let args = |i: usize| -> Vec<String> {
        ["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard", &format!("{i}/4")]
            .map(String::from)
            .to_vec()
    };
    let run = |i: usize, delay: u64| {
        let a = args(i);
        spawn(&d, &a.iter().map(String::as_str).collect::<Vec<_>>(), delay)
    };
    // Shard 2 owns view slots 40..60; it is slowed to 40 ms per slot and killed after 5.
    let children: Vec<Child> = [0, 1, 3].into_iter().map(|i| run(i, 0)).collect();
    let slow = run(2, 40);
    let stats = d.path("sh.eig.partial/stats");
    let done = || (40..60).filter(|v| stats.join(v.to_string()).join("zarr.json").exists()).count();
    let at_kill = kill_after(slow, 5, done);
    assert!((5..20).contains(&at_kill), "killed after {at_kill} slots");
    for (c, i) in children.into_iter().zip([0, 1, 3]) {
        wait_ok(c, &format!("shard {i}"));
    }
    // The kill is seen: shard 2 incomplete, the others done; finalising is refused.
    let st = status_json(&d, "sh.eig");
    assert_eq!((st["kind"].as_str(), st["total"].as_u64()), (Some("compress"), Some(81)));
    let shards = st["shards"].as_array().unwrap();
    assert_eq!(shards.len(), 4, "{st}");
    for (i, s) in shards.iter().enumerate() {
        let want = if i == 2 { "incomplete" } else { "done" };
        assert_eq!(s["state"], want, "shard {i}: {st}");
    }
    let s2 = &shards[2];
    assert_eq!(s2["units"], 20);
    assert_eq!(s2["done"].as_u64().unwrap() + s2["missing"].as_u64().unwrap(), 20, "{st}");
    assert!(s2["done"].as_u64().unwrap() >= at_kill as u64 - 1, "{st}");
    assert_eq!(st["complete"], false);
    let human = d.ok(&["status", "sh.eig"]);
    assert!(human.lines().any(|l| l.contains("2/4") && l.ends_with("incomplete")), "{human}");
    let before = tree_with_partial(&d, "sh.eig");
    let err = d.fails(&["finalize", "sh.eig"]);
    assert!(err.contains("cannot finalise") && err.contains("missing"), "{err}");
    assert!(tree_with_partial(&d, "sh.eig") == before, "a refused finalize changed the output");
    // A damaged chunk of a finished slot (one bit of shard 0's slot 3) is seen by its
    // checksum: status calls the slot corrupt, naming the file; the shard's next run
    // computes it again.
    let chunk = d.path("sh.eig.partial/weights/c.3.0.0");
    let mut bytes = std::fs::read(&chunk).unwrap();
    bytes[0] ^= 1;
    std::fs::write(&chunk, &bytes).unwrap();
    let st = status_json(&d, "sh.eig");
    assert_eq!(
        (st["corrupt"].as_u64(), st["shards"][0]["state"].as_str()),
        (Some(1), Some("corrupt"))
    );
    let why = st["corrupt_units"][0].to_string();
    assert!(
        why.contains("slot 3") && why.contains("weights/c.3.0.0") && why.contains("crc32c"),
        "{why}"
    );
    let out = d.ok(&["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard", "0/4"]);
    assert!(out.contains("(1 computed, 19 already done)"), "{out}");
    let st = status_json(&d, "sh.eig");
    assert_eq!(
        (st["corrupt"].as_u64(), st["shards"][0]["state"].as_str()),
        (Some(0), Some("done"))
    );
    let before = tree_with_partial(&d, "sh.eig");
    // Disagreeing writers are refused before writing anything: another -c, another store.
    let err = d.fails(&["compress", "m.btf", "-c", "8", "-o", "sh.eig", "--shard", "2/4"]);
    assert!(err.contains("meta.components: was 4, now 8"), "{err}");
    store_81(&d.path("other.btf"), 0.01);
    let err = d.fails(&["compress", "other.btf", "-c", "4", "-o", "sh.eig", "--shard", "2/4"]);
    assert!(err.contains("job.input.fingerprint: was"), "{err}");
    let err = d.fails(&["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard", "1/2"]);
    assert!(err.contains("job.shards: was 4, now 2"), "{err}");
    let args = ["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard", "2/4", "--gram", "f32"];
    let err = d.fails(&args);
    assert!(err.contains("job.gram: was \"f64\", now \"f32\""), "{err}");
    assert!(tree_with_partial(&d, "sh.eig") == before, "a refused writer changed the output");
    // The restarted shard keeps what it finished and computes the rest; this time its
    // index comes from the variable a Kubernetes Indexed Job sets.
    let shard_count = |var: Option<(&str, &str)>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_btf"));
        c.args(["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard-count", "4"])
            .current_dir(d.tmp.path())
            .env("BTF_NO_PROGRESS", "1")
            .env_remove("JOB_COMPLETION_INDEX")
            .env_remove("SLURM_ARRAY_TASK_ID");
        if let Some((k, v)) = var {
            c.env(k, v);
        }
        c.output().unwrap()
    };
    let o = shard_count(None);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("JOB_COMPLETION_INDEX"), "{err}");
    let o = shard_count(Some(("SLURM_ARRAY_TASK_ID", "4")));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("SLURM_ARRAY_TASK_ID=4"), "{err}");
    assert!(tree_with_partial(&d, "sh.eig") == before, "a refused writer changed the output");
    let o = shard_count(Some(("JOB_COMPLETION_INDEX", "2")));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.starts_with("shard 2/4: view slots 40..60"), "{out}");
    assert!(out.contains("already done"), "{out}");
    let resumed: usize =
        out.split(" computed, ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(resumed >= at_kill - 1 && resumed < 20, "{out}");
    let st = status_json(&d, "sh.eig");
    assert_eq!((st["done"].as_u64(), st["complete"].as_bool()), (Some(81), Some(true)), "{st}");
    d.ok(&["finalize", "sh.eig"]);
    let again = d.ok(&["finalize", "sh.eig", "--json"]);
    let report: serde_json::Value = serde_json::from_str(&again).unwrap();
    // A shard retried after the finalisation has nothing to do; one of another job is
    // refused (the finished store's metadata is the input's, with c and quantisation).
    let late = d.ok(&["compress", "m.btf", "-c", "4", "-o", "sh.eig", "--shard", "1/4"]);
    assert!(late.contains("0 computed, 20 already done"), "{late}");
    let err = d.fails(&["compress", "m.btf", "-c", "3", "-o", "sh.eig", "--shard", "1/4"]);
    assert!(err.contains("already finalised for another job (components: was 4, now 3)"), "{err}");
    assert!(!d.path("sh.eig.partial").exists());
    assert_eq!(report["slots"].as_array().unwrap().len(), 81);
    let single: serde_json::Value = serde_json::from_str(&d.ok(&[
        "compress",
        "m.btf",
        "-c",
        "4",
        "-o",
        "single2.eig",
        "--json",
    ]))
    .unwrap();
    assert_eq!(report["rel_rmse"], single["rel_rmse"], "the report over all slots");
    assert_eq!(report["psnr_db"], single["psnr_db"]);
    let (a, b) = (tree(&d.path("single.eig")), tree(&d.path("sh.eig")));
    assert!(a.len() > 81 * 5, "{} files", a.len());
    assert_same_tree(&a, &b, strip_seconds);
    assert!(!d.path("sh.eig.partial").exists());
}

/// Byte for byte the single-process store, except the wall-clock `seconds` each slot's
/// statistics record (`stats/<view>/zarr.json`): timings legitimately differ.
pub(crate) fn strip_seconds(name: &str, bytes: &[u8]) -> Vec<u8> {
    if !name.starts_with("stats/") {
        return bytes.to_vec();
    }
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    if let Some(r) = v["attributes"]["record"].as_object_mut() {
        r.remove("seconds");
    }
    v.to_string().into_bytes()
}

/// 2 environments × 100 rotations = 200 frames of 16² (the plane of the relight tests).
const ROTATIONS: &str = "100";

fn relight_args(out: &str, shard: Option<usize>) -> Vec<String> {
    let mut a: Vec<String> = [
        "relight",
        "s.toml",
        "--env",
        "white.exr",
        "--env",
        "sky.exr",
        "--rotations",
        ROTATIONS,
        "--exr",
        "-o",
        out,
    ]
    .map(String::from)
    .to_vec();
    if let Some(i) = shard {
        a.extend(["--shard".to_string(), format!("{i}/4")]);
    }
    a
}

#[test]
fn relight_of_200_frames_in_four_shards_with_one_killed_matches_one_process() {
    let d = setup();
    std::fs::write(d.path("s.toml"), scene("per-vertex", "white.exr", "")).unwrap();
    // job.json records the output's cache folder by the path given: both runs write to
    // `sh`, the single-process one moved aside afterwards.
    let single = relight_args("sh", None);
    if run_gpu(&d, &single.iter().map(String::as_str).collect::<Vec<_>>()).is_none() {
        return;
    }
    std::fs::rename(d.path("sh"), d.path("single")).unwrap();
    let run = |i: usize, delay: u64| {
        let a = relight_args("sh", Some(i));
        spawn(&d, &a.iter().map(String::as_str).collect::<Vec<_>>(), delay)
    };
    // Shard 1 owns frames 50..100: white_r050 … white_r099.
    let children: Vec<Child> = [0, 2, 3].into_iter().map(|i| run(i, 0)).collect();
    let slow = run(1, 40);
    let frame = |r: usize| d.path(&format!("sh/white_r{r:03}.png"));
    let at_kill = kill_after(slow, 5, || (50..100).filter(|&r| frame(r).exists()).count());
    assert!((5..50).contains(&at_kill), "killed after {at_kill} frames");
    for (c, i) in children.into_iter().zip([0, 2, 3]) {
        wait_ok(c, &format!("shard {i}"));
    }
    let st = status_json(&d, "sh");
    assert_eq!((st["kind"].as_str(), st["total"].as_u64()), (Some("relight"), Some(200)));
    let states: Vec<&str> =
        st["shards"].as_array().unwrap().iter().map(|s| s["state"].as_str().unwrap()).collect();
    assert_eq!(states, ["done", "incomplete", "done", "done"], "{st}");
    let missing = st["missing"].as_u64().unwrap() as usize;
    assert!(missing > 0 && missing <= 50 - at_kill + 1, "{st}");
    assert_eq!(st["missing_units"].as_array().unwrap().len(), missing);
    // Other rotations (a different job) are refused before anything is written.
    let before = tree(&d.path("sh"));
    let mut other = relight_args("sh", Some(1));
    other[7] = "50".into();
    let err = d.fails(&other.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(err.contains("rotations: was 100, now 50"), "{err}");
    assert!(tree(&d.path("sh")) == before, "a refused writer changed the output");
    // So is another environment map behind the same path (the original moved aside and
    // back: a rename keeps its size and modification time).
    std::fs::rename(d.path("sky.exr"), d.path("sky.orig")).unwrap();
    crate::relight::write_env(&d.path("sky.exr"), |_, _| [0.5; 3]);
    let mine = relight_args("sh", Some(1));
    let err = d.fails(&mine.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(err.contains("inputs.--env 1"), "{err}");
    assert!(tree(&d.path("sh")) == before, "a refused writer changed the output");
    std::fs::rename(d.path("sky.orig"), d.path("sky.exr")).unwrap();
    let err = d.fails(&["finalize", "sh"]);
    assert!(err.contains("cannot finalise") && err.contains("white_r"), "{err}");
    // A truncated frame of shard 1 is corrupt (its PNG does not decode), named by status.
    let bytes = std::fs::read(frame(50)).unwrap();
    std::fs::write(frame(50), &bytes[..bytes.len() / 2]).unwrap();
    let st = status_json(&d, "sh");
    assert_eq!(
        (st["corrupt"].as_u64(), st["shards"][1]["state"].as_str()),
        (Some(1), Some("corrupt"))
    );
    assert!(st["corrupt_units"][0]["unit"] == "white_r050.png", "{st}");
    // Restarted, the shard renders only what is missing or corrupt.
    wait_ok(run(1, 0), "restarted shard 1");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path("sh/shards/summary-1-of-4.json")).unwrap())
            .unwrap();
    assert_eq!(summary["frames_rendered"].as_u64(), Some(missing as u64 + 1), "{summary}");
    // What a shard killed inside a write leaves (a temporary name) is swept by finalize.
    std::fs::write(d.path("sh/.white_r050.png.tmp-4242123"), "half a frame").unwrap();
    d.ok(&["finalize", "sh"]);
    let out = d.ok(&["finalize", "sh"]);
    assert!(out.contains("already finalised"), "{out}");
    let st = status_json(&d, "sh");
    assert_eq!((st["complete"].as_bool(), st["finalised"].as_bool()), (Some(true), Some(true)));
    // Byte for byte the single-process folder (frames, EXRs, job.json, the visibility
    // cache), except summary.json, which holds timings (and, sharded, every shard's).
    let (a, b) = (tree(&d.path("single")), tree(&d.path("sh")));
    assert_eq!(a.keys().filter(|k| k.ends_with(".png")).count(), 200);
    assert_eq!(a.keys().filter(|k| k.ends_with(".exr")).count(), 200);
    assert_same_tree(
        &a,
        &b,
        |name, bytes| {
            if name == "summary.json" { Vec::new() } else { bytes.to_vec() }
        },
    );
    let merged: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path("sh/summary.json")).unwrap()).unwrap();
    assert_eq!(merged["frames"], 200);
    assert_eq!(merged["shards"].as_array().unwrap().len(), 4);
}

#[test]
fn synth_material_in_four_shards_matches_one_process_and_refuses_another_kind() {
    let d = Dir::new();
    let base = ["synth", "material", "--kind", "woven", "--size", "4"];
    let with = |extra: &[&str]| -> Vec<String> {
        base.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let single = with(&["-o", "one.btf"]);
    d.ok(&single.iter().map(String::as_str).collect::<Vec<_>>());
    let children: Vec<Child> = (0..4)
        .map(|i| {
            let a = with(&["-o", "sh.btf", "--shard", &format!("{i}/4")]);
            spawn(&d, &a.iter().map(String::as_str).collect::<Vec<_>>(), 0)
        })
        .collect();
    for (i, c) in children.into_iter().enumerate() {
        wait_ok(c, &format!("shard {i}"));
    }
    let st = status_json(&d, "sh.btf");
    assert_eq!((st["kind"].as_str(), st["done"].as_u64()), (Some("synth"), Some(81)), "{st}");
    let before = tree_with_partial(&d, "sh.btf");
    let err = d.fails(&[
        "synth", "material", "--kind", "lambert", "--size", "4", "-o", "sh.btf", "--shard", "0/4",
    ]);
    assert!(err.contains("meta.provenance.kind: was \"woven\", now \"lambert\""), "{err}");
    assert!(tree_with_partial(&d, "sh.btf") == before, "a refused writer changed the output");
    d.ok(&["finalize", "sh.btf"]);
    assert!(d.ok(&["finalize", "sh.btf"]).contains("already finalised"));
    // No timings in a BTF store: every byte is the single-process store's.
    assert!(tree(&d.path("one.btf")) == tree(&d.path("sh.btf")));
}

#[test]
fn relight_with_eigenweightsets_in_four_shards_matches_one_process() {
    // Each environment's error report goes with its first frame's shard; the frames do not
    // depend on which shard ran when (every vertex side's visibility is computed).
    let d = setup();
    std::fs::write(d.path("sphere.obj"), crate::relight::sphere(16, 8)).unwrap();
    let s = scene("per-vertex", "sky.exr", "").replace("plane.obj", "sphere.obj").replace(
        "visibility_res = 16",
        "visibility_res = 16\neigenweightsets = { rotations = 12, components = 3 }",
    );
    std::fs::write(d.path("s.toml"), s).unwrap();
    let args = |shard: Option<usize>| {
        let mut a: Vec<String> =
            ["relight", "s.toml", "--env", "sky.exr", "--env", "white.exr", "--rotations", "6"]
                .map(String::from)
                .to_vec();
        a.extend(["-o".into(), "sh".into()]);
        if let Some(i) = shard {
            a.extend(["--shard".to_string(), format!("{i}/4")]);
        }
        a
    };
    if run_gpu(&d, &args(None).iter().map(String::as_str).collect::<Vec<_>>()).is_none() {
        return;
    }
    std::fs::rename(d.path("sh"), d.path("single")).unwrap();
    let children: Vec<Child> = (0..4)
        .map(|i| spawn(&d, &args(Some(i)).iter().map(String::as_str).collect::<Vec<_>>(), 0))
        .collect();
    for (i, c) in children.into_iter().enumerate() {
        wait_ok(c, &format!("shard {i}"));
    }
    d.ok(&["finalize", "sh"]);
    let (a, b) = (tree(&d.path("single")), tree(&d.path("sh")));
    for report in ["eigen/sky-error.csv", "eigen/white-error.csv", "eigen/sky-heat-e8.png"] {
        assert!(a.contains_key(report), "{report}");
    }
    assert_same_tree(
        &a,
        &b,
        |name, bytes| {
            if name == "summary.json" { Vec::new() } else { bytes.to_vec() }
        },
    );
}

#[test]
fn capture_process_in_three_shards_matches_one_process() {
    // 5 view slots (the pole and a ring of 4) over 3 shards: blocks of 1, 2 and 2 slots.
    let d = Dir::new();
    let synth = ["synth", "capture", "--material", "lambert", "--sampling", "rings:0x1,45x4"];
    d.ok(&[&synth[..], &["-o", "raw"]].concat());
    d.ok(&["capture", "process", "raw", "-o", "one.btf", "--size", "32"]);
    let children: Vec<Child> = (0..3)
        .map(|i| {
            let shard = format!("{i}/3");
            let a =
                ["capture", "process", "raw", "-o", "sh.btf", "--size", "32", "--shard", &shard];
            spawn(&d, &a, 0)
        })
        .collect();
    for (i, c) in children.into_iter().enumerate() {
        wait_ok(c, &format!("shard {i}"));
    }
    let before = tree_with_partial(&d, "sh.btf");
    let err =
        d.fails(&["capture", "process", "raw", "-o", "sh.btf", "--size", "16", "--shard", "1/3"]);
    assert!(err.contains("job.options: was") && err.contains("size: 32"), "{err}");
    assert!(tree_with_partial(&d, "sh.btf") == before, "a refused writer changed the output");
    let shards = status_json(&d, "sh.btf")["shards"].clone();
    let units: Vec<u64> =
        shards.as_array().unwrap().iter().map(|s| s["done"].as_u64().unwrap()).collect();
    assert_eq!(units, [1, 2, 2]);
    d.ok(&["finalize", "sh.btf"]);
    // Every byte, the provenance with every slot's registration and plate tilt included.
    assert!(tree(&d.path("one.btf")) == tree(&d.path("sh.btf")));
}
