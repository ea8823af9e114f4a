//! Environment lighting of the synthetic shirt on the CPU (`[S03 eq. 10–13]`; BENCHMARKS.md
//! "environment lighting"): each fast path timed against its reference in the same run, its
//! output compared once before timing (bit for bit; the rotation paths to `f32` rounding).
//!
//! Set-up: the low shirt (925 vertices; `BTF_MEASURE_HIGH=1`: 9160), hemicube 32², two-sided,
//! ubo81 store with c = 16, the synthetic Preetham sky 512×256; visibility from a cache
//! written once (its cost is the `visibility` bench's).
//!
//! - group `gather`: `filter` (binning the map, `EnvCube::new`), `gather` (the vertex-pair
//!   gather `g` of an environment change) against `gather reference` (**baseline**,
//!   frame by frame), and `full U` (`U = G·P`, one sgemm);
//! - group `prepare`: `scene environment` — `SceneEnvironment::new` with eigenweightsets
//!   (30 gathers + PCA, e = 5), visibility from the cache;
//! - group `rotation` (e = 5, the front camera's view slots): `all of G` (forming `G(δ)`),
//!   `gamma* of the view slots` (`G(δ)` then `γ*` per picked slot), `gamma* through the basis`
//!   (`GammaBasis::at`); and the renderer's path, `fill through the camera basis`
//!   (`set_rotation` + `EnvCoefficients::fill`) against `fill direct` (**baseline**,
//!   `fill_direct`: `G(δ)`, then `γ*`).
//!
//! After criterion: markdown tables of the medians and ratios, then (low shirt only) the
//! eigenweightset error table (e = 1…8, at and between the 30 sampled rotations) and the
//! `o_k(δ)` plot (`target/tmp/eigenweight-coefficients.png`).
//!
//! `cargo bench -p btf-light --bench envlight` (`-- --quick` for a short run, `-- rotation`
//! for one group).

mod common;

use btf_core::InterpMode;
use btf_image::plot::{Plot, Series};
use btf_light::eigenweights::relative_error;
use btf_light::math::Vec3;
use btf_light::tangent::compute_tangents;
use btf_light::{
    EnvCoefficients, EnvCube, EnvMesh, EnvironmentParams, GatherInput, Hemicube, HemicubeFrame,
    LightTable, Radiances, SceneEnvironment, Slots, ViewInput, VisibilityMaps,
};
use common::*;
use criterion::SamplingMode;
use std::cell::RefCell;
use std::time::Instant;

/// The camera of the rotation measurements.
const EYE: [f32; 3] = [0.0, -3.0, 0.5];

