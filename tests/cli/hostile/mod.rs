//! The hostile suite (issue #26): every rule about what a command may do to files, run
//! against every command it applies to, end to end through the `btf` binary.
//!
//! One module per class of fault: outputs that are inputs ([`overlap`]), sizes claimed by
//! headers and metadata ([`claims`], with each refusal's peak memory), replacing what
//! the toolkit did not make ([`replace`]), leftovers after a refusal ([`leftovers`]),
//! non-finite values ([`nonfinite`]), extreme finite values ([`extreme`]), panics
//! ([`panics`]), a full disk ([`disk_full`]), resumes of another job ([`resume`]) and
//! `kill -9` in the middle of a write ([`kill`]); the knit commands under all of them
//! ([`knit`]). Each test asserts what survives
//! (a snapshot of the input's bytes) and what the message names.

use crate::common;

mod claims;
mod disk_full;
mod extreme;
mod kill;
mod knit;
mod leftovers;
mod nonfinite;
mod overlap;
mod panics;
mod replace;
mod resume;

use common::Dir;
use std::collections::BTreeMap;
use std::path::Path;

/// Every file below `root` (relative path → bytes); a folder's snapshot.
pub fn snapshot(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    if root.is_file() {
        out.insert(String::new(), std::fs::read(root).unwrap());
        return out;
    }
    let mut stack = vec![root.to_owned()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// Names in `dir` that a failed run must not leave: partial stores and temporary files.
pub fn leftovers(dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".partial")
                || btf_core::fs::is_temp_name(&name)
                || name.contains(".tmp")
            {
                bad.push(e.path().display().to_string());
            }
            if e.path().is_dir() {
                stack.push(e.path());
            }
        }
    }
    bad
}

/// A folder with a small BTF store `A.btf` (5 × 5 directions, 8² texels), its eigen store
/// `B.eig` (c = 2), a plane mesh and a scene `s.toml` that renders `B.eig` on it.
pub fn fixture() -> Dir {
    let d = Dir::new();
    d.ok(&[
        "synth",
        "material",
        "--kind",
        "corduroy",
        "--size",
        "8",
        "--sampling",
        "rings:0x1,45x4",
        "-o",
        "A.btf",
    ]);
    d.ok(&["compress", "A.btf", "-c", "2", "-o", "B.eig"]);
    std::fs::write(d.path("plane.obj"), common_plane()).unwrap();
    std::fs::write(d.path("s.toml"), scene_toml("")).unwrap();
    d
}

/// A unit square in the xy-plane with UVs.
pub fn common_plane() -> &'static str {
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
}

/// The fixture's scene with `extra` appended (more lights, say).
pub fn scene_toml(extra: &str) -> String {
    format!(
        "[output]\nwidth = 16\nheight = 16\n[[meshes]]\npath = \"plane.obj\"\n[[materials]]\nstore = \"B.eig\"\n\
         [camera]\neye = [0.5, 0.5, 2.0]\ntarget = [0.5, 0.5, 0.0]\n[[lights]]\nkind = \"directional\"\n\
         direction = [0.2, 0.3, 1.0]\nirradiance = [2.0, 2.0, 2.0]\n{extra}"
    )
}

/// The GPU is needed for this test: with `BTF_REQUIRE_GPU=1` (CI) always run it; otherwise
/// only where an adapter exists.
pub fn gpu_available() -> bool {
    if std::env::var("BTF_REQUIRE_GPU").is_ok_and(|v| v == "1") {
        return true;
    }
    btf_render::Gpu::new().is_ok()
}

/// No line of `stderr` tells of a panic or an abort.
pub fn assert_no_panic(stderr: &str) {
    for bad in ["panicked", "RUST_BACKTRACE", "memory allocation of", "SIGABRT"] {
        assert!(!stderr.contains(bad), "a panic or abort: {stderr}");
    }
}

/// Copies a folder tree.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let t = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), t).unwrap();
        }
    }
}
