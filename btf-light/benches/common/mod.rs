//! Shared fixtures of btf-light's benches (no GPU): the synthetic shirt and sky, a small
//! checker eigen store with its coefficient matrix, criterion's modest defaults, and
//! [`Samples`], where the timed closures leave every measured value so that a bench's
//! `main` can print its table (markdown) after criterion.
#![allow(dead_code)]

use btf_core::Sampling;
use btf_core::eigen::{EigenMeta, EigenSlot, EigenStore, EigenWriter, Quantization};
use btf_core::eigen::{QuantizedSlot, quantize};
use btf_core::store::BtfMeta;
use btf_image::EnvMap;
use btf_light::CoefficientMatrix;
use btf_light::mesh::Mesh;
use criterion::Criterion;
use datasets::mesh::{MeshKind, Resolution};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::f32::consts::TAU;
use std::path::Path;
use std::rc::Rc;
use std::time::{Duration, Instant};

/// The synthetic shirt: low (925 vertices), or high (9160) with `BTF_MEASURE_HIGH=1`.
pub fn shirt(dir: &Path) -> (&'static str, Mesh) {
    let (name, res) = if env_flag("BTF_MEASURE_HIGH") {
        ("shirt high", Resolution::High)
    } else {
        ("shirt low", Resolution::Low)
    };
    let m = datasets::mesh::synth_mesh(MeshKind::Shirt, res).unwrap();
    let p = dir.join("shirt.obj");
    datasets::mesh::write_obj(&m, &p, "shirt").unwrap();
    (name, Mesh::load_obj(&p, None).unwrap())
}

/// The synthetic Preetham sky with sun, 512×256.
pub fn sky() -> EnvMap {
    let params = datasets::env::EnvParams::default();
    let m = datasets::env::synth_env(datasets::env::EnvKind::Sky, &params, 512).unwrap();
    EnvMap::new(m.width, m.height, m.pixels, "sky").unwrap()
}

/// A `w × h` checker eigen store with `ubo81` samplings and `c` components (f16), written
/// to `dir/m.eigen`, and its coefficient matrix `P` (plain weights, no bias).
pub fn store(dir: &Path, (w, h): (usize, usize), c: usize) -> (EigenStore, CoefficientMatrix) {
    let q = Quantization::F16;
    let views = Sampling::ubo81();
    let lights = Sampling::ubo81();
    let meta = EigenMeta {
        btf: BtfMeta::new(views.clone(), lights.clone(), w, h),
        components: c,
        quantization: q,
    };
    let path = dir.join("m.eigen");
    let writer = EigenWriter::create(&path, meta, false).unwrap();
    for j in 0..views.len() {
        let vd = views.direction(j).to_vector();
        let mut mean = vec![0f32; w * h * 3];
        let mut basis = vec![0f32; c * w * h * 3];
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
                let s = 0.5 + 0.3 * (TAU * fx * 2.0).sin() * (TAU * fy * 3.0).cos();
                let t = (y * w + x) * 3;
                for ch in 0..3 {
                    mean[t + ch] = 0.2 * s * (1.0 + 0.3 * vd[2] as f32) * [1.0, 0.8, 0.6][ch];
                    for k in 0..c {
                        let pk = (TAU
                            * (fx * (k % 3 + 1) as f32 + fy * (k / 3) as f32 + 0.1 * ch as f32))
                            .cos();
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
    let store = EigenStore::open(&path).unwrap();
    let slots: Vec<EigenSlot> =
        (0..store.view_sampling().len()).map(|j| store.read_slot(j).unwrap()).collect();
    let p = CoefficientMatrix::from_slots(&slots, store.light_sampling().len(), c);
    (store, p)
}

/// `true` when the environment variable `name` is `1`.
pub fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| v == "1")
}

/// Criterion with modest defaults (10 flat samples are set per group; 1 s warm-up, 4 s
/// measurement, no plots); the command line (`--quick`, filters …) overrides them.
pub fn criterion() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .without_plots()
        .configure_from_args()
}

/// Milliseconds since `t`.
pub fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Times `iters` runs of `f` (its wall time), each also recorded as `case` in `samples`.
pub fn timed<T>(iters: u64, samples: &Samples, case: &str, mut f: impl FnMut() -> T) -> Duration {
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        let t = Instant::now();
        std::hint::black_box(f());
        let d = t.elapsed();
        samples.push(case, d.as_secs_f64() * 1e3);
        total += d;
    }
    total
}

/// What the timed closures measured (ms), per case. Cheap to clone (shared).
#[derive(Clone, Default)]
pub struct Samples(Rc<RefCell<BTreeMap<String, Vec<f64>>>>);

impl Samples {
    /// Records one value for `case`.
    pub fn push(&self, case: &str, v: f64) {
        self.0.borrow_mut().entry(case.to_string()).or_default().push(v);
    }

    /// The median of `case` (`None` when it did not run, e.g. filtered out).
    pub fn median(&self, case: &str) -> Option<f64> {
        Some(median(self.0.borrow().get(case)?.clone()))
    }

    /// How many values of `case` were recorded.
    pub fn count(&self, case: &str) -> usize {
        self.0.borrow().get(case).map_or(0, Vec::len)
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
