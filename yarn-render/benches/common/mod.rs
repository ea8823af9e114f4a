//! What the `lights`, `hairs` and `fiber_shadows` benches share: per-case frame times with their medians,
//! and the scene (Crane's 22 × 22-stitch plain knit in cotton-2ply, not periodic, 3 872
//! control points, seen whole by the orthographic camera of the `fibers` bench).

use criterion::{Criterion, SamplingMode};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;
use std::time::Duration;
use std::time::Instant;
use yarn::YarnParams;
use yarn::knit::crane::CraneKnit;
use yarn_render::{FiberCamera, FiberLight, FiberRenderer, FiberStats, PackOptions, PackedYarns};

/// Per-case frame times (ms), for the medians after criterion.
#[derive(Clone, Default)]
pub struct Samples(Rc<RefCell<BTreeMap<String, Vec<f64>>>>);

impl Samples {
    /// Records one frame of `key`.
    pub fn push(&self, key: &str, v: f64) {
        self.0.borrow_mut().entry(key.to_string()).or_default().push(v);
    }

    /// The median of `key`'s frames (NaN without any).
    pub fn median(&self, key: &str) -> f64 {
        let mut v = self.0.borrow().get(key).cloned().unwrap_or_default();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n == 0 {
            return f64::NAN;
        }
        if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
    }
}

/// The patch, its yarn and the whole-patch camera: (packed, params, camera, centre, span).
pub fn crane_scene() -> (PackedYarns, YarnParams, FiberCamera, [f64; 3], f64) {
    let p = YarnParams::preset("cotton-2ply").unwrap();
    let k = CraneKnit::for_yarn_radius(p.yarn_radius());
    let mut set = k.yarn_set(22, 22, 8).unwrap();
    set.period = None;
    let packed = PackedYarns::new(&set, std::slice::from_ref(&p), &PackOptions::default()).unwrap();
    let (lo, hi) = packed.bounds;
    let c = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (s, co) = 35f64.to_radians().sin_cos();
    let d = 2.0 * span;
    let cam = FiberCamera::orthographic(
        [c[0], c[1] - d * s, c[2] + d * co],
        c,
        [0.0, 1.0, 0.0],
        1.1 * span,
    );
    (packed, p, cam, c, span)
}

/// The perspective close-up of the `hairs` and `fiber_shadows` benches: a fifth of the
/// patch across (centre `c`, span `span`), from 0.35 patch widths away, 35° off the normal.
#[allow(dead_code)] // the lights bench has no close-up
pub fn close_camera(c: [f64; 3], span: f64) -> FiberCamera {
    let (s, co) = 35f64.to_radians().sin_cos();
    let e = 0.35 * span;
    FiberCamera::perspective([c[0], c[1] - e * s, c[2] + e * co], c, [0.0, 0.0, 1.0], 30.0)
}

/// One case of the `hairs` and `fiber_shadows` benches: a renderer, the camera it draws
/// from (an index into the bench's cameras) and the case its frame time is a ratio to.
#[allow(dead_code)] // the `lights` bench varies lights, not cameras: its own cases
pub struct Case {
    /// Criterion id and table row.
    pub name: &'static str,
    /// The plain-tube case of the same camera.
    pub baseline: &'static str,
    /// What draws the frame.
    pub renderer: FiberRenderer,
    /// Index into the cameras.
    pub camera: usize,
}

/// One warm-up frame of every case (pipelines, bakes; its stats are the table's counts),
/// then each timed in criterion group `group` ([`time_cases`]) at `size` under `light`.
#[allow(dead_code)] // the `lights` bench varies lights, not cameras: its own cases
pub fn run_cases(
    cr: &mut Criterion,
    gpu: &btf_render::Gpu,
    group: &str,
    cases: &[Case],
    cams: &[FiberCamera],
    light: &[FiberLight],
    size: (u32, u32),
) -> (Vec<FiberStats>, Samples) {
    let frame = |c: &Case| {
        let t = Instant::now();
        let img = c.renderer.render(gpu, &cams[c.camera], light, size, [0.0; 4]).unwrap();
        std::hint::black_box(img.pixels.len());
        (t.elapsed().as_secs_f64() * 1e3, img.stats)
    };
    let stats = cases.iter().map(|c| frame(c).1).collect();
    let names: Vec<&'static str> = cases.iter().map(|c| c.name).collect();
    (stats, time_cases(cr, group, &names, |i| frame(&cases[i]).0))
}

/// Times each case `i` (`frame(i)`: one frame, its wall-clock ms) in criterion group
/// `group`, 10 samples a case (frames take 0.2–7 s on lavapipe), recording every frame
/// under `names[i]`.
pub fn time_cases(
    cr: &mut Criterion,
    group: &str,
    names: &[&'static str],
    frame: impl Fn(usize) -> f64,
) -> Samples {
    let samples = Samples::default();
    let mut g = cr.benchmark_group(group);
    g.sampling_mode(SamplingMode::Flat);
    g.sample_size(10);
    for (i, name) in names.iter().enumerate() {
        let smp = samples.clone();
        let frame = &frame;
        g.bench_function(*name, |b| {
            b.iter_custom(|iters| {
                let mut total = 0.0;
                for _ in 0..iters {
                    let ms = frame(i);
                    smp.push(name, ms);
                    total += ms;
                }
                Duration::from_secs_f64(total / 1e3)
            })
        });
    }
    g.finish();
    samples
}
