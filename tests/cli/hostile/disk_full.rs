//! Class 9: a full disk. On a small tmpfs filled to the last byte, every writer exits
//! non-zero, leaves the previous file untouched and no temporary file behind.
//!
//! Needs `mount` (root, as in CI); elsewhere the test says so and passes vacuously only
//! when not root.

use crate::hostile::{assert_no_panic, fixture, leftovers, snapshot};
use std::path::{Path, PathBuf};
use std::process::Command;

struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(at: &Path, kib: u32) -> Option<Tmpfs> {
        let root = Command::new("id").arg("-u").output().ok()?;
        if String::from_utf8_lossy(&root.stdout).trim() != "0" {
            eprintln!("disk_full: not root, cannot mount a tmpfs; skipped");
            return None;
        }
        std::fs::create_dir_all(at).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kib}k"), "tmpfs"])
            .arg(at)
            .status()
            .unwrap()
            .success();
        assert!(ok, "root but mount -t tmpfs failed");
        Some(Tmpfs(at.to_owned()))
    }

    /// Fills the file system to its last byte.
    fn fill(&self) {
        use std::io::Write;
        let mut f = std::fs::File::create(self.0.join("filler")).unwrap();
        let block = vec![0u8; 4096];
        while f.write_all(&block).is_ok() {}
        let one = [0u8; 1];
        while f.write_all(&one).is_ok() {}
        let _ = f.flush();
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.0).status();
    }
}

#[test]
fn writers_on_a_full_disk_fail_and_keep_the_previous_output() {
    let d = fixture();
    let Some(fs) = Tmpfs::mount(&d.path("full"), 2048) else { return };
    // Previous outputs, made while there was room.
    d.ok(&["synth", "mesh", "--kind", "plane", "-o", "full/m.obj"]);
    d.ok(&["synth", "env", "--kind", "sky", "--width", "16", "-o", "full/e.exr"]);
    d.ok(&["export", "A.btf", "--format", "npy", "--slot", "0", "-o", "full/s.npy"]);
    d.ok(&["compress", "A.btf", "-c", "2", "-o", "full/C.eig"]);
    d.ok(&["reconstruct", "B.eig", "--view", "0,0", "--light", "0,0", "-o", "full/r.exr"]);
    let gpu = crate::hostile::gpu_available();
    if gpu {
        d.ok(&["render", "s.toml", "-o", "full/o.png"]);
    }
    let before = snapshot(&d.path("full"));
    fs.fill();
    let filler = before.len();
    let mut cases: Vec<Vec<&str>> = vec![
        vec!["synth", "mesh", "--kind", "sphere", "-o", "full/m.obj"],
        vec!["synth", "env", "--kind", "studio", "--width", "32", "-o", "full/e.exr"],
        vec!["export", "A.btf", "--format", "npy", "--slot", "1", "-o", "full/s.npy"],
        vec!["compress", "A.btf", "-c", "3", "-o", "full/C.eig"],
        vec!["reconstruct", "B.eig", "--view", "30,0", "--light", "0,0", "-o", "full/r.exr"],
        vec![
            "synth",
            "material",
            "--kind",
            "lambert",
            "--size",
            "8",
            "--sampling",
            "rings:0x1",
            "-o",
            "full/N.btf",
        ],
    ];
    if gpu {
        cases.push(vec!["render", "s.toml", "-o", "full/o.png", "--width", "24"]);
    }
    for args in &cases {
        let o = d.btf(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "btf {args:?} succeeded on a full disk");
        assert_no_panic(&err);
        assert!(err.contains("No space left") || err.contains("space"), "btf {args:?}: {err}");
        let mut now = snapshot(&d.path("full"));
        now.remove("filler");
        assert_eq!(now, before, "btf {args:?} changed what was on the disk");
        let left: Vec<String> =
            leftovers(&d.path("full")).into_iter().filter(|p| !p.ends_with(".partial")).collect();
        assert!(left.is_empty(), "btf {args:?} left {left:?}");
    }
    let _ = filler;
}