fn main() {
    let dir = tempfile::tempdir().unwrap();
    let (name, mesh) = shirt(dir.path());
    let (store, p) = store(dir.path(), (4, 4), 16);
    let lights = store.light_sampling().clone();
    let views = store.view_sampling().clone();
    let env = sky();
    let tangents = compute_tangents(&mesh);
    let n = mesh.positions.len();
    let cube = Hemicube::new(32).unwrap();
    let frames = HemicubeFrame::of_mesh(&mesh.positions, &mesh.normals, &tangents, true);
    let cache = dir.path().join("cache");
    let t = Instant::now();
    let (vis, _) =
        VisibilityMaps::cached(&cache, &cube, &frames, &mesh.positions, &mesh.triangles).unwrap();
    println!(
        "{name}: {n} vertices, {} triangles, hemicube 32², two-sided; visibility {:.0} ms (cached for the rest)",
        mesh.triangles.len(),
        ms(t)
    );
    let table = LightTable::new(&cube, &lights, InterpMode::Four).unwrap();
    let input = GatherInput {
        table: &table,
        visibility: &vis,
        frames: &frames,
        dirs: &cube.dirs,
        lights: lights.len(),
    };
    let env_cube = EnvCube::new(&env, 32);
    let same = Radiances::gather(&input, &env_cube, 20.0)
        == Radiances::gather_reference(&input, &env_cube, 20.0);
    println!("{name}: gather and frame-by-frame gather bit-identical: {same}");
    let em = EnvMesh {
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        triangles: &mesh.triangles,
    };
    let params = EnvironmentParams {
        rotation_deg: 0.0,
        exposure: 1.0,
        visibility_res: 32,
        two_sided: true,
        eigen: Some((30, 5)),
        cache_dir: Some(cache),
    };
    let new_env =
        || SceneEnvironment::new(params.clone(), &env, &em, &lights, vec![p.clone()]).unwrap();
    let s = RefCell::new(new_env());

    // the front camera's view slots (frame, slot), and the renderer's per-vertex inputs
    let mut picks = vec![];
    for v in 0..n {
        let to = [0, 1, 2].map(|a| EYE[a] - mesh.positions[v][a]);
        let [t, b, nn] = frames[v].axes;
        let dot = |a: [f32; 3], b: [f32; 3]| (0..3).map(|i| (a[i] * b[i]) as f64).sum::<f64>();
        let (z, f) = if dot(to, nn) >= 0.0 { (dot(to, nn), v) } else { (-dot(to, nn), n + v) };
        let Some(d) = btf_core::Direction::from_vector([dot(to, t), dot(to, b), z]) else {
            continue;
        };
        for &(j, _) in views.view_weights(d, InterpMode::Four).as_slice() {
            picks.push((f, j));
        }
    }
    let k3 = 3 * p.per_slot();
    let stride = 2 + 3 * p.components.div_ceil(4);
    let material_of = vec![0usize; n];
    let samplings = [&views];
    let view = ViewInput {
        eye: Vec3::new(EYE[0], EYE[1], EYE[2]),
        ortho_to_camera: None,
        view_mode: InterpMode::Four,
        positions: &mesh.positions,
        normals: &mesh.normals,
        tangents: &tangents,
        material_of: &material_of,
        view_samplings: &samplings,
    };
    let at = Slots { l: 0, n_lights: 1, stride };

    let samples = Samples::default();
    let mut c = criterion();
    let mut g = c.benchmark_group("gather");
    g.sampling_mode(SamplingMode::Flat);
    let sm = samples.clone();
    g.bench_function("filter", |b| {
        b.iter_custom(|k| timed(k, &sm, "filter", || EnvCube::new(&env, 32)))
    });
    let mut delta = 0.0;
    g.bench_function("gather", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "gather", || {
                delta += 10.0;
                Radiances::gather(&input, &env_cube, delta)
            })
        })
    });
    g.bench_function("gather reference", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "gather reference", || {
                Radiances::gather_reference(&input, &env_cube, 20.0)
            })
        })
    });
    g.bench_function("full U", |b| {
        b.iter_custom(|k| timed(k, &sm, "full U", || s.borrow().radiances().full_u(&p)))
    });
    g.finish();

    let mut g = c.benchmark_group("prepare");
    g.sampling_mode(SamplingMode::Flat);
    g.bench_function("scene environment", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "scene environment", || {
                let e = new_env();
                sm.push("weights", e.timings.weights_ms);
                sm.push("eigen", e.timings.eigen_ms);
            })
        })
    });
    g.finish();

    let mut g = c.benchmark_group("rotation");
    g.sampling_mode(SamplingMode::Flat);
    let mut delta = 7.0;
    let mut turn = || {
        delta = (delta + 13.0) % 360.0;
        delta
    };
    g.bench_function("all of G", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "all of G", || {
                let mut s = s.borrow_mut();
                s.set_rotation(turn());
                std::hint::black_box(s.radiances());
            })
        })
    });
    let mut out = vec![0f32; picks.len() * k3];
    g.bench_function("gamma* of the view slots", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "gamma*", || {
                let mut s = s.borrow_mut();
                s.set_rotation(turn());
                for (i, &(f, j)) in picks.iter().enumerate() {
                    s.radiances().gamma_star(&p, f, j, &mut out[i * k3..(i + 1) * k3]);
                }
            })
        })
    });
    let mut basis = None;
    g.bench_function("gamma* through the basis", |b| {
        let s = s.borrow();
        let ews = s.eigenweightsets().unwrap();
        let basis = basis.get_or_insert_with(|| {
            let t = Instant::now();
            let basis = ews.gamma_basis(&p, &picks, 5).unwrap();
            sm.push("basis build", ms(t));
            basis
        });
        b.iter_custom(|k| {
            timed(k, &sm, "gamma basis at", || basis.at(&ews.coefficients_at(turn(), 5), &mut out))
        })
    });
    let mut coef = vec![[0f32; 4]; n * 4 * stride];
    let mut ec: Option<EnvCoefficients> = None;
    g.bench_function("fill through the camera basis", |b| {
        let ec = ec.get_or_insert_with(|| {
            let mut s = s.borrow_mut();
            let mut ec = EnvCoefficients::default();
            ec.fill(&s, &mut coef, &view, at);
            let t = Instant::now();
            s.set_rotation(3.0);
            ec.fill(&s, &mut coef, &view, at);
            sm.push("fill first", ms(t));
            assert!(ec.used_basis());
            ec
        });
        b.iter_custom(|k| {
            timed(k, &sm, "fill basis", || {
                let mut s = s.borrow_mut();
                s.set_rotation(turn());
                ec.fill(&s, &mut coef, &view, at);
                assert!(ec.used_basis());
            })
        })
    });
    g.bench_function("fill direct", |b| {
        b.iter_custom(|k| {
            timed(k, &sm, "fill direct", || {
                let mut s = s.borrow_mut();
                s.set_rotation(turn());
                btf_light::env_coefficients::fill_direct(&s, &mut coef, &view, at);
            })
        })
    });
    g.finish();
    c.final_summary();

    let m = |case: &str| samples.median(case);
    println!("\n## envlight: {name} ({n} vertices, {} vertex sides), medians\n", frames.len());
    println!("| | ms | baseline | baseline ms | × |");
    println!("|---|---:|---|---:|---:|");
    let row = |label: &str, case: &str, base_label: &str, base: &str| {
        if m(case).is_some() || m(base).is_some() {
            println!(
                "| {label} | {} | {base_label} | {} | {} |",
                num(m(case), 2),
                num(m(base), 2),
                ratio(m(base), m(case), 1)
            );
        }
    };
    let single = |label: &str, case: &str| {
        if m(case).is_some() {
            println!("| {label} | {} | | | |", num(m(case), 2));
        }
    };
    single("filter the map (`EnvCube::new`)", "filter");
    row("gather `g` (environment change)", "gather", "frame-by-frame gather", "gather reference");
    if let (Some(f), Some(gm)) = (m("filter"), m("gather")) {
        println!("| environment change = filter + gather | {:.2} | | | |", f + gm);
    }
    single(&format!("full U = G·P ({} floats)", s.borrow().radiances().full_u(&p).len()), "full U");
    single("scene environment (filter + gather + eigenweightsets 30 + PCA)", "scene environment");
    single("… of which filter + gather", "weights");
    single("… of which eigenweightsets", "eigen");
    single("rotation: all of G", "all of G");
    single(&format!("rotation: G, then γ* of {} view slots", picks.len()), "gamma*");
    single("rotation: γ* through the basis (`GammaBasis::at`)", "gamma basis at");
    single("building the camera's basis (once)", "basis build");
    row(
        "renderer rotation, e = 5 (`set_rotation` + fill) through the camera basis",
        "fill basis",
        "direct fill",
        "fill direct",
    );
    single("first rotation at this camera (builds the basis)", "fill first");

    if !env_flag("BTF_MEASURE_HIGH") {
        error_table(&s.borrow());
    }
}

