//! A tiny harness for end-to-end tests of the `btf` binary: a temporary folder, a runner
//! that captures output, and small stores with known content.

use btf_core::store::{BtfMeta, BtfWriter};
use btf_core::zarr::DType;
use btf_core::{Ring, Sampling};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A temporary working folder.
pub struct Dir {
    pub tmp: tempfile::TempDir,
}

impl Dir {
    pub fn new() -> Self {
        Dir { tmp: tempfile::tempdir().unwrap() }
    }
    pub fn path(&self, name: &str) -> PathBuf {
        self.tmp.path().join(name)
    }
    /// Runs `btf ARGS` in the folder.
    pub fn btf(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_btf"))
            .args(args)
            .current_dir(self.tmp.path())
            .env("BTF_NO_PROGRESS", "1")
            .output()
            .expect("btf runs")
    }
    /// Runs and expects success; returns stdout.
    pub fn ok(&self, args: &[&str]) -> String {
        let o = self.btf(args);
        assert!(
            o.status.success(),
            "btf {args:?} failed:\n{}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    }
    /// Runs and expects failure; returns stderr.
    pub fn fails(&self, args: &[&str]) -> String {
        let o = self.btf(args);
        assert!(!o.status.success(), "btf {args:?} should have failed");
        String::from_utf8(o.stderr).unwrap()
    }
}

/// A small sampling: the pole and a ring of 6 at 40°.
pub fn small_sampling() -> Sampling {
    Sampling::new(
        "custom",
        vec![
            Ring { theta_deg: 0.0, count: 1, phi_offset_deg: 0.0 },
            Ring { theta_deg: 40.0, count: 6, phi_offset_deg: 0.0 },
        ],
    )
    .unwrap()
}

/// The value of texel value `t` of image `(view, light)` in the test BTF: a few smooth
/// modes that vary with the light plus a view-dependent tint.
pub fn value(view: usize, light: usize, t: usize) -> f32 {
    let l = light as f32;
    let x = t as f32;
    0.3 + 0.1 * view as f32
        + 0.2 * (0.7 * l + 0.05 * x).cos()
        + 0.1 * (1.3 * l).sin() * (0.11 * x).sin()
        + 0.02 * ((l * 7.0 + x * 3.0) % 5.0)
}

/// Writes the test BTF (`size × size` texels) to `path`.
pub fn write_test_btf(path: &Path, size: usize) {
    write_test_btf_as(path, size, DType::F32)
}

/// [`write_test_btf`] with values stored as `dtype`.
pub fn write_test_btf_as(path: &Path, size: usize, dtype: DType) {
    let s = small_sampling();
    let meta = BtfMeta::new(s.clone(), s, size, size);
    let w = BtfWriter::create(path, meta, dtype, false).unwrap();
    let n = size * size * 3;
    for v in 0..7 {
        for l in 0..7 {
            let img: Vec<f32> = (0..n).map(|t| value(v, l, t)).collect();
            w.write_image(v, l, &img).unwrap();
        }
    }
    w.finish().unwrap();
}

/// Reads a float32 RGB EXR into `(w, h, [y][x][rgb])`.
pub fn read_exr(path: &Path) -> (usize, usize, Vec<f32>) {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![0f32; res.width() * res.height() * 3]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = (pos.y() * *w + pos.x()) * 3;
            px[i] = r;
            px[i + 1] = g;
            px[i + 2] = b;
        },
    )
    .unwrap();
    let size = img.layer_data.size;
    (size.width(), size.height(), img.layer_data.channel_data.pixels.1)
}
