//! Shared fixtures of btf-render's benches: the synthetic eigen store of the GPU tests, the
//! GPU guard (no adapter: a clear line and exit 0), criterion's modest defaults, and
//! [`Samples`], where the timed closures leave every measured value so that a bench's
//! `main` can print its ratio table (markdown) after criterion.
#![allow(dead_code)]

use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenWriter, Quantization, QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_render::{Gpu, Renderer};
use criterion::Criterion;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::f32::consts::TAU;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::Duration;

/// Spatial pattern of the synthetic material.
#[derive(Clone, Copy, PartialEq)]
pub enum Pattern {
    /// Ribs: varies along texture x only.
    Ribs,
    /// Texture-varying in x and y, smooth in view and light.
    Checker,
}

/// Writes an eigen store with `ubo81` samplings and `c` components (the GPU tests' store:
/// `μ_j + Σ_k p_ikj B_kj` with smooth dependence on both directions).
pub fn write_store(
    dir: &Path,
    name: &str,
    pattern: Pattern,
    w: usize,
    h: usize,
    c: usize,
    q: Quantization,
) -> PathBuf {
    let views = Sampling::ubo81();
    let lights = Sampling::ubo81();
    let meta = EigenMeta {
        btf: BtfMeta::new(views.clone(), lights.clone(), w, h),
        components: c,
        quantization: q,
    };
    let path = dir.join(name);
    let writer = EigenWriter::create(&path, meta, false).unwrap();
    for j in 0..views.len() {
        let vd = views.direction(j).to_vector();
        let mut mean = vec![0f32; w * h * 3];
        let mut basis = vec![0f32; c * w * h * 3];
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
                let s = match pattern {
                    Pattern::Ribs => 0.5 + 0.4 * (TAU * fx * 4.0).cos(),
                    Pattern::Checker => 0.5 + 0.3 * (TAU * fx * 2.0).sin() * (TAU * fy * 3.0).cos(),
                };
                let t = (y * w + x) * 3;
                for ch in 0..3 {
                    mean[t + ch] = 0.2 * s * (1.0 + 0.3 * vd[2] as f32) * [1.0, 0.8, 0.6][ch];
                    for k in 0..c {
                        let pk = match pattern {
                            Pattern::Ribs => {
                                (TAU * (fx * (k % 3 + 1) as f32 + 0.1 * ch as f32)).cos()
                            }
                            Pattern::Checker => (TAU
                                * (fx * (k % 3 + 1) as f32
                                    + fy * (k / 3) as f32
                                    + 0.1 * ch as f32))
                                .cos(),
                        };
                        basis[k * w * h * 3 + t + ch] =
                            0.15 * pk * (1.0 + 0.5 * vd[0] as f32) / (1.0 + k as f32);
                    }
                }
            }
        }
        let mut weights = vec![0f32; lights.len() * c];
        for i in 0..lights.len() {
            let ld = lights.direction(i).to_vector();
            for k in 0..c {
                weights[i * c + k] = (ld[2] as f32 * 2.0 - 1.0) * (1.0 + k as f32 * 0.1)
                    + (ld[0] as f32 * (k + 1) as f32).sin()
                    + 0.5 * ld[1] as f32 * ((k % 2) as f32 - 0.5);
            }
        }
        let (eigentextures, scale_offset) = quantize(&basis, c, q);
        let slot = QuantizedSlot {
            mean,
            eigentextures,
            scale_offset,
            weights,
            eigenvalues: vec![1.0; lights.len()],
        };
        writer.write_slot(j, &slot).unwrap();
    }
    writer.finish().unwrap();
    path
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The example sphere-over-plane mesh (`examples/scenes/sphere-on-plane.obj`) copied into
/// `dir` as `mesh.obj`.
pub fn sphere_on_plane(dir: &Path) -> PathBuf {
    let obj = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/sphere-on-plane.obj"
    ))
    .unwrap();
    write(dir, "mesh.obj", &obj)
}

/// A device, or `None` after printing why nothing is measured (the bench then exits 0).
pub fn gpu_or_skip(bench: &str) -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => {
            let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
            let load = load.split_whitespace().take(3).collect::<Vec<_>>().join(" ");
            println!(
                "{bench}: adapter {} ({:?}, {}), pass timing {}; load average {load}",
                g.info.name,
                g.info.device_type,
                g.info.driver,
                if g.timestamps { "gpu-timestamps" } else { "cpu" }
            );
            Some(g)
        }
        Err(e) => {
            println!("{bench}: no GPU adapter ({e}); nothing measured");
            None
        }
    }
}

/// `true` when the environment variable `name` is `1`.
pub fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v == "1")
}

/// The environment variable `name` parsed, or `default`.
pub fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|s| s.trim().parse().ok()).unwrap_or(default)
}

/// Criterion with modest defaults for lavapipe (10 samples, 1 s warm-up, 4 s measurement,
/// no plots); the command line (`--quick`, filters, `--sample-size` …) overrides them.
pub fn criterion() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .without_plots()
        .configure_from_args()
}

/// What the timed closures measured, per case, in insertion order: every sample of each
/// named quantity (ms unless said otherwise). Cheap to clone (shared).
#[derive(Clone, Default)]
pub struct Samples(Rc<RefCell<BTreeMap<String, Vec<f64>>>>);

impl Samples {
    /// Records one value of `quantity` for `case`.
    pub fn push(&self, case: &str, quantity: &str, v: f64) {
        self.0.borrow_mut().entry(format!("{case}\u{1f}{quantity}")).or_default().push(v);
    }

    /// The median of `quantity` of `case` (`None` when the case did not run, e.g. filtered).
    pub fn median(&self, case: &str, quantity: &str) -> Option<f64> {
        let map = self.0.borrow();
        let v = map.get(&format!("{case}\u{1f}{quantity}"))?;
        Some(median(v.clone()))
    }

    /// How many values of `quantity` of `case` were recorded.
    pub fn count(&self, case: &str, quantity: &str) -> usize {
        self.0.borrow().get(&format!("{case}\u{1f}{quantity}")).map_or(0, Vec::len)
    }
}

/// Median (`NaN` of nothing).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// `a / b` formatted with `digits`, or `—` when either is missing.
pub fn ratio(a: Option<f64>, b: Option<f64>, digits: usize) -> String {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.*}", digits, a / b),
        _ => "—".into(),
    }
}

/// `v` formatted with `digits`, or `—`.
pub fn num(v: Option<f64>, digits: usize) -> String {
    v.map_or("—".into(), |v| format!("{v:.digits$}"))
}

/// Times `iters` frames of `r` for criterion by their `Stats::frame_ms` (per-frame CPU
/// work, encoding and GPU execution; the read-back of the image is not included), each
/// frame also recorded as `frame` of `case` in `samples` (warm-up frames included).
pub fn time_frames(
    iters: u64,
    gpu: &Gpu,
    r: &mut Renderer,
    samples: &Samples,
    case: &str,
) -> Duration {
    let mut total = 0.0;
    for _ in 0..iters {
        let f = r.render(gpu).unwrap();
        total += f.stats.frame_ms;
        samples.push(case, "frame", f.stats.frame_ms);
    }
    Duration::from_secs_f64(total / 1e3)
}