fn error_table(s: &SceneEnvironment) {
    let metric = s.metric();
    println!(
        "\n| e | max rel. error at the 30 sampled rotations | max rel. error between them (δ = 6° + 12°·a) |"
    );
    println!("|---|---:|---:|");
    let exact_mid: Vec<_> = (0..30).map(|a| s.gather(6.0 + 12.0 * a as f64)).collect();
    let exact_on: Vec<_> = (0..30).map(|a| s.gather(12.0 * a as f64)).collect();
    let ews = btf_light::EigenWeightSets::build(&exact_on, &metric, 29).unwrap();
    let ev = &ews.eigenvalues;
    let total: f64 = ev.iter().sum();
    for e in 1..=8 {
        let on = (0..30)
            .map(|a| relative_error(&ews.reconstruct(12.0 * a as f64, e), &exact_on[a], &metric))
            .fold(0.0, f64::max);
        let mid = (0..30)
            .map(|a| {
                relative_error(&ews.reconstruct(6.0 + 12.0 * a as f64, e), &exact_mid[a], &metric)
            })
            .fold(0.0, f64::max);
        println!("| {e} | {on:.4} | {mid:.4} |");
    }
    let share: Vec<String> = ev[..8].iter().map(|l| format!("{:.3}", l / total)).collect();
    println!("\nEigenvalue shares (k = 1…8): {}", share.join(", "));
    let curves: Vec<Vec<f64>> = (0..ews.kept().min(5))
        .map(|k| (0..360).map(|d| ews.coefficients_at(d as f64, k + 1)[k]).collect())
        .collect();
    let out =
        std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("eigenweight-coefficients.png");
    let plot = Plot {
        title: "eigenweightset coefficients o_k(delta)".into(),
        x_label: "rotation delta (deg)".into(),
        y_label: "o_k".into(),
        log_x: false,
        log_y: false,
        series: curves
            .iter()
            .enumerate()
            .map(|(k, c)| Series {
                name: format!("k = {}", k + 1),
                points: c.iter().enumerate().map(|(d, v)| (d as f64, *v)).collect(),
            })
            .collect(),
    };
    btf_image::write::write_png(&out, &btf_image::plot::render(&plot)).unwrap();
    println!("o_k(δ) plot: {}", out.display());
}
