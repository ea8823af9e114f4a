//! Class 11: a resume never mixes jobs. A partial store records the job that began it
//! (metadata, parameters, input identity); `--resume` by another job is refused naming the
//! first field that differs, and a killed writer's temporary files are swept when the
//! store is committed.

use crate::hostile::{assert_no_panic, fixture, snapshot};
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization};
use btf_core::store::BtfStore;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Starts `btf ARGS` in `dir` and kills it with SIGKILL once `marker` exists.
pub fn kill_when(dir: &std::path::Path, args: &[&str], marker: &std::path::Path) -> bool {
    let mut child = Command::new(env!("CARGO_BIN_EXE_btf"))
        .args(args)
        .current_dir(dir)
        .env("BTF_NO_PROGRESS", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !marker.exists() && t0.elapsed() < Duration::from_secs(60) {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    let _ = child.wait();
    true
}

#[test]
fn synth_material_resume_refuses_another_kind() {
    let d = crate::common::Dir::new();
    let args = [
        "synth",
        "material",
        "--kind",
        "corduroy",
        "--size",
        "48",
        "--sampling",
        "rings:0x1,45x8,75x8",
        "-o",
        "M.btf",
    ];
    let killed = kill_when(d.tmp.path(), &args, &d.path("M.btf.partial/normtextures/c.0.0.0.0.0"));
    assert!(killed, "the run ended before it could be interrupted");
    assert!(d.path("M.btf.partial").is_dir());
    let err = d.fails(&[
        "synth",
        "material",
        "--kind",
        "lambert",
        "--size",
        "48",
        "--sampling",
        "rings:0x1,45x8,75x8",
        "--resume",
        "-o",
        "M.btf",
    ]);
    assert_no_panic(&err);
    assert!(err.contains("different job") && err.contains("provenance.kind"), "{err}");
    assert!(err.contains("\"corduroy\"") && err.contains("\"lambert\""), "{err}");
    // The same job resumes and gives the bytes of an uninterrupted run.
    let mut resume = args.to_vec();
    resume.push("--resume");
    d.ok(&resume);
    let clean = crate::common::Dir::new();
    clean.ok(&args);
    assert_eq!(snapshot(&d.path("M.btf")), snapshot(&clean.path("M.btf")));
}

fn partial_from(d: &crate::common::Dir, input: &str, out: &str) {
    let store = BtfStore::open(&d.path(input)).unwrap();
    let meta =
        EigenMeta { btf: store.meta().clone(), components: 2, quantization: Quantization::F16 };
    let job = serde_json::json!({ "input": btf_core::fs::input_identity(&d.path(input)) });
    drop(EigenWriter::create_for_job(&d.path(out), meta, false, job).unwrap());
}

#[test]
fn compress_resume_refuses_another_input_and_sweeps_temporaries() {
    let d = fixture();
    // The same store content under another name: only the input identity differs.
    crate::hostile::copy_dir(&d.path("A.btf"), &d.path("A2.btf"));
    partial_from(&d, "A.btf", "O.eig");
    let err = d.fails(&["compress", "A2.btf", "-c", "2", "--resume", "-o", "O.eig"]);
    assert!(err.contains("different job") && err.contains("job.input"), "{err}");
    // Other parameters: a different component count.
    let err = d.fails(&["compress", "A.btf", "-c", "3", "--resume", "-o", "O.eig"]);
    assert!(err.contains("meta.components"), "{err}");
    // The same job resumes; a temporary file a killed writer left is swept at commit.
    let tmp = d.path("O.eig.partial/mean/.c.0.0.0.0.tmp-99999");
    std::fs::create_dir_all(tmp.parent().unwrap()).unwrap();
    std::fs::write(&tmp, "half a chunk").unwrap();
    d.ok(&["compress", "A.btf", "-c", "2", "--resume", "-o", "O.eig"]);
    let files = snapshot(&d.path("O.eig"));
    assert!(files.keys().all(|k| !k.contains(".tmp-")), "{:?}", files.keys().collect::<Vec<_>>());
    // A partial that records no job (say, from an older version) is not resumed.
    std::fs::rename(d.path("O.eig"), d.path("P.eig.partial")).unwrap();
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path("P.eig.partial/zarr.json")).unwrap()).unwrap();
    doc["attributes"].as_object_mut().unwrap().remove("partial_job");
    std::fs::write(d.path("P.eig.partial/zarr.json"), doc.to_string()).unwrap();
    let err = d.fails(&["compress", "A.btf", "-c", "2", "--resume", "-o", "P.eig"]);
    assert!(err.contains("records no job"), "{err}");
}

#[test]
fn synth_capture_refuses_to_mix_with_another_capture() {
    let d = crate::common::Dir::new();
    let base = [
        "synth",
        "capture",
        "--material",
        "lambert",
        "--size",
        "8",
        "--sampling",
        "rings:0x1",
        "--resolution",
        "64,48",
        "--out",
        "raw",
    ];
    d.ok(&base);
    let mut other = base.to_vec();
    other.extend(["--seed", "9"]);
    let before = snapshot(&d.path("raw"));
    let err = d.fails(&other);
    assert!(err.contains("different capture") && err.contains("seed"), "{err}");
    assert_eq!(snapshot(&d.path("raw")), before);
    d.ok(&base);
}
