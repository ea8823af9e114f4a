//! Measured figures of environment lighting on the synthetic shirts (ignored by default):
//! `CARGO_PROFILE_DEV_OPT_LEVEL=3 cargo test -p btf-render --test envlight_measure --
//! --ignored --nocapture` (add `BTF_MEASURE_HIGH=1` for the 9160-vertex shirt). Prints visibility, gather, eigenweightset and full-U timings,
//! the eigenweightset error table (e = 1…8) and writes the o_k(δ) plot.

mod common;

use btf_core::eigen::Quantization;
use btf_render::envlight::eigenweights::relative_error;
use btf_render::envlight::scene_env::EnvMesh;
use btf_render::envlight::{EnvMap, EnvironmentParams, SceneEnvironment, heatmap};
use btf_render::material::MaterialData;
use btf_render::mesh::Mesh;
use btf_render::tangent::compute_tangents;
use datasets::mesh::{MeshKind, Resolution};
use std::time::Instant;

fn sky() -> EnvMap {
    let params = datasets::env::EnvParams::default();
    let m = datasets::env::synth_env(datasets::env::EnvKind::Sky, &params, 512).unwrap();
    EnvMap::new(m.width, m.height, m.pixels, "sky").unwrap()
}

fn shirt(dir: &std::path::Path, res: Resolution) -> Mesh {
    let m = datasets::mesh::synth_mesh(MeshKind::Shirt, res).unwrap();
    let p = dir.join("shirt.obj");
    datasets::mesh::write_obj(&m, &p, "shirt").unwrap();
    Mesh::load_obj(&p, None).unwrap()
}

#[test]
#[ignore = "a measurement (minutes): run for BENCHMARKS.md"]
fn measure_shirts() {
    let dir = tempfile::tempdir().unwrap();
    let store = common::write_store(
        dir.path(),
        "m.eigen",
        common::Pattern::Checker,
        4,
        4,
        16,
        Quantization::F16,
    );
    let mat = MaterialData::load(&store, None).unwrap();
    let env = sky();
    let mut runs = vec![("shirt low", Resolution::Low)];
    if std::env::var("BTF_MEASURE_HIGH").is_ok_and(|v| v == "1") {
        runs.push(("shirt high", Resolution::High));
    }
    for (name, res) in runs {
        let mesh = shirt(dir.path(), res);
        let tangents = compute_tangents(&mesh);
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
            cache_dir: None,
        };
        let t = Instant::now();
        let mut s = SceneEnvironment::new(params, &env, &em, &[&mat]).unwrap();
        let total = t.elapsed().as_secs_f64();
        let tm = s.timings;
        let n = mesh.positions.len();
        eprintln!(
            "{name}: {n} vertices, {} triangles, res 32, two-sided: visibility {:.0} ms ({:.3} ms/vertex-side), gather {:.1} ms, eigenweightsets (30 gathers + PCA) {:.0} ms, total {total:.2} s",
            mesh.triangles.len(),
            tm.visibility_ms,
            tm.visibility_ms / (2 * n) as f64,
            tm.weights_ms,
            tm.eigen_ms
        );
        let t = Instant::now();
        let u = s.weights().full_u(&btf_render::envlight::CoefficientMatrix::from_material(&mat));
        eprintln!(
            "{name}: full U = G·P ({} floats, one sgemm) {:.1} ms",
            u.len(),
            t.elapsed().as_secs_f64() * 1e3
        );
        let mut rot = vec![];
        for k in 0..10 {
            s.set_rotation(7.0 + 13.0 * k as f64);
            rot.push(s.timings.rotation_ms);
        }
        rot.sort_by(f64::total_cmp);
        eprintln!("{name}: rotation through eigenweightsets (e = 5) median {:.2} ms", rot[5]);
        if res == Resolution::Low {
            error_table(&s, dir.path());
        }
    }
}

fn error_table(s: &SceneEnvironment, _dir: &std::path::Path) {
    let metric = s.metric();
    let _ = s.eigenweightsets();
    eprintln!(
        "| e | max rel. error at the 30 sampled rotations | max rel. error between them (δ = 6° + 12°·a) |"
    );
    eprintln!("|---|---|---|");
    let exact_mid: Vec<_> = (0..30).map(|a| s.gather(6.0 + 12.0 * a as f64)).collect();
    let exact_on: Vec<_> = (0..30).map(|a| s.gather(12.0 * a as f64)).collect();
    let ews = btf_render::envlight::EigenWeightSets::build(&exact_on, &metric, 29).unwrap();
    let ev = &ews.eigenvalues;
    let total: f64 = ev.iter().sum();
    let share: Vec<String> = ev[..8].iter().map(|l| format!("{:.3}", l / total)).collect();
    eprintln!("eigenvalue shares (k = 1…8): {}", share.join(", "));
    for e in 1..=8 {
        let on = (0..30)
            .map(|a| relative_error(&ews.reconstruct(12.0 * a as f64, e), &exact_on[a], &metric))
            .fold(0.0, f64::max);
        let mid = (0..30)
            .map(|a| {
                relative_error(&ews.reconstruct(6.0 + 12.0 * a as f64, e), &exact_mid[a], &metric)
            })
            .fold(0.0, f64::max);
        eprintln!("| {e} | {on:.4} | {mid:.4} |");
    }
    let curves: Vec<Vec<f64>> = (0..ews.kept().min(5))
        .map(|k| (0..360).map(|d| ews.coefficients_at(d as f64, k + 1)[k]).collect())
        .collect();
    let out =
        std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("eigenweight-coefficients.png");
    heatmap::write_rgb8(&out, 480, 200, heatmap::line_plot(&curves, 480, 200)).unwrap();
    eprintln!("o_k(δ) plot: {}", out.display());
}
